"""Results directories: atomic JSON/text writes on rank 0, software versions, the resolved scene."""

from __future__ import annotations

import json
import os
from pathlib import Path

from mpi4py import MPI


def versions() -> dict[str, str]:
    """Versions of fepen and the libraries that shape its numbers."""
    import dolfinx
    import numpy
    from petsc4py import PETSc

    import fepen

    out = {"fepen": fepen.__version__, "dolfinx": dolfinx.__version__,
           "petsc": ".".join(str(v) for v in PETSc.Sys.getVersion()), "numpy": numpy.__version__,
           "mpi": MPI.Get_library_version().splitlines()[0].strip()}
    try:
        import gmsh

        out["gmsh"] = gmsh.__version__
    except ImportError:  # pragma: no cover
        pass
    return out


def write_text(path: Path, text: str, comm: MPI.Comm = MPI.COMM_WORLD) -> None:
    """Write a text file on rank 0 through a temporary file, so it is never left half-written."""
    if comm.rank != 0:
        return
    path = Path(path)
    tmp = path.with_name(path.name + f".tmp{os.getpid()}")
    tmp.write_text(text)
    os.replace(tmp, path)


def write_json(path: Path, data: dict, comm: MPI.Comm = MPI.COMM_WORLD) -> None:
    """Write a JSON file on rank 0, atomically."""
    write_text(path, json.dumps(data, indent=2, sort_keys=False) + "\n", comm)


def prepare(out: str | Path, comm: MPI.Comm = MPI.COMM_WORLD) -> Path:
    """Create the results directory (rank 0) and wait for it on every rank."""
    out = Path(out)
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    return out


def peak_memory_bytes(comm: MPI.Comm = MPI.COMM_WORLD) -> int:
    """Peak resident memory of the run: the sum over ranks of each process's peak RSS (bytes)."""
    import resource
    import sys

    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # KiB on Linux, bytes on macOS
    return comm.allreduce(int(rss) * (1 if sys.platform == "darwin" else 1024), op=MPI.SUM)


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
