"""Results directories: atomic JSON/text writes on rank 0, software versions, the resolved scene."""

from __future__ import annotations

import json
from pathlib import Path

from mpi4py import MPI

from fepen.atomic import replacing
from fepen.version import __version__


def versions() -> dict[str, str]:
    """Versions of fepen and of the libraries that shaped this process's numbers (dolfinx and PETSc only
    when the run imported them: a rigid run does not)."""
    import sys

    import numpy

    out = {"fepen": __version__, "numpy": numpy.__version__, "mpi": MPI.Get_library_version().splitlines()[0].strip()}
    if "dolfinx" in sys.modules:
        import dolfinx
        from petsc4py import PETSc

        out["dolfinx"] = dolfinx.__version__
        out["petsc"] = ".".join(str(v) for v in PETSc.Sys.getVersion())
    if "gmsh" in sys.modules:
        out["gmsh"] = sys.modules["gmsh"].__version__
    return out


def write_text(path: Path, text: str, comm: MPI.Comm = MPI.COMM_WORLD) -> None:
    """Write a text file on rank 0 through a temporary file, so it is never left half-written."""
    if comm.rank != 0:
        return
    with replacing(path) as tmp:
        tmp.write_text(text)


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
