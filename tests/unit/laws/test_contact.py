"""The shell-charge contact law on node pairs (fepen.laws.contact), mesh-free."""

import numpy as np
import pytest

from fepen.laws.contact import pair_forces, pair_work


# ---- the pair law, mesh-free -------------------------------------------------------------------------
def one_pair(xa, xb, va, vb, aa, ab, ma=2.0, mb=3.0, n=(0.0, 0.0, 1.0), dt=1e-3, dt_avg=1e-3, mu=0.1):
    x, vel, acc = (np.array([p, q], dtype=float) for p, q in ((xa, xb), (va, vb), (aa, ab)))
    mass = np.array([ma, mb])
    force, fn, state = np.zeros((1, 3)), np.zeros(1), np.zeros(1, dtype=np.int8)
    pair_forces(x, vel, acc, mass, np.array([0]), np.array([1]), np.array([n], dtype=float), dt, dt_avg, mu,
                force, fn, state)
    v_new = vel + dt_avg * acc + dt_avg * np.array([force[0], -force[0]]) / mass[:, None]
    return force[0], fn[0], state[0], v_new, x + dt * v_new


def test_closing_pair_ends_the_step_touching_and_keeps_its_momentum():
    """Shell node a above charge node b (n = +z out of the charge), closing at 3 m/s with a gap of 1 mm:
    the step would overshoot by 2 mm; the normal force brings the gap to zero exactly and the pair's
    momentum is unchanged by it."""
    f, fn, state, v, x = one_pair([0, 0, 1e-3], [0, 0, 0], [0, 0, -2.0], [0, 0, 1.0], [0] * 3, [0] * 3, mu=0.0)
    assert fn > 0 and state == 1
    assert x[0, 2] - x[1, 2] == pytest.approx(0.0, abs=1e-15)
    assert np.allclose(2.0 * v[0] + 3.0 * v[1], 2.0 * np.array([0, 0, -2.0]) + 3.0 * np.array([0, 0, 1.0]),
                       rtol=0, atol=1e-12)


def test_opening_pair_is_free():
    f, fn, state, _, _ = one_pair([0, 0, 0], [0, 0, 0], [0, 0, 1.0], [0, 0, -1.0], [0] * 3, [0] * 3)
    assert np.all(f == 0.0) and fn == 0.0 and state == 0


def test_coulomb_friction_sticks_below_and_slides_at_mu_fn():
    """Pressed together (closing 1 m/s, in contact), sliding at w tangentially: below the friction cone the
    relative tangential velocity is removed (stuck), above it the tangential force is μ F_N against the
    sliding direction and the pair keeps sliding the same way."""
    for w, stuck in ((0.05, True), (5.0, False)):
        f, fn, state, v, _ = one_pair([0, 0, 0], [0, 0, 0], [w, 0, -1.0], [0, 0, 0.0], [0] * 3, [0] * 3, mu=0.1)
        ft = f - fn * np.array([0, 0, 1.0])
        if stuck:
            assert state == 1 and abs(v[0, 0] - v[1, 0]) < 1e-12 and np.linalg.norm(ft) <= 0.1 * fn
        else:
            assert state == 2 and ft[0] == pytest.approx(-0.1 * fn, rel=1e-12) and ft[1] == 0.0
            assert v[0, 0] - v[1, 0] > 0


def test_pair_work_of_sliding_is_the_friction_dissipation():
    """A pair sliding at constant closing load: the tangential work over the step is −μ F_N × the
    tangential relative displacement (trapezoidal), the normal work zero (the gap stays closed)."""
    dt = 1e-3
    x = np.zeros((2, 3))
    vel, acc = np.array([[5.0, 0, -1.0], [0, 0, 0]]), np.zeros((2, 3))
    mass = np.array([2.0, 3.0])
    nrm = np.array([[0, 0, 1.0]])
    force, fn, state = np.zeros((1, 3)), np.zeros(1), np.zeros(1, dtype=np.int8)
    pa, pb = np.array([0]), np.array([1])
    pair_forces(x, vel, acc, mass, pa, pb, nrm, dt, dt, 0.1, force, fn, state)
    out = np.zeros(2)
    pair_work(vel, acc, mass, pa, pb, nrm, force, fn, dt, dt, dt, np.array([True]), out)
    v_new = vel + dt * np.array([force[0], -force[0]]) / mass[:, None]
    slip = 0.5 * (dt * 5.0 + dt * (v_new[0, 0] - v_new[1, 0]))
    assert out[1] == pytest.approx(-0.1 * fn[0] * slip, rel=1e-12) and out[1] < 0
    assert out[0] == pytest.approx(0.5 * fn[0] * (-dt * 1.0), rel=1e-12)  # the closing half step before
