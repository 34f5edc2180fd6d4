"""The projectile mesh in dolfinx: built on rank 0 with gmsh (cached), distributed in deterministic parts
(bands along the projectile, halved across the plane of the shot), its cavity sized to a mass on the mesh, its
wall split for a sliding charge (docs/theory.md §2, §11, §13).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import logging
import math
import os
import threading
import time
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path

import numpy as np
from mpi4py import MPI

from fepen.atomic import replacing, sha256_file
from fepen.geometry import gmsh_model, tags, tetra
from fepen.geometry.cad import CadBody
from fepen.geometry.checks import check
from fepen.geometry.shape import Shape
from fepen.version import __version__

#: mesh-mass tolerance of the cavity sizing (kg)
MASS_TOLERANCE = 2.5e-4

#: whether a mesh built by gmsh shows its progress bar (set by ``progress``: fepen run, fepen mesh)
_PROGRESS = {"on": False}


@contextlib.contextmanager
def progress(on: bool):
    """Within it, a mesh that gmsh builds (not one read from the cache) shows a bar on rank 0's stderr: the
    stage (building, meshing, optimising, and the try when a seed is retried) and the elapsed time. Quiet when
    stderr is not a terminal, unless FEPEN_PROGRESS=1 (a run under mpirun started from one); FEPEN_PROGRESS=0
    keeps it quiet.

    Args:
        on: the switch (the run's progress switch).
    """
    before, _PROGRESS["on"] = _PROGRESS["on"], bool(on)
    try:
        yield
    finally:
        _PROGRESS["on"] = before


@contextlib.contextmanager
def phase(desc: str, rank: int = 0):
    """A phase without steps to count (a deformable run's set-up: ffcx, numba and the C kernels compiled on a
    first run), shown as its name and the elapsed time, on rank 0 within ``progress(True)`` and on a terminal
    (as the mesh's bar).

    Args:
        desc: what is being done ("setup: compiling the kernels"). rank: this process's rank.
    """
    bar = _MeshBar(desc) if _PROGRESS["on"] and rank == 0 else None
    try:
        yield
    finally:
        if bar is not None:
            bar.close()


def bar_disabled() -> bool | None:
    """tqdm's ``disable`` for a bar that is wanted: FEPEN_PROGRESS=1 shows it, 0 hides it, unset: None (shown
    only on a terminal)."""
    env = os.environ.get("FEPEN_PROGRESS")
    return None if env not in ("0", "1") else env == "0"


class _MeshBar:
    """The stages of gmsh and the elapsed time, refreshed every second by a thread (gmsh's calls release the
    interpreter lock). ``desc``: the first stage's words."""

    def __init__(self, desc: str = "mesh: building"):
        import sys

        from tqdm import tqdm

        self.bar = tqdm(desc=desc, bar_format="{desc} [{elapsed}]", file=sys.stderr, leave=False,
                        disable=bar_disabled())
        self.tries, self.done = 0, threading.Event()
        self.thread = threading.Thread(target=self._tick, daemon=True)
        self.thread.start()

    def _tick(self) -> None:
        while not self.done.wait(1.0):
            self.bar.refresh()

    def stage(self, name: str) -> None:
        self.tries += name == "building"
        self.bar.set_description_str(f"mesh: {name}" + (f" (try {self.tries})" if self.tries > 1 else ""))

    def close(self) -> None:
        self.done.set()
        self.thread.join()
        self.bar.close()


def _code_hash() -> str:
    """Hash of the source that shapes meshes: a change to it rebuilds cached meshes. The modules whose code
    decides the .msh a key stands for: gmsh_model (the model, the options, the seeds), shape and profile (the
    exact outline gmsh revolves: a changed arc or point of profile.py changes the mesh of the same shape record),
    tetra (the shortest altitude that picks the best seed), cad (a STEP body's import and its tracked ends),
    checks (run on every cavity length the mass sizing tries), and of this module the mass sizing itself
    (_build_on_root, _gmsh_mass and MASS_TOLERANCE: the cavity length the entry is cut to). mass_rule.py is
    not needed: it only chooses the shape passed in, and that shape's whole record is in the key (_key)."""
    import inspect

    from fepen.geometry import cad, checks, profile, tetra
    from fepen.geometry import shape as _shape

    h = hashlib.sha256()
    for mod in (gmsh_model, _shape, profile, tetra, cad, checks):
        h.update(Path(mod.__file__).read_bytes())
    for fn in (_build_on_root, _gmsh_mass):
        h.update(inspect.getsource(fn).encode())
    h.update(repr(MASS_TOLERANCE).encode())
    return h.hexdigest()[:12]


@dataclass
class ProjectileMesh:
    """A distributed projectile mesh with its tags and the shape it was built from.

    Attributes:
        mesh: the dolfinx mesh (tetrahedra, SI units, body frame of fepen.geometry.shape).
        cell_tags: SHELL / CHARGE cell markers.
        facet_tags: OUTER / CAVITY facet markers (and CHARGE_FACE, the charge's side of a split wall).
        shape: the exact geometry meshed (cavity length as corrected on the mesh), or the CadBody (its
            tracked ends the mesh's nodes).
        charge: whether the cavity is meshed as the charge.
        split: whether the charge has nodes of its own on the cavity wall (frictional contact).
        mesh_s: wall time spent meshing on rank 0 (0 when read from the cache).
        cached: whether the mesh came from the cache.
    """

    mesh: object
    cell_tags: object
    facet_tags: object
    shape: Shape | CadBody
    charge: bool
    mesh_s: float
    cached: bool
    split: bool = False


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
    project = Path(__file__).resolve().parents[2]  # fepen/geometry/mesh.py -> the checkout's root
    here = project / "meshes"
    if (project / "pyproject.toml").is_file() and here.is_dir() and os.access(here, os.W_OK):
        return here / "cache"
    return Path.home() / ".cache" / "fepen" / "meshes"


#: the fields of CAD bodies when one Shape type held them too (nose "cad"), at a parametric shape's values:
#: every cache key and sidecar still holds them (_record), so that a body keeps its key but for the code hash
_CAD_FIELDS = {"cad_file": "", "cad_scale": 1.0, "cad_digest": "", "tip_point": (), "tail_point": ()}


@functools.singledispatch
def _record(body) -> dict:
    """The body as the mesh-cache key and sidecar hold it, in the layout of the one Shape type that held
    CAD bodies too, by the body's kind.

    Args:
        body: a Shape or a CadBody.

    Returns:
        A Shape's fields and _CAD_FIELDS; for a CadBody, nose "cad", its calibre, length and CAD fields and
        every other Shape field at its default.
    """
    raise TypeError(f"no mesh-cache record for a {type(body).__name__}")


@_record.register(Shape)
def _shape_record(body) -> dict:
    """A Shape's fields and _CAD_FIELDS at a parametric shape's values."""
    return {**asdict(body), **_CAD_FIELDS}


@_record.register(CadBody)
def _cad_record(body) -> dict:
    """Nose "cad", the CAD body's calibre, length and CAD fields, every other Shape field at its default."""
    rec = {f.name: f.default for f in fields(Shape)}
    rec.update(diameter=body.diameter, length=body.length, nose="cad", cad_file=body.file,
               cad_scale=body.scale, cad_digest=body.digest, tip_point=body.tip_point,
               tail_point=body.tail_point)
    return rec


def _from_record(rec: dict) -> Shape | CadBody:
    """The body of a sidecar's record (_record).

    Args:
        rec: the record, as read from JSON.

    Returns:
        A CadBody when its nose is "cad", else a Shape.
    """
    if rec.get("nose") == "cad":
        return CadBody(rec["diameter"], rec["length"], rec["cad_file"], rec["cad_scale"], rec["cad_digest"],
                       rec["tip_point"], rec["tail_point"])
    return Shape(**{k: v for k, v in rec.items() if k not in _CAD_FIELDS})


def _key(shape: Shape | CadBody, opts: gmsh_model.MeshOptions, charge: bool, mass, rho_s, rho_c) -> str:
    import gmsh

    blob = json.dumps([_record(shape), asdict(opts), charge, mass, rho_s, rho_c, gmsh.__version__,
                       _code_hash()], sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:20]


class _BadEntry(Exception):
    """A mesh-cache entry that must not be used (the message says why)."""


def _entry_stamp() -> dict:
    """What a cache entry records of the code that wrote it, and must match to be read."""
    import gmsh

    return {"fepen": __version__, "gmsh": gmsh.__version__, "code": _code_hash()}


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
    for name, ours in _entry_stamp().items():
        if meta[name] != ours:
            raise _BadEntry(f"written by {name} {meta[name]!r}, this is {ours!r}")
    if not msh.is_file():
        raise _BadEntry(f"{msh.name} is missing")
    if sha256_file(msh) != meta["sha256"]:
        raise _BadEntry(f"{msh.name} does not match its SHA-256 (damaged or truncated)")
    return _from_record(meta["shape"])


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
        got = _gmsh_mass(rho_s, rho_c)
        if abs(got - mass) > max(MASS_TOLERANCE, 0.01 * mass):  # the sizing may stop short of its tolerance
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


def _read_entry(key: str, msh: Path, side: Path, verify: tuple) -> Shape | CadBody | None:
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


def _warn_if_shared(folder: Path) -> None:
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


def _write_entry(msh: Path, side: Path, shape: Shape | CadBody, seconds: float) -> None:
    """Rank 0: write the model in gmsh as a cache entry, the .msh first and its sidecar (shape, SHA-256 of the
    .msh, the versions that wrote it) last, each replaced whole: a sidecar only exists for a complete .msh."""
    import gmsh

    msh.parent.mkdir(parents=True, exist_ok=True)
    side.unlink(missing_ok=True)  # no sidecar of an older entry beside the new .msh, even for a moment
    with replacing(msh, ".msh") as tmp:
        gmsh.write(str(tmp))
        digest = sha256_file(tmp)
    meta = {"shape": _record(shape), "mesh_s": seconds, "sha256": digest, **_entry_stamp()}
    with replacing(side) as tmp:
        tmp.write_text(json.dumps(meta))


def _gmsh_mass(rho_s: float, rho_c: float | None) -> float:
    m = rho_s * gmsh_model.tet_volumes(tags.SHELL).sum()
    if rho_c is not None:
        m += rho_c * gmsh_model.tet_volumes(tags.CHARGE).sum()
    return m


def _mesh_on_root(shape: Shape | CadBody, opts, charge: bool, mass, rho_s, rho_c, use_cache: bool):
    """Rank 0: leave the meshed model in gmsh. Returns (final shape, meshing seconds, from cache)."""
    import gmsh

    if not gmsh.isInitialized():
        gmsh.initialize(interruptible=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.clear()
    folder = cache_dir()
    key = _key(shape, opts, charge, mass, rho_s, rho_c)
    msh, side = folder / f"{key}.msh", folder / f"{key}.json"
    if use_cache and side.is_file():
        _warn_if_shared(folder)
        cached = _read_entry(key, msh, side, (charge, mass, rho_s, rho_c))
        if cached is not None:
            return cached, 0.0, True

    bar = _MeshBar() if _PROGRESS["on"] else None
    gmsh_model.stage_hook = bar.stage if bar is not None else None
    try:
        return _build_on_root(shape, opts, charge, mass, rho_s, rho_c, use_cache, msh, side, key)
    finally:
        gmsh_model.stage_hook = None
        if bar is not None:
            bar.close()


def _build_on_root(shape, opts, charge: bool, mass, rho_s, rho_c, use_cache: bool, msh: Path, side: Path,
                   key: str):
    """Rank 0, not from the cache: gmsh's mesh, its cavity sized to the mass, cached and read back."""
    import gmsh

    t0 = time.perf_counter()
    current = shape
    for attempt in range(5):  # the cavity sized to the mass on seed 1's meshes; then the seeds for the altitude
        gmsh.clear()
        gmsh_model.build(current, opts, charge, 1)
        if mass is None or not current.has_cavity:
            break
        error = _gmsh_mass(rho_s, rho_c) - mass
        if abs(error) <= MASS_TOLERANCE or attempt == 4:
            break
        r = 0.5 * current.cavity_diameter
        step = error / ((rho_s - (rho_c or 0.0)) * math.pi * r * r)
        current = replace(current, cavity_length=current.cavity_length + step)
        check(current)
    gmsh_model.best_seed(opts)  # the volumes again with other seeds: the surface mesh, hence the mass, kept
    current = current.after_meshing()  # a CAD body's tracked ends: mesh nodes
    seconds = time.perf_counter() - t0
    if use_cache:
        try:
            _write_entry(msh, side, current, seconds)
        except OSError as err:  # a full disk or a read-only cache: the run goes on without caching its mesh
            logging.getLogger("fepen").warning(f"mesh cache entry {key}: not written ({err}); the mesh is used "
                                               "as gmsh made it")
            return current, seconds, False
        # the run goes on with the mesh as the cache holds it: the .msh file keeps 16 significant digits,
        # so a mesh used straight from gmsh would differ in the last bits from the same mesh read back,
        # and a run's numbers would depend on whether its mesh was cached
        gmsh.clear()
        gmsh.open(str(msh))
    return current, seconds, False


def create(shape: Shape | CadBody, opts: gmsh_model.MeshOptions, comm: MPI.Comm = MPI.COMM_WORLD, charge: bool = False,
           mass: float | None = None, shell_density: float = 7850.0, charge_density: float | None = None,
           split: bool = False, use_cache: bool = True) -> ProjectileMesh:
    """Build (or read from the cache) and distribute a projectile mesh.

    Args:
        shape: the checked exact geometry (its cavity length a first guess when ``mass`` is given), or a
            CadBody.
        opts: element sizes and optimiser.
        comm: the communicator to distribute over; gmsh runs on its rank 0.
        charge: mesh the cavity as the charge (volume tag CHARGE).
        mass: total mass to reach on the mesh by correcting the cavity length (kg), or None.
        shell_density, charge_density: densities for that mass (kg/m^3).
        split: give the charge its own nodes on the cavity wall (frictional contact; needs ``charge``).
        use_cache: read/write the mesh cache.

    Returns:
        The ProjectileMesh.
    """
    rho_c = charge_density if charge else None
    result = None
    if comm.rank == 0:
        result = _mesh_on_root(shape, opts, charge, mass, shell_density, rho_c, use_cache)
    shape, seconds, cached = comm.bcast(result, root=0)
    split = bool(split and charge)
    mesh, ct, ft = _model_to_mesh(comm, split)
    if comm.rank == 0:
        import gmsh

        gmsh.clear()
    return ProjectileMesh(mesh, ct, ft, shape, charge, seconds, cached, split)


def split_wall(n_nodes, cells, cell_values, facets, facet_values):
    """Double the nodes of the CAVITY wall: the charge's cells take new copies (numbered after the
    existing nodes) and the copied wall facets are tagged CHARGE_FACE.

    Args:
        n_nodes: number of nodes (gmsh may keep nodes that no cell uses: copies go after all of them).
        cells: (n_cells, 4) node indices; cell_values: SHELL / CHARGE per cell.
        facets: (n_facets, 3) node indices of the tagged facets; facet_values: their tags.

    Returns:
        (cells, facets, facet_values, wall nodes (the originals; their copies are n_nodes + i in that
        order), links: (k, 2) pairs of cells, a shell cell and a charge cell around the same wall node).
    """
    wall = np.unique(facets[facet_values == tags.CAVITY])
    twin = np.arange(n_nodes, dtype=np.int64)
    twin[wall] = n_nodes + np.arange(len(wall))
    cells = cells.copy()
    charge = cell_values == tags.CHARGE
    cells[charge] = twin[cells[charge]]
    new = twin[facets[facet_values == tags.CAVITY]]
    facets = np.vstack([facets, new])
    facet_values = np.concatenate([facet_values, np.full(len(new), tags.CHARGE_FACE, dtype=facet_values.dtype)])
    # cells around each wall node, on either side (the charge's through the copies)
    original = np.concatenate([np.arange(n_nodes), wall])  # node index -> original node
    on_wall = np.zeros(n_nodes, dtype=bool)
    on_wall[wall] = True
    c_idx = np.repeat(np.arange(len(cells)), 4)
    node = original[cells.ravel()]
    keep = on_wall[node]
    c_idx, node, side = c_idx[keep], node[keep], charge[c_idx[keep]]
    links = []
    order = np.argsort(node, kind="stable")
    c_idx, node, side = c_idx[order], node[order], side[order]
    cuts = np.flatnonzero(np.diff(node)) + 1
    for cs, sd in zip(np.split(c_idx, cuts), np.split(side, cuts)):
        sh, ch = np.unique(cs[~sd]), np.unique(cs[sd])
        links.append(np.stack(np.meshgrid(sh, ch, indexing="ij"), axis=-1).reshape(-1, 2))
    links = np.unique(np.concatenate(links), axis=0) if links else np.zeros((0, 2), dtype=np.int64)
    return cells, facets, facet_values, wall, links


def _model_to_mesh(comm, split: bool):
    """dolfinx.io.gmshio.model_to_mesh for tetrahedra, distributed with band_partitioner, the wall split
    when asked (split_wall). Returns (mesh, cell tags, facet tags)."""
    from fepen import dolfinx_api as dx

    gmshio = dx.gmsh_io()
    TET, TRI = 4, 2  # gmsh element types
    links = None  # rank 0, a split wall: extra links between cells for the partitioner
    if comm.rank == 0:
        import gmsh

        model = gmsh.model
        x = gmshio.extract_geometry(model)
        topo = dx.gmsh_topology(model)
        cells = np.asarray(topo[TET]["topology"], dtype=np.int64)
        cell_values = np.asarray(topo[TET]["cell_data"], dtype=np.int32)
        facets = np.asarray(topo[TRI]["topology"], dtype=np.int64)
        facet_values = np.asarray(topo[TRI]["cell_data"], dtype=np.int32)
        # number the nodes the cells use 0..n-1: a model just meshed keeps unused nodes, and dolfinx's
        # distribute_entity_data reads node indices as positions among the used ones (beyond: a crash)
        used = np.unique(cells)
        renumber = np.full(len(x), -1, dtype=np.int64)
        renumber[used] = np.arange(len(used))
        x, cells, facets = x[used], renumber[cells], renumber[facets]
        if split:
            cells, facets, facet_values, wall, links = split_wall(len(x), cells, cell_values, facets, facet_values)
            x = np.vstack([x, x[wall]])
            from scipy.sparse import coo_matrix

            n = len(cells)
            ones = np.ones(2 * len(links))
            links = coo_matrix((ones, (np.concatenate([links[:, 0], links[:, 1]]),
                                              np.concatenate([links[:, 1], links[:, 0]]))), shape=(n, n)).tocsr()
    else:
        x = np.zeros((0, 3))
        cells = np.zeros((0, 4), dtype=np.int64)
        cell_values = np.zeros(0, dtype=np.int32)
        facets = np.zeros((0, 3), dtype=np.int64)
        facet_values = np.zeros(0, dtype=np.int32)
    parts = mirror_parts(x, cells, comm.size) if comm.rank == 0 else None
    cells = cells[:, dx.cell_perm("tetrahedron", 4)]
    partitioner = functools.partial(band_partitioner, extra_links=links, parts=parts)
    mesh = dx.tet_mesh(comm, cells, x, partitioner)
    tdim = 3
    ct = dx.entity_tags(mesh, tdim, cells, cell_values)
    ct.name = "Cell tags"
    facets = facets[:, dx.cell_perm("triangle", 3)]
    mesh.topology.create_connectivity(tdim - 1, tdim)
    ft = dx.entity_tags(mesh, tdim - 1, facets, facet_values)
    ft.name = "Facet tags"
    return mesh, ct, ft


def mirror_parts(x: np.ndarray, cells: np.ndarray, nparts: int) -> np.ndarray:
    """The part of each cell (rank 0, before distribution): bands across the axis (y), each band cut in two
    halves of equal cell count across the plane of the shot (z = 0: the impact's plane, the body turns about z)
    when nparts is even.

    The target's load and the plastic flow gather at the nose, and a band partition left both to the rank
    holding the nose, the other ranks waiting for it at every step (docs/theory.md §3.4). Two halves mirrored
    across the plane of the shot carry mirrored loads: for a shot in that plane the two ranks of a band do the
    same work. The numbers do not depend on the partition (the sums are exact), only the time does.

    Args:
        x: (n_nodes, 3) node coordinates; cells: (n_cells, 4) node indices; nparts: the number of ranks.

    Returns:
        (n_cells,) int32 parts: band b's halves are parts 2b and 2b + 1 (b alone when nparts is odd).
    """
    n = len(cells)
    halves = 2 if nparts % 2 == 0 else 1
    bands = nparts // halves
    c = x[cells].mean(axis=1)
    part = np.zeros(n, dtype=np.int32)
    order = np.argsort(c[:, 1], kind="stable")  # along the axis
    band = np.empty(n, dtype=np.int64)
    band[order] = np.arange(n, dtype=np.int64) * bands // max(n, 1)
    for b in range(bands):
        mine = np.flatnonzero(band == b)
        side = np.empty(len(mine), dtype=np.int64)
        side[np.argsort(c[mine, 2], kind="stable")] = np.arange(len(mine), dtype=np.int64) * halves // max(len(mine), 1)
        part[mine] = (b * halves + side).astype(np.int32)
    return part


def band_partitioner(comm, nparts: int, graph, ghosting: bool, extra_links=None, parts=None):
    """A deterministic partition of the cells' dual graph into nparts bands along the projectile, or the
    parts given (mirror_parts).

    SCOTCH, dolfinx's default, gives a different partition from run to run on the same input, so that
    two runs on the same number of ranks differ in the last bits (and a checkpoint could not be matched
    cell for cell). Here, without parts: cells in breadth-first order from a pseudo-peripheral cell (the end of
    a breadth-first sweep from cell 0: the nose tip or the tail of a slender body), cut into nparts runs of
    equal length; each rank gets a band of the projectile, whose interfaces are cross-sections. With
    ghosting, a cell is also sent to the ranks owning its facet neighbours. A split wall (split_wall) adds
    its links to the graph: the parts cross both bodies, and a cell is also ghosted where its links are.

    Args:
        comm: communicator; graph: this rank's rows of the dual graph (global cell indices);
        nparts: number of parts; ghosting: return ghost destinations too.
        extra_links: rank 0, a split wall's cell links (scipy sparse, n x n), or None.
        parts: rank 0, the part of every cell in the global order (mirror_parts), or None: the bands.

    Returns:
        AdjacencyList_int32: per local row, the owner rank then the ghost ranks.
    """
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import breadth_first_order

    from fepen import dolfinx_api as dx

    offsets = np.asarray(graph.offsets, dtype=np.int64)
    array = np.asarray(graph.array, dtype=np.int64)
    rows = comm.gather((offsets, array), root=0)
    dest = None
    if comm.rank == 0:
        sizes = [len(o) - 1 for o, _ in rows]
        n = sum(sizes)
        indptr = np.concatenate([[0], np.cumsum(np.concatenate([np.diff(o) for o, _ in rows]))])
        indices = np.concatenate([a for _, a in rows]) if n else np.zeros(0, dtype=np.int64)
        part = np.zeros(n, dtype=np.int32)
        if n:
            g = csr_matrix((np.ones(len(indices)), indices, indptr), shape=(n, n))
            if extra_links is not None and extra_links.shape == (n, n):
                g = (g + extra_links).tocsr()
                g.sort_indices()
                indptr, indices = g.indptr.astype(np.int64), g.indices.astype(np.int64)
            if parts is not None and len(parts) == n:
                part[:] = parts
            else:
                start = int(breadth_first_order(g, 0, directed=False, return_predecessors=False)[-1])
                order = breadth_first_order(g, start, directed=False, return_predecessors=False)
                if len(order) < n:  # a disconnected mesh: the rest in index order
                    rest = np.setdiff1d(np.arange(n), order)
                    order = np.concatenate([order, rest])
                part[order] = (np.arange(n, dtype=np.int64) * nparts // n).astype(np.int32)
        dest = []
        lo = 0
        for size in sizes:
            data, offs = [], [0]
            for c in range(lo, lo + size):
                owner = int(part[c])
                ghosts = sorted({int(part[j]) for j in indices[indptr[c]:indptr[c + 1]]} - {owner}) if ghosting else []
                data += [owner, *ghosts]
                offs.append(len(data))
            dest.append((np.array(data, dtype=np.int32), np.array(offs, dtype=np.int32)))
            lo += size
    data, offs = comm.scatter(dest, root=0)
    return dx.adjacency_int32(data, offs)


def cell_points(mesh) -> np.ndarray:
    """Node coordinates of the locally owned cells, shape (n_owned, 4, 3)."""
    n = mesh.topology.index_map(mesh.topology.dim).size_local
    from fepen import dolfinx_api as dx

    dofs = dx.geometry_dofs(mesh)[:n]
    return mesh.geometry.x[dofs]


def owned_cells_tagged(pm: ProjectileMesh, tag: int) -> np.ndarray:
    """Local indices of the owned cells carrying a volume tag."""
    n = pm.mesh.topology.index_map(pm.mesh.topology.dim).size_local
    cells = pm.cell_tags.find(tag)
    return cells[cells < n]


def metrics(pm: ProjectileMesh, density: dict, speed: dict, safety: float, nominal_size: float) -> dict:
    """The figures of mesh.json: sizes, mass, volume, quality, shortest altitude, stable step.

    Args:
        pm: the mesh.
        density, speed: per volume tag (tags.SHELL, tags.CHARGE), the density (kg/m^3) and dilatational
            wave speed (m/s).
        safety: the stable-step safety factor; the stable step is safety x min over cells of (shortest
            altitude / wave speed of the cell's material).
        nominal_size: the nominal element size (m).
    """
    comm = pm.mesh.comm
    p = cell_points(pm.mesh)
    vol = np.abs(tetra.signed_volumes(p))
    alt = tetra.shortest_altitudes(p)
    q = tetra.mean_ratio(p)
    tag = np.full(len(vol), tags.SHELL)
    if pm.charge:
        tag[owned_cells_tagged(pm, tags.CHARGE)] = tags.CHARGE
    rho = np.array([density.get(int(t), 0.0) for t in (tags.SHELL, tags.CHARGE)])[tag - tags.SHELL]
    c = np.array([speed.get(int(t), 1.0) for t in (tags.SHELL, tags.CHARGE)])[tag - tags.SHELL]

    def total(a):
        return comm.allreduce(float(np.sum(a)), op=MPI.SUM)

    def smallest(a):
        return comm.allreduce(float(np.min(a)) if len(a) else math.inf, op=MPI.MIN)

    shell_v = total(vol[tag == tags.SHELL])
    charge_v = total(vol[tag == tags.CHARGE])
    exact_total = pm.shape.exact_volume(pm.charge)  # a CAD body's: None (no exact volume)
    volume = shell_v + charge_v
    h = nominal_size
    shortest = smallest(alt)
    return {
        "cells": pm.mesh.topology.index_map(3).size_global,
        "nodes": pm.mesh.geometry.index_map().size_global,
        "mass_kg": total(vol * rho),
        "volume_m3": volume,
        "shell_volume_m3": shell_v,
        "charge_volume_m3": charge_v,
        "exact_volume_m3": exact_total,
        "volume_error": None if exact_total is None else volume / exact_total - 1.0,
        "min_quality": smallest(q),
        "shortest_altitude_m": shortest,
        "nominal_size_m": h,
        "altitude_over_size": shortest / h,
        "stable_dt_s": safety * smallest(alt / c),
        "cavity_length_m": pm.shape.cavity_length,  # a CAD body's: 0.0 (no cavity sized)
        "mesh_s": pm.mesh_s,
        "from_cache": pm.cached,
        "ranks": comm.size,
    }
