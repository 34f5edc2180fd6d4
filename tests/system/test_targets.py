"""Projectiles of every nose family and targets of every kind, against closed forms: the deformable
fidelity's facet load points on each family's mesh, Forrestal–Warren's rigid depth into 6061-T6511, layered
targets (touching layers, gaps, a thin slab's residual speed), and a deformable shot through a layered target
into a metal plate on 1 and 2 ranks."""

import math
import tempfile

import numpy as np
import pytest
from mpi4py import MPI

from fepen import scene
from fepen.geometry import revolution
from fepen.laws import target as tg
from fepen.runs import rigid, setup
from fepen.runs.deformable import DeformableRun
from fepen.runs.rigid import RigidRun
from fepen.studies import closed_forms

NORMAL = ["effects.fidelity=rigid", "impact.obliquity_deg=0", "impact.attack_deg=0"]
FAMILIES = {"ogive": [], "secant": ["projectile.nose_length=0.025", "projectile.crh=4.0"],
            "cone": ["projectile.nose_length=0.03"], "hemisphere": [], "ellipsoid": ["projectile.nose_length=0.03"],
            "flat": [], "ogive-meplat": ["projectile.meplat_diameter=0.008"],
            "cone-meplat": ["projectile.nose_length=0.03", "projectile.meplat_diameter=0.008"]}


@pytest.mark.parametrize("name", list(FAMILIES))
def test_mesh_facets_give_the_closed_form_nose_force(name):
    """The deformable fidelity's load points (one per outer facet of the default 2.5 mm mesh, on the exact
    surface) on a nose moving along its axis: (π d²/4)(σ_s + N* ρ V²) within 0.5 %."""
    sc = scene.Scene(None, [f"projectile.nose={name.split('-')[0]}", "effects.crater=none",
                            "effects.free_surface=false", "mesh.optimize=none",
                            "target.separation_angle_deg=0", *NORMAL,
                            *FAMILIES[name]])
    pts, _, _ = rigid.mesh_points(sc, MPI.COMM_SELF)
    law, shape = setup.target_law(sc), setup.projectile_shape(sc)
    V = 800.0
    x = pts["X"] - np.array([0.0, 10.0, 0.0])
    v = np.tile([0.0, -V, 0.0], (len(x), 1))
    load = tg.load_on_points(law, x, v, pts["N"], pts["area0"], pts["radius"], pts["R_meridian"], pts["sin_phi0"],
                             np.array([0.0, -1.0, 0.0]))
    exact = math.pi * shape.radius**2 * (law.sigma_s + shape.nose_factor() * law.density * V * V)
    assert load.total[1] == pytest.approx(exact, rel=5e-3)


METAL = ["target.material='6061-T6511'", "projectile.diameter=0.0071", "projectile.length=0.071",
         "projectile.cavity_diameter=0", "projectile.material.name='aisi-4340'", "effects.free_surface=false",
         "effects.tunnel=false", *NORMAL]


def forrestal_warren_depth(sc) -> float:
    """The closed form (fepen.studies.closed_forms.depth_with_nose_entry) of the scene's tangent ogive (m)."""
    shape, law = setup.projectile_shape(sc), setup.target_law(sc)
    m = revolution.mass_properties(shape, sc.projectile.material.density)[0]
    r, slope, ln = closed_forms.tangent_ogive(shape.radius, shape.crh)
    return closed_forms.depth_with_nose_entry(r, slope, ln, m, law.density, law.B, law.sigma_s, shape.nose_factor(),
                                              sc.impact.velocity)


@pytest.mark.parametrize("v0", [500.0, 800.0, 1100.0])
def test_rigid_depth_into_6061_against_forrestal_warren(v0):
    """A CRH-3, 7.1 mm 4340 rod into 6061-T6511: the depth within 1 % of the closed form (it is within
    1e-4)."""
    sc = scene.Scene(None, [*METAL, f"impact.velocity={v0}"])
    depth = RigidRun(sc, None, MPI.COMM_SELF).run()["depth_mm"]
    assert depth == pytest.approx(1e3 * forrestal_warren_depth(sc), rel=1e-2)


