"""The rigid fidelity in the concrete target: force and depth against Forrestal's closed forms, events,
mass properties, rank-count invariance."""

import math

import numpy as np
import pytest
from mpi4py import MPI
from scipy.integrate import trapezoid

from fepen import dolfinx_api as dx
from fepen import scene
from fepen.geometry import mesh, revolution
from fepen.io.results import COL
from fepen.laws import rigid_body as rigid
from fepen.laws import target as tg
from fepen.runs import setup
from fepen.runs.rigid import RigidRun
from fepen.solver import surface

SIGMA_S = tg.forrestal_S(40e6) * 40e6  # Forrestal's S fc: the standard check of such codes
CLOSED_FORM = ["effects.fidelity=rigid", f"target.quasi_static_stress={SIGMA_S}", "target.inertial_factor=1",
               "effects.crater=none", "effects.separation=false", "effects.free_surface=false",
               "impact.obliquity_deg=0", "impact.attack_deg=0",
               "effects.tunnel=false"]  # the closed forms: a rate-independent sigma_s on the nose alone


def nose_force(sc, law, g, crh, speed):
    """The target's forces on load points g moving along the axis at speed, and the closed-form axial force."""
    f, _ = tg.normal_stress(law, g["X"] - [0.0, 1.0, 0.0], np.tile([0.0, -speed, 0.0], (len(g["X"]), 1)), g["N"],
                            g["area0"], g["radius"], g["R_meridian"], g["sin_phi0"], np.array([0.0, -1.0, 0.0]))
    a = 0.5 * sc.projectile.diameter
    return f, math.pi * a * a * (SIGMA_S + tg.ogive_nose_factor(crh) * 2400.0 * speed**2)


@pytest.mark.parametrize("crh", [1.0, 2.0, 3.0, 4.5, 6.0])
def test_nose_force_on_the_exact_surface(crh):
    """The rigid fidelity's load points (rings on the exact surface, fepen.geometry.revolution) of a tangent
    ogive moving along its axis give (pi d^2/4)(sigma_s + N* rho V^2), N* = (8 psi - 1)/(24 psi^2), within
    1e-5, and no side force (the rings are symmetric): |F_x|, |F_z| below 1e-12 of the axial force."""
    sc = scene.load(None, [f"projectile.crh={crh}", *CLOSED_FORM])
    g = revolution.load_points(setup.projectile_shape(sc), sc.mesh.size)
    law = setup.target_law(sc)
    for speed in (300.0, 900.0):
        f, expect = nose_force(sc, law, g, crh, speed)
        assert f[:, 1].sum() == pytest.approx(expect, rel=1e-5)
        assert abs(f[:, 0].sum()) < 1e-12 * expect and abs(f[:, 2].sum()) < 1e-12 * expect


@pytest.mark.parametrize("crh", [2.0, 3.0, 4.5])
def test_nose_force_at_the_default_mesh(crh):
    """The deformable fidelity's load points (mesh facets projected on the exact surface) give the same
    force within 0.5 %; an unstructured mesh is not exactly symmetric: side force below 0.3 %."""
    sc = scene.load(None, [f"projectile.crh={crh}", *CLOSED_FORM])
    pm = setup.mesh(sc, MPI.COMM_SELF)
    V = dx.vector_space(pm.mesh)
    g = surface.gather_global(surface.outer_surface(V, pm.facet_tags, pm.shape), MPI.COMM_SELF)
    law = setup.target_law(sc)
    for speed in (300.0, 900.0):
        f, expect = nose_force(sc, law, g, crh, speed)
        assert f[:, 1].sum() == pytest.approx(expect, rel=5e-3)
        assert abs(f[:, 0].sum()) < 3e-3 * expect and abs(f[:, 2].sum()) < 3e-3 * expect


def nose_entry_speed(rows, nose_length_mm):
    d = np.array(rows)
    depth, speed = d[:, COL["nose_y_mm"]], d[:, COL["speed_m_s"]]
    i = np.flatnonzero(depth >= nose_length_mm)[0]
    return float(np.interp(nose_length_mm, depth[i - 1:i + 1], speed[i - 1:i + 1]))


