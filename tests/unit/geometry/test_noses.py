"""Every nose family, the boat-tail, cavity sections and drawn profiles, mesh-free: volume, mass centre and
inertia against independent quadratures of each family's own r(z), the nose factor N* against its closed
form, and the rigid load rings' axial force against (π d²/4)(σ_s + N* ρ V²)."""

import math

import numpy as np
import pytest
from scipy import integrate

from fepen import scene
from fepen.errors import InputError
from fepen.geometry import revolution
from fepen.geometry.checks import check
from fepen.geometry.shape import Shape
from fepen.laws import target as tg
from fepen.runs import rigid, setup

D, L = 0.0236, 0.144
a = D / 2


def r_ogive(z, psi, ln_full, rm=0.0, zm=0.0):
    s = psi * D
    z = z + zm
    return math.sqrt(max(s * s - (ln_full - z) ** 2, 0.0)) - (s - a)


def families():
    """name -> (Shape, r(z) written from the textbook definitions, nose length)."""
    out = {}
    psi = 3.0
    l0 = a * math.sqrt(4 * psi - 1)
    out["ogive"] = (Shape(D, L, "ogive", psi), lambda z: r_ogive(z, psi, l0) if z < l0 else a, l0)
    # secant: circle of radius s through the tip (0, 0) and the shoulder (a, l)
    s, ls = 4.0 * D, 0.025
    c = math.hypot(a, ls)
    h = math.sqrt(s * s - c * c / 4)
    cr, cz = a / 2 - h * ls / c, ls / 2 + h * a / c
    out["secant"] = (Shape(D, L, "secant", 4.0, nose_length_given=ls),
                     lambda z: cr + math.sqrt(s * s - (z - cz) ** 2) if z < ls else a, ls)
    lc = 0.03
    out["cone"] = (Shape(D, L, "cone", nose_length_given=lc), lambda z: a * z / lc if z < lc else a, lc)
    out["hemisphere"] = (Shape(D, L, "hemisphere"),
                         lambda z: math.sqrt(max(a * a - (a - z) ** 2, 0)) if z < a else a, a)
    le = 0.03
    out["ellipsoid"] = (Shape(D, L, "ellipsoid", nose_length_given=le),
                        lambda z: a * math.sqrt(max(1 - ((le - z) / le) ** 2, 0)) if z < le else a, le)
    out["flat"] = (Shape(D, L, "flat"), lambda z: a, 0.0)
    # blunted ogive: the tangent ogive cut where r = rm, the cut face at z = 0
    rm = 0.004
    zm = l0 - math.sqrt((psi * D) ** 2 - (rm - a + psi * D) ** 2)
    out["ogive-meplat"] = (Shape(D, L, "ogive", psi, meplat_diameter=2 * rm),
                           lambda z: r_ogive(z, psi, l0, zm=zm) if z < l0 - zm else a, l0 - zm)
    out["cone-meplat"] = (Shape(D, L, "cone", nose_length_given=lc, meplat_diameter=2 * rm),
                          lambda z: rm + (a - rm) * z / (lc * (1 - rm / a)) if z < lc * (1 - rm / a) else a,
                          lc * (1 - rm / a))
    lb, rb = 0.02, 0.009  # a boat-tail on the ogive
    out["ogive-boattail"] = (Shape(D, L, "ogive", psi, boattail_length=lb, boattail_diameter=2 * rb),
                             lambda z: r_ogive(z, psi, l0) if z < l0 else (a if z < L - lb else
                                                                           a - (a - rb) * (z - L + lb) / lb), l0)
    return out


def quad_props(r, breaks, rho=7850.0):
    """Mass, centre and inertia of a solid of revolution r(z) by adaptive quadrature."""
    def q(f):
        return sum(integrate.quad(f, lo, hi, epsabs=0, epsrel=1e-13, limit=200)[0]
                   for lo, hi in zip(breaks[:-1], breaks[1:]))
    m = rho * q(lambda z: math.pi * r(z) ** 2)
    yc = rho * q(lambda z: math.pi * r(z) ** 2 * z) / m
    i_ax = rho * q(lambda z: 0.5 * math.pi * r(z) ** 4)
    i_tr = rho * q(lambda z: 0.25 * math.pi * r(z) ** 4 + math.pi * r(z) ** 2 * (z - yc) ** 2)
    return m, yc, i_ax, i_tr


