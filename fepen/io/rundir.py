"""A results directory that cannot be mistaken (docs/results.md, "What a run directory holds"):

- a run into a directory that holds another run's results refuses (InputError naming --force and --resume),
  or, with force, first removes what a fepen run writes there (OUTPUT_NAMES; nothing else);
- a lock file ``.fepen.lock`` (host, pid, start) keeps a second run out while the first goes on; a lock left
  by a process that no longer exists on this host is stale and taken over with a warning;
- ``run.json``: the command line, ranks, fepen version and code revision, host, start and end time, outcome
  and exit code (of the first run and of every resume);
- ``fepen.log``: what the console showed on rank 0 (the lines said before the directory was claimed
  included), plus the warnings of any rank.
"""

from __future__ import annotations

import errno
import fnmatch
import json
import logging
import os
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

from mpi4py import MPI

from fepen.atomic import replacing
from fepen.errors import InputError, MachineFault, describe_os_error
from fepen.version import __version__

LOCK = ".fepen.lock"
#: space held back while a run goes on, given back to write the record of a stop on a full disk
RESERVE, RESERVE_BYTES = ".fepen.reserve", 256 * 1024
#: a directory holding one of these holds a run's results
MARKERS = ("summary.json", "run.json", "history.csv", "fields.xdmf", "checkpoint")
#: what a fepen run writes into its directory: ``--force`` removes these and nothing else
OUTPUT_NAMES = ("summary.json", "run.json", "fepen.log", "scene.toml", "history.csv", "history.png", "checkpoint",
                "probes.csv",
                "fields.xdmf", "fields.h5", "fields.d", "fields_*.xdmf", "fields_*.h5", "view.py", "*.png",
                "accelerations.csv", "gauges*.csv", "hazard*.csv", "sections*.csv", "charge*.csv", "charge*.json",
                "nose_profile*.csv", "profile*.csv", "strains*.csv", "*.vtu", "*.tmp*", "run.log", RESERVE)

_log_path: Path | None = None
_transcript: list[str] = []
#: the command line being run, recorded in run.json and fepen.log (set by begin_command; None: this process's)
_command_line: list[str] | None = None


#: True while fepen.cli.main runs a command: the API calls it makes leave its command line in place
_in_cli = False


def api_call(command: list[str]) -> None:
    """A call of the Python API (fepen.api) begins: it is the command run.json records, unless the API call is
    made by a ``fepen`` command line (whose line stays the record)."""
    if not _in_cli:
        begin_command(command)


def begin_command(command: list[str] | None) -> None:
    """A new command (fepen.cli.main calls it first): the command line the run directories it claims record
    (None: this process's ``sys.argv``), no log yet, nothing kept. The one way to set the recorded command
    line besides RunDirectory's own ``command`` argument."""
    global _command_line
    _command_line = None if command is None else list(command)
    forget()


def forget() -> None:
    """No log yet, nothing kept."""
    global _log_path
    _log_path = None
    _transcript.clear()


def release_reserve() -> None:
    """Give back the space the run held (rank 0): the record of a stop fits in it on a full disk."""
    if _log_path is not None:
        (_log_path.parent / RESERVE).unlink(missing_ok=True)


def log_line(line: str) -> None:
    """A line the console showed (rank 0): into fepen.log when a run directory is claimed, else kept until
    one is."""
    if _log_path is None:
        _transcript.append(line)
        del _transcript[:-200]  # what a command says before its run directory exists is short
        return
    _append(_log_path, [line])


def _append(path: Path, lines) -> None:
    try:
        with open(path, "a") as f:
            f.write("".join(f"{ln}\n" for ln in lines))
    except OSError:  # the log is a record, never a reason to stop a run
        pass


class _Tee(logging.Handler):
    """fepen's log records into fepen.log: every record on rank 0, warnings and above from the other ranks."""

    def __init__(self, rank: int):
        super().__init__(logging.INFO if rank == 0 else logging.WARNING)
        self.rank = rank

    def emit(self, record) -> None:
        line = f"fepen: {record.getMessage()}" if self.rank == 0 else f"fepen (rank {self.rank}): {record.getMessage()}"
        if self.rank == 0:
            log_line(line)
        elif _log_path is not None:
            _append(_log_path, [line])


def tee_logging(rank: int) -> None:
    """Send the "fepen" and "py.warnings" loggers' records to fepen.log too (once per process)."""
    for name in ("fepen", "py.warnings"):
        logger = logging.getLogger(name)
        if not any(isinstance(h, _Tee) for h in logger.handlers):
            logger.addHandler(_Tee(rank))
    logging.captureWarnings(True)


def revision() -> str | None:
    """The git revision of this fepen's source tree ("+dirty" when it has uncommitted changes), or None."""
    root = Path(__file__).resolve().parents[2]
    if not (root / ".git").exists():
        return None
    try:
        head = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True,
                              timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "-uno"], capture_output=True,
                               text=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None
    return (head + ("+dirty" if dirty else "")) or None


def _now() -> str:
    return time.strftime("%Y-%m-%dT%H:%M:%S%z")


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