@pytest.mark.parametrize("crh", [2.0, 3.0, 4.5])
def test_depth_after_the_nose_is_embedded(crh):
    """Acceptance 2: rigid, normal, sigma_s given, B = 1, no crater: once the nose is in at V_e, the rest of
    the depth is M/(2 pi a^2 rho N*) ln(1 + N* rho V_e^2 / sigma_s), within 1 %, for V0 = 300, 600, 900."""
    for v0 in (300.0, 600.0, 900.0):
        depth, rest, summ = after_the_nose(CLOSED_FORM, crh, v0)
        assert depth == pytest.approx(rest, rel=0.01), v0
        # the unstructured mesh is not exactly symmetric: sideways drift below 1 % of the depth
        assert abs(summ["Hx_mm"]) < 1e-2 * summ["Hy_mm"]


#: issue 58's closed form at fepen's defaults: the tunnel on (its elastic wall), the end of the path at 5 m/s,
#: separation at 1 deg; sigma_s given, B = 1, no crater, no free surface, no friction, normal incidence
AT_DEFAULTS = ["effects.fidelity=rigid", f"target.quasi_static_stress={SIGMA_S}", "target.inertial_factor=1",
               "effects.crater=none", "effects.free_surface=false", "effects.friction=false",
               "impact.obliquity_deg=0", "impact.attack_deg=0", "target.separation_angle_deg=1"]


def after_the_nose(sets, crh, v0):
    """(the depth after the nose is in, its closed form M/(2 pi a^2 rho N*) ln(1 + N* rho V_e^2/sigma_s)) (m), and
    the run's summary."""
    sc = scene.load(None, [f"projectile.crh={crh}", f"impact.velocity={v0}", *sets])
    run = RigidRun(sc, None, MPI.COMM_SELF)
    summ = run.run()
    assert summ["outcome"] == "embedded"
    ln_mm = run.shape.nose_length * 1e3
    ve = nose_entry_speed(run.rows, ln_mm)
    a, N, rho = 0.5 * sc.projectile.diameter, tg.ogive_nose_factor(crh), 2400.0
    return (summ["Hy_mm"] - ln_mm) * 1e-3, run.mass / (2 * math.pi * a * a * rho * N) * math.log(
        1 + N * rho * ve**2 / SIGMA_S), summ


@pytest.mark.parametrize("crh", [2.0, 3.0, 4.5])
def test_the_closed_form_holds_at_the_defaults(crh):
    """Issue 58, acceptance 1: Forrestal's tunnel-stage depth at fepen's defaults (the tunnel's wall on, every
    rule at its default) within 1 % for 300, 600 and 900 m/s, and within 0.1 point of the same shot with the
    tunnel off (before: up to +4.69 % at CRH 4.5, 300 m/s, the nose's speed ramp and the wall's damper moving it;
    the tunnel off: +0.25 to +0.53 %)."""
    for v0 in (300.0, 600.0, 900.0):
        on, closed, _ = after_the_nose(AT_DEFAULTS, crh, v0)
        off, _, _ = after_the_nose([*AT_DEFAULTS, "effects.tunnel=false"], crh, v0)
        assert on == pytest.approx(closed, rel=0.01), (v0, on / closed - 1)
        assert abs(on - off) / closed < 1e-3, (v0, on / closed - 1, off / closed - 1)


def test_the_end_of_the_path_is_short_of_the_rest_by_at_most_its_bound(monkeypatch):
    """The run ends embedded at END_SPEED (5 m/s); run on to 0.5 m/s the body goes further by no more than
    M v^2/(2F) (fepen.runs.events.end_of_path), F the nose's static axial force: sigma_s over the projected area
    of its loaded points (here the whole nose: separation at 1 deg), and by more than half of it (the bound is
    not slack: the inertial term is small at 5 m/s)."""
    from fepen.runs import events

    sc = scene.load(None, ["projectile.crh=3", "impact.velocity=600", *AT_DEFAULTS])
    at5 = RigidRun(sc, None, MPI.COMM_SELF).run()
    monkeypatch.setattr(events, "END_SPEED", 0.5)
    run = RigidRun(sc, None, MPI.COMM_SELF)
    at05 = run.run()
    a = 0.5 * sc.projectile.diameter
    bound = events.end_of_path(run.mass, SIGMA_S * math.pi * a * a, 5.0)
    further = (at05["Hy_mm"] - at5["Hy_mm"]) * 1e-3
    assert 0.5 * bound < further <= bound * (1 + 1e-3), (further, bound)
    assert bound < 1e-4  # a tenth of a millimetre at most


