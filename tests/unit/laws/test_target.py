"""The target resistance law on plain arrays (no mesh): limits, closed forms, switches."""

import math
from dataclasses import replace

import numpy as np
import pytest
import target_oracle as oracle

from fepen import scene
from fepen.laws import target as tg
from fepen.runs import setup

SMALL = 1e-12  # m^2: a load point so small that it is wholly on one side of a face


def law(**kw):
    base = dict(density=2400.0, Y=40e6, E=32.5e9, T=4e6, lam=0.67, sigma_s=300e6, B=1.0,
                c_over_a=tg.cavity_ratio(40e6, 32.5e9, 4e6))
    base.update(kw)
    return tg.TargetLaw(**base)


def test_quasi_static_stress_limits():
    Y, E, T = 40e6, 32.5e9, 4e6
    ca = tg.cavity_ratio(Y, E, T)
    assert (1 / ca) ** 3 == pytest.approx(9 * Y / (4 * E) * math.sqrt(Y / (2 * T)), rel=1e-14)
    tresca = Y * (1 + 2 * math.log(ca))
    assert tg.quasi_static_stress(Y, E, T, 0.0) == pytest.approx(tresca, rel=1e-14)
    for lam in (1e-6, 1e-9):
        assert tg.quasi_static_stress(Y, E, T, lam) == pytest.approx(tresca, rel=10 * lam)
    # the direct formula for a finite lambda
    lam = 0.67
    alpha = 6 / (3 + 2 * lam)
    direct = Y / lam * (2 / alpha * ca ** (alpha * lam) - (3 - lam) / 3)
    assert tg.quasi_static_stress(Y, E, T, lam) == pytest.approx(direct, rel=1e-13)
    # no plastic zone (c = a): the stress at the wall is the unconfined strength
    assert tg.quasi_static_stress(Y, E, T, lam, 1.0) == pytest.approx(Y, rel=1e-14)
    # tau0 = (3 - lambda) Y / 3 is Table 3's 31.07 MPa
    assert (3 - 0.67) * 40 / 3 == pytest.approx(31.07, abs=0.005)