@pytest.mark.parametrize("name", list(families()))
def test_mass_centre_and_inertia_of_each_family_against_quadrature(name):
    shape, r, ln = families()[name]
    check(shape)
    breaks = sorted({0.0, ln, L, L - shape.boattail_length, L})
    m, yc, i_ax, i_tr = quad_props(r, breaks)
    mm, c, inertia = revolution.mass_properties(shape, 7850.0)
    assert shape.nose_length == pytest.approx(ln, rel=1e-12, abs=1e-15)
    assert mm == pytest.approx(m, rel=1e-9)
    assert shape.outer_volume() == pytest.approx(m / 7850.0, rel=1e-9)
    assert c[1] == pytest.approx(yc, rel=1e-9)
    assert inertia[1, 1] == pytest.approx(i_ax, rel=1e-9)
    assert inertia[0, 0] == pytest.approx(i_tr, rel=1e-9)
    for z in np.linspace(0, L, 37):
        assert shape.outer_radius(z) == pytest.approx(r(z), abs=1e-12)


def blunted_ogive_factor(psi, rm_over_a):
    """N* of a tangent ogive with a meplat, by quadrature of its arc: ∫ (−n_y)³ dA / (π a²)."""
    s = psi * D
    cr = a - s
    t_m = math.acos((rm_over_a * a - cr) / s)  # the arc angle where r = rm (measured from the r axis)
    f = integrate.quad(lambda t: 2 * math.pi * (cr + s * math.cos(t)) * math.sin(t) ** 3 * s, 0.0, t_m)[0]
    return rm_over_a**2 + f / (math.pi * a * a)


@pytest.mark.parametrize("name, exact", [
    ("ogive", (8 * 3 - 1) / (24 * 9)), ("cone", 1 / (1 + 4 * (0.03 / D) ** 2)), ("hemisphere", 0.5), ("flat", 1.0),
    ("ogive-meplat", blunted_ogive_factor(3.0, 0.004 / a)), ("ellipsoid", None), ("secant", None)])
def test_nose_factor_against_its_closed_form(name, exact):
    shape = families()[name][0]
    if exact is None:  # the integral of the family's own r(z): N* = ∫ 2 r r'^3 / (1 + r'^2) dz / a²
        r = families()[name][1]
        ln = families()[name][2]

        def dr(z, h=1e-9):
            return (r(min(z + h, ln)) - r(max(z - h, 0.0))) / (min(z + h, ln) - max(z - h, 0.0))
        exact = integrate.quad(lambda z: 2 * r(z) * dr(z) ** 3 / (1 + dr(z) ** 2) ** 1.5 * math.sqrt(1 + dr(z) ** 2),
                               1e-7, ln, limit=400)[0] / (a * a)
        assert shape.nose_factor() == pytest.approx(exact, rel=2e-4)
    else:
        assert shape.nose_factor() == pytest.approx(exact, rel=1e-10)


@pytest.mark.parametrize("name", list(families()))
def test_rigid_rings_give_the_closed_form_nose_force(name):
    """A nose moving along its axis, deep in the target, frictionless, no crater, no free surface, no onsets:
    the axial force is (π d²/4)(σ_s + N* ρ V²) within 0.5 % (the rings do it within 1e-4)."""
    shape = families()[name][0]
    sc = scene.Scene(None, ["effects.fidelity=rigid", "effects.crater=none", "effects.free_surface=false",
                            "target.separation_angle_deg=0"])
    law = setup.target_law(sc)
    pts = rigid.ring_points(shape)
    V = 800.0
    x = pts["X"] - np.array([0.0, 10.0, 0.0])
    v = np.tile([0.0, -V, 0.0], (len(x), 1))
    load = tg.load_on_points(law, x, v, pts["N"], pts["area0"], pts["radius"], pts["R_meridian"], pts["sin_phi0"],
                             np.array([0.0, -1.0, 0.0]))
    exact = math.pi * a * a * (law.sigma_s + shape.nose_factor() * law.density * V * V)
    assert load.total[1] == pytest.approx(exact, rel=1e-4)  # moving to -y, pushed back to +y
    assert np.hypot(load.total[0], load.total[2]) < 1e-9 * exact  # symmetric


