"""SIGTERM and SIGINT during a run (docs/results.md, "Under a scheduler"): the first signal asks the run to
stop at its next check, where it writes a checkpoint, flushes history.csv and the fields, writes
summary.json with outcome "interrupted", and ends with exit code 4; ``fepen run --resume DIR`` then finishes
it with the same results. A second SIGINT stops at once (Ctrl-C twice). Under MPI the ranks agree at each
check (one reduction every few steps): a signal to any rank stops them all at the same step.
"""

from __future__ import annotations

import signal
import threading

from mpi4py import MPI

#: the signals a run catches
SIGNALS = (signal.SIGTERM, signal.SIGINT)


class Interrupts:
    """Catch SIGTERM and SIGINT while a run goes on (a context manager; the previous handlers come back at its
    end). Only in the main thread: elsewhere the signals keep their handlers and ``stop`` stays None.

    Args:
        comm: the run's communicator.
    """

    def __init__(self, comm=MPI.COMM_WORLD):
        self.comm = comm
        self.caught: int | None = None
        self._previous: dict = {}

    def __enter__(self) -> Interrupts:
        if threading.current_thread() is threading.main_thread():
            for sig in SIGNALS:
                self._previous[sig] = signal.signal(sig, self._catch)
        return self

    def __exit__(self, *exc) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)
        self._previous.clear()

    def _catch(self, signum, frame) -> None:
        if self.caught == signal.SIGINT and signum == signal.SIGINT:
            raise KeyboardInterrupt  # the second Ctrl-C: at once
        self.caught = signum

    def stop(self) -> str | None:
        """The name of the signal any rank caught ("SIGTERM", "SIGINT"), else None (collective)."""
        caught = self.caught or 0
        if self.comm.size > 1:
            caught = self.comm.allreduce(caught, op=MPI.MAX)
        return signal.Signals(caught).name if caught else None
