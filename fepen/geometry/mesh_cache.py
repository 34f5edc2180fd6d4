"""The mesh cache (meshes/README.md): an entry per body, options, charge and mass, keyed by their record and
the hash of the code that shapes meshes; each entry a .msh and its sidecar, written whole, and read only after
its checksum, versions, tags, mass, volume and extent match the shot's (a damaged or forged entry is deleted
and meshed afresh).
"""

from __future__ import annotations

import functools
import hashlib
import json
import logging
import os
from dataclasses import asdict, fields
from pathlib import Path

import numpy as np

from fepen.atomic import replacing, sha256_file
from fepen.geometry import gmsh_model, mass_rule, tags
from fepen.geometry.cad import CadBody
from fepen.geometry.shape import Shape
from fepen.version import __version__

__all__ = ["cache_dir", "code_hash", "record", "from_record", "key", "entry_stamp", "read_entry", "write_entry",
           "warn_if_shared", "VOLUME_TOLERANCE"]


def cache_dir() -> Path:
    """Where meshes are cached (meshes/README.md).

    Returns:
        $FEPEN_MESH_CACHE when it is set; else, when fepen runs from a source checkout (the README's editable
        install: fepen/ beside pyproject.toml and meshes/), that checkout's meshes/cache if meshes/ can be
        written; else ~/.cache/fepen/meshes (an installed fepen).
    """
    env = os.environ.get("FEPEN_MESH_CACHE")
    if env:
        return Path(env)
    project = Path(__file__).resolve().parents[2]  # fepen/geometry/mesh_cache.py -> the checkout's root
    here = project / "meshes"
    if (project / "pyproject.toml").is_file() and here.is_dir() and os.access(here, os.W_OK):
        return here / "cache"
    return Path.home() / ".cache" / "fepen" / "meshes"


def code_hash() -> str:
    """Hash of the source that shapes meshes: a change to it rebuilds cached meshes. The modules whose code
    decides the .msh a key stands for: gmsh_model (the model, the options, the seeds), shape and profile (the
    exact outline gmsh revolves: a changed arc or point of profile.py changes the mesh of the same shape record),
    tetra (the shortest altitude that picks the best seed), cad (a STEP body's import and its tracked ends),
    checks (run on every cavity length the mass sizing tries), and of mass_rule the mesh's sizing itself
    (mesh_to_mass, mesh_mass and MASS_TOLERANCE: the cavity length the entry is cut to); the rest of mass_rule
    is not needed: it only chooses the shape passed in, and that shape's whole record is in the key (key).

    Returns:
        12 hexadecimal digits."""
    import inspect

    from fepen.geometry import cad, checks, profile, tetra
    from fepen.geometry import shape as _shape

    h = hashlib.sha256()
    for mod in (gmsh_model, _shape, profile, tetra, cad, checks):
        h.update(Path(mod.__file__).read_bytes())
    for fn in (mass_rule.mesh_to_mass, mass_rule.mesh_mass):
        h.update(inspect.getsource(fn).encode())
    h.update(repr(mass_rule.MASS_TOLERANCE).encode())
    return h.hexdigest()[:12]


#: the fields of CAD bodies when one Shape type held them too (nose "cad"), at a parametric shape's values:
#: every cache key and sidecar still holds them (record), so that a body keeps its key but for the code hash
_CAD_FIELDS = {"cad_file": "", "cad_scale": 1.0, "cad_digest": "", "tip_point": (), "tail_point": ()}


@functools.singledispatch
def record(body) -> dict:
    """The body as the mesh-cache key and sidecar hold it, in the layout of the one Shape type that held
    CAD bodies too, by the body's kind.

    Args:
        body: a Shape or a CadBody.

    Returns:
        A Shape's fields and _CAD_FIELDS; for a CadBody, nose "cad", its calibre, length and CAD fields and
        every other Shape field at its default.
    """
    raise TypeError(f"no mesh-cache record for a {type(body).__name__}")


@record.register(Shape)
def _shape_record(body) -> dict:
    """A Shape's fields and _CAD_FIELDS at a parametric shape's values."""
    return {**asdict(body), **_CAD_FIELDS}


@record.register(CadBody)
def _cad_record(body) -> dict:
    """Nose "cad", the CAD body's calibre, length and CAD fields, every other Shape field at its default."""
    rec = {f.name: f.default for f in fields(Shape)}
    rec.update(diameter=body.diameter, length=body.length, nose="cad", cad_file=body.file,
               cad_scale=body.scale, cad_digest=body.digest, tip_point=body.tip_point,
               tail_point=body.tail_point)
    return rec


