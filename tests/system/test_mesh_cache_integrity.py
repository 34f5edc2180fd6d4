"""Mesh-cache entries carry the SHA-256 of their .msh and the versions that wrote them: a damaged, truncated or
foreign entry is rebuilt with one warning line, never used and never a crash (issue 18, item 7)."""

import hashlib
import json
import logging
import shutil

import numpy as np
import pytest
from mpi4py import MPI

from fepen import scene
from fepen.geometry import mesh_cache
from fepen.runs import setup

SETS = ["mesh.size=0.008", "mesh.optimize=none"]  # a coarse mesh with its cavity sized to the mass: < 1 s


def entry(folder):
    """The one cache entry in a folder: (.msh path, sidecar path)."""
    (msh,) = folder.glob("*.msh")
    return msh, msh.with_suffix(".json")


def build(folder, monkeypatch):
    monkeypatch.setenv("FEPEN_MESH_CACHE", str(folder))
    return setup.mesh(scene.load(None, SETS), MPI.COMM_SELF)


@pytest.fixture(scope="module")
def pristine(tmp_path_factory):
    """A good entry, built once: (folder, node coordinates of the fresh mesh)."""
    folder = tmp_path_factory.mktemp("pristine")
    with pytest.MonkeyPatch.context() as mp:
        pm = build(folder, mp)
    assert not pm.cached
    return folder, pm.mesh.geometry.x.copy()


@pytest.fixture
def cache(tmp_path, pristine):
    """A copy of the good entry in a folder of this test's own."""
    for f in pristine[0].iterdir():
        shutil.copy(f, tmp_path / f.name)
    return tmp_path


class Records(logging.Handler):
    def __init__(self):
        super().__init__(logging.WARNING)
        self.records = []

    def emit(self, record):
        self.records.append(record)


@pytest.fixture
def warnings():
    """The warnings of the "fepen" logger (a handler of its own: another test may have changed propagation)."""
    logger, handler = logging.getLogger("fepen"), Records()
    level = logger.level
    logger.setLevel(logging.WARNING)
    logger.addHandler(handler)
    yield handler
    logger.removeHandler(handler)
    logger.setLevel(level)


def test_a_good_entry_is_reused(cache, pristine, monkeypatch, warnings):
    msh, side = entry(cache)
    meta = json.loads(side.read_text())
    assert meta["sha256"] == hashlib.sha256(msh.read_bytes()).hexdigest()
    assert {k: meta[k] for k in ("fepen", "gmsh", "code")} == mesh_cache.entry_stamp()
    pm = build(cache, monkeypatch)
    assert pm.cached
    assert np.array_equal(pm.mesh.geometry.x, pristine[1])
    assert not warnings.records


