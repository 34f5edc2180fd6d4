"""[[output.probes]] before any mesh: the rows checked, a point outside the exact body refused naming the probe,
the columns of probes.csv (fepen.runs.probes, fepen.io.probes)."""

import pytest

from fepen import scene
from fepen.errors import InputError
from fepen.io import probes as probes_io
from fepen.runs import shot

TAIL = {"name": "tail", "point": [0.0, 0.144, 0.0]}


def probes(*rows, sets=()):
    return scene.Scene({"output": {"probes": list(rows)}}, list(sets))


def test_inside_points_resolve_with_their_columns():
    sh = shot.resolve(probes(TAIL, {"name": "wall", "point": [0.0, 0.1, 0.0105], "kind": "cell"}))
    assert [p["kind"] for p in sh.probes] == ["node", "cell"]
    assert probes_io.columns(sh.probes) == ["t_s", *[f"tail_{q}" for q in probes_io.NODE_COLUMNS],
                                            *[f"wall_{q}" for q in probes_io.CELL_COLUMNS]]


@pytest.mark.parametrize("point,why", [([0.0, -0.001, 0.0], "length"), ([0.0, 0.15, 0.0], "length"),
                                       ([0.0, 0.1, 0.0125], "radius"), ([0.0, 0.002, 0.004], "radius"),
                                       ([0.0, 0.1, 0.0], "cavity")])
def test_a_point_outside_the_exact_body_is_refused_before_any_mesh(point, why):
    with pytest.raises(InputError) as err:
        shot.resolve(probes(TAIL, {"name": "out", "point": point}))
    assert err.value.key == "output.probes[1].point" and why in str(err.value)


def test_the_charge_fills_the_cavity():
    sh = shot.resolve(probes({"name": "charge", "point": [0.0, 0.1, 0.0], "kind": "cell"},
                             sets=["effects.charge=true"]))
    assert sh.probes[0]["name"] == "charge"


def test_cell_probes_are_refused_with_the_rigid_fidelity():
    with pytest.raises(InputError) as err:
        probes(TAIL, {"name": "c", "point": [0.0, 0.1, 0.0105], "kind": "cell"}, sets=["effects.fidelity=rigid"])
    assert err.value.key == "output.probes[1].kind"