def from_record(rec: dict) -> Shape | CadBody:
    """The body of a sidecar's record (record).

    Args:
        rec: the record, as read from JSON.

    Returns:
        A CadBody when its nose is "cad", else a Shape.
    """
    if rec.get("nose") == "cad":
        return CadBody(rec["diameter"], rec["length"], rec["cad_file"], rec["cad_scale"], rec["cad_digest"],
                       rec["tip_point"], rec["tail_point"])
    return Shape(**{k: v for k, v in rec.items() if k not in _CAD_FIELDS})


def key(shape: Shape | CadBody, opts: gmsh_model.MeshOptions, charge: bool, mass, rho_s, rho_c) -> str:
    import gmsh

    blob = json.dumps([record(shape), asdict(opts), charge, mass, rho_s, rho_c, gmsh.__version__,
                       code_hash()], sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:20]


class _BadEntry(Exception):
    """A mesh-cache entry that must not be used (the message says why)."""


def entry_stamp() -> dict:
    """What a cache entry records of the code that wrote it, and must match to be read."""
    import gmsh

    return {"fepen": __version__, "gmsh": gmsh.__version__, "code": code_hash()}


def _check_entry(msh: Path, side: Path) -> Shape | CadBody:
    """The shape a cache entry holds after checking its sidecar, versions and checksum; raises _BadEntry."""
    try:
        meta = json.loads(side.read_text())
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise _BadEntry(f"sidecar {side.name} is not JSON ({e})") from None
    if not isinstance(meta, dict):
        raise _BadEntry(f"sidecar {side.name} is not a JSON object")
    missing = [k for k in ("shape", "sha256", "fepen", "gmsh", "code") if k not in meta]
    if missing:
        raise _BadEntry(f"sidecar {side.name} lacks {', '.join(missing)} (an older or foreign entry)")
    for name, ours in entry_stamp().items():
        if meta[name] != ours:
            raise _BadEntry(f"written by {name} {meta[name]!r}, this is {ours!r}")
    if not msh.is_file():
        raise _BadEntry(f"{msh.name} is missing")
    if sha256_file(msh) != meta["sha256"]:
        raise _BadEntry(f"{msh.name} does not match its SHA-256 (damaged or truncated)")
    return from_record(meta["shape"])


#: how far a cached mesh's volume may lie from its exact body's (the faceting of a coarse mesh: -0.35 % at
#: 2.5 mm on the default body, a few per cent at the coarsest size)
VOLUME_TOLERANCE = 0.1


def _verify_model(shape: Shape | CadBody, charge: bool, mass, rho_s, rho_c) -> None:
    """Rank 0: the mesh in gmsh against what the shot asks for (_BadEntry when it disagrees): its tags (a shell,
    a charge when asked, the outer surface), its mass (within 1 % of the one asked for: the sizing stops after five
    tries, within MASS_TOLERANCE or not), and for an
    exact body its volume (within VOLUME_TOLERANCE) and extent (the nodes within the calibre, from the tip at
    y = 0 to the base at y = length, to 1e-6 of the length): an entry forged or damaged with a valid checksum is
    not used."""
    import gmsh

    groups = set(gmsh.model.getPhysicalGroups())
    need = {(3, tags.SHELL), (2, tags.OUTER)} | ({(3, tags.CHARGE)} if charge else set())
    if need - groups:
        raise _BadEntry(f"it lacks the tags {sorted(t for _, t in need - groups)}")
    if charge != ((3, tags.CHARGE) in groups):
        raise _BadEntry("its charge does not match the shot's")
    if mass is not None and shape.has_cavity:
        got = mass_rule.mesh_mass(rho_s, rho_c)
        if abs(got - mass) > max(mass_rule.MASS_TOLERANCE, 0.01 * mass):  # the sizing may stop short of its tolerance
            raise _BadEntry(f"its mass is {got:.6g} kg, the shot's {mass:.6g} kg")
    _verify_extent(shape, charge)


@functools.singledispatch
def _verify_extent(shape, charge: bool) -> None:
    """Rank 0: the mesh in gmsh against the body's exact volume and extent (_BadEntry when it disagrees), by the
    body's kind.

    Args:
        shape: a Shape or a CadBody. charge: the charge is meshed.
    """
    raise TypeError(f"no extent to verify for a {type(shape).__name__}")