def test_a_drawn_profile_is_the_family_it_draws(tmp_path):
    """A CSV of the tangent ogive with a boat-tail (an arc row with its radius) gives the family's shape."""
    shape = families()["ogive-boattail"][0]
    ln = shape.nose_length
    csv = tmp_path / "p.csv"
    csv.write_text(f"z_m, r_m, arc_radius_m\n0, 0\n{ln!r}, {a!r}, {3.0 * D!r}\n{L - 0.02!r}, {a!r}\n{L!r}, 0.009\n")
    sc = scene.Scene(None, [f"projectile.profile={str(csv)!r}"])
    drawn = setup.projectile_shape(sc)
    assert drawn.diameter == pytest.approx(D) and drawn.length == pytest.approx(L)
    assert drawn.has_cavity is False
    m0, c0, i0 = revolution.mass_properties(shape, 7850.0)
    m1, c1, i1 = revolution.mass_properties(drawn, 7850.0)
    assert m1 == pytest.approx(m0, rel=1e-12)
    assert np.allclose(i1, i0, rtol=1e-12, atol=0)
    assert drawn.nose_factor() == pytest.approx(shape.nose_factor(), rel=1e-12)


def test_cavity_sections_are_sized_to_the_mass_and_a_drawn_cavity_fixes_it(tmp_path):
    sc = scene.Scene(None, ["projectile.cavity_sections=[[0.01, 0.006], [0.02, 0.009], [0.05, 0.012]]"])
    sh = setup.projectile_shape(sc)
    assert sh.mass(7850.0) == pytest.approx(0.367, abs=1e-9)
    secs = sh.cavity_sections()
    assert [round(2 * r, 6) for _, _, r in secs] == [0.006, 0.009, 0.012]
    assert secs[0][1] - secs[0][0] == pytest.approx(0.01) and secs[1][1] - secs[1][0] == pytest.approx(0.02)
    assert secs[-1][1] == pytest.approx(L - 0.015)
    csv = tmp_path / "in.csv"
    csv.write_text("0.06, 0\n0.06, 0.005\n0.12, 0.005\n0.12, 0\n")
    sc = scene.Scene(None, [f"projectile.inner_profile={str(csv)!r}"])
    sh = setup.projectile_shape(sc)
    assert sh.cavity_volume() == pytest.approx(math.pi * 0.005**2 * 0.06, rel=1e-12)
    m, _, _ = revolution.mass_properties(sh, 7850.0)
    assert m == pytest.approx(7850.0 * (families()["ogive"][0].outer_volume() - math.pi * 0.005**2 * 0.06), rel=1e-12)


@pytest.mark.parametrize("sets, key", [
    (["projectile.nose=cone"], "projectile.nose_length"),
    (["projectile.nose=secant", "projectile.nose_length=0.06"], "projectile.nose_length"),
    (["projectile.meplat_diameter=0.03"], "projectile.meplat_diameter"),
    (["projectile.nose=flat", "projectile.meplat_diameter=0.005"], "projectile.meplat_diameter"),
    (["projectile.boattail_length=0.02"], "projectile.boattail_diameter"),
    (["projectile.boattail_length=0.02", "projectile.boattail_diameter=0.03"], "projectile.boattail_diameter"),
    (["projectile.cavity_sections=[[0.01, 0.05]]"], "projectile.cavity_sections"),
    (["projectile.cavity_sections=[[0.01]]"], "projectile.cavity_sections[0]"),
    (["projectile.nose=profile"], "projectile.nose"),
    (["projectile.profile='/nonexistent.csv'"], "projectile.profile"),
])
def test_bad_geometry_names_its_key(sets, key):
    with pytest.raises(InputError) as err:
        setup.projectile(scene.Scene(None, sets))
    assert err.value.key == key
