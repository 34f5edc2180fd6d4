"""What each kind of record may write into the folder it owns, declared once (docs/results.md, "What fepen owns
in DIR"), and the one way fepen removes what it wrote.

A folder fepen writes into on a command's behalf is owned by a *record*: ``run.json`` of a run, a mesh or a study
(fepen.io.rundir), whose manifest (``files``) lists the top-level names that command wrote. What may be below
them is declared here, as a tree of names and patterns per kind:

- a run: RUN_NAMES; inside ``checkpoint/`` the step files and state.json, inside ``fields.d/`` the mesh and the
  output times;
- a mesh: MESH_NAMES;
- a study: its ``names`` (fepen.studies.study.Study.names, declared by ``declare`` when the study is registered);
  inside ``shots/`` the shots' folders ``NNNNN``, inside ``rounds/`` the rounds' folders ``NNN`` or ``ranks-K``
  (each with its ``shots.jsonl`` and ``shots/``), inside ``runs/`` any folder; every such shot or run folder, and
  every top-level folder of a study (a Table 1 shot, an uncertainty study's sweeps), is a folder with a record of
  its own, removed by that record.

Temporaries: a file is written through ``NAME.tmpPID-XXXXXXXX[.EXT]`` beside it (fepen.atomic.replacing) and
renamed over NAME. A kill between the two leaves the temporary; it is fepen's when NAME is a name its folder's
layout declares, and is swept when the folder is claimed again (a re-run, ``--resume``, ``--fresh``) and when it
is removed.

``remove_owned`` removes exactly the names a record lists and its kind can write, and below them only what the
layout declares: a user's file anywhere inside stays, and so do the folders holding it. Links are never
followed, and never removed below the top level (fepen never makes one).
"""

from __future__ import annotations

import json
import os
import re
import stat
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["Folder", "LEAF", "RECORD", "RUN", "MESH", "RECORD_NAMES", "RUN_NAMES", "MESH_NAMES", "LOCK", "RESERVE",
           "RECORD_MAX", "TEMPORARY", "declare", "layout_of", "temporary_of", "undeclared", "remove_owned",
           "remove_entry", "sweep_temporaries", "read_record", "manifest"]

LOCK = ".fepen.lock"
#: space held back while a run goes on, given back to write the record of a stop on a full disk
RESERVE = ".fepen.reserve"
#: the names of a command's record: a directory whose manifest holds nothing else holds no results
RECORD_NAMES = frozenset({"run.json", "fepen.log", RESERVE})
#: every top-level name a fepen run may write into its directory
RUN_NAMES = frozenset({
    "summary.json", "run.json", "fepen.log", "scene.toml", RESERVE, "history.csv", "history.png", "probes.csv",
    "fields.xdmf", "fields.h5", "fields.d", "checkpoint", "view.py", "accelerations.csv", "hazard.csv",
    "hazard.png", "strains.csv", "nose_profile.csv", "nose_profile.png", "stress_maps_peak.png",
    "stress_maps_peak.vtu", "stress_maps_end.png", "stress_maps_end.vtu", "trajectory.png", "deformed.png",
    "charge_sections.csv", "charge_histories.png", "stress_maps.png", "stress_maps.vtu", "cross_sections.png",
    "cross_sections.vtu", "interface.png", "attitude.png"})
#: what ``fepen mesh`` writes
MESH_NAMES = frozenset({"run.json", "fepen.log", RESERVE, "mesh.json", "scene.toml", "mesh.xdmf", "mesh.h5",
                        "mesh.vtu", "mesh_facets.xdmf", "mesh_facets.vtu", "mesh.png"})
#: the largest run.json or lock file read back (bytes): a record is small; anything larger is not fepen's
RECORD_MAX = 16 << 20
#: a temporary of fepen.atomic.replacing: the name it replaces, the writer's pid, mkstemp's eight characters
TEMPORARY = re.compile(r"(?P<name>.+)\.tmp(?P<pid>[0-9]+)-[a-z0-9_]{8}(?P<ext>\.[A-Za-z0-9]+)?")


class _Leaf:
    """A name declared as a file, or as a folder with a record of its own (removed by that record)."""

    def __init__(self, name: str, files: bool):
        self.name, self.files = name, files

    def __repr__(self) -> str:
        return self.name


#: a file, or a folder with a record of its own
LEAF = _Leaf("LEAF", True)
#: a folder with a record of its own only (a study's shot): a file of that name is a user's
RECORD = _Leaf("RECORD", False)


@dataclass(frozen=True)
class Folder:
    """The names fepen may write in one folder.

    Attributes:
        names: exact names -> LEAF or a Folder (what is below them).
        patterns: (regular expression matched whole, LEAF or Folder), tried after the exact names.
    """

    names: dict = field(default_factory=dict)
    patterns: tuple = ()

    def node(self, name: str):
        """What ``name`` is in this folder (LEAF or a Folder), or None when fepen never writes it here."""
        if name in self.names:
            return self.names[name]
        for pattern, node in self.patterns:
            if re.fullmatch(pattern, name):
                return node
        return None

    def temporary(self, name: str) -> bool:
        """``name`` is a temporary of a file this folder declares (a write a kill cut short)."""
        m = TEMPORARY.fullmatch(name)
        return m is not None and self.node(m.group("name")) is LEAF  # a file's

    def with_names(self, names) -> Folder:
        """This folder with more exact names (LEAF unless a Folder is given in a dict)."""
        extra = names if isinstance(names, dict) else {n: LEAF for n in names}
        return Folder({**self.names, **extra}, self.patterns)


