"""The exact projectile geometry (no mesh): volumes against closed forms, cavity sizing, bad geometry."""

import math

import pytest

from fepen import scene
from fepen.errors import InputError
from fepen.geometry.checks import check, front_limit, max_cavity_length
from fepen.geometry.mass_rule import reach_mass
from fepen.geometry.shape import Shape
from fepen.runs import setup


def ogive_volume(a, crh):
    """Closed-form volume of a tangent ogive of base radius a: pi (s^2 l - l^3/3 - c s^2 asin(l/s))."""
    s = 2 * a * crh
    c = s - a
    ln = math.sqrt(s * s - c * c)
    return math.pi * (s * s * ln - ln**3 / 3 - c * s * s * math.asin(ln / s))


@pytest.mark.parametrize("crh", [0.5, 1.0, 2.0, 3.0, 4.5])
def test_outer_volume_against_closed_form(crh):
    sh = Shape(diameter=0.0236, length=0.144, crh=crh)
    a = sh.radius
    exact = ogive_volume(a, crh) + math.pi * a * a * (sh.length - sh.nose_length)
    assert sh.outer_volume() == pytest.approx(exact, rel=1e-12)
    if crh == 0.5:  # hemisphere
        assert ogive_volume(a, crh) == pytest.approx(2 * math.pi * a**3 / 3, rel=1e-12)


def test_ogive_profile_is_tangent_and_continuous():
    sh = Shape(diameter=0.0236, length=0.144, crh=3.0)
    ln = sh.nose_length
    assert sh.outer_radius(0.0) == pytest.approx(0.0, abs=1e-15)
    assert sh.outer_radius(ln) == pytest.approx(sh.radius, rel=1e-14)
    eps = 1e-7
    slope = (sh.outer_radius(ln) - sh.outer_radius(ln - eps)) / eps
    assert abs(slope) < 1e-3  # tangent: the ogive meets the shank with zero slope


def test_default_projectile_reaches_the_papers_mass():
    sh = setup.projectile_shape(scene.load())
    assert sh.mass(7850.0) == pytest.approx(0.367, abs=1e-9)
    (z0, z1, r0), (z2, z3, r1) = sh.cavity_sections()
    assert z1 == pytest.approx(z2) and r0 < r1  # the wall-thickness step
    assert z3 == pytest.approx(0.144 - 0.015)
    assert z0 > front_limit(sh, r0) - 1e-12  # the cavity keeps the minimum wall


def test_charge_filled_cavity_is_sized_on_total_mass():
    sc = scene.load(None, ["effects.charge=true"])
    sh = setup.projectile_shape(sc)
    assert sh.mass(7850.0, 1850.0) == pytest.approx(0.367, abs=1e-9)
    assert sh.cavity_volume() > setup.projectile_shape(scene.load()).cavity_volume()


@pytest.mark.parametrize("sets, key", [
    (["projectile.mass=0.5", "projectile.cavity_diameter=0.012"], "projectile.mass"),
    (["projectile.mass=0.2", "projectile.cavity_step_length=0.02"], "projectile.mass"),
    (["projectile.mass=0.2", "effects.charge=true"], "projectile.mass"),
    (["projectile.cavity_diameter=0.03"], "projectile.cavity_diameter"),
    (["projectile.cavity_diameter=0.0230"], "projectile.cavity_diameter"),
    (["projectile.cavity_step_diameter=0.014"], "projectile.cavity_step_diameter"),
    (["projectile.cavity_length=0.2"], "projectile.cavity_length"),
    (["projectile.length=0.03"], "projectile.length"),
])
def test_impossible_geometry_names_the_key(sets, key):
    with pytest.raises(InputError) as err:
        setup.projectile_shape(scene.load(None, sets))
    assert err.value.key == key