def truncate(msh, side):
    data = msh.read_bytes()
    msh.write_bytes(data[: len(data) // 2])


def flip_byte(msh, side):
    data = bytearray(msh.read_bytes())
    data[len(data) // 2] ^= 0x01
    msh.write_bytes(bytes(data))


def foreign_version(msh, side):
    meta = json.loads(side.read_text())
    side.write_text(json.dumps({**meta, "fepen": "0.0.0-foreign"}))


def not_json(msh, side):
    side.write_text('{"shape": {"length": 0.2')


def old_entry(msh, side):
    """An entry written before the checks: a sidecar with the shape and meshing time only."""
    meta = json.loads(side.read_text())
    side.write_text(json.dumps({"shape": meta["shape"], "mesh_s": meta["mesh_s"]}))


def unreadable(msh, side):
    """A .msh gmsh cannot read, though its checksum matches: the read fails in gmsh itself."""
    msh.write_bytes(b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\nnot a number\n")
    meta = json.loads(side.read_text())
    side.write_text(json.dumps({**meta, "sha256": hashlib.sha256(msh.read_bytes()).hexdigest()}))


def _move_nodes(msh, side, move):
    """Move the nodes of an ASCII MSH 4.1 file with ``move`` ((n, 3) -> (n, 3)) and recompute the sidecar's
    checksum: a forged entry that passes every check of the file itself."""
    lines = msh.read_text().splitlines()
    i = lines.index("$Nodes") + 1
    blocks = int(lines[i].split()[0])
    i += 1
    for _ in range(blocks):
        parametric, count = int(lines[i].split()[2]), int(lines[i].split()[3])
        first = i + 1 + count
        for k in range(first, first + count):
            xyz = np.array([float(v) for v in lines[k].split()[:3]])
            rest = lines[k].split()[3:]
            lines[k] = " ".join(repr(float(v)) for v in move(xyz[None, :])[0]) + (" " + " ".join(rest) if rest else "")
        i = first + count
        assert parametric in (0, 1)
    msh.write_text("\n".join(lines) + "\n")
    meta = json.loads(side.read_text())
    side.write_text(json.dumps({**meta, "sha256": hashlib.sha256(msh.read_bytes()).hexdigest()}))


def forged_shrunk(msh, side):
    """Every node pulled 20 % toward the axis (a 0.235 kg body for a 0.367 kg scene, as found in issue 43)."""
    _move_nodes(msh, side, lambda x: x * np.array([0.8, 1.0, 0.8]))


def forged_longer(msh, side):
    """The base pushed 0.5 mm back: mass and volume within their tolerances, the extent not."""
    _move_nodes(msh, side, lambda x: np.where(x[:, 1:2] > 0.14, x + np.array([0.0, 0.0005, 0.0]), x))


@pytest.mark.parametrize("damage, why", [
    (truncate, "SHA-256"), (flip_byte, "SHA-256"), (foreign_version, "fepen '0.0.0-foreign'"),
    (not_json, "not JSON"), (old_entry, "lacks sha256"), (unreadable, "cannot be read"),
    (forged_shrunk, "mass"), (forged_longer, "nodes span"),
])
def test_a_bad_entry_is_rebuilt_with_one_warning(cache, pristine, monkeypatch, warnings, damage, why):
    msh, side = entry(cache)
    key = msh.stem
    damage(msh, side)
    pm = build(cache, monkeypatch)
    assert not pm.cached
    # the same mesh as a fresh build
    assert pm.mesh.geometry.index_map().size_global == len(pristine[1])
    assert np.array_equal(pm.mesh.geometry.x, pristine[1])
    # one warning line, naming the entry and why
    lines = [r.getMessage() for r in warnings.records if r.levelno >= logging.WARNING]
    assert len(lines) == 1, lines
    assert lines[0].startswith(f"mesh cache entry {key}: ") and lines[0].endswith("; rebuilding")
    assert why in lines[0] and "\n" not in lines[0]
    # a good entry in its place, read from the cache next time without a warning
    assert entry(cache) == (msh, side)
    assert json.loads(side.read_text())["sha256"] == hashlib.sha256(msh.read_bytes()).hexdigest()
    assert not list(cache.glob("*.tmp*"))
    again = build(cache, monkeypatch)
    assert again.cached and np.array_equal(again.mesh.geometry.x, pristine[1])
    assert len(warnings.records) == 1


def test_a_cache_others_can_write_is_named_once_and_its_entries_still_checked(cache, pristine, monkeypatch, warnings):
    """A cache directory writable by other users: one warning naming it, and a forged entry in it is still
    rebuilt (issue 43: a writable FEPEN_MESH_CACHE once served a forged mesh silently)."""
    import os

    os.chmod(cache, 0o777)
    mesh_cache._warned_shared.clear()
    msh, side = entry(cache)
    forged_shrunk(msh, side)
    pm = build(cache, monkeypatch)
    assert not pm.cached and np.array_equal(pm.mesh.geometry.x, pristine[1])
    lines = [r.getMessage() for r in warnings.records]
    assert any("can be written by other users" in ln for ln in lines) and any("mass" in ln for ln in lines)
    build(cache, monkeypatch)
    assert sum("can be written by other users" in r.getMessage() for r in warnings.records) == 1
