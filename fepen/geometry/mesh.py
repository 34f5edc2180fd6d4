"""The projectile mesh in dolfinx: built on rank 0 with gmsh, its cavity sized to a mass on the mesh
(fepen.geometry.mass_rule.mesh_to_mass), kept in the mesh cache (fepen.geometry.mesh_cache) and distributed
in deterministic parts with the wall split for a sliding charge (fepen.geometry.partition); its metrics
(docs/theory.md §2, §11, §13).
"""

from __future__ import annotations

import contextlib
import logging
import math
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from mpi4py import MPI

from fepen.geometry import gmsh_model, mass_rule, mesh_cache, partition, tags, tetra
from fepen.geometry.cad import CadBody
from fepen.geometry.mass_rule import MASS_TOLERANCE  # noqa: F401 - the mesh's mass tolerance, named here too
from fepen.geometry.mesh_cache import VOLUME_TOLERANCE, cache_dir  # noqa: F401 - named here too
from fepen.geometry.partition import band_partitioner, mirror_parts, split_wall  # noqa: F401 - named here too
from fepen.geometry.shape import Shape

#: whether a mesh built by gmsh shows its progress bar (set by ``progress``: fepen run, fepen mesh)
_PROGRESS = {"on": False}


@contextlib.contextmanager
def progress(on: bool):
    """Within it, a mesh that gmsh builds (not one read from the cache) shows a bar on rank 0's stderr: the
    stage (building, meshing, optimising, and the try when a seed is retried) and the elapsed time, where
    fepen.progress shows a bar (a terminal, mpirun's terminal, a notebook; FEPEN_PROGRESS=1 or 0).

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
    first run), shown as its name and the elapsed time, on rank 0 within ``progress(True)`` and where
    fepen.progress shows a bar (as the mesh's bar).

    Args:
        desc: what is being done ("setup: compiling the kernels"). rank: this process's rank.
    """
    bar = _MeshBar(desc) if _PROGRESS["on"] and rank == 0 else None
    try:
        yield
    finally:
        if bar is not None:
            bar.close()


class _MeshBar:
    """The stages of gmsh and the elapsed time, refreshed every second by a thread (gmsh's calls release the
    interpreter lock). ``desc``: the first stage's words."""

    def __init__(self, desc: str = "mesh: building"):
        from fepen import progress

        self.bar = progress.bar(desc=desc, bar_format="{desc} [{elapsed}]", leave=False)
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


def _mesh_on_root(shape: Shape | CadBody, opts, charge: bool, mass, rho_s, rho_c, use_cache: bool):
    """Rank 0: leave the meshed model in gmsh. Returns (final shape, meshing seconds, from cache)."""
    import gmsh

    if not gmsh.isInitialized():
        gmsh.initialize(interruptible=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.clear()
    folder = mesh_cache.cache_dir()
    key = mesh_cache.key(shape, opts, charge, mass, rho_s, rho_c)
    msh, side = folder / f"{key}.msh", folder / f"{key}.json"
    if use_cache and side.is_file():
        mesh_cache.warn_if_shared(folder)
        cached = mesh_cache.read_entry(key, msh, side, (charge, mass, rho_s, rho_c))
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
    """Rank 0, not from the cache: gmsh's mesh, its cavity sized to the mass (mass_rule.mesh_to_mass), cached
    and read back."""
    import gmsh

    t0 = time.perf_counter()
    current = mass_rule.mesh_to_mass(shape, opts, charge, mass, rho_s, rho_c)
    seconds = time.perf_counter() - t0
    if use_cache:
        try:
            mesh_cache.write_entry(msh, side, current, seconds)
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
    mesh, ct, ft = partition.model_to_mesh(comm, split)
    if comm.rank == 0:
        import gmsh

        gmsh.clear()
    return ProjectileMesh(mesh, ct, ft, shape, charge, seconds, cached, split)


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