def _leaves(names) -> dict:
    return {n: LEAF for n in names}


#: a run's folder: its files, its checkpoint's step files and state, its fields' per-time files
RUN = Folder({**_leaves(RUN_NAMES),
              "checkpoint": Folder({"state.json": LEAF}, ((r"step[0-9]{9}-rank[0-9]+\.npz", LEAF),)),
              "fields.d": Folder({"mesh.h5": LEAF}, ((r"[0-9]{6}\.h5", LEAF),))})
MESH = Folder(_leaves(MESH_NAMES))
#: a folder that should hold a record and holds none (a kill before its record was written): fepen's leftovers
#: only (its reserve; a temporary of its record and a stale lock are recognised by name)
_BARE = Folder({RESERVE: LEAF})
#: a study's shots' folders (each a run's, with its record)
SHOTS = Folder({}, ((r"[0-9]{5}", RECORD),))
#: one round of a study: its records and its shots' folders
ROUND = Folder({"shots.jsonl": LEAF, "shots": SHOTS})
#: the folders the study skeleton (fepen.studies.study, fepen.studies.engine) makes in any study's folder
STUDY_FOLDERS = {"shots": SHOTS, "rounds": Folder({}, ((r"[0-9]{3}|ranks-[0-9]+", ROUND),)),
                 "runs": Folder({}, ((r"[^/]+", RECORD),))}

#: each kind of record's folder: "run" and "mesh" here, each study's by ``declare``
_KINDS: dict[str, Folder] = {"run": RUN, "mesh": MESH}
#: a study's names by kind, for a kind not declared yet in this process (set by fepen.studies.study: the study's
#: module is imported on first use)
study_names: Callable[[str], tuple] | None = None


def declare(kind: str, names) -> Folder:
    """A study's folder: its declared top-level ``names`` (and the record's own), the skeleton's folders below
    them. Called when the study is registered (fepen.studies.study.register)."""
    names = set(names) | RECORD_NAMES
    folder = Folder({n: STUDY_FOLDERS.get(n, LEAF) for n in sorted(names)})
    _KINDS[kind] = folder
    return folder


def layout_of(kind) -> Folder | None:
    """The folder of a kind of record ("run", "mesh", a study's name), or None when fepen knows no such kind."""
    if not isinstance(kind, str):
        return None
    if kind not in _KINDS and study_names is not None:
        try:
            declare(kind, study_names(kind))
        except Exception:  # noqa: BLE001 - no study of that name: an unknown kind
            return None
    return _KINDS.get(kind)


def temporary_of(name: str) -> str | None:
    """The name a temporary replaces (``run.json`` of ``run.json.tmp123-abcdefgh``), or None."""
    m = TEMPORARY.fullmatch(name)
    return m.group("name") if m else None


def undeclared(kind, names) -> list[str]:
    """The names a record of ``kind`` lists that its kind never writes (sorted); every name when the kind is
    unknown."""
    folder = layout_of(kind)
    return sorted(n for n in names if folder is None or folder.node(n) is None)


def read_record(out: Path) -> tuple[dict | None, str | None]:
    """The record (run.json) of the last fepen command in ``out``: (record, None); (None, None) when there is
    none; (None, why) when a run.json there is not one fepen wrote (a link, not JSON, not a record, too large)."""
    path = Path(out) / "run.json"
    try:
        st = os.lstat(path)
    except (FileNotFoundError, NotADirectoryError):
        return None, None
    if stat.S_ISLNK(st.st_mode) or not stat.S_ISREG(st.st_mode):
        return None, "a link or not a regular file"
    if st.st_size > RECORD_MAX:
        return None, f"{st.st_size} bytes, not a record fepen wrote"
    try:
        rec = json.loads(path.read_text())
    except (OSError, ValueError, RecursionError):
        return None, "not a record fepen wrote (not JSON)"
    if not isinstance(rec, dict) or not isinstance(rec.get("command"), list) or "fepen" not in rec:
        return None, "not a record fepen wrote"
    return rec, None


def _plain_name(name) -> bool:
    """A manifest entry fepen can have written: one name in the directory, no path."""
    return (isinstance(name, str) and name not in ("", ".", "..", LOCK) and "/" not in name and "\0" not in name
            and "\\" not in name)


def manifest(record: dict) -> set[str] | None:
    """The names a record's commands wrote (its "files"), or None when it keeps no valid manifest (an earlier
    fepen, or a list of anything but plain names)."""
    files = record.get("files")
    if not isinstance(files, list) or not all(_plain_name(f) for f in files):
        return None
    return set(files)


