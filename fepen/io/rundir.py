"""A results directory fepen owns by manifest (docs/results.md, "What a run directory holds"):

- ``run.json`` records the run: the command line, ranks, fepen version and code revision, host, start and end
  time, outcome and exit code (of the first run and of every resume), the digest of its inputs, and ``files``:
  the manifest, every top-level name this run (and the runs it resumes) wrote, updated as each new name is
  written (fepen.atomic.Claim);
- a run into a directory that holds another run's results refuses (InputError naming --force and --resume);
  with force it first removes exactly the names that run's manifest lists, never by pattern, and nothing in a
  directory that holds no fepen run; a directory whose last run ended before it wrote any result (a full disk at
  its claim) is taken over;
- no run writes over, or through, a name it does not own: a user's file or link with a name a run writes is
  refused before the run starts (RUN_NAMES), and any other at its write (fepen.atomic.ForeignFile);
- a lock file ``.fepen.lock`` (host, pid, start) keeps a second run out while the first goes on; a lock left
  by a process that no longer exists on this host is stale and taken over with a warning;
- ``fepen.log``: what the console showed on rank 0 (the lines said before the directory was claimed
  included), plus the warnings of any rank; opened without following links.
"""

from __future__ import annotations

import errno
import json
import logging
import os
import socket
import stat
import subprocess
import sys
import time
from pathlib import Path

from mpi4py import MPI

from fepen import atomic
from fepen.atomic import replacing
from fepen.errors import InputError, MachineFault, describe_os_error
from fepen.io import layout
from fepen.io.files import _make_directory, inject
from fepen.version import __version__

#: the names and the record's limits, declared once with what each kind of record writes (fepen.io.layout)
LOCK, RESERVE, RECORD_NAMES, RUN_NAMES, MESH_NAMES = (layout.LOCK, layout.RESERVE, layout.RECORD_NAMES,
                                                      layout.RUN_NAMES, layout.MESH_NAMES)
RESERVE_BYTES = 256 * 1024
RECORD_MAX = layout.RECORD_MAX
read_record, manifest = layout.read_record, layout.manifest

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
        _remove_reserve(_log_path.parent)


def _remove_reserve(out: Path) -> None:
    """Remove the reserve file (a name, never what a link there points to)."""
    try:
        os.unlink(out / RESERVE)
    except FileNotFoundError:
        pass


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
        with atomic.open_append(path) as f:  # never through a link
            f.write("".join(f"{ln}\n" for ln in lines))
    except (OSError, atomic.ForeignFile):  # the log is a record, never a reason to stop a run
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


class ChatterToLog(logging.Handler):
    """Other packages' log records (and Python's warnings) into fepen.log, named by their logger, never to the
    console: ``ffcx: ...``, ``py.warnings: ...`` (rank 0's; the other ranks' are dropped)."""

    def emit(self, record) -> None:
        from mpi4py import MPI

        if MPI.COMM_WORLD.rank == 0:
            log_line(f"{record.name}: {' '.join(record.getMessage().split())[:2000]}")


def chatter_to_log() -> None:
    """Route the root logger (every package but fepen) to fepen.log only, at INFO (once per process); Python's
    warnings are captured into it too."""
    root = logging.getLogger()
    if not any(isinstance(h, ChatterToLog) for h in root.handlers):
        root.addHandler(ChatterToLog())
    root.setLevel(logging.INFO)
    logging.captureWarnings(True)
    logging.getLogger("py.warnings").propagate = True


def tee_logging(rank: int) -> None:
    """Send the "fepen" and "py.warnings" loggers' records to fepen.log too (once per process; Python's warnings
    not again when the command line routes every other package there: chatter_to_log)."""
    chatter = any(isinstance(h, ChatterToLog) for h in logging.getLogger().handlers)
    for name in ("fepen",) if chatter else ("fepen", "py.warnings"):
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
        dirty = subprocess.run(["git", "-C", str(root), "--no-optional-locks", "status", "--porcelain", "-uno"],
                               capture_output=True, text=True, timeout=10).stdout.strip()  # never .git/index.lock
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


