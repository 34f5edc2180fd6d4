"""What a run writes while it advances, as objects the time loop (fepen.runs.run.Run.advance) iterates over:
each has ``due(run)``, ``write(run)`` and ``close(run, completed)``; the timed ones share one catch-up clock.

    History      a history row (with the gauges and the charge sections) every history interval (both fidelities)
    Fields       the fields (fepen.io.fields) every run.output_interval, and history.csv with them
    Checkpoint   a checkpoint (fepen.runs.checkpoint) every run.checkpoint_interval, and history.csv
    Progress     the tqdm bar on rank 0
"""

from __future__ import annotations

from time import perf_counter


class Clock:
    """Due when the time reaches ``next``; after a write, ``next`` moves on by whole intervals past t.

    Args:
        interval: simulated time between two outputs (s); 0 or less: never due.
        next: the first output time (s).
    """

    def __init__(self, interval: float, next: float = 0.0):
        self.interval, self.next = interval, next

    def due(self, t: float) -> bool:
        return self.interval > 0.0 and t >= self.next

    def advance(self, t: float) -> None:
        while self.next <= t:
            self.next += self.interval


class Timed:
    """An output due on its Clock of simulated time."""

    def __init__(self, interval: float, first: float = 0.0):
        self.clock = Clock(interval, first)

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
        from tqdm import tqdm

        self.bar = tqdm(total=round(end * 1e6), initial=round(t * 1e6), unit="us", desc="fepen", leave=False)

    def due(self, run) -> bool:
        return run.step_count % self.EVERY == 0

    def write(self, run) -> None:
        self.bar.n = round(run.t * 1e6)
        self.bar.total = max(self.bar.total, self.bar.n)  # a run longer than expected
        self.bar.refresh()

    def close(self, run, completed: bool) -> None:
        self.bar.close()
