"""Whole ``fepen`` processes, as a user would start them (studies, demos and tests)."""

from __future__ import annotations

import os


def run_fepen_process(args: list[str], ranks: int = 1) -> tuple[int, float, str]:
    """Run ``python -m fepen ARGS`` as a whole process, under ``mpirun -n RANKS`` when ranks > 1 (as a
    user would; OpenMPI allowed to run as root and to oversubscribe).

    Returns:
        (exit code, wall seconds, the last "fepen:" line of its stderr, or its tail).
    """
    import subprocess
    import sys
    import time

    cmd = [sys.executable, "-m", "fepen", *map(str, args)]
    if ranks > 1:
        cmd = ["mpirun", "-n", str(ranks), *cmd]
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1")
    t0 = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    lines = [ln for ln in r.stderr.strip().splitlines() if ln.startswith("fepen:")]
    return r.returncode, wall, (lines[-1] if lines else r.stderr.strip()[-400:])
