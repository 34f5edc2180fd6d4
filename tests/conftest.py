"""Shared test helpers. Tests marked ``mpi`` also run under ``mpirun -n 2`` (see the Makefile)."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def run_fepen(*args, cwd=None, ranks: int = 1, timeout: float = 600):
    """Run ``python -m fepen ARGS`` in a subprocess (on ``ranks`` MPI ranks); return CompletedProcess."""
    return _run([sys.executable, "-m", "fepen", *map(str, args)], cwd, ranks, timeout)


def _run(cmd, cwd, ranks, timeout):
    if ranks > 1:
        cmd = ["mpirun", "-n", str(ranks), *cmd]
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", PYTHONPATH=str(ROOT))
    return subprocess.run(cmd, cwd=cwd or ROOT, capture_output=True, text=True, timeout=timeout, env=env)


def run_python(script, *args, ranks: int = 1, timeout: float = 600):
    """Run a Python script (a demo) in a subprocess, on ``ranks`` MPI ranks; return CompletedProcess."""
    return _run([sys.executable, str(script), *map(str, args)], None, ranks, timeout)


@pytest.fixture
def fepen_cli():
    return run_fepen