def _mass_rule_cases():
    """24 projectiles: diameters 10-80 mm, L/D 4-12, CRH 1-6, masses from the lightest hollow body to
    slightly over the solid one (fractions of the solid mass)."""
    cases = []
    for i, (D, LD, crh) in enumerate([(0.010, 4, 1.0), (0.0129, 8, 3.0), (0.0203, 6, 3.0), (0.0236, 6.1, 3.0),
                                      (0.0305, 10, 3.0), (0.050, 12, 6.0), (0.0762, 7, 4.5), (0.080, 4, 2.0)]):
        for frac in ((0.55, 0.8, 0.995) if i % 2 else (0.7, 0.93, 1.02)):
            cases.append((D, LD * D, crh, frac))
    return cases


@pytest.mark.parametrize("D, L, crh, frac", _mass_rule_cases())
def test_mass_rule_builds_any_projectile_to_its_mass(D, L, crh, frac):
    """issue 13 item 4: an outside and a mass are enough; the default cavity is sized, reduced or dropped
    (a solid with adjusted density last), within 0.5 % of the mass, and a change is said in one line."""
    rho = 7850.0
    solid = Shape(D, L, "ogive", crh)
    mass = frac * rho * solid.outer_volume()
    sc = scene.load(None, [f"projectile.diameter={D}", f"projectile.length={L}", f"projectile.crh={crh}",
                           f"projectile.mass={mass}"])
    built = setup.projectile(sc)
    check(built.shape)
    got = built.shape.mass(built.shell_density)
    assert got == pytest.approx(mass, rel=5e-3)
    default = Shape(D, L, "ogive", crh, 0.012, 0.0, 0.008, 0.020, 0.015)
    kept = (built.shape.cavity_diameter == default.cavity_diameter and built.shape.step_length == 0.020)
    assert kept or built.note.startswith("projectile.mass")
    if built.shell_density != rho:
        assert not built.shape.has_cavity and "density adjusted" in built.note
        assert abs(built.shell_density / rho - 1.0) <= 0.03  # only near-solid masses come here
    if built.shape.has_cavity:  # the thinnest wall is kept everywhere
        assert built.shape.cavity_length <= max_cavity_length(built.shape) * (1 + 1e-9)


def test_mass_rule_prefers_the_given_cavity():
    """The paper's projectile keeps its two-section cavity, only sized, with no note."""
    built = setup.projectile(scene.load(None, []))
    assert built.note == "" and built.shape.step_length == 0.020 and built.shell_density == 7850.0


def test_bad_outside_is_refused_without_meshing():
    """A nose longer than the body is refused by the exact geometry, before gmsh is imported."""
    import subprocess
    import sys
    code = ("import sys; from fepen import scene; from fepen.runs import setup; from fepen.errors import InputError\n"
            "try:\n    setup.projectile(scene.load(None, ['projectile.length=0.03', 'projectile.mass=0.1']))\n"
            "except InputError as e:\n    print(e.key, 'gmsh' in sys.modules, 'dolfinx' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["projectile.length", "False", "False"]


def test_solid_flat_rod():
    sc = scene.load(None, ["projectile.nose=flat", "projectile.cavity_diameter=0"])
    sh = setup.projectile_shape(sc)
    assert not sh.has_cavity and sh.nose_length == 0.0
    assert sh.outer_volume() == pytest.approx(math.pi * 0.0118**2 * 0.144, rel=1e-14)
    assert sc.get("projectile.mass") is None


def test_mass_rule_ends_of_the_range():
    """Lighter than the widest cavity: that cavity with lighter steel (at most 25 %); beyond either end
    of the range, InputError naming projectile.mass and the reachable range."""
    rho = 7850.0
    shape = Shape(0.025, 0.168, "ogive", 6.0, 0.012, 0.0, 0.008, 0.020, 0.015)
    built = reach_mass(shape, 0.246, rho)  # a thin-walled 25 mm body (Sun et al. 2010)
    assert built.shape.has_cavity and built.shell_density < rho and "widest cavity" in built.note
    assert built.shape.mass(built.shell_density) == pytest.approx(0.246, rel=1e-12)
    solid = Shape(0.025, 0.168, "ogive", 6.0).mass(rho)
    for m in (0.1, 1.3 * solid):
        with pytest.raises(InputError, match=r"must be in \[") as err:
            reach_mass(shape, m, rho)
        assert err.value.key == "projectile.mass"