def _lstat(path: Path):
    try:
        return os.lstat(path)
    except (FileNotFoundError, NotADirectoryError):
        return None


def remove_entry(path: Path, node) -> bool:
    """Remove what fepen wrote at ``path``, which its folder's layout declares as ``node`` (LEAF or a Folder): a
    file; a folder with a record of its own, by that record; a declared folder, by its layout; a folder with
    neither, only fepen's own leftovers in it (a lock, a reserve, a temporary of its record). A folder goes when
    nothing is left in it. Links are left alone (fepen never makes one below the top level).

    Returns:
        True when nothing is left at ``path``.
    """
    st = _lstat(path)
    if st is None:
        return True
    if stat.S_ISLNK(st.st_mode) or not stat.S_ISDIR(st.st_mode) and node is RECORD:
        return False
    if not stat.S_ISDIR(st.st_mode):
        path.unlink()
        return True
    rec, _ = read_record(path)
    if rec is not None and isinstance(node, _Leaf):
        _remove_by_record(path, rec)
    else:
        folder = node if isinstance(node, Folder) else _BARE
        for child in sorted(path.iterdir()):
            sub = folder.node(child.name)
            if sub is not None:
                remove_entry(child, sub)
            elif (folder.temporary(child.name) or temporary_of(child.name) in RECORD_NAMES
                  or child.name == LOCK and _stale_lock(child)):
                _unlink_file(child)
    try:
        path.rmdir()
        return True
    except OSError:  # a user's file inside: the folder stays
        return False


def _remove_by_record(path: Path, rec: dict) -> None:
    """A folder with a record of its own (a study's shot, a sub-study): exactly what its manifest lists and its
    kind can write, its temporaries, then its lock. A record that lists what its kind never writes is left
    whole (nothing it lists is trusted)."""
    names = manifest(rec)
    folder = layout_of(rec.get("kind", "run"))
    if names is None or folder is None or undeclared(rec.get("kind", "run"), names):
        return
    for name in sorted(names - {"run.json"}):
        remove_entry(path / name, folder.node(name))
    for child in sorted(path.iterdir()):
        if folder.temporary(child.name):
            _unlink_file(child)
    remove_entry(path / "run.json", LEAF)  # the record last: a kill before this leaves it to say what is left
    if _stale_lock(path / LOCK):
        _unlink_file(path / LOCK)


def _unlink_file(path: Path) -> None:
    st = _lstat(path)
    if st is not None and not stat.S_ISDIR(st.st_mode):
        path.unlink()


def _stale_lock(path: Path) -> bool:
    """A lock no running fepen holds (its process gone, on this host): safe to remove."""
    import socket

    st = _lstat(path)
    if st is None or not stat.S_ISREG(st.st_mode) or st.st_size > RECORD_MAX:
        return False
    try:
        other = json.loads(path.read_text())
    except (OSError, ValueError, RecursionError):
        return True  # cut short by a kill as it was written
    if not isinstance(other, dict):
        return True
    pid = other.get("pid")
    if other.get("host") != socket.gethostname() or not isinstance(pid, int):
        return False
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except (PermissionError, OverflowError):
        return False
    return False


def remove_owned(out: Path, names, kind) -> set[str]:
    """Remove the names a record of ``kind`` lists in ``out`` (its manifest), each by the layout; the caller
    refused a manifest with names its kind never writes (``undeclared``).

    Returns:
        The names still there: folders that keep a user's file (still fepen's).
    """
    folder = layout_of(kind) or Folder()
    kept = set()
    for name in sorted(names):
        if not remove_entry(Path(out) / name, folder.node(name) or LEAF):
            if os.path.isdir(Path(out) / name) and not os.path.islink(Path(out) / name):
                kept.add(name)
    return kept


def sweep_temporaries(out: Path, kind, owned=()) -> list[str]:
    """Remove the temporaries a killed command left in ``out`` and in the folders below it that its layout
    declares (the claim's lock held: no writer of this folder is alive). Returns their paths, relative."""
    folder = layout_of(kind)
    if folder is None:
        return []
    gone: list[str] = []
    _sweep(Path(out), folder, "", gone)
    return gone


def _sweep(path: Path, folder: Folder, prefix: str, gone: list) -> None:
    try:
        children = sorted(os.scandir(path), key=lambda e: e.name)
    except OSError:
        return
    for entry in children:
        name = entry.name
        if entry.is_symlink():
            continue
        if folder.temporary(name) and not entry.is_dir(follow_symlinks=False):
            try:
                os.unlink(entry.path)
                gone.append(prefix + name)
            except OSError:
                pass
            continue
        node = folder.node(name)
        if node is None or not entry.is_dir(follow_symlinks=False):
            continue
        if isinstance(node, Folder):
            _sweep(Path(entry.path), node, f"{prefix}{name}/", gone)
        else:
            rec, _ = read_record(Path(entry.path))
            sub = layout_of(rec.get("kind", "run")) if rec is not None else None
            if sub is not None:
                _sweep(Path(entry.path), sub, f"{prefix}{name}/", gone)
