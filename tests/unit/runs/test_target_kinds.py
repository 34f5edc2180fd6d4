"""The target's kinds (fepen.runs.targets): a target of one material, a layered target and the rigid wall each
answer the same questions their own way (issue 60, item 5), and a resolved Shot carries what its kind says."""

import inspect
import pickle

import numpy as np
import pytest

from fepen import scene
from fepen.errors import InputError
from fepen.laws import layers as fl
from fepen.laws import target as tg
from fepen.runs import setup, shot, targets

LAYERS = """
[impact]
velocity = 800.0

[[target.layers]]
material = "concrete"
thickness = 0.1
gap = 0.2

[[target.layers]]
material = "concrete"
thickness = 0.1
"""


def one_material(*sets):
    return scene.load(None, list(sets))


def layered(*sets):
    return scene.Scene(LAYERS, sets=list(sets))


def wall(*sets):
    return scene.load(None, ['target.kind="rigid-wall"', *sets])


def test_a_scene_s_kind_and_its_law():
    assert isinstance(targets.of(one_material()), targets.SingleTarget)
    assert isinstance(targets.of(layered()), targets.LayeredTarget)
    assert isinstance(targets.of(wall()), targets.RigidWall)
    assert isinstance(targets.of(one_material()).law(one_material()), tg.TargetLaw)
    assert isinstance(targets.of(layered()).law(layered()), fl.Layered)
    assert targets.of(wall()).law(wall()) is None
    # the material's law whatever target.kind (fepen.runs.setup.target_law, the studies' and the tests')
    assert isinstance(setup.target_law(wall()), tg.TargetLaw)


def test_the_hard_end_reaches_a_layered_target_s_last_face():
    sc = layered()
    law = targets.of(sc).law(sc)
    last = law.faces()[-1][0]  # the last front face: 0.1 m of concrete and a 0.2 m gap
    assert last == pytest.approx(0.3) and law.hard_end(5e-3, 800.0) == fl.LAYERED_TIME * last / 800.0 > 5e-3
    assert law.hard_end(1.0, 800.0) == 1.0
    assert targets.of(sc).hard_end(law, 5e-3, 800.0) == law.hard_end(5e-3, 800.0)
    one = one_material()
    assert targets.of(one).hard_end(targets.of(one).law(one), 5e-3, 800.0) == 5e-3
    assert targets.of(wall()).hard_end(None, 5e-3, 800.0) == 5e-3


def test_only_a_target_of_one_material_opens_a_tunnel():
    assert targets.of(one_material()).tunnel(one_material("effects.tunnel=true"))
    assert not targets.of(one_material()).tunnel(one_material("effects.tunnel=false"))
    assert not targets.of(layered()).tunnel(layered("effects.tunnel=true"))
    assert not targets.of(wall()).tunnel(wall("effects.tunnel=true"))


def test_only_a_layered_target_records_crossings():
    sc = layered()
    law = targets.of(sc).law(sc)
    crossings = targets.of(sc).crossings(law)
    assert isinstance(crossings, fl.Crossings) and crossings.faces == law.faces()
    one = one_material()
    assert targets.of(one).crossings(targets.of(one).law(one)) is None
    assert targets.of(wall()).crossings(None) is None


def test_plates_names_and_checks_per_kind():
    one = one_material("target.thickness=0.3")
    assert targets.of(one).plates(one) == [("target.thickness", 0.3)]
    assert targets.of(layered()).plates(layered()) == [("target.layers[0].thickness", 0.1),
                                                       ("target.layers[1].thickness", 0.1)]
    assert targets.of(wall()).plates(wall()) == []
    assert targets.of(one).envelope_name(one) == one.target.material
    assert targets.of(layered()).envelope_name(layered()) == "layered"
    assert targets.of(wall()).envelope_name(wall()) == "a rigid wall"
    with pytest.raises(InputError) as err:
        targets.of(wall()).check(wall("effects.fidelity=rigid"))
    assert err.value.key == "effects.fidelity"
    targets.of(wall()).check(wall("effects.fidelity=plastic"))
    with pytest.raises(InputError) as err:
        targets.of(one).check(one_material("effects.friction=true"))
    assert err.value.key == "effects.friction"


