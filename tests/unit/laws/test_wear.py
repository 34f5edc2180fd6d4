"""Nose wear on plain arrays (no mesh): the interface heat against its closed form on an exact ogive, the
melt enthalpy, the melted mass."""

import math

import numpy as np
import pytest
import target_oracle as oracle
from test_target import law, ogive_surface

from fepen.laws import target as tg
from fepen.laws import wear


def ogive_heat_rate(crh, sigma_s, rho, V, mu, a=0.0118):
    """μ V ∫ σ_n sin β dA over a tangent ogive moving along its axis at V, σ_n = σ_s + ρ (V cos β)²: with the
    meridian angle α from the shoulder (normal n = (cos α radial, sin α axial), r = (a − s) + s cos α,
    dA = 2π r s dα, cos α_tip = (s − a)/s), integrated in closed form."""
    s = 2 * a * crh
    c = a - s
    at = math.acos(-c / s)
    static = c * math.sin(at) + s * (at / 2 + math.sin(2 * at) / 4)
    inertial = c * math.sin(at) ** 3 / 3 + s * (at / 8 - math.sin(4 * at) / 32)
    return 2 * math.pi * s * mu * V * (sigma_s * static + rho * V * V * inertial)


@pytest.mark.parametrize("crh", [2.0, 3.0, 4.5])
def test_heat_rate_on_an_exact_ogive_is_the_closed_form(crh):
    L = law()
    st = ogive_surface(crh)
    f, _ = oracle.forces(L, st)
    q = wear.heat_rate(f, st.n, st.v, 0.1)
    assert q == pytest.approx(ogive_heat_rate(crh, L.sigma_s, L.density, 600.0, 0.1), rel=1e-6)
    # a friction force (tangential) does not change the heat: only σ_n A = −f·n enters
    Lf = tg.TargetLaw(**{**L.__dict__, "friction": True, "mu": 0.3})
    f2, _ = oracle.forces(Lf, st)
    assert wear.heat_rate(f2, st.n, st.v, 0.1) == pytest.approx(q, rel=1e-12)


def test_sharper_noses_slide_more_per_unit_of_axial_work():
    ratio = [ogive_heat_rate(c, 3e8, 2400.0, 600.0, 1.0) / (math.pi * 0.0118**2 * (3e8 + tg.ogive_nose_factor(c)
             * 2400.0 * 600.0**2) * 600.0) for c in (1.0, 2.0, 3.0, 4.5, 6.0)]
    assert all(b > a for a, b in zip(ratio, ratio[1:])) and 1.0 < ratio[0]


def test_heat_rate_limits():
    n = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0]])
    f = np.array([[0.0, 5.0, 0.0], [-2.0, 0.0, 0.0]])  # normal forces of 5 N and 2 N
    v = np.array([[0.0, -100.0, 0.0], [0.0, -300.0, 0.0]])
    # a face pushed head-on does not slide; a side sliding at 300 m/s under 2 N gives 0.1 * 2 * 300
    assert wear.heat_rate(f, n, v, 0.1) == pytest.approx(60.0, rel=1e-14)
    assert wear.heat_rate(-f, n, v, 0.1) == 0.0  # a pull is no contact
    assert wear.heat_rate(f, n, v, 0.0) == 0.0


def test_melt_enthalpy_and_mass():
    h = wear.melt_enthalpy(470.0, 1765.0, 294.0)
    assert h == pytest.approx(470.0 * 1471.0 + 2.7e5, rel=1e-14)
    assert 8e5 < h < 1.1e6  # about 1 MJ/kg for steels
    assert wear.melted_mass(h, 1.0, h) == pytest.approx(1.0)
    assert wear.melted_mass(1e4, 0.0, h) == 0.0


def test_point_heat_rates_sum_to_the_heat_rate():
    rng = np.random.default_rng(3)
    f, n, v = rng.normal(size=(50, 3)), rng.normal(size=(50, 3)), rng.normal(size=(50, 3)) * 300
    n /= np.linalg.norm(n, axis=1)[:, None]
    q = wear.heat_rates(f, n, v, 0.15)
    assert np.all(q >= 0.0)
    assert q.sum() == pytest.approx(wear.heat_rate(f, n, v, 0.15), rel=1e-12)
    assert np.all(q[np.einsum("ij,ij->i", f, n) > 0.0] == 0.0)  # a point pulled outward takes no heat


def test_recession_depth_melts_the_heat_s_mass():
    """d = eta Q / (h rho A): the melted mass over the area's mass per unit depth; zero area, zero depth."""
    h = wear.melt_enthalpy(470.0, 1765.0, 294.0)
    heat, area = np.array([1.0e3, 2.0e3, 5.0]), np.array([1e-4, 1e-4, 0.0])
    d = wear.recession_depth(heat, area, 0.5, h, 7850.0)
    assert d[:2] * 7850.0 * area[:2] == pytest.approx(wear.melted_mass(heat[:2], 0.5, h), rel=1e-14)
    assert d[2] == 0.0
