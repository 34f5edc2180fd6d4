"""Results directories: atomic JSON/text writes on rank 0, software versions, the resolved scene."""

from __future__ import annotations

import errno
import json
import os
from pathlib import Path

from mpi4py import MPI

from fepen.atomic import replacing
from fepen.errors import InputError, MachineFault, describe_os_error
from fepen.version import __version__

#: the environment variable that injects a write fault (tests): ``KIND:K[,KIND:K...]`` raises ENOSPC at the
#: K-th write of KIND in this process ("history", "fields", "checkpoint", "summary", "reserve": the space a run
#: holds back, "figure": a picture)
INJECT = "FEPEN_INJECT_FAULT"
_writes: dict[str, int] = {}


def inject(kind: str) -> None:
    """Count a write of ``kind``; raise OSError(ENOSPC) at the K-th when FEPEN_INJECT_FAULT asks for it (a
    full disk, made on purpose by the tests; nothing happens without the variable)."""
    spec = os.environ.get(INJECT)
    if not spec:
        return
    _writes[kind] = _writes.get(kind, 0) + 1
    for item in spec.split(","):
        name, _, k = item.partition(":")
        if name == kind and k.isdigit() and _writes[kind] == int(k):
            raise OSError(errno.ENOSPC, f"No space left on device (injected at write {k} of the {kind})")


def agree(comm: MPI.Comm, what: str, fn, root_only: bool = True):
    """Run a write and agree on its failure across the ranks.

    Args:
        comm: the communicator of the run.
        what: what is being written, for the message ("history.csv").
        fn: the write (no arguments); called on rank 0 only when ``root_only``, else on every rank.
        root_only: see fn.

    Returns:
        fn's result on the ranks that called it (None elsewhere).

    Raises:
        MachineFault: on every rank, when the write raised an OSError on any rank (disk full, permission);
            the file it was replacing is left as it was (fepen.atomic).
        InputError: on every rank, when the write was refused on any rank (fepen.atomic.ForeignFile: a file
            fepen did not write, or a link, in its way).
    """
    result, error = None, None
    if comm.rank == 0 or not root_only:
        try:
            result = fn()
        except InputError as err:  # a file fepen did not write in the way (fepen.atomic.ForeignFile)
            error = ("input", err.key, err.message)
        except OSError as err:
            error = ("fault", None, f"{describe_os_error(err)} writing {what}")
    errors = [e for e in comm.allgather(error) if e] if comm.size > 1 else [e for e in (error,) if e]
    if errors:
        kind, key, message = errors[0]
        raise InputError(key, message) if kind == "input" else MachineFault(message)
    return result


def versions() -> dict[str, str]:
    """Versions of fepen and of the libraries that shaped this process's numbers (dolfinx and PETSc only
    when the run imported them: a rigid run does not)."""
    import platform
    import sys

    import numpy

    from fepen import dolfinx_api

    out = {"fepen": __version__, "python": platform.python_version(), "numpy": numpy.__version__,
           "mpi": MPI.Get_library_version().replace("\0", "").splitlines()[0].strip()}
    out.update(dolfinx_api.versions())
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


def prepare(out: str | Path, comm: MPI.Comm = MPI.COMM_WORLD, key: str = "--out") -> Path:
    """Create the results directory (rank 0) and wait for it on every rank.

    Raises:
        InputError: (``key``) when it names a file or cannot be created or written (on every rank).
        MachineFault: when the disk is full.
    """
    out = Path(out)
    problem = None
    if comm.rank == 0:
        problem = _make_directory(out)
    problem = comm.bcast(problem, root=0) if comm.size > 1 else problem
    if problem is not None:
        kind, message = problem
        raise MachineFault(message) if kind == "fault" else InputError(key, message)
    return out


def _make_directory(out: Path) -> tuple[str, str] | None:
    """Create ``out``; None, or (kind "input" or "fault", the message)."""
    if out.exists() and not out.is_dir():
        return "input", f"{out} is a file, not a directory: name a directory (it is created if absent)"
    from fepen.atomic import ForeignFile, guard

    try:
        guard(out)  # inside a claimed directory (a study's shot folder): fepen's or new, never a link
    except ForeignFile as err:
        return "input", err.message
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        if err.errno in (errno.ENOSPC, errno.EDQUOT, errno.EIO):
            return "fault", f"{describe_os_error(err)} creating {out}"
        return "input", f"cannot create the directory {out}: {describe_os_error(err)}"
    if not os.access(out, os.W_OK | os.X_OK):
        return "input", f"cannot write into {out}: permission denied"
    return None


def peak_memory_bytes(comm: MPI.Comm = MPI.COMM_WORLD) -> int:
    """Peak resident memory of the run: the sum over ranks of each process's peak RSS (bytes)."""
    import resource
    import sys

    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # KiB on Linux, bytes on macOS
    return comm.allreduce(int(rss) * (1 if sys.platform == "darwin" else 1024), op=MPI.SUM)
