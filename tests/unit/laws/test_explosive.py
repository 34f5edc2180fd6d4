"""The charge-safety criteria on plain arrays (fepen.laws.explosive) and the study's boundary, mesh-free:
eigenvalues against LAPACK, invariants against their closed forms, the friction heat of a sliding pair against
mu F_N |v_t| dt, the set-forward pressure against a column's momentum balance."""

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from fepen.laws import explosive
from fepen.laws.contact import pair_forces, pair_work

stress = st.lists(st.floats(-1e9, 1e9, allow_nan=False), min_size=6, max_size=6)


@settings(max_examples=200, deadline=None)
@given(stress)
@example([3.6686946964304837e-137, 0.0, 3.6686946964304837e-137, 2055128.0, 0.0, 2.0])
def test_largest_principal_is_the_largest_eigenvalue(s):
    """Against LAPACK's general eigenvalue solver (its symmetric one, dsyevd, is 0.22 off on the example: exact
    sqrt(2055128^2 + 4), with diagonal entries of 1e-137)."""
    xx, yy, zz, xy, yz, xz = s
    A = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    scale = max(np.abs(A).max(), 1.0)
    expect = np.linalg.eigvals(A).real.max()
    assert explosive.largest_principal(np.array([s]))[0] == pytest.approx(expect, abs=1e-7 * scale)


def test_principal_and_von_mises_of_simple_states():
    """Uniaxial tension σ: σ1 = σ, von Mises σ; hydrostatic p: σ1 = p, von Mises 0; pure shear τ: σ1 = τ, von
    Mises √3 τ; uniaxial compression: σ1 = 0 (the two free directions)."""
    states = np.array([[5e6, 0, 0, 0, 0, 0], [-3e7, -3e7, -3e7, 0, 0, 0], [0, 0, 0, 2e6, 0, 0],
                       [0, -4e7, 0, 0, 0, 0]], dtype=float)
    np.testing.assert_allclose(explosive.largest_principal(states), [5e6, -3e7, 2e6, 0.0], atol=1e-6)
    np.testing.assert_allclose(explosive.von_mises(states), [5e6, 0.0, math.sqrt(3) * 2e6, 4e7], atol=1e-6)


def test_margins_are_threshold_over_demand():
    assert explosive.margin(45e6, 90e6) == 0.5
    assert explosive.margin(45e6, 0.0) == math.inf  # no demand
    assert explosive.margin(None, 90e6) is None  # no threshold: no margin
    np.testing.assert_array_equal(explosive.margins(2.0, np.array([1.0, 4.0, 0.0])), [2.0, 0.5, np.inf])


def slide(mu: float, dt: float = 1e-6):
    """One shell node (a) pressed onto one charge node (b) through 1 µm of overlap, a sliding at 5 m/s along x:
    the pair's force, the heat the kernel books and the interface work pair_work sums."""
    x = np.array([[0.0, 0.0, -1e-6], [0.0, 0.0, 0.0]])
    vel = np.array([[5.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    acc = np.zeros((2, 3))
    mass = np.array([1e-3, 1e-3])
    pa, pb, n = np.array([0]), np.array([1]), np.array([[0.0, 0.0, 1.0]])
    force, fn, state = np.zeros((1, 3)), np.zeros(1), np.zeros(1, dtype=np.int8)
    pair_forces(x, vel, acc, mass, pa, pb, n, dt, dt, mu, force, fn, state)
    area = np.array([2e-6])
    heat, work, power, peak = np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(1)
    explosive.pair_friction(vel, acc, mass, pa, pb, n, force, fn, dt, dt, dt, area, heat, work, power, peak)
    sums = np.zeros(2)
    pair_work(vel, acc, mass, pa, pb, n, force, fn, dt, dt, dt, np.array([True]), sums)
    return force[0], fn[0], state[0], heat[0], work[0], power[0], peak[0], sums, area[0], dt


def test_a_sliding_pair_heats_by_mu_fn_times_its_slip():
    """Sliding (the friction cannot stop 5 m/s in a step): the heat is μ F_N times the pair's relative slip
    over the two half steps (5 m/s before; after, less what the friction took), per unit area the work, its
    rate μ p v̄; the heat is exactly the dissipation pair_work sums for the energy balance."""
    f, fn, state, heat, work, power, peak, sums, area, dt = slide(0.1)
    assert state == 2 and fn > 0
    ft = math.hypot(f[0], f[1])
    assert ft == pytest.approx(0.1 * fn, rel=1e-12)
    v_after = 5.0 + dt * f[0] * (1 / 1e-3 + 1 / 1e-3)  # f[0] < 0 slows a relative to b
    assert heat == pytest.approx(ft * 0.5 * (5.0 + v_after) * dt, rel=1e-12)
    assert heat == pytest.approx(-sums[1], rel=1e-12)
    assert work == pytest.approx(heat / area, rel=1e-12)
    assert power == pytest.approx(work / dt, rel=1e-12) and peak == power


def test_a_frictionless_or_open_pair_does_not_heat():
    assert slide(0.0)[3] == pytest.approx(0.0, abs=1e-18)


def test_set_forward_pressure_is_the_columns_momentum_balance():
    """A 100 mm column of 1850 kg/m³ stopped at 60,000 g: ρ L a = 108.9 MPa on its face (the face's force over
    its area equals the column's mass times its deceleration)."""
    a = 6.0e4 * 9.80665
    assert explosive.set_forward_pressure(1850.0, 0.1, -a) == pytest.approx(1850.0 * 0.1 * a)
    area = 3e-4
    assert explosive.set_forward_pressure(1850.0, 0.1, a) * area == pytest.approx(1850.0 * 0.1 * area * a)


def test_the_boundary_is_where_the_log_margin_crosses_zero():
    from fepen.studies.charge_safety import boundary

    assert boundary([600.0, 1000.0], [2.0, 0.5]) == pytest.approx(800.0)
    assert boundary([600.0, 800.0, 1000.0], [3.0, 1.5, 1.2]) is None  # never crosses
    assert boundary([600.0, 800.0, 1000.0], [None, 2.0, 0.5]) == pytest.approx(900.0)  # a point without a result
    assert boundary([600.0, 800.0], [1.0, 0.5]) == pytest.approx(600.0)  # at the threshold on a point


def test_the_runs_compiled_pass_gives_the_same_invariants():
    """cell_demands (what a run evaluates at each row) unfiltered (alpha = 1) on random full tensors, without the
    nodal pressure: its von Mises and largest principal stress are LAPACK's, and its peaks keep the largest."""
    rng = np.random.default_rng(3)
    sd = rng.uniform(-5e7, 5e7, (50, 6))
    dofs, mat, cells = np.zeros((50, 4), dtype=np.int64), np.ones(50, dtype=np.int64), np.arange(50)
    filtered, demand, peak, raw = np.zeros((50, 6)), np.zeros((2, 50)), np.zeros((2, 50)), np.zeros(1)
    explosive.cell_demands(sd, np.zeros((1, 2)), dofs, mat, cells, False, 1.0, filtered, demand, peak, raw)
    eig = [np.linalg.eigvalsh(np.array([[a, d, f], [d, b, e], [f, e, c]]))[-1] for a, b, c, d, e, f in sd]
    np.testing.assert_allclose(demand[1], eig, rtol=0, atol=1e-7 * 5e7)
    np.testing.assert_allclose(demand[0], explosive.von_mises(sd), rtol=1e-12)
    assert raw[0] == pytest.approx(demand[0].max(), rel=1e-12) and np.array_equal(peak, np.maximum(demand, 0.0))
