"""A relaunched rank keeps the stop it was asked for while it loaded (fepen.errors.catch_early_stop): the study's
Interrupts then holds it as caught, and a rank that was not relaunched is left with the default action."""

import os
import signal

from mpi4py import MPI

from fepen import errors
from fepen.runs.interrupts import Interrupts


def test_a_stop_before_the_study_catches_signals_is_kept(monkeypatch):
    before = signal.getsignal(signal.SIGUSR1)
    try:
        monkeypatch.delenv(errors.RELAUNCHED, raising=False)
        errors.catch_early_stop()
        assert signal.getsignal(signal.SIGUSR1) == before  # not relaunched: nothing changes
        monkeypatch.setenv(errors.RELAUNCHED, "1")
        errors.catch_early_stop()
        os.kill(os.getpid(), signal.SIGUSR1)  # delivered before the next bytecode: not the default's death
        assert errors.EARLY_STOP == [signal.SIGUSR1]
        with Interrupts(MPI.COMM_SELF) as stop:
            assert stop.caught == signal.SIGUSR1 and stop.stop() == "SIGUSR1"
        assert errors.EARLY_STOP == []  # taken once
        with Interrupts(MPI.COMM_SELF) as stop:
            assert stop.caught is None
    finally:
        signal.signal(signal.SIGUSR1, before)
        errors.EARLY_STOP.clear()