def run(text, sets):
    return RigidRun(scene.Scene(text, NORMAL + ["impact.velocity=700", *sets]), None, MPI.COMM_SELF).run()


def test_two_touching_layers_are_one_layer_of_their_summed_thickness():
    one = run("[target]\nthickness = 1.0\n", [])
    two = run("[[target.layers]]\nthickness = 0.15\n[[target.layers]]\nthickness = 0.85\n", [])
    assert two["depth_mm"] == pytest.approx(one["depth_mm"], rel=5e-3)
    assert two["outcome"] == one["outcome"] == "embedded"


def test_a_gap_changes_nothing_but_the_time():
    runs = {gap: run(f"[[target.layers]]\nthickness = 0.1\ngap = {gap}\n[[target.layers]]\n", [])
            for gap in (0.5, 1.0)}
    near, far = runs[0.5], runs[1.0]
    assert far["depth_in_last_layer_mm"] == pytest.approx(near["depth_in_last_layer_mm"], rel=1e-3)
    v_exit = near["layers"][0]["exit_speed_m_s"]
    assert far["layers"][0]["exit_speed_m_s"] == pytest.approx(v_exit, rel=1e-9)
    for r in (near, far):  # nothing is lost in the air
        assert r["layers"][1]["entry_speed_m_s"] == pytest.approx(r["layers"][0]["exit_speed_m_s"], rel=1e-4)
    dt = far["layers"][1]["entry_time_s"] - near["layers"][1]["entry_time_s"]
    assert dt == pytest.approx(0.5 / v_exit, rel=1e-4)


@pytest.mark.parametrize("h", [0.05, 0.1])
def test_a_thin_slabs_residual_speed_against_its_closed_form(h):
    """No crater, no free surface: v_r² = (v0² + σ_s/(N* ρ)) exp(−2 π a² N* ρ h / m) − σ_s/(N* ρ)."""
    sets = ["effects.crater=none", "effects.free_surface=false", "impact.velocity=800",
            "target.separation_angle_deg=0", "effects.tunnel=false"]  # the closed form
    sc = scene.Scene(f"[target]\nthickness = {h}\n", NORMAL + sets)
    s = RigidRun(sc, None, MPI.COMM_SELF).run()
    law, shape = setup.target_law(sc), setup.projectile_shape(sc)
    exact = closed_forms.slab_residual_speed(800.0, h, shape.radius, s["mass_kg"], law.density, law.sigma_s,
                                             shape.nose_factor())
    assert s["outcome"] == "perforated"
    assert s["residual_speed_m_s"] == pytest.approx(exact, rel=2e-2)


LAYERED_METAL = """
[[target.layers]]
material = "concrete"
thickness = 0.03
gap = 0.005
[[target.layers]]
material = "6061-T6511"
"""


def layered_history(comm):
    sc = scene.Scene(LAYERED_METAL, ["effects.fidelity=plastic", "impact.velocity=800", "impact.obliquity_deg=5",
                                     "mesh.size=0.004", "run.fields=false", "run.end_time=6e-5",
                                     "run.figures=false"])
    out = comm.bcast(tempfile.mkdtemp(prefix="fepen-") if comm.rank == 0 else None, root=0)
    sim = DeformableRun(sc, out, comm)
    summary = sim.run()
    return np.array(sim.rows), summary


@pytest.mark.mpi
def test_a_deformable_shot_through_a_slab_into_a_metal_plate_is_the_same_on_any_rank_count():
    world, sw = layered_history(MPI.COMM_WORLD)
    alone, sa = layered_history(MPI.COMM_SELF)
    assert world.shape == alone.shape
    cols = [1, 2, 3, 4, 5]  # nose x, y, tail x, y, speed
    assert np.max(np.abs(world[:, cols] - alone[:, cols])) <= 1e-10 * np.abs(alone[:, cols]).max()
    assert sa["layers"][1]["entry_time_s"] is not None  # the nose reached the plate (the tail is still in the slab)
    assert sw["layers"][1]["entry_speed_m_s"] == pytest.approx(sa["layers"][1]["entry_speed_m_s"], rel=1e-10)
    assert alone[-1, 2] > 40.0  # the nose is in the plate