@pytest.mark.parametrize("v0", [300.0, 600.0, 900.0])
def test_forrestal_two_stage_depth_with_the_linear_crater(v0):
    """Acceptance 2: with the linear crater (force c z up to k D), Forrestal's two-stage depth within 1 %."""
    sets = [s for s in CLOSED_FORM if not s.startswith("effects.crater")]
    sc = scene.load(None, [f"impact.velocity={v0}", "effects.crater=linear", *sets])
    run = RigidRun(sc, None, MPI.COMM_SELF)
    summ = run.run()
    expect = tg.ForrestalCrater(run.law, run.mass, v0, 3.0).depth()
    assert summ["Hy_mm"] * 1e-3 == pytest.approx(expect, rel=0.01)


@pytest.mark.parametrize("crh", [2.0, 3.0, 4.5])
def test_rigid_shot_has_no_sideways_drift(crh):
    """issue 13 acceptance 5: the default rigid body (rings on the exact surface, the exact solid's mass
    properties; fepen.geometry.revolution) at normal incidence goes straight: sideways travel of the nose
    below 1e-6 of its depth (the volume mesh's facets: up to 1e-2), and the depth within 0.3 % of the
    meshed rigid body's at the default 2.5 mm mesh."""
    # phi_min 0 and no free face: at the calibrated 12 deg the facets' edge of the loaded region puts the meshed
    # body's depth 0.7-1.8 % from the rings', and the free face (now acting at normal incidence) 0.24 %
    # (issue 29's closing note); and with the recalibrated sigma_s (a larger share of the force) the facets'
    # area error puts it 0.25-0.28 % off where the earlier sigma_s gave under 0.2 %: within 0.3 %
    sc = scene.load(None, [f"projectile.crh={crh}", "effects.fidelity=rigid", "impact.obliquity_deg=0",
                           "impact.attack_deg=0", "impact.velocity=700", "target.separation_angle_deg=0",
                           "effects.free_surface=false"])
    free = RigidRun(sc, None, MPI.COMM_SELF).run()
    meshed = RigidRun(sc, None, MPI.COMM_SELF, points="mesh").run()
    assert free["outcome"] == "embedded" and free["cells"] == 0 and meshed["cells"] > 0
    assert abs(free["Hx_mm"]) <= 1e-6 * free["Hy_mm"]
    assert free["Hy_mm"] == pytest.approx(meshed["Hy_mm"], rel=3e-3)


def test_ricochet_and_perforation():
    """Acceptance 6: 250 m/s at 75 degrees ricochets; 800 m/s into a 150 mm slab perforates with a residual
    speed (below the striking speed, above the speed a semi-infinite target would leave at that depth)."""
    rico = RigidRun(scene.load(None, ["effects.fidelity=rigid", "impact.velocity=250", "impact.obliquity_deg=75",
                                      "impact.attack_deg=0"]), None, MPI.COMM_SELF).run()
    assert rico["outcome"] == "ricochet" and 0 < rico["residual_speed_m_s"] < 250
    perf = RigidRun(scene.load(None, ["effects.fidelity=rigid", "impact.velocity=800", "impact.obliquity_deg=0",
                                      "impact.attack_deg=0", "target.thickness=0.15"]), None, MPI.COMM_SELF).run()
    assert perf["outcome"] == "perforated"
    assert 300 < perf["residual_speed_m_s"] < 800
    deep = RigidRun(scene.load(None, ["effects.fidelity=rigid", "impact.velocity=800", "impact.obliquity_deg=0",
                                      "impact.attack_deg=0"]), None, MPI.COMM_SELF).run()
    assert deep["outcome"] == "embedded" and deep["Hy_mm"] > 150 + 144


@pytest.mark.parametrize("sets", [["projectile.nose=flat", "projectile.cavity_diameter=0"], [],
                                  ["effects.charge=true"], ["projectile.crh=1", "projectile.cavity_diameter=0"]])
