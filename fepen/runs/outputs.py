"""What a run writes while it advances, as objects the time loop (fepen.runs.run.Run.advance) iterates over:
each has ``due(run)``, ``write(run)`` and ``close(run, completed)``; the timed ones share one catch-up clock.

    History      a history row (with the gauges and the charge sections) every history interval (both fidelities)
    Fields       the fields (fepen.io.fields) every run.output_interval, and history.csv with them
    Checkpoint   a checkpoint (fepen.runs.checkpoint) every run.checkpoint_interval, and history.csv
    Progress     the tqdm bar on rank 0

The deformable run's steps end on the output times (``Landing``: the explicit solver shortens the step that
would cross one), so that its clocks, on the grid (``Clock(grid=True)``), give rows at k x interval exactly.
The rigid fidelity's clock keeps its steps' times (its RK4 step is longer than the history interval: every
step is a row, and the batched path, fepen/laws/rigid_batch.c, repeats that clock bit for bit).
"""

from __future__ import annotations

import math
from time import perf_counter

#: two output times closer than this fraction of an interval are one time (k x 1e-6 and m x 5e-5 differ by
#: rounding where they coincide)
GRID_TOLERANCE = 1e-9


def next_multiple(interval: float, t: float) -> float:
    """The first k x interval (k an integer) later than t by more than GRID_TOLERANCE x interval.

    Args:
        interval: the output interval (s), > 0. t: the time now (s).

    Returns:
        k x interval (s), rounded to 15 significant digits: the same bits wherever it is computed, and one
        time where two grids meet (10 x 1e-6 and 1 x 1e-5 are both 1e-05, as the files print them).
    """
    tol = GRID_TOLERANCE * interval
    k = math.floor(t / interval) + 1
    while k > 1 and _decimal((k - 1) * interval) > t + tol:
        k -= 1
    while _decimal(k * interval) <= t + tol:
        k += 1
    return _decimal(k * interval)


def _decimal(x: float) -> float:
    """x to 15 significant digits (within 5e-16 of it)."""
    return float(f"{x:.15g}")


class Clock:
    """Due when the time reaches ``next``; after a write, ``next`` moves on by whole intervals past t.

    Args:
        interval: simulated time between two outputs (s); 0 or less: never due.
        next: the first output time (s).
        grid: the times are k x interval (products, not sums: no drift), and a time within GRID_TOLERANCE of
            an interval of ``next`` is due (a run whose steps land on the output times, Landing); False: the
            rigid fidelity's clock (next += interval past t, due at t >= next).
    """

    def __init__(self, interval: float, next: float = 0.0, grid: bool = False):
        self.interval, self.next, self.grid = interval, next, grid

    def due(self, t: float) -> bool:
        if self.interval <= 0.0:
            return False
        return t >= self.next - (GRID_TOLERANCE * self.interval if self.grid else 0.0)

    def advance(self, t: float) -> None:
        if self.grid:
            self.next = next_multiple(self.interval, t)
            return
        while self.next <= t:
            behind = (t - self.next) / self.interval
            if behind > 1000.0:  # an interval far below the step (a row is due at every step anyway): jump
                self.next += math.floor(behind) * self.interval  # instead of adding it a billion times
            self.next += self.interval


class Landing:
    """The next time a step must end on: the first output time of any clock after t, or the run's end.

    Args:
        intervals: the clocks' intervals (s); those <= 0 are never due and ignored.
        end: the time the run ends at the latest (s).

    Calling it with the time now (s) and the stable step (s) returns that time (s). An interval shorter than the
    stable step is not landed on: its output is due at every step, at the steps' own times (landing on it
    would cut every step to that interval: a row asked every 1e-11 s would take a million steps a microsecond).
    """

    def __init__(self, intervals, end: float):
        self.intervals = tuple(i for i in intervals if i > 0.0)
        self.end = end

    def __call__(self, t: float, dt: float = 0.0) -> float:
        intervals = [i for i in self.intervals if i >= dt]
        target = min((next_multiple(i, t) for i in intervals), default=math.inf)
        tol = GRID_TOLERANCE * min(intervals, default=0.0)
        if t < self.end <= target + tol:
            return self.end
        return target


def landing(shot) -> Landing:
    """The Landing of a deformable shot's outputs: its history rows, its fields (run.fields), its checkpoints
    and its end.

    Args:
        shot: the fepen.runs.shot.Shot.

    Returns:
        The Landing (the explicit solver's ``landing``).
    """
    o = shot.outputs
    return Landing((o.history_interval, o.output_interval if o.fields else 0.0, o.checkpoint_interval),
                   shot.hard_end)


class Timed:
    """An output due on its Clock of simulated time (on the grid: Clock's ``grid``)."""

    def __init__(self, interval: float, first: float = 0.0, grid: bool = False):
        self.clock = Clock(interval, first, grid)

    def due(self, run) -> bool:
        return self.clock.due(run.t)

    def state(self) -> dict:
        """The next output time (for checkpoints)."""
        return {"next": self.clock.next}

    def restore(self, state: dict) -> None:
        """Put back what state() returned."""
        self.clock.next = state["next"]


class History(Timed):
    """The history row (``run.record()``: with the strain gauges and charge sections of a deformable run) at every
    interval; history.csv at the close, kept even when the run failed."""

    def write(self, run) -> None:
        run.record()
        self.clock.advance(run.t)

    def close(self, run, completed: bool) -> None:
        run.write_history()  # kept even when the run failed


class Fields(Timed):
    """fields.xdmf / fields.h5 (``run.write_fields()``) at every run.output_interval, history.csv with them."""

    def write(self, run) -> None:
        t0 = perf_counter()
        run.write_fields()
        run.write_history()
        self.clock.advance(run.t)
        run.output_s += perf_counter() - t0

    def close(self, run, completed: bool) -> None:
        from fepen.errors import MachineFault

        if completed or not isinstance(run.stop, (MachineFault, KeyboardInterrupt)):
            run.fields.consolidate()  # else left as the per-time files a resume goes on from


class Checkpoint(Timed):
    """A checkpoint (``run.write_checkpoint()``) at every run.checkpoint_interval, history.csv with it."""

    def write(self, run) -> None:
        t0 = perf_counter()
        self.clock.advance(run.t)
        run.write_history()
        run.write_checkpoint()
        run.output_s += perf_counter() - t0

    def close(self, run, completed: bool) -> None:
        if completed:
            run.drop_checkpoints()  # nothing left to resume


class Progress:
    """The tqdm bar of rank 0, refreshed every EVERY steps, in microseconds of simulated time, to the run's
    expected end (fepen.runs.expected_end)."""

    EVERY = 200

    def __init__(self, end: float, t: float):
        from fepen import progress

        # where the user sees it (fepen.progress: a terminal, mpirun's terminal, a notebook; FEPEN_PROGRESS)
        self.bar = progress.bar(total=round(end * 1e6), initial=round(t * 1e6), unit="µs", desc="fepen",
                                leave=False)

    def due(self, run) -> bool:
        return run.step_count % self.EVERY == 0

    def write(self, run) -> None:
        self.bar.n = round(run.t * 1e6)
        self.bar.total = max(self.bar.total, self.bar.n)  # a run longer than expected
        self.bar.refresh()

    def close(self, run, completed: bool) -> None:
        self.bar.close()
