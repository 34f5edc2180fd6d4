"""Files that are never half-written, and never written over a file that is not fepen's.

Every file fepen writes goes through ``replacing``: the content goes to a new temporary file beside the target
(created exclusively, so that no planted name or link can redirect it), which is renamed over the target when
complete (an atomic rename on POSIX) and removed when the writing fails.

A directory fepen writes into on a run's behalf (a run's or a study's results directory, fepen.io.rundir) is
*claimed*: the claim knows which of its top-level names are fepen's (the manifest of the runs that wrote there,
and whatever this one writes). Inside a claimed directory a write

- over an existing name that is not fepen's (a user's file, whatever its name and extension) is refused
  (ForeignFile, naming the file), and so is any write through a symbolic link: fepen never makes a link, so a
  link is never fepen's, and a write never follows one out of the directory;
- of a new name adds it to the claim, and the claim's owner (the run directory on rank 0) records it in the
  manifest at once, so that ``--force`` later removes exactly what fepen wrote.
"""

from __future__ import annotations

import os
import stat
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from fepen.errors import InputError


class ForeignFile(InputError):
    """A write that would replace a file fepen did not write, or go through a link: refused (exit 2)."""

    def __init__(self, path, why: str = "a file fepen did not write"):
        self.path = str(path)
        super().__init__("--out", f"{path} is {why}; fepen never overwrites, deletes or writes through such a "
                                  "file: move it away or name another --out")

    def __reduce__(self):
        return (type(self), (self.path,))


class UndeclaredName(RuntimeError):
    """A write of a name the folder's kind of record does not declare (fepen.io.layout): a bug in fepen, refused
    before anything is written, so that every name a record lists is one its kind can write."""


class Claim:
    """A directory fepen writes into, and its top-level names that are fepen's.

    Args:
        directory: the directory (made absolute; not resolved: a link the user named as the directory itself is
            the user's choice).
        owned: the names already fepen's (a previous run's manifest).
        on_new: called with each name fepen adds (rank 0: the manifest in run.json), or None.
        strict: refuse a write over a top-level name not owned (rank 0, which makes every top-level name of a
            run); False: refuse only links (the other ranks, which write inside directories rank 0 made and
            would not know their names).
        declared: name -> whether the directory's kind of record writes it (fepen.io.layout), or None: a new
            top-level name it does not declare is a bug in fepen (UndeclaredName), never written.
    """

    def __init__(self, directory, owned=(), on_new: Callable[[str], None] | None = None, strict: bool = True,
                 declared: Callable[[str], bool] | None = None):
        self.dir = Path(os.path.abspath(directory))
        self.owned: set[str] = set(owned)
        self.added: list[str] = []
        self.on_new = on_new
        self.strict = strict
        self.declared = declared

    def check(self, path: Path) -> None:
        """Refuse (ForeignFile) a write of ``path`` (inside this directory) over a foreign file or through a
        link; record a new top-level name as fepen's."""
        rel = path.relative_to(self.dir)
        if not rel.parts:
            return
        top = rel.parts[0]
        cur = self.dir
        for i, part in enumerate(rel.parts):
            cur = cur / part
            try:
                mode = os.lstat(cur).st_mode
            except FileNotFoundError:
                break
            if stat.S_ISLNK(mode):
                raise ForeignFile(cur, "a symbolic link")
            if i == 0 and self.strict and top not in self.owned:
                raise ForeignFile(cur)
        self.own(top)

    def own(self, name: str) -> None:
        """``name`` (a top-level entry) is fepen's from now on (in the manifest before it is made)."""
        if name not in self.owned:
            if self.declared is not None and not self.declared(name):
                raise UndeclaredName(f"fepen would write {name!r} into {self.dir}, which the layout of what it "
                                     "writes there does not declare (fepen.io.layout)")
            self.owned.add(name)
            self.added.append(name)
            if self.on_new is not None:
                self.on_new(name)


_claims: list[Claim] = []