@_verify_extent.register(CadBody)
def _cad_extent(shape, charge: bool) -> None:
    """A CAD body: no exact volume; its extent is the file's (nothing to check)."""


@_verify_extent.register(Shape)
def _exact_extent(shape, charge: bool) -> None:
    """The exact body: its volume within VOLUME_TOLERANCE, its nodes within the calibre, from the tip at y = 0
    to the base at y = length (to 1e-6 of the length)."""
    import gmsh

    volume = gmsh_model.tet_volumes(tags.SHELL).sum() + (gmsh_model.tet_volumes(tags.CHARGE).sum() if charge else 0.0)
    exact = shape.exact_volume(charge)
    if abs(volume / exact - 1.0) > VOLUME_TOLERANCE:
        raise _BadEntry(f"its volume is {volume:.6g} m^3, the body's {exact:.6g} m^3")
    x = np.asarray(gmsh.model.mesh.getNodes()[1]).reshape(-1, 3)
    tol = 1e-6 * shape.length
    radius = np.hypot(x[:, 0], x[:, 2])
    if (abs(radius.max() - 0.5 * shape.diameter) > tol or abs(x[:, 1].min()) > tol
            or abs(x[:, 1].max() - shape.length) > tol):
        raise _BadEntry(f"its nodes span radius {radius.max():.6g} m and y {x[:, 1].min():.6g} to "
                        f"{x[:, 1].max():.6g} m, the body's {0.5 * shape.diameter:.6g} m and 0 to {shape.length:.6g} m")


def read_entry(key: str, msh: Path, side: Path, verify: tuple) -> Shape | CadBody | None:
    """Rank 0: open a checked cache entry in gmsh, verify it against the shot (_verify_model, with ``verify``:
    charge, mass and densities) and return its shape; or, for an entry that fails a check or cannot be read,
    log one warning, delete the entry and return None (the caller meshes afresh)."""
    import gmsh

    opened = False
    try:
        shape = _check_entry(msh, side)
        opened = True
        gmsh.open(str(msh))
        if 4 not in gmsh.model.mesh.getElementTypes(3):  # 4: tetrahedra
            raise _BadEntry(f"{msh.name} holds no tetrahedra")
        _verify_model(shape, *verify)
        return shape
    except Exception as e:  # whatever is wrong with an entry, it is rebuilt
        why = str(e) if isinstance(e, _BadEntry) else f"cannot be read ({type(e).__name__}: {e})"
        logging.getLogger("fepen").warning(f"mesh cache entry {key}: {why}; rebuilding")
        if opened:  # a read that failed inside gmsh leaves it locked ("I'm busy"; gmsh.clear() does not
            # help), and the rebuild would mesh nothing: start gmsh afresh (it keeps no state between meshes)
            gmsh.finalize()
            gmsh.initialize(interruptible=False)
            gmsh.option.setNumber("General.Terminal", 0)
        for path in (side, msh):  # the sidecar first: a .msh without one is never read
            try:
                path.unlink(missing_ok=True)
            except OSError:
                pass
        return None


_warned_shared: set[str] = set()


def warn_if_shared(folder: Path) -> None:
    """One warning per process when the cache directory can be written by other users: its entries are used
    only after _verify_model's checks, as every entry is."""
    import stat

    try:
        mode = folder.stat().st_mode
    except OSError:
        return
    if mode & (stat.S_IWGRP | stat.S_IWOTH) and str(folder) not in _warned_shared:
        _warned_shared.add(str(folder))
        logging.getLogger("fepen").warning(f"mesh cache {folder} can be written by other users: each entry is used "
                                           "only after its mass, volume, extent and tags match the shot's")


def write_entry(msh: Path, side: Path, shape: Shape | CadBody, seconds: float) -> None:
    """Rank 0: write the model in gmsh as a cache entry, the .msh first and its sidecar (shape, SHA-256 of the
    .msh, the versions that wrote it) last, each replaced whole: a sidecar only exists for a complete .msh."""
    import gmsh

    msh.parent.mkdir(parents=True, exist_ok=True)
    side.unlink(missing_ok=True)  # no sidecar of an older entry beside the new .msh, even for a moment
    with replacing(msh, ".msh") as tmp:
        gmsh.write(str(tmp))
        digest = sha256_file(tmp)
    meta = {"shape": record(shape), "mesh_s": seconds, "sha256": digest, **entry_stamp()}
    with replacing(side) as tmp:
        tmp.write_text(json.dumps(meta))
