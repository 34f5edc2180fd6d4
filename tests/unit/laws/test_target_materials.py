"""The target-material library and the layered target, mesh-free: Forrestal–Warren's metal cavity stress
against its limits and its own integral, every named material's law, and a block of touching layers being
one layer of their summed thickness point by point."""

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy import integrate

from fepen import scene
from fepen.data import TARGETS
from fepen.errors import InputError
from fepen.laws import layers as fl
from fepen.laws import target as tg
from fepen.runs import setup


def test_metal_cavity_stress_is_hills_for_a_perfectly_plastic_metal():
    E, Y = 70e9, 300e6
    assert tg.metal_cavity_stress(E, Y, 0.0) == pytest.approx(2 * Y / 3 * (1 + math.log(2 * E / (3 * Y))), rel=1e-14)


@pytest.mark.parametrize("n", [0.02, 0.051, 0.1, 0.3])
def test_metal_cavity_stress_against_its_integral(n):
    """σ_s/Y = (2/3)[1 + (2E/3Y)^n ∫_0^(1−3Y/2E) (−ln x)^n/(1−x) dx], the integral taken directly."""
    E, Y = 68.9e9, 276e6
    beta = 1.5 * Y / E
    direct = integrate.quad(lambda x: (-math.log(x)) ** n / (1 - x), 0, 1 - beta, limit=400, epsrel=1e-12,
                            points=[1e-12, 1e-6, 1e-3])[0]
    exact = Y * (2 / 3) * (1 + (1 / beta) ** n * direct)
    assert tg.metal_cavity_stress(E, Y, n) == pytest.approx(exact, rel=1e-7)
    assert tg.metal_cavity_stress(E, Y, n) > tg.metal_cavity_stress(E, Y, 0.0)  # hardening raises it


@pytest.mark.parametrize("name", list(TARGETS))
def test_every_named_material_gives_a_positive_law(name):
    sc = scene.Scene(None, [f"target.material={name!r}"])
    law = setup.target_law(sc)
    family = TARGETS[name]["family"]
    assert law.sigma_s > 0 and law.density == TARGETS[name]["density"]
    assert law.B == (1.5 if family == "metal" else 1.0)
    assert law.crater == TARGETS[name]["crater"]
    if family == "metal":
        assert law.sigma_s == pytest.approx(tg.metal_cavity_stress(law.E, law.Y, TARGETS[name]["hardening_exponent"]))
    # an explicit constant wins over the material's
    sc = scene.Scene(None, [f"target.material={name!r}", "target.density=2000.0"])
    assert setup.target_law(sc).density == 2000.0


def points(k=400, seed=3):
    rng = np.random.default_rng(seed)
    x = rng.uniform([-0.02, -0.5, -0.02], [0.02, 0.02, 0.02], (k, 3))
    n = rng.normal(size=(k, 3))
    n /= np.linalg.norm(n, axis=1)[:, None]
    v = np.tile([30.0, -600.0, 10.0], (k, 1))
    area = rng.uniform(1e-6, 4e-6, k)
    radius = rng.uniform(1e-3, 0.0118, k)
    return x, v, n, area, radius, np.full(k, 0.07), np.abs(n[:, 1]), np.array([0.0, -1.0, 0.0])


def layered(text):
    return setup.target_law(scene.Scene(text))


def test_two_touching_layers_of_one_material_are_one_layer():
    one = layered("[target]\nthickness = 0.3\n")
    two = layered("[[target.layers]]\nthickness = 0.12\n[[target.layers]]\nthickness = 0.18\n")
    assert two.thickness == pytest.approx(0.3) and len(two.block_tops) == 1
    p = points()
    a = tg.load_on_points(one, *p)
    b = tg.load_on_points(two, *p)
    assert np.allclose(b.force, a.force, rtol=1e-12, atol=1e-9 * np.abs(a.force).max())
    assert b.total == pytest.approx(a.total, rel=1e-12)


def test_a_gap_leaves_its_points_unloaded_and_the_next_layer_has_its_own_face():
    law = layered("[[target.layers]]\nthickness = 0.1\ngap = 0.2\n[[target.layers]]\nthickness = 0.1\n")
    assert law.block_tops == pytest.approx((0.0, 0.3))
    x, v, n, area, radius, Rm, sphi, axis = points()
    x[:, 1] = np.linspace(-0.45, 0.0, len(x))
    load = tg.load_on_points(law, x, v, n, area, radius, Rm, sphi, axis)
    ell = np.sqrt(area)
    in_gap = (x[:, 1] < -0.1 - ell) & (x[:, 1] > -0.3 + ell)
    beyond = x[:, 1] < -0.4 - ell
    assert np.all(load.force[in_gap | beyond] == 0.0)
    # the second slab, moved up to the face, loads exactly like the first
    single = replace(law.layers[0].law)
    shifted = x.copy()
    shifted[:, 1] += 0.3
    ref = tg.load_on_points(single, shifted, v, n, area, radius, Rm, sphi, axis)
    second = (x[:, 1] < -0.3 + ell) & (x[:, 1] > -0.4 - ell)
    assert np.allclose(load.force[second], ref.force[second], rtol=1e-12, atol=0)


def test_crossings_interpolate_entry_and_exit():
    c = fl.Crossings([(0.0, 0.1), (0.3, None)])
    c.update(0.0, 0.0, -0.14, 800.0)
    c.update(1e-4, 0.08, -0.06, 700.0)
    c.update(2e-4, 0.16, 0.02, 600.0)
    c.update(6e-4, 0.32, 0.18, 600.0)
    assert c.entry[0] == (0.0, 800.0)
    assert c.exit[0][0] == pytest.approx(2e-4 + 4e-4 * (0.1 - 0.02) / 0.16)
    assert c.entry[1][0] == pytest.approx(2e-4 + 4e-4 * (0.3 - 0.16) / 0.16)
    assert c.exit[1] is None


@pytest.mark.parametrize("text, key", [
    ("[[target.layers]]\nmaterial = 'cheese'\n", "target.layers[0].material"),
    ("[[target.layers]]\ngap = 1.0\n[[target.layers]]\n", "target.layers[0].thickness"),
    ("[[target.layers]]\nthickness = 0.1\nstrenght = 3\n", "target.layers[0].strenght"),
    ("[[target.layers]]\nthickness = -0.1\n", "target.layers[0].thickness"),
    ("[target]\nthickness = 0.2\n[[target.layers]]\nthickness = 0.1\n", "target.thickness"),
    ("[effects]\ncrater = 'linear'\n[[target.layers]]\nthickness = 0.1\n", "effects.crater"),
    ("[target]\nlayers = 3\n", "target.layers"),
])
def test_bad_layers_name_their_key(text, key):
    with pytest.raises(InputError) as err:
        scene.Scene(text)
    assert err.value.key == key