def test_a_shot_carries_its_target_s_kind():
    sh = shot.resolve(layered("effects.fidelity=rigid", "impact.velocity=100.0"), toml=False)
    assert isinstance(sh.target, targets.LayeredTarget) and not sh.tunnel
    assert sh.hard_end == fl.LAYERED_TIME * sh.law.faces()[-1][0] / sh.speed > shot.MAX_TIME["rigid"]
    one = shot.resolve(one_material("effects.fidelity=rigid", "effects.tunnel=true"), toml=False)
    assert isinstance(one.target, targets.SingleTarget) and one.tunnel and one.hard_end == shot.MAX_TIME["rigid"]
    assert pickle.loads(pickle.dumps(one.target)) == one.target != sh.target


def test_every_target_law_takes_the_one_point_forces_signature():
    """fepen.laws.target.load_on_points calls ``law.point_forces(kernel, ..., tunnel, body_xi)`` on every target
    law once TargetLaw has the method (issue 60, item 5): the layered target's takes the same arguments and
    gives the same forces as each of its layers' law alone when there is one layer."""
    params = list(inspect.signature(fl.Layered.point_forces).parameters)
    assert params[-2:] == ["tunnel", "body_xi"]
    sc = scene.Scene("[[target.layers]]\nmaterial = \"concrete\"\n")
    law = targets.of(sc).law(sc)
    x = np.array([[0.0, -0.01, 0.0], [0.01, -0.02, 0.0]])
    v = np.tile([0.0, -300.0, 0.0], (2, 1))
    n = np.array([[0.0, -1.0, 0.0], [0.7071067811865476, -0.7071067811865476, 0.0]])
    args = (x, v, n, np.full(2, 1e-5), np.array([0.0, 0.01]), np.full(2, np.inf), np.array([1.0, 0.7]),
            np.array([0.0, -1.0, 0.0]))
    f, sums = law.point_forces(tg.point_forces, *args, None, None)
    f1, sums1 = tg.point_forces(law.layers[0].law, *args)
    assert np.array_equal(f, f1) and np.array_equal(sums, sums1)
    if hasattr(tg.TargetLaw, "point_forces"):  # once fepen.laws.target gives it (merged separately)
        one = law.layers[0].law
        assert all(np.array_equal(a, b) for a, b in zip(one.point_forces(tg.point_forces, *args, None, None),
                                                        tg.point_forces(one, *args)))


def test_the_wall_answers_for_the_law_it_lacks():
    """What a run asked of a law (its thickness, its crater, its load's zones, a rigid preview) each kind
    answers, the rigid wall without a law: not perforated, no crater, no zones, no rigid shot."""
    one, lay, w = one_material("target.thickness=0.3"), layered(), wall()
    law1, law2 = targets.of(one).law(one), targets.of(lay).law(lay)
    assert targets.of(one).thickness(law1) == pytest.approx(0.3)
    assert targets.of(lay).thickness(law2) == law2.thickness and targets.of(w).thickness(None) is None
    assert targets.of(one).splits_load() and targets.of(lay).splits_load() and not targets.of(w).splits_load()
    assert targets.of(one).takes_rigid() and targets.of(lay).takes_rigid() and not targets.of(w).takes_rigid()
    assert targets.of(w).crater(None, 1.0, 500.0, 3.0, 1.0) is None
    assert targets.of(one).crater(law1, 1.6, 584.0, 3.0, 1.0) is None  # the energy crater is in the law
    lin = one_material("effects.crater=linear")
    crater = targets.of(lin).crater(targets.of(lin).law(lin), 1.6, 584.0, 3.0, 1.0)
    assert isinstance(crater, tg.ForrestalCrater) and crater.depth() > 0.0
