"""The output clocks on the grid and the landing times of the deformable run's steps (fepen.runs.outputs)."""

import math

import numpy as np
import pytest

from fepen.runs import outputs


@pytest.mark.parametrize("interval", [1e-6, 5e-5, 3.3e-5, 1.5e-5, 0.1])
def test_next_multiple_is_the_next_k_times_the_interval(interval):
    """From any time, the first k x interval past it (a time on the grid moves on to the next one)."""
    t = 0.0
    for k in range(1, 400):
        nxt = outputs.next_multiple(interval, t)
        assert nxt == float(f"{k * interval:.15g}")  # the product, no drift as with repeated sums
        assert math.isclose(nxt, k * interval, rel_tol=1e-15)
        t = nxt
    rng = np.random.default_rng(1)
    for t in rng.uniform(0.0, 300 * interval, 200):
        nxt = outputs.next_multiple(interval, t)
        assert t < nxt <= t + interval * (1 + 1e-9)
        assert abs(nxt / interval - round(nxt / interval)) < 1e-9


def test_grid_clock_is_due_on_the_grid_and_the_old_clock_keeps_its_sums():
    grid, old = outputs.Clock(1e-6, 0.0, grid=True), outputs.Clock(1e-6, 0.0)
    for k in range(300):
        t = k * 1e-6
        assert grid.due(t)
        grid.advance(t)
        assert grid.next == float(f"{k + 1}e-6")
    for _ in range(300):
        old.advance(old.next)
    assert old.next != 300 * 1e-6  # the rigid fidelity's clock: sums (rigid_batch.c repeats them)
    assert math.isclose(old.next, 300e-6, rel_tol=1e-12)


def test_a_clock_far_behind_catches_up_in_one_jump():
    """A rigid run's history every 1e-13 s (run.output_interval = 1e-12) over its 1 ms: the clock reaches the
    time in one jump, not in 1e10 additions, and is then due at the next step, as every row of a clock
    whose interval is below the step; a clock a few intervals behind still adds (the same sums as before)."""
    far = outputs.Clock(1e-13)
    far.advance(1e-3)
    assert 1e-3 < far.next <= 1e-3 + 1e-13 * (1 + 1e-6) and far.due(1e-3 + 5e-9)
    near, sums = outputs.Clock(1e-6), 0.0
    near.advance(5.5e-6)
    for _ in range(6):
        sums += 1e-6
    assert near.next == sums


def test_landing_merges_the_grids_and_lands_on_the_end():
    land = outputs.Landing((1e-6, 5e-5, 0.0, 3.3e-5), end=1.205e-4)
    assert land(0.0) == 1e-6
    assert land(49e-6) == 5e-5  # one time where two grids meet (their products differ by rounding)
    assert land(32.5e-6) == 3.3e-5 and land(9.5e-6) == 1e-5  # the times as the files print them
    assert land(33.5e-6) == 34e-6
    assert land(1.2e-4) == 1.205e-4  # the end, not the grid past it
    assert land(1.2e-4 + 0.25e-6) == 1.205e-4
    assert outputs.Landing((1e-6,), end=3e-5)(29e-6) == 3e-5  # the end where it meets the grid


def test_an_interval_below_the_stable_step_is_not_landed_on():
    """A row at every step (an interval far below the step) must not cut the steps to that interval; the
    other outputs and the end are still landed on."""
    land = outputs.Landing((1e-11, 5e-6), end=6e-5)
    assert land(0.0, dt=1e-8) == 5e-6
    assert land(59.99e-6, dt=1e-8) == 6e-5
    assert outputs.Landing((1e-11,), end=6e-5)(0.0, dt=1e-8) == 6e-5  # only the end
    assert land(0.0) == 1e-11  # with no step given, every interval counts


def test_grid_clock_restores_from_its_state():
    a = outputs.History(1e-6, grid=True)
    a.clock.advance(12e-6)
    b = outputs.History(1e-6, grid=True)
    b.restore(a.state())
    assert b.clock.next == a.clock.next == 13e-6 and b.due(type("R", (), {"t": 13e-6})())