def claim(directory, owned=(), on_new: Callable[[str], None] | None = None, strict: bool = True,
          declared: Callable[[str], bool] | None = None) -> Claim:
    """Claim a directory for this process's writes (Claim); ``release`` ends it."""
    c = Claim(directory, owned, on_new, strict, declared)
    _claims.append(c)
    return c


def release(c: Claim) -> None:
    """End a claim."""
    if c in _claims:
        _claims.remove(c)


def claim_of(path) -> Claim | None:
    """The innermost claim holding ``path``, or None."""
    p = Path(os.path.abspath(path))
    best = None
    for c in _claims:
        if p == c.dir or c.dir in p.parents:
            if best is None or len(c.dir.parts) > len(best.dir.parts):
                best = c
    return best


def guard(path) -> Path:
    """Check a write of ``path`` against the claim holding it (ForeignFile when refused; nothing outside a
    claim). Returns the path made absolute."""
    p = Path(os.path.abspath(path))
    c = claim_of(p)
    if c is not None and p != c.dir:
        c.check(p)
    return p


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


#: the permission bits of a new file (what open() would give it): mkstemp's are 0600
_MODE = 0o666 & ~_umask()


@contextmanager
def replacing(path, suffix: str = "") -> Iterator[Path]:
    """A temporary path to write ``path`` through.

    Args:
        path: the file to (re)place; in a claimed directory it must be fepen's or new (guard).
        suffix: an ending the writer needs to see (".npz" for numpy, ".msh" for gmsh, ".png").

    Yields:
        The temporary path, a new file made for this write alone; renamed over ``path`` when the block ends
        normally, removed when it raises.

    Raises:
        ForeignFile: ``path`` is a file fepen did not write, or a link, in a claimed directory.
    """
    path = guard(path)
    fd, name = tempfile.mkstemp(prefix=f"{path.name}.tmp{os.getpid()}-", suffix=suffix, dir=path.parent)
    os.close(fd)
    tmp = Path(name)
    try:
        os.chmod(tmp, _MODE)
        yield tmp
        _kill_point(tmp)
        os.replace(tmp, path)
    finally:
        if os.path.lexists(tmp):
            tmp.unlink()


#: the environment variable that kills this process (SIGKILL) at its K-th write, the temporary complete and not
#: yet renamed ("K"), or lists every write's temporary in a file ("trace:FILE", one path a line), for the tests of
#: what a kill leaves (tests/system/test_study_safety.py); nothing happens without it
KILL = "FEPEN_INJECT_KILL"
_temporaries = [0]


def _kill_point(tmp: Path) -> None:
    spec = os.environ.get(KILL)
    if not spec:
        return
    _temporaries[0] += 1
    if spec.startswith("trace:"):
        with open(spec[6:], "a") as f:
            f.write(f"{tmp}\n")
    elif spec.isdigit() and _temporaries[0] == int(spec):
        import signal

        os.kill(os.getpid(), signal.SIGKILL)


def make_dir(path) -> Path:
    """Create the directory ``path`` (its parents too) unless it is there; in a claimed directory it must be
    fepen's or new, and not a link (guard)."""
    p = guard(path)
    p.mkdir(parents=True, exist_ok=True)
    if p.is_symlink() or not p.is_dir():
        raise ForeignFile(p, "not a directory fepen made")
    return p


def open_append(path):
    """``path`` opened to append text, never through a link (O_NOFOLLOW); guarded as ``replacing`` is."""
    p = guard(path)
    fd = os.open(p, os.O_WRONLY | os.O_APPEND | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0), _MODE)
    return os.fdopen(fd, "a")


def create_new(path, mode: str = "wb"):
    """``path`` created anew (O_EXCL: an existing name or link there is refused with FileExistsError); guarded
    as ``replacing`` is."""
    p = guard(path)
    fd = os.open(p, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), _MODE)
    return os.fdopen(fd, mode)


def sha256_file(path) -> str:
    """The SHA-256 of a file's bytes (hex), read in blocks: the checksum checkpoints and mesh-cache entries
    carry."""
    import hashlib

    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()