def test_exact_mass_properties_against_the_mesh(sets):
    """The exact solid of revolution (fepen.geometry.revolution) against the exact integrals over a fine
    tetrahedral mesh of the same body: mass and centre within the mesh's faceting (its volume deficit is
    about h^2/(6 R^2)), the inertia likewise; a flat solid rod against the closed forms to round-off. The
    default 2.5 mm mesh (the faceting bound 1.1 %; 1.5 mm gave 0.6 % for four times the meshing)."""
    h = 2.5e-3
    sc = scene.load(None, [f"mesh.size={h}", *sets])
    shape = setup.projectile_shape(sc)
    rho_c = sc.charge.material.density if sc.effects.charge else None
    m, c, inertia = revolution.mass_properties(shape, 7850.0, rho_c)
    if sets[:1] == ["projectile.nose=flat"]:
        R, L = 0.0118, 0.144
        assert m == pytest.approx(7850.0 * math.pi * R * R * L, rel=1e-13)
        assert c[1] == pytest.approx(L / 2, rel=1e-13)
        assert inertia[1, 1] == pytest.approx(0.5 * m * R * R, rel=1e-13)
        assert inertia[0, 0] == pytest.approx(m * (3 * R * R + L * L) / 12, rel=1e-13)
    assert m == pytest.approx(shape.mass(7850.0, rho_c), rel=1e-12)
    pm = setup.mesh(sc, MPI.COMM_SELF)
    p = mesh.cell_points(pm.mesh)
    rho = np.full(len(p), 7850.0)
    if sc.effects.charge:
        rho[mesh.owned_cells_tagged(pm, 2)] = rho_c
    mm, first, second = rigid.tet_mass_properties(p, rho)
    cm, im = rigid.inertia_about_centre(mm, first, second)
    faceting = 1.5 * (h / 0.0118) ** 2 / 6  # the inscribed mesh's volume deficit, with a margin
    assert mm == pytest.approx(m, rel=faceting)  # (a hollow mesh's cavity is sized to reach the mass)
    assert cm[1] == pytest.approx(c[1], rel=faceting)
    assert np.diag(im) == pytest.approx(np.diag(inertia), rel=2 * faceting)
    assert inertia[0, 1] == inertia[0, 2] == inertia[1, 2] == 0.0


def test_mass_properties_of_a_cylinder():
    """Exact tetrahedral integration: a solid flat rod's mass, centre and inertia against closed forms."""
    sc = scene.load(None, ["projectile.nose=flat", "projectile.cavity_diameter=0", "mesh.size=0.003"])
    pm = setup.mesh(sc, MPI.COMM_SELF)
    p = mesh.cell_points(pm.mesh)
    m, first, second = rigid.tet_mass_properties(p, np.full(len(p), 7850.0))
    c, inertia = rigid.inertia_about_centre(m, first, second)
    vol = sum(np.abs(np.linalg.det(np.stack([q[1] - q[0], q[2] - q[0], q[3] - q[0]]))) / 6 for q in p)
    assert m == pytest.approx(7850.0 * vol, rel=1e-12)
    R, L = 0.0118, 0.144
    assert c == pytest.approx([0.0, L / 2, 0.0], abs=1e-5)  # unstructured mesh: ~1 um off the axis
    assert inertia[1, 1] == pytest.approx(0.5 * m * R * R, rel=0.02)  # faceting of the radius
    assert inertia[0, 0] == pytest.approx(m * (3 * R * R + L * L) / 12, rel=0.01)
    assert abs(inertia[0, 1]) < 1e-6 * inertia[0, 0]


def test_quaternions_round_trip():
    rng = np.random.default_rng(1)
    for _ in range(5):
        q = rng.standard_normal(4)
        q /= np.linalg.norm(q)
        R = rigid.quat_to_matrix(q)
        assert np.allclose(R @ R.T, np.eye(3), atol=1e-14)
        q2 = rigid.matrix_to_quat(R)
        assert np.allclose(q2, q if q2 @ q > 0 else -q, atol=1e-12)


@pytest.mark.mpi
def test_rigid_run_is_the_same_on_any_rank_count():
    """Acceptance 5: a rigid shot on COMM_WORLD and on one process agree to round-off: 1e-12 of the depth
    for lengths (the mass properties are summed in the cells' original order and the load points sorted by
    position; what remains differs in the last bit, and C7's tail travel of ~1.5 mm is a small difference
    of large numbers)."""
    sets = ["effects.fidelity=rigid", 'impact.shot="C7"']
    world = RigidRun(scene.load(None, sets), None, MPI.COMM_WORLD).run()
    alone = RigidRun(scene.load(None, sets), None, MPI.COMM_SELF).run()
    scale = {"residual_speed_m_s": 1.0}
    for k in ("Hx_mm", "Hy_mm", "Tx_mm", "Ty_mm", "residual_speed_m_s"):
        assert world[k] == pytest.approx(alone[k], rel=0, abs=1e-12 * scale.get(k, abs(alone["Hy_mm"]))), k
    assert world["steps"] == alone["steps"]


