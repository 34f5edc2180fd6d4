"""Shared test helpers. Tests marked ``mpi`` compare 1 and 2 ranks: make test runs them under ``mpirun -n 2``
only, and the serial lanes (``-m "not mpi"``) leave them out (see the Makefile)."""

from pathlib import Path

import pytest

from fepen.studies import processes

ROOT = Path(__file__).resolve().parents[1]


def run_fepen(*args, cwd=None, ranks: int = 1, timeout: float = 600):
    """Run ``python -m fepen ARGS`` in a subprocess (on ``ranks`` MPI ranks); return CompletedProcess."""
    return processes.run(args, ranks, cwd=cwd, timeout=timeout)


def run_python(script, *args, ranks: int = 1, timeout: float = 600):
    """Run a Python script (a demo) in a subprocess, on ``ranks`` MPI ranks; return CompletedProcess."""
    return processes.run([script, *args], ranks, fepen=False, timeout=timeout)


@pytest.fixture
def fepen_cli():
    return run_fepen