def ogive_surface(crh, a=0.0118, nz=4000, nt=64, speed=600.0):
    """Exact quadrature points on a tangent-ogive nose moving along -y (tip at the origin, body at y > 0),
    embedded deep in the target."""
    s = 2 * a * crh
    ln = a * math.sqrt(4 * crh - 1)
    zg, wz = np.polynomial.legendre.leggauss(nz // 8)
    edges = np.linspace(0, ln, 9)
    z = np.concatenate([0.5 * (b - a_) * (zg + 1) + a_ for a_, b in zip(edges[:-1], edges[1:])])
    wzz = np.concatenate([0.5 * (b - a_) * wz for a_, b in zip(edges[:-1], edges[1:])])
    r = np.sqrt(s * s - (ln - z) ** 2) - (s - a)
    dr = (ln - z) / np.sqrt(s * s - (ln - z) ** 2)
    th = (np.arange(nt) + 0.5) * 2 * math.pi / nt
    Z, TH = np.meshgrid(z, th, indexing="ij")
    R, DR = np.meshgrid(r, th, indexing="ij")[0], np.meshgrid(dr, th, indexing="ij")[0]
    W = np.meshgrid(wzz, th, indexing="ij")[0] * 2 * math.pi / nt
    norm = np.sqrt(1 + DR**2)
    n = np.stack([np.cos(TH) / norm, -DR / norm, np.sin(TH) / norm], axis=-1).reshape(-1, 3)
    x = np.stack([R * np.cos(TH), Z - 10.0, R * np.sin(TH)], axis=-1).reshape(-1, 3)
    area = (R * norm * W).ravel()
    v = np.tile([0.0, -speed, 0.0], (len(area), 1))
    flat = np.full(len(area), np.inf)
    return oracle.SurfaceState(x, v, n, area, R.ravel(), flat, np.zeros(len(area)))


@pytest.mark.parametrize("crh", [2.0, 3.0, 4.5])
def test_exact_ogive_force_is_forrestals(crh):
    """Integrating the nodal law over the exact ogive gives (pi d^2/4)(sigma_s + N* rho V^2)."""
    L = law()
    s = ogive_surface(crh)
    f, sig = oracle.forces(L, s)
    a, V = 0.0118, 600.0
    expect = math.pi * a * a * (L.sigma_s + tg.ogive_nose_factor(crh) * L.density * V * V)
    assert f[:, 1].sum() == pytest.approx(expect, rel=1e-6)
    assert abs(f[:, 0].sum()) < 1e-9 * expect and abs(f[:, 2].sum()) < 1e-9 * expect


def test_only_inside_and_approaching_points_are_loaded():
    L = law(thickness=0.1)
    n = np.array([[0, -1.0, 0]] * 4)
    x = np.array([[0, 0.01, 0], [0, -0.05, 0], [0, -0.2, 0], [0, -0.05, 0]])
    v = np.array([[0, -100.0, 0], [0, -100.0, 0], [0, -100.0, 0], [0, 100.0, 0]])  # last one moves away
    st = oracle.SurfaceState(x, v, n, np.full(4, SMALL), np.ones(4), np.full(4, np.inf), np.zeros(4))
    sig, ins, vn = oracle.compiled_stress(L, st)
    assert list(ins) == [False, True, False, True]
    assert sig[0] == 0 and sig[2] == 0 and sig[3] == 0
    assert sig[1] == pytest.approx(300e6 + 2400 * 100.0**2)


def test_separation_angle_unloads_shallow_surfaces():
    L = law(separation=True, phi_min=math.radians(10))
    ang = np.radians([5.0, 15.0])
    n = np.stack([np.cos(ang), -np.sin(ang), 0 * ang], axis=1)  # surface at angle phi to the motion (-y)
    st = oracle.SurfaceState(np.array([[0, -0.05, 0]] * 2), np.array([[0, -300.0, 0]] * 2), n, np.full(2, SMALL),
                         np.ones(2), np.full(2, np.inf), np.zeros(2))
    sig, _, _ = oracle.compiled_stress(L, st)
    assert sig[0] == 0 and sig[1] > 0
    assert oracle.compiled_stress(law(), st)[0][0] > 0  # without separation both are loaded


def test_free_surface_truncates_the_plastic_zone():
    L = law(free_surface=True, sigma_s=float(tg.quasi_static_stress(40e6, 32.5e9, 4e6, 0.67)))
    n = np.array([[0.0, 1.0, 0.0]] * 3)  # facing the face, moving towards it (v.n > 0)
    x = np.array([[0, -1e-5, 0], [0, -0.005, 0], [0, -1.0, 0]])
    v = np.array([[0, 1e-3, 0]] * 3)
    st = oracle.SurfaceState(x, v, n, np.full(3, SMALL), np.full(3, 0.01), np.full(3, np.inf), np.zeros(3))
    sig, _, _ = oracle.compiled_stress(L, st)
    assert sig[0] == pytest.approx(40e6, rel=2e-3)  # at the face: Y
    assert sig[0] < sig[1] < sig[2]
    assert sig[2] == pytest.approx(L.sigma_s, rel=1e-9)  # deep: the full cavity-expansion stress


def test_escape_length_is_the_shortest_distance_to_a_face():
    """L_e is the distance to the nearest face whatever the normal (theory.md §8.3): the depth below the
    front face, or the distance to a slab's rear face when that is nearer; finite at normal incidence. Seen
    through the free-surface rule, which truncates the plastic zone at L_e."""
    base = dict(free_surface=True, sigma_s=float(tg.quasi_static_stress(40e6, 32.5e9, 4e6, 0.67)))

    def sigma(x, **kw):
        k = len(x)
        st = oracle.SurfaceState(np.array(x), np.tile([0.0, 1e-3, 0.0], (k, 1)), np.tile([0.0, 1.0, 0.0], (k, 1)),
                                 np.full(k, SMALL), np.full(k, 0.1), np.full(k, np.inf), np.zeros(k))
        return oracle.compiled_stress(law(**base, **kw), st)[0]  # radius 0.1: c/a is cut short to 0.29 m

    half = sigma([[0.0, -0.01, 0.0], [0.0, -0.05, 0.0], [0.3, -0.05, 0.2], [0.0, -0.29, 0.0]])
    assert half[1] == half[2]  # lateral position does not matter
    assert half[0] < half[1] < half[3]
    slab = sigma([[0.0, -0.29, 0.0], [0.0, -0.05, 0.0]], thickness=0.3)
    assert slab[0] == pytest.approx(half[0], rel=1e-12)  # 0.01 from the rear face is 0.01 from the front
    assert slab[1] == pytest.approx(half[1], rel=1e-12)


def test_free_surface_reach_scales_the_truncation():
    """surface_range r: c/a -> min(c/a, 1 + L_e/(r rho)): r = 2 at depth 2h gives what r = 1 gives at h."""
    base = dict(free_surface=True, sigma_s=float(tg.quasi_static_stress(40e6, 32.5e9, 4e6, 0.67)))
    n = np.array([[0.0, -1.0, 0.0]])
    v = np.array([[0.0, -100.0, 0.0]])

    def sigma(r, h):
        st = oracle.SurfaceState(np.array([[0.0, -h, 0.0]]), v, n, np.full(1, SMALL), np.full(1, 0.01),
                             np.full(1, np.inf), np.zeros(1))
        return oracle.compiled_stress(law(surface_range=r, **base), st)[0][0]

    assert sigma(2.0, 0.02) == pytest.approx(sigma(1.0, 0.01), rel=1e-12)
    assert sigma(2.0, 0.02) < sigma(1.0, 0.02)


def test_cube_strength_converts_by_eurocode_2():
    """EN 1992-1-1 Table 3.1: C40/50 (a 50 MPa cube is a 40 MPa cylinder), linear between classes, the end
    classes' ratios outside; a cylinder strength is returned as is; anything else is refused."""
    assert tg.cylinder_strength(50e6, "cube") == pytest.approx(40e6)
    assert tg.cylinder_strength(41e6, "cube") == pytest.approx(32.5e6)  # between C30/37 and C35/45
    assert tg.cylinder_strength(10e6, "cube") == pytest.approx(8e6)
    assert tg.cylinder_strength(210e6, "cube") == pytest.approx(180e6)
    assert tg.cylinder_strength(33e6, "cylinder") == 33e6
    cubes = np.linspace(5e6, 200e6, 300)
    assert np.all(np.diff([tg.cylinder_strength(c, "cube") for c in cubes]) > 0)  # monotonic
    with pytest.raises(ValueError):
        tg.cylinder_strength(40e6, "prism")


def test_the_papers_concrete_is_a_cube_strength():
    """The default concrete is the paper's C40 (cube): f_c = 31.875 MPa, T = f_c/10; a strength given without
    a basis is a cylinder's, and a given cube strength is converted."""
    L = setup.target_law(scene.load(None, []))
    assert L.Y == pytest.approx(31.875e6) and L.T == pytest.approx(3.1875e6)
    L = setup.target_law(scene.load(None, ["target.compressive_strength=40e6"]))
    assert L.Y == 40e6 and L.T == pytest.approx(4e6)
    L = setup.target_law(scene.load(None, ["target.compressive_strength=50e6", 'target.strength_basis="cube"']))
    assert L.Y == pytest.approx(40e6)


def test_friction_opposes_sliding():
    L = law(friction=True, mu=0.2)
    n = np.array([[1.0, 0.0, 0.0]])
    v = np.array([[50.0, -400.0, 0.0]])
    st = oracle.SurfaceState(np.array([[0, -0.05, 0]]), v, n, np.array([2e-6]), np.ones(1), np.full(1, np.inf),
                         np.zeros(1))
    f, sig = oracle.forces(L, st)
    assert f[0, 0] == pytest.approx(-sig[0] * 2e-6)
    assert f[0, 1] == pytest.approx(0.2 * sig[0] * 2e-6)  # against the -y sliding
    assert f[0, 2] == 0


def test_energy_crater_limits():
    """At the face the medium is thrown out (no resistance); deep down it is the tunnel law."""
    L = law(crater="energy", D=0.0236, k=2.37, c_over_a=tg.cavity_ratio(40e6, 32.5e9, 4e6))
    ny = math.sin(math.radians(30))
    n = np.array([[math.cos(math.radians(30)), ny, 0.0]] * 3)
    depths = np.array([1e-5, 0.02, 2.0])  # the last is past k D: always the tunnel law
    x = np.stack([np.full(3, 0.01), -depths, np.zeros(3)], axis=1)
    v = np.tile(np.array(n[0]) * 300.0, (3, 1))
    st = oracle.SurfaceState(x, v, n, np.full(3, SMALL), np.full(3, 0.01), np.full(3, 0.07), np.full(3, 0.3))
    sig, _, vn = oracle.compiled_stress(L, st)
    tunnel = L.sigma_s + L.density * vn**2
    assert sig[0] == 0.0
    assert sig[2] == pytest.approx(tunnel[2])
    # the balance alone: deep but shallower than k D, a slow point is confined, a fast one is thrown out
    x2 = np.array([[0.01, -0.04, 0.0]] * 2)
    v2 = np.stack([np.array(n[0]) * 10.0, np.array(n[0]) * 2000.0])
    st2 = oracle.SurfaceState(x2, v2, n[:2], np.full(2, SMALL), np.full(2, 0.01), np.full(2, 0.07), np.full(2, 0.3))
    sig2 = oracle.compiled_stress(L, st2)[0]
    assert sig2[0] > 0.0 and sig2[1] == 0.0


def test_forrestal_two_stage_depth_closed_form():
    L = law(sigma_s=tg.forrestal_S(40e6) * 40e6, D=0.0236, k=2.0)
    fc = tg.ForrestalCrater(L, 0.367, 600.0, 3.0)
    a, kd, N = 0.0118, 2.0 * 0.0236, tg.ogive_nose_factor(3.0)
    # continuity at k D and energy of stage 1: M (V0^2 - V1^2) / 2 = c (kd)^2 / 2
    assert 0.367 * (600.0**2 - fc.v1_sq) == pytest.approx(fc.c * kd * kd, rel=1e-12)
    assert fc.c * kd == pytest.approx(math.pi * a * a * (L.sigma_s + N * 2400 * fc.v1_sq), rel=1e-12)
    assert fc.scale(kd / 2, 1.0) == pytest.approx(fc.c * kd / 2)
    assert fc.scale(2 * kd, 123.0) == 1.0


def test_scene_builds_the_law():
    sc = scene.load(None, ["effects.crater=linear", "target.quasi_static_stress=4.4e8"])
    L = setup.target_law(sc)
    assert L.sigma_s == 4.4e8 and L.crater == "linear" and L.given_sigma_s
    L2 = setup.target_law(scene.load(None, ["target.strength_model=cavity-expansion",
                                            "target.compressive_strength=40e6"]))
    E = 4.7e9 * math.sqrt(40.0)  # ACI 318 from fc when target.youngs_modulus is absent
    assert L2.E == pytest.approx(E) and not L2.given_sigma_s
    assert L2.sigma_s == pytest.approx(float(tg.quasi_static_stress(40e6, E, 4e6, 0.67)))
    assert L2.crush_strain == 0.376  # the calibrated value of the paper's concrete (validation-depth.md)
    assert setup.target_law(scene.load(None, ['target.material="limestone"'])).crush_strain == pytest.approx(
        1 - 2300 / 2710)  # absent: 1 - rho0/Q1


def test_friction_with_the_calibrated_strength_is_refused_and_with_a_users_strength_taken():
    """σ_s must not count the interface twice: scaled-S's constants hold friction's share, so effects.friction
    with them is refused naming the key before anything runs; with the user's own a (and D0), a given σ_s or
    another strength model it runs, and σ_s is the user's."""
    from fepen.errors import InputError

    with pytest.raises(InputError) as err:
        setup.check_friction(scene.load(None, ["effects.friction=true"]))
    assert err.value.key == "effects.friction" and "target.S_coefficient" in err.value.message
    for ok in (["target.S_coefficient=80", "target.S_size=0.06"], ["target.quasi_static_stress=1e8"],
               ['target.strength_model="forrestal-S"'], []):
        setup.check_friction(scene.load(None, ["effects.friction=true", *ok] if ok else []))
    off = setup.target_law(scene.load(None, []))
    given = setup.target_law(scene.load(None, ["effects.friction=true", "target.S_coefficient=80"]))
    assert given.sigma_s == pytest.approx(80 / tg.SCALED_S_COEFFICIENT * off.sigma_s, rel=1e-12)
    assert given.friction and not off.friction


def test_immersion_is_the_submerged_fraction_of_a_patch():
    L = law(thickness=0.1)
    A = 4e-6  # a 2 mm patch
    y = np.array([0.002, 0.001, 0.0, -0.001, -0.05, -0.099, -0.1, -0.101, -0.2])
    x = np.stack([np.zeros_like(y), y, np.zeros_like(y)], axis=1)
    k = len(y)
    st = oracle.SurfaceState(x, np.tile([0.0, -100.0, 0.0], (k, 1)), np.tile([0.0, -1.0, 0.0], (k, 1)),
                             np.full(k, A), np.ones(k), np.full(k, np.inf), np.zeros(k))
    w = oracle.compiled_stress(L, st)[0] / (L.sigma_s + L.density * 100.0**2)
    assert np.allclose(w, [0, 0, 0.5, 1, 1, 1, 0.5, 0, 0], rtol=0, atol=1e-12)


def test_sigma_s_is_whole_at_any_speed_into_the_target():
    """Issue 58: the nose carries sigma_s at any speed into the target, down to a grazing 0.5 deg and a
    millimetre per second (sigma_s is the static limit of the cavity pressure; before, it was ramped over the
    first 2 deg and over the first 10 m/s of the normal speed, and a slender nose sat on the ramp until
    20-50 m/s)."""
    L = law()
    ang = np.radians([0.5, 1.0, 5.0])
    n = np.stack([np.cos(ang), -np.sin(ang), 0 * ang], axis=1)
    for speed in (1e-3, 1.0, 300.0):
        st = oracle.SurfaceState(np.array([[0, -0.05, 0]] * 3), np.array([[0, -speed, 0]] * 3), n, np.full(3, SMALL),
                                 np.ones(3), np.full(3, np.inf), np.zeros(3))
        sig, _, vn = oracle.compiled_stress(L, st)
        assert sig == pytest.approx(300e6 + 2400 * vn**2, rel=1e-12)


def test_velocity_dependent_sliding_friction_limits():
    """mu(v) = mu_d + (mu_s - mu_d) exp(-c |v|): mu_s at rest, mu_d when sliding fast, the constant Coulomb
    mu when c = 0 or mu_d = mu_s; the tangential force is mu(v_t) sigma_n A against the sliding velocity."""
    base = tg.TargetLaw(density=2400.0, Y=40e6, E=32.5e9, T=4e6, lam=0.67, sigma_s=400e6, friction=True, mu=0.3)
    def mu(law, speed_t):
        """f_t / (σ_n A) of a point pressed into the target (v·n = 100 m/s) sliding at speed_t along x"""
        st = oracle.SurfaceState(np.array([[0.0, -0.05, 0.0]]), np.array([[speed_t, -100.0, 0.0]]),
                                 np.array([[0.0, -1.0, 0.0]]), np.array([1e-4]), np.array([0.01]),
                                 np.array([np.inf]), np.array([0.0]), None)
        f, sig = oracle.forces(law, st)
        return -f[0, 0] / (sig[0] * 1e-4), f, sig

    assert [mu(base, s)[0] for s in (1e-3, 500.0)] == pytest.approx([0.3, 0.3], rel=1e-12)
    law = replace(base, mu_dynamic=0.05, mu_decay=0.02)
    got = [mu(law, s)[0] for s in (1e-6, 1.0 / 0.02, 1e4)]
    assert got == pytest.approx([0.3, 0.05 + 0.25 / np.e, 0.05], rel=1e-6)
    _, f, sig = mu(law, 300.0)
    assert f[0, 1] == pytest.approx(sig[0] * 1e-4, rel=1e-12)  # the normal part is unchanged


def test_forrestal_strength_model_gives_s_fc():
    for fc in (13.5e6, 40e6, 62.8e6):
        law = setup.target_law(scene.load(None, ["target.strength_model=forrestal-S",
                                                 f"target.compressive_strength={fc}"]))
        assert law.sigma_s == pytest.approx(82.6 * (fc / 1e6) ** -0.544 * fc, rel=1e-12)
    cavity = setup.target_law(scene.load(None, ["target.strength_model=cavity-expansion",
                                                "target.youngs_modulus=32.5e9",
                                                    "target.compressive_strength=40e6"]))
    assert cavity.sigma_s == pytest.approx(369e6, rel=0.01)  # theory.md §8.1, the paper's concrete


def test_scaled_strength_has_forrestal_power_law_and_bazant_size_effect():
    """S = a fc^-b / sqrt(1 + D/D0): the power law in fc at any D, Bažant's 1/sqrt(1 + D/D0) in D (half
    the square root at D = 3 D0, none as D0 -> inf), and Forrestal's S at D0 = inf."""
    a, b, D0 = 70.0, 0.5, 0.1
    s1 = tg.strength_S(20e6, 0.03, a, b, D0)
    assert tg.strength_S(80e6, 0.03, a, b, D0) / s1 == pytest.approx(4.0**-0.5, rel=1e-14)
    assert tg.strength_S(20e6, 3 * D0, a, b, D0) / tg.strength_S(20e6, 0.0, a, b, D0) == pytest.approx(0.5)
    assert tg.strength_S(20e6, 1.0, a, b, math.inf) == pytest.approx(a * 20.0**-0.5, rel=1e-14)
    assert tg.forrestal_S(40e6) == pytest.approx(82.6 * 40.0**-0.544, rel=1e-14)


def test_concrete_from_its_strength_alone():
    """target.compressive_strength and target.density are enough: E from ACI 318 (4.7 sqrt(fc) GPa),
    T = fc/10, and the scaled-S sigma_s; a given E is used as given."""
    for fc in (13.5e6, 40e6, 160e6):
        L = setup.target_law(scene.load(None, [f"target.compressive_strength={fc}"]))
        assert L.E == pytest.approx(4.7e9 * math.sqrt(fc / 1e6), rel=1e-14) and L.T == pytest.approx(fc / 10)
        a, b, D0 = tg.S_MODELS["scaled-S"]
        assert L.sigma_s == pytest.approx(tg.strength_S(fc, 0.0236, a, b, D0) * fc, rel=1e-14)
        assert L.given_sigma_s  # the free surface scales it, does not replace it by the cavity expansion
    L = setup.target_law(scene.load(None, ["target.youngs_modulus=20e9", "target.S_coefficient=50",
                                           "target.S_exponent=0", "target.S_size=1e6",
                                               "target.compressive_strength=40e6"]))
    assert L.E == 20e9 and L.sigma_s == pytest.approx(50 * 40e6, rel=1e-6)
