"""The deformable model of a shot: mesh, explicit solver, target or wall, contact, wear, erosion and the
initial state (dolfinx; built from a fepen.runs.shot.Shot, never from the scene)."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from mpi4py import MPI

from fepen.geometry import mesh as fmesh
from fepen.geometry import revolution, tags
from fepen.laws import target as tg
from fepen.runs import outputs, setup, shot
from fepen.solver import assembly, erosion, explicit, probes, recession, shell_charge, surface


# ---------------------------------------------------------------------------------------------------------
@dataclass
class Model:
    """What a deformable run advances.

    Attributes:
        pm: the projectile mesh. solver: the ExplicitSolver, at its initial state.
        load: the target (TargetLoad) or the rigid wall (RigidWall), hooked in as ``solver.external``.
        contact: the shell-charge contact (hooked in as ``solver.interface``), or None.
        tip, tail: node handles of the nose tip and the tail centre (ExplicitSolver.node_at).
        v0: striking speed (m/s). surface: the target's load points (None on the rigid wall).
        law: the target law (None on the rigid wall). mesh_s, setup_s: wall seconds meshing and building.
        erosion: element erosion (effects.erosion) or None. recession: the surface recession of the nose
            (effects.wear, in the target) or None.
    """

    pm: fmesh.ProjectileMesh
    solver: explicit.ExplicitSolver
    load: explicit.Load
    contact: shell_charge.ShellChargeContact | None
    tip: tuple[int, int]
    tail: tuple[int, int]
    v0: float
    surface: surface.Surface | None
    law: tg.TargetLaw | None
    mesh_s: float
    setup_s: float
    erosion: erosion.Erosion | None = None
    recession: recession.Recession | None = None


def solver(sh, pm: fmesh.ProjectileMesh, kernel: str | None = None) -> explicit.ExplicitSolver:
    """The explicit solver on a shot's mesh: the shell's material, and the charge's on its cells.

    Args:
        sh: the Shot (a Scene is resolved).
        kernel: "C", "numba" or None (the C trial pass where it can be built).
    """
    sh = shot.of(sh)
    mats = [sh.materials[0]]
    cellmat = np.zeros(pm.mesh.topology.index_map(3).size_local, dtype=np.int64)
    if pm.charge:  # material 1: the charge, tied through shared wall nodes or in contact (split)
        mats.append(sh.materials[1])
        cellmat[fmesh.owned_cells_tagged(pm, tags.CHARGE)] = 1
    s = explicit.ExplicitSolver(pm.mesh, mats, cellmat, sh.safety_factor, kernel=kernel)
    if sh.stable_step == "eigenvalue":
        s.calibrate_step()
    return s


def build(sh, comm: MPI.Comm = MPI.COMM_WORLD) -> Model:
    """Mesh, solver, target or wall, contact and initial state of a deformable run.

    Args:
        sh: the Shot (a Scene is resolved).
    """
    sh = shot.of(sh)
    t0 = time.perf_counter()
    pm = setup.build_mesh(sh.built, sh.mesh, comm)
    mesh_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    with fmesh.phase("setup: solver and kernels (compiled once per machine)", comm.rank):
        s = solver(sh, pm)
    contact = None
    if pm.split:
        contact = shell_charge.ShellChargeContact(s, pm.facet_tags, sh.charge_friction)
        s.interface = contact
    tip = probes.node_at(s, pm.shape.tip)
    tail = probes.node_at(s, pm.shape.tail)
    surf, load = sh.target.load(s, pm, sh, tip, tail)  # a target's load on its surface, or the rigid wall
    s.external = load
    eroding = receding = None
    if sh.erosion is not None:
        eroding = erosion.Erosion(s, surf, sh.erosion.strain, sh.erosion.step_ratio)
    if sh.wear is not None and surf is not None:
        w = sh.wear
        y_c = _nose_zone(s, surf, sh.built.shape) if w.distribution == "nose" else None
        receding = recession.Recession(s, surf, w.friction, w.efficiency, w.enthalpy, w.density, zone_end=y_c)
        load.wear = receding
        receding.rotation = load.body_rotation  # the recession in the body's frame (theory.md §14.2)
    s.landing = outputs.landing(sh)  # the steps end on the output times
    R, v, w = sh.rotation, sh.velocity, sh.angular_velocity
    if np.any(w):  # the body turning at impact: v + ω × (x − x_c) about its centre of mass (exact sums)
        n = s.n_owned
        xc = assembly.exact_sum(s.mass[:n, None] * s.X[:n], s.comm) / s.total_mass
        s.set_initial(displacement=lambda X: X @ R.T - X, velocity=lambda X: v + np.cross(w, (X - xc) @ R.T))
    else:
        s.set_initial(displacement=lambda X: X @ R.T - X, velocity=lambda X: np.tile(v, (len(X), 1)))
    return Model(pm, s, load, contact, tip, tail, sh.speed, surf, sh.law, mesh_s, time.perf_counter() - t0,
                 eroding, receding)


def _nose_zone(s, surf, shape) -> float:
    """The nose zone's end y_c (m) of the meshed body (fepen.geometry.revolution.nose_zone by its kind: a Shape's
    from its meridian, a CAD body's from its surface nodes on every rank; collective)."""
    xb = s.X[np.unique(surf.tri.ravel())]
    return revolution.nose_zone(shape, xb, np.hypot(xb[:, 0], xb[:, 2]), s.comm)[0]
