"""SIGTERM, SIGINT, SIGHUP and SIGUSR1 during a run or a study (docs/results.md, "Under a scheduler"): the first
signal asks the run to stop at its next check, where it writes a checkpoint, flushes history.csv and the fields,
writes summary.json with outcome "interrupted", and ends with exit code 4; ``fepen run --resume DIR`` then
finishes it with the same results. A study stops at its next shot boundary (fepen.studies.engine) and is
continued by the same command. A second SIGINT stops at once (Ctrl-C twice). Under MPI the ranks agree at each
check (one reduction every few steps): a signal to any rank stops them all at the same step. SIGUSR1 is the
stop a relaunching command (``fepen sweep`` started without mpirun) forwards through its mpirun, which passes it
to every rank without ending them (fepen.studies.processes.relaunch).
"""

from __future__ import annotations

import signal
import threading

from mpi4py import MPI

#: the innermost Interrupts catching now (a study's, or a run's inside it)
_active: Interrupts | None = None
#: the signals a run catches
SIGNALS = (signal.SIGTERM, signal.SIGINT, signal.SIGHUP, signal.SIGUSR1)


class Interrupts:
    """Catch SIGTERM, SIGINT, SIGHUP and SIGUSR1 while a run or a study goes on (a context manager; the previous
    handlers come back at its end). Only in the main thread: elsewhere the signals keep their handlers and ``stop``
    stays None. A run's Interrupts inside a study's passes what it catches on to the study's (``outer``).

    Args:
        comm: the run's communicator.
    """

    def __init__(self, comm=MPI.COMM_WORLD):
        self.comm = comm
        self.caught: int | None = None
        self._previous: dict = {}
        self.outer: Interrupts | None = None

    def __enter__(self) -> Interrupts:
        global _active
        if threading.current_thread() is threading.main_thread():
            for sig in SIGNALS:
                self._previous[sig] = signal.signal(sig, self._catch)
            self.outer, _active = _active, self
            from fepen import errors

            if errors.EARLY_STOP:  # asked for while the rank loaded (errors.catch_early_stop)
                self.caught = errors.EARLY_STOP[0]
                errors.EARLY_STOP.clear()
        return self

    def __exit__(self, *exc) -> None:
        global _active
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)
        if self._previous:
            _active = self.outer
        self._previous.clear()

    def _catch(self, signum, frame) -> None:
        if self.caught == signal.SIGINT and signum == signal.SIGINT:
            raise KeyboardInterrupt  # the second Ctrl-C: at once
        self.caught = signum
        if self.outer is not None:  # a run inside a study: the study stops after it too
            self.outer.caught = self.outer.caught or signum

    @property
    def name(self) -> str | None:
        """The name of the signal this rank caught ("SIGTERM"), or None."""
        return signal.Signals(self.caught).name if self.caught else None

    def stop(self) -> str | None:
        """The name of the signal any rank caught ("SIGTERM", "SIGINT"), else None (collective)."""
        caught = self.caught or 0
        if self.comm.size > 1:
            caught = self.comm.allreduce(caught, op=MPI.MAX)
        return signal.Signals(caught).name if caught else None