class RunDirectory:
    """The claim of one run on its results directory (rank 0 does the file work; every rank gets the verdict).

    Args:
        out: the results directory.
        comm: the run's communicator.
        mode: "new" (refuse a directory holding results), "force" (remove them first) or "resume".
        command: the command line to record (default: the one begin_command set, else this process's).
    """

    def __init__(self, out, comm=MPI.COMM_WORLD, mode: str = "new", command: list[str] | None = None):
        self.out, self.comm, self.mode = Path(out), comm, mode
        if command is None:
            command = _command_line or [Path(sys.argv[0]).name, *sys.argv[1:]]
        self.command = list(command)
        self.record: dict = {}

    # ------------------------------------------------------------------------------------------------
    def __enter__(self) -> RunDirectory:
        global _log_path
        _log_path = None  # lines from here on belong to this run
        tee_logging(self.comm.rank)
        problem = self._claim() if self.comm.rank == 0 else None
        if self.comm.size > 1:
            problem = self.comm.bcast(problem, root=0)
        if problem is not None:
            kind, key, message = problem
            raise MachineFault(message) if kind == "fault" else InputError(key, message)
        _log_path = self.out / "fepen.log"
        if self.comm.rank == 0:
            _append(_log_path, [f"# {_now()} {self.mode}: {' '.join(self.command)}", *_transcript])
            _transcript.clear()
        return self

    def __exit__(self, kind, err, tb) -> None:
        from fepen.errors import stop_outcome

        if kind is None:
            outcome, code = "finished", 0
        else:
            o = stop_outcome(err)
            outcome, code = o.name, o.exit_code
        if self.comm.rank == 0:
            self._close(outcome, code, None if err is None else str(err).splitlines()[0] if str(err) else kind.__name__)

    # ------------------------------------------------------------------------------------------------
    def _claim(self) -> tuple | None:
        """Rank 0: check, lock and record. None, or (kind, key, message) of the refusal."""
        from fepen.io.files import _make_directory

        made = _make_directory(self.out)
        if made is not None:
            return made[0], "--out", made[1]
        key = "--resume" if self.mode == "resume" else "--out"
        try:
            held = self._lock()
            if held:
                return "input", key, held
            if self.mode == "new":
                found = [m for m in MARKERS if (self.out / m).exists()]
                if found:
                    self._unlock()
                    return "input", "--out", (f"{self.out} holds another run's results ({', '.join(found)}): "
                                              "add --force to clear them first, or continue that run with "
                                              f"`fepen run --resume {self.out}`, or name another --out")
            elif self.mode == "force":
                self._clear()
            self._write_record()
            with open(self.out / RESERVE, "wb") as f:
                f.write(b"\0" * RESERVE_BYTES)
        except OSError as err:
            self._unlock()
            bad = err.errno in (errno.ENOSPC, errno.EDQUOT, errno.EIO)
            return ("fault" if bad else "input"), key, f"{describe_os_error(err)} in {self.out}"
        return None

    def _lock(self) -> str | None:
        """Take the lock file; a message when another live run holds it."""
        path = self.out / LOCK
        mine = {"host": socket.gethostname(), "pid": os.getpid(), "start": _now(), "command": self.command}
        for _ in range(2):
            try:
                fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                try:
                    other = json.loads(path.read_text())
                except (OSError, ValueError):
                    other = {}
                host, pid = other.get("host"), other.get("pid")
                if host == mine["host"] and isinstance(pid, int) and not _alive(pid):
                    logging.getLogger("fepen").warning(f"{path}: a stale lock of process {pid} (no longer "
                                                       "running) is taken over")
                    path.unlink(missing_ok=True)
                    continue
                where = (f"process {pid} on this host" if host == mine["host"]
                         else f"process {pid} on host {host} (if that run is gone, delete {path})")
                return (f"{self.out} is in use by another run: {where}, since {other.get('start', '?')}; "
                        "wait for it to end or name another --out")
            with os.fdopen(fd, "w") as f:
                f.write(json.dumps(mine) + "\n")
            return None
        return f"{self.out}: could not take the lock {path}"

    def _unlock(self) -> None:
        path = self.out / LOCK
        try:
            if json.loads(path.read_text()).get("pid") == os.getpid():
                path.unlink()
        except (OSError, ValueError):
            pass

    def _clear(self) -> None:
        """Remove what a fepen run writes (OUTPUT_NAMES), nothing else."""
        for entry in self.out.iterdir():
            if entry.name != LOCK and any(fnmatch.fnmatch(entry.name, p) for p in OUTPUT_NAMES):
                shutil.rmtree(entry) if entry.is_dir() and not entry.is_symlink() else entry.unlink()

    def _write_record(self) -> None:
        path = self.out / "run.json"
        earlier = {}
        if self.mode == "resume" and path.is_file():
            try:
                earlier = json.loads(path.read_text())
            except ValueError:
                earlier = {}
        this = {"command": self.command, "cwd": os.getcwd(), "ranks": self.comm.size, "fepen": __version__,
                "revision": revision(), "host": socket.gethostname(), "pid": os.getpid(), "start": _now(),
                "end": None, "outcome": "running", "exit_code": None}
        if earlier:
            self.record = dict(earlier)
            self.record.setdefault("resumes", []).append(this)
        else:
            self.record = this
        self._save()

    def _save(self) -> None:
        with replacing(self.out / "run.json") as tmp:
            tmp.write_text(json.dumps(self.record, indent=1) + "\n")

    def _close(self, outcome: str, code: int, message: str | None) -> None:
        last = self.record["resumes"][-1] if self.record.get("resumes") else self.record
        from fepen.io.files import versions

        last.update(end=_now(), outcome=outcome, exit_code=code, **({"message": message} if message else {}),
                    versions=versions())  # at the end: dolfinx and PETSc are named when the run imported them
        if "resumes" in self.record:  # the first invocation's record stays; the whole run's verdict beside it
            self.record.update(final_outcome=outcome, final_exit_code=code)
        (self.out / RESERVE).unlink(missing_ok=True)
        try:
            self._save()
        except OSError:  # a full disk: run.json keeps its "running" record; the lock goes all the same
            pass
        _append(self.out / "fepen.log", [f"# {last['end']} {outcome} (exit {code})"])
        self._unlock()