def wear_run(v0, *sets, out=None):
    sc = scene.load(None, ["effects.fidelity=rigid", "effects.wear=true", f"impact.velocity={v0}",
                           "impact.obliquity_deg=0", "impact.attack_deg=0", *sets])
    return RigidRun(sc, out, MPI.COMM_SELF).run()


def test_rigid_wear_conserves_mass_and_energy_and_scales_with_striking_energy(tmp_path):
    """Scalar wear: the removed mass is η Q/h of the interface heat, the mass is conserved, the energy balance
    holds with the removed material's kinetic energy, and the mass loss grows with the striking kinetic
    energy (Silling and Forrestal 2007)."""
    eta1 = ("projectile.wear.efficiency=1", 'projectile.wear.distribution="surface"')
    runs = {v: wear_run(v, *eta1, out=tmp_path / str(v) if v == 700 else None) for v in (500, 700, 900)}
    for v, s in runs.items():
        ke0 = 0.5 * s["mass_kg"] * v * v
        h = 470.0 * (1765.0 - 294.0) + 2.7e5
        assert s["mass_loss_kg"] == pytest.approx(s["wear_heat_J"] / h, rel=1e-12)  # eta = 1 here
        assert s["energy_error"] < 1e-6
        assert 0.0 < s["removed_kinetic_J"] < 0.5 * s["mass_loss_kg"] * v * v
        assert 0.2 < s["wear_heat_J"] / ke0 < 0.6  # μ = 0.1 on a CRH 3 nose
    ratio = [runs[v]["mass_loss_kg"] / v**2 for v in (500, 700, 900)]
    assert max(ratio) / min(ratio) < 1.15
    hist = np.genfromtxt(tmp_path / "700" / "history.csv", delimiter=",", names=True)
    s = runs[700]
    assert hist["mass_kg"][0] == pytest.approx(s["mass_kg"], rel=1e-15)
    assert hist["mass_kg"][0] - hist["mass_kg"][-1] == pytest.approx(s["mass_loss_kg"], rel=1e-6)  # 9 digits
    for s in runs.values():  # the body's mass, decremented step by step, and the removed mass add up
        assert s["remaining_mass_kg"] + s["mass_loss_kg"] == pytest.approx(s["mass_kg"], rel=1e-12)
    assert np.all(np.diff(hist["wear_heat_J"]) >= 0.0)


def test_rigid_wear_off_or_without_melting_changes_nothing():
    """At one σ_s (wear on otherwise takes its own scaled-S constants): no melting is no wear; the calibrated
    wear shortens the nose by about 1.95 mm per percent of mass (the nose's own volume), and the worn
    projectile stops sooner."""
    sigma = "target.quasi_static_stress=5.0e8"
    plain = wear_run(700, "effects.wear=false", sigma)
    none = wear_run(700, "projectile.wear.efficiency=0", sigma)
    assert none["mass_loss_kg"] == 0.0 and none["wear_heat_J"] > 0.0
    assert none["Hy_mm"] == pytest.approx(plain["Hy_mm"], rel=1e-12)
    assert plain["mass_loss_kg"] == 0.0 and plain["wear_heat_J"] == 0.0  # the removal keys of every run
    assert none["length_change_mm"] == 0.0
    worn = wear_run(700, sigma)
    assert worn["Hy_mm"] < plain["Hy_mm"]  # a lighter, blunter projectile stops sooner
    from fepen.runs import setup

    sc = scene.load(None, [])
    shp, rho = setup.projectile_shape(sc), sc.projectile.material.density
    z = np.linspace(0.0, shp.nose_length, 20001)
    zone = np.pi * trapezoid(shp.outer_radius(z) ** 2, z)  # the nose's volume ahead of the shoulder
    per_kg = shp.nose_length / (rho * zone)  # m of length per kg: exact for the contraction
    assert -worn["length_change_mm"] * 1e-3 == pytest.approx(per_kg * worn["mass_loss_kg"], rel=1e-6)
    assert -worn["length_change_mm"] / worn["mass_loss_percent"] == pytest.approx(1.95, rel=0.05)  # about
    mass_only = wear_run(700, sigma, 'projectile.wear.distribution="surface"')
    assert mass_only["length_change_mm"] == 0.0 and worn["Hy_mm"] < mass_only["Hy_mm"]


def test_erosion_on_a_rigid_run_is_refused_before_meshing():
    with pytest.raises(Exception, match="effects.erosion"):
        scene.load(None, ["effects.erosion=true", "effects.fidelity=rigid"])