def results_in(record: dict) -> list[str]:
    """The result files a record lists (its manifest without the record itself and the scene)."""
    return sorted((manifest(record) or set()) - RECORD_NAMES - {"scene.toml"})


def _names(names) -> str:
    names = sorted(names)
    return ", ".join(names[:4]) + (f" and {len(names) - 4} more" if len(names) > 4 else "")


class RunDirectory:
    """The claim of one command on its results directory (rank 0 does the file work; every rank gets the
    verdict and the claim of fepen.atomic that guards every write).

    Args:
        out: the results directory.
        comm: the run's communicator.
        mode: "new" (refuse a directory holding results), "force" (remove the files its manifest lists first),
            "resume", or "continue" (a study: keep what the same kind of study wrote there and go on; refuse
            another kind's results).
        command: the command line to record (default: the one begin_command set, else this process's).
        kind: what the command is ("run", "mesh", or a study's name): a new "mesh" replaces an earlier mesh's
            files as a new run never replaces a run's.
        inputs: the digest of the run's inputs, recorded (a resume compares its own with it).
        names: the top-level names the command may write, refused before it starts when a file fepen did not
            write holds one (default: RUN_NAMES, or MESH_NAMES for a mesh).
        digest: what a study's folder holds (fepen.studies.study): "continue" refuses a folder of the same kind
            of study with another digest.
    """

    def __init__(self, out, comm=MPI.COMM_WORLD, mode: str = "new", command: list[str] | None = None,
                 kind: str = "run", inputs: dict | None = None, names=None, digest: str | None = None):
        self.out, self.comm, self.mode, self.kind = Path(out), comm, mode, kind
        if command is None:
            command = _command_line or [Path(sys.argv[0]).name, *sys.argv[1:]]
        self.command = list(command)
        default = MESH_NAMES if kind == "mesh" else RUN_NAMES
        self.names = default if names is None else RECORD_NAMES | frozenset(names)
        if names is not None and kind not in ("run", "mesh"):
            layout.declare(kind, names)
        self.layout = layout.layout_of(kind)
        self.inputs, self.digest = inputs, digest
        self.record: dict = {}
        self.claim: atomic.Claim | None = None
        self._outer_log: Path | None = None

    # ------------------------------------------------------------------------------------------------
    def __enter__(self) -> RunDirectory:
        global _log_path
        self._outer_log = _log_path  # a study's shot claims its own folder inside the study's: back to it at exit
        _log_path = None  # lines from here on belong to this run
        tee_logging(self.comm.rank)
        verdict = self._claim() if self.comm.rank == 0 else None
        if self.comm.size > 1:
            verdict = self.comm.bcast(verdict, root=0)
        problem, owned = verdict
        if problem is not None:
            kind, key, message = problem
            raise MachineFault(message) if kind == "fault" else InputError(key, message)
        if self.comm.rank != 0:  # links only: rank 0 makes and records every top-level name
            self.claim = atomic.claim(self.out, owned, strict=False)
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
            if outcome == "fault" and tb is not None:  # out of memory: the failed run's frames let go of theirs
                import traceback

                traceback.clear_frames(tb)
        global _log_path
        try:
            if self.comm.rank == 0:
                text = "" if err is None else next((ln for ln in str(err).splitlines() if ln.strip()), "")
                self._close(outcome, code, None if err is None else text or kind.__name__)
        finally:
            atomic.release(self.claim)
            if self._outer_log is not None:  # a shot's folder inside a study's: the study's log again (a run's own
                _log_path = self._outer_log  # log keeps what the command says after it: its summary lines)

    @property
    def written(self) -> list[str]:
        """The names the directory's manifest lists that are there now (rank 0), sorted."""
        if self.claim is None:
            return []
        return sorted(n for n in self.claim.owned if n != RESERVE and os.path.lexists(self.out / n))

    # ------------------------------------------------------------------------------------------------
    def _claim(self) -> tuple:
        """Rank 0: check, lock, clear (force) and record. (None, the owned names), or ((kind, key, message) of
        the refusal, ())."""
        made = _make_directory(self.out)
        if made is not None:
            return (made[0], "--out", made[1]), ()
        key = "--resume" if self.mode == "resume" else "--out"
        try:
            held = self._lock()
            if held:
                return ("input", key, held), ()
            refused = self._previous()
            if isinstance(refused, str):
                self._unlock()
                return ("input", key, refused), ()
            owned = refused
            self.claim = atomic.claim(self.out, owned, on_new=self._new_name, declared=self._declares)
            for name in ("run.json", "fepen.log", RESERVE):
                self.claim.owned.add(name)
            self._write_record()
        except OSError as err:
            self._unlock()
            atomic.release(self.claim)
            bad = err.errno in (errno.ENOSPC, errno.EDQUOT, errno.EIO)
            return (("fault" if bad else "input"), key, f"{describe_os_error(err)} in {self.out}"), ()
        try:
            _remove_reserve(self.out)  # a killed run's (its manifest's: a foreign one or a link was refused above)
            with atomic.create_new(self.out / RESERVE) as f:
                f.write(b"\0" * (RESERVE_BYTES // 2))
                inject("reserve")
                f.write(b"\0" * (RESERVE_BYTES - RESERVE_BYTES // 2))
        except OSError as err:  # a disk too small for the reserve: the record says so, and nothing is left
            message = f"{describe_os_error(err)} in {self.out} (holding back {RESERVE_BYTES >> 10} KiB for the record)"
            self._abandon(message)
            return ("fault", key, message), ()
        return None, set(self.claim.owned)

    def _previous(self) -> set[str] | str:
        """Rank 0, the lock held: the names of the earlier command's files that this one may replace (removed
        first by force, or when that command left no results), or the refusal's message."""
        rec, foreign = read_record(self.out)
        if foreign:
            return (f"{self.out / 'run.json'} is {foreign}: fepen writes its record there and never replaces a "
                    "file it did not write; move it away or name another --out")
        owned: set[str] = set()
        if rec is not None:
            files = manifest(rec)
            if files is None:
                return (f"{self.out} holds the results of an earlier fepen, which kept no manifest of its files: "
                        "fepen removes only what a manifest lists; remove them by hand, or name another --out")
            results = results_in(rec)
            same_kind = rec.get("kind", "run") == self.kind
            if self.mode == "new" and results and not (same_kind and self.kind == "mesh"):
                return (f"{self.out} holds another run's results ({_names(results)}): add --force to remove "
                        f"them first (exactly the files that run wrote), or continue that run with "
                        f"`fepen run --resume {self.out}`, or name another --out")
            if self.mode == "continue" and results and not same_kind:
                return (f"{self.out} holds the results of a {rec.get('kind', 'run')}, not of a {self.kind}: name "
                        "another --out, or --fresh to remove them first (exactly the files it wrote)")
            if self.mode == "continue" and same_kind and results and rec.get("digest") != self.digest:
                changed = _study_changed(rec.get("inputs"), self.inputs)
                return (f"{self.out} holds the results of a {self.kind} made of other inputs ({changed}): a "
                        f"continued {self.kind} runs the rest of the same shots with the same model; --fresh to "
                        "replace them, or a new --out")
            owned = files
            kind = rec.get("kind", "run")
            extra = layout.undeclared(kind, files)
            if extra:  # a record is trusted only for what its kind writes
                return (f"{self.out / 'run.json'} lists {_names(extra)}, which a fepen {kind} never writes: fepen "
                        "removes or replaces only what its record lists and its kind writes; take them out of its "
                        "\"files\" (or move them away), or name another --out")
        elif self.mode == "resume":
            return f"{self.out} holds no fepen run to resume (no run.json)"
        blocking = [n for n in sorted(self.names | owned) if os.path.lexists(self.out / n)
                    and (n not in owned or os.path.islink(self.out / n))]
        if blocking:
            what = ", ".join(f"{n} (a link)" if os.path.islink(self.out / n) else n for n in blocking[:4])
            return (f"{self.out} holds {what}, which fepen did not write and this {self.kind} would replace: fepen "
                    "never overwrites a file it did not write; move it away or name another --out")
        self._sweep(rec)
        if rec is not None and self.mode in ("new", "force"):
            if self.mode == "new":
                logging.getLogger("fepen").info(f"{self.out}: the files of its last {rec.get('kind', 'run')} "
                                                f"({rec.get('outcome')}) are replaced")
            owned = self._clear(owned, rec.get("kind", "run"))
        return owned

    def _sweep(self, rec: dict | None) -> None:
        """Rank 0, the lock held: the temporaries a killed command left here (its kind's and this one's layout:
        fepen.io.layout), named in fepen.log."""
        gone = []
        for kind in dict.fromkeys([self.kind, *([rec.get("kind", "run")] if rec else [])]):
            gone += layout.sweep_temporaries(self.out, kind)
        if gone:
            log_line(f"fepen: {len(gone)} temporar{'y' if len(gone) == 1 else 'ies'} a killed command left removed: "
                     f"{_names(gone)}")

    def _declares(self, name: str) -> bool:
        """This command's kind writes ``name`` at the top of its folder (fepen.io.layout)."""
        return self.layout is not None and self.layout.node(name) is not None

    def _new_name(self, name: str) -> None:
        """A name newly written into the directory: the manifest in run.json at once (rank 0)."""
        if self.record:
            self._save()

    def _abandon(self, message: str) -> None:
        """A claim that cannot go on (a full disk at the reserve): no reserve, the record's outcome, no lock."""
        _remove_reserve(self.out)
        self.claim.owned.discard(RESERVE)
        self.record.update(end=_now(), outcome="fault", exit_code=4, message=message)
        try:
            self._save()
        except OSError:
            pass
        self._unlock()
        atomic.release(self.claim)

    def _lock(self) -> str | None:
        """Take the lock file; a message when another live run holds it."""
        path = self.out / LOCK
        mine = {"host": socket.gethostname(), "pid": os.getpid(), "start": _now(), "command": self.command}
        for _ in range(2):
            try:
                fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY | getattr(os, "O_NOFOLLOW", 0), 0o644)
            except FileExistsError:
                st = os.lstat(path)
                if stat.S_ISLNK(st.st_mode) or not stat.S_ISREG(st.st_mode) or st.st_size > RECORD_MAX:
                    return f"{path} is not a lock fepen wrote (a link or another file): move it away"
                try:
                    other = json.loads(path.read_text())
                except (OSError, ValueError):
                    other = {}
                other = other if isinstance(other, dict) else {}
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
            if not path.is_symlink() and json.loads(path.read_text()).get("pid") == os.getpid():
                path.unlink()
        except (OSError, ValueError, AttributeError):
            pass

    def _clear(self, names: set[str], kind: str) -> set[str]:
        """Remove exactly ``names`` (the earlier command's manifest, all of them names its ``kind`` writes; links
        among them were refused before), each by its kind's layout (fepen.io.layout). Returns the names still
        there: folders that keep a user's file, fepen's still."""
        return layout.remove_owned(self.out, names, kind)

    def _write_record(self) -> None:
        path = self.out / "run.json"
        earlier = {}
        if self.mode in ("resume", "continue") and path.is_file():
            earlier, _ = read_record(self.out)
            earlier = earlier if earlier and earlier.get("kind", "run") == self.kind else {}
            if self.mode == "continue" and earlier.get("digest") != self.digest:  # it had no results: a new study
                earlier = {}
        this = {"command": self.command, "cwd": os.getcwd(), "ranks": self.comm.size, "fepen": __version__,
                "revision": revision(), "host": socket.gethostname(), "pid": os.getpid(), "start": _now(),
                "end": None, "outcome": "running", "exit_code": None}
        if earlier:
            self.record = dict(earlier)
            self.record.setdefault("resumes", []).append(this)
        else:
            self.record = {"kind": self.kind, **this, **({"inputs": self.inputs} if self.inputs else {}),
                           **({"digest": self.digest} if self.digest else {})}
        self._save()

    def _save(self) -> None:
        self.record["files"] = sorted(self.claim.owned)
        with replacing(self.out / "run.json") as tmp:
            tmp.write_text(json.dumps(self.record, indent=1) + "\n")

    def _close(self, outcome: str, code: int, message: str | None) -> None:
        last = self.record["resumes"][-1] if self.record.get("resumes") else self.record
        from fepen.io.files import versions

        try:
            last.update(end=_now(), outcome=outcome, exit_code=code, **({"message": message} if message else {}))
            refused = self.mode == "resume" and outcome == "bad-input"  # a refused resume leaves the run as it was
            if "resumes" in self.record and not refused:  # the first invocation's record stays; the run's beside it
                self.record.update(final_outcome=outcome, final_exit_code=code)
            _remove_reserve(self.out)
            self.claim.owned.discard(RESERVE)
            try:
                last["versions"] = versions()  # at the end: dolfinx and PETSc are named when the run imported them
            except (OSError, MemoryError, ImportError):  # out of memory: the record without them
                pass
            try:
                self._save()
            except (OSError, MemoryError):  # a full disk, or no memory left: run.json keeps "running"
                pass
            _append(self.out / "fepen.log", [f"# {last['end']} {outcome} (exit {code})"])
        finally:
            self._unlock()  # the lock goes all the same


def _study_changed(before, now) -> str:
    """What differs between a study's recorded inputs (fepen.studies.study.inputs_of) and a continuation's, in one
    phrase."""
    if not isinstance(before, dict) or not isinstance(now, dict):
        return "recorded by an earlier fepen, without its inputs"
    parts = []
    if before.get("fepen") != now.get("fepen"):
        parts.append(f"fepen {before.get('fepen')} -> {now.get('fepen')}")
    if before.get("study") != now.get("study"):
        parts.append("its shots or their scene")
    for what, label in (("data", "fepen/data/"), ("files", "")):
        old, new = before.get(what) or {}, now.get(what) or {}
        if not isinstance(old, dict) or not isinstance(new, dict):
            continue
        changed = sorted(k for k in set(old) | set(new) if old.get(k) != new.get(k))
        parts += [f"{label}{k} {'changed' if k in old and k in new else 'added' if k in new else 'gone'}"
                  for k in changed[:3]]
    return "; ".join(parts) or "its inputs' digest differs"


def study_directory(out, comm, fresh: bool, kind: str, names, digest: str | None = None,
                    inputs: dict | None = None) -> RunDirectory:
    """The claim of a study on its results directory (a RunDirectory of its ``kind``): ``fresh`` removes what
    the study's manifest lists first ("force"), else the study goes on with what the same kind of study wrote
    there ("continue"), unless its ``digest`` differs (another study of that kind: refused); ``names``, the
    top-level names it writes, are refused before it starts where a file fepen did not write holds one. Each
    shot's own folder inside it is a run directory of its own."""
    return RunDirectory(out, comm, "force" if fresh else "continue", kind=kind, names=names, digest=digest,
                        inputs=inputs)


def own_name(out: Path, name: str) -> None:
    """Rank 0: ``name`` in the claimed directory ``out`` is this command's before any other rank makes it. A
    study's groups share OUT: another group's rank may be the first to create OUT/shots (its own claim of OUT
    cannot tell rank 0's), and rank 0's claim, which guards the shots its own group keeps there, would then take
    it for a user's. Nothing is created; a name already there stays whatever it is (a user's is refused as
    before), and so does a name the folder's kind does not declare (its shots keep no folders there)."""
    c = atomic.claim_of(out / name)
    if c is not None and c.dir == Path(os.path.abspath(out)) and not os.path.lexists(out / name) and (
            c.declared is None or c.declared(name)):
        c.own(name)
