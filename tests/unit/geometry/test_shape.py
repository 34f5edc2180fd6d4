"""The exact projectile geometry (no mesh): volumes against closed forms, cavity sizing, bad geometry."""

import math

import pytest

from fepen import scene
from fepen.errors import InputError
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
    assert z0 > sh.front_limit(r0) - 1e-12  # the cavity keeps the minimum wall


def test_charge_filled_cavity_is_sized_on_total_mass():
    sc = scene.load(None, ["effects.charge=true"])
    sh = setup.projectile_shape(sc)
    assert sh.mass(7850.0, 1850.0) == pytest.approx(0.367, abs=1e-9)
    assert sh.cavity_volume() > setup.projectile_shape(scene.load()).cavity_volume()


@pytest.mark.parametrize("sets, key", [
    (["projectile.mass=0.5"], "projectile.mass"),
    (["projectile.mass=0.2"], "projectile.mass"),
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


def test_solid_flat_rod():
    sc = scene.load(None, ["projectile.nose=flat", "projectile.cavity_diameter=0"])
    sh = setup.projectile_shape(sc)
    assert not sh.has_cavity and sh.nose_length == 0.0
    assert sh.outer_volume() == pytest.approx(math.pi * 0.0118**2 * 0.144, rel=1e-14)
    assert sc.get("projectile.mass") is None
