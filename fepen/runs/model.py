"""The deformable model of a scene: mesh, explicit solver, target or wall, contact and initial state
(dolfinx; the scene is read through fepen.runs.setup)."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from mpi4py import MPI

from fepen.geometry import mesh as fmesh
from fepen.geometry import tags
from fepen.laws import target as tg
from fepen.laws import wear
from fepen.runs import setup
from fepen.solver import erosion, explicit, probes, recession, rigid_wall, shell_charge, surface, target_load


# ---------------------------------------------------------------------------------------------------------
@dataclass
class Model:
    """What a deformable run advances.

    Attributes:
        pm: the projectile mesh. solver: the ExplicitSolver, at its initial state.
        load: the target (TargetLoad) or the rigid wall (RigidWall), hooked in as ``solver.external``.
        contact: the shell-charge contact (hooked in as ``solver.interface``), or None.
        tip, tail: node handles of the nose tip and the tail centre (probes.node_at).
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


def solver(scene, pm: fmesh.ProjectileMesh, kernel: str | None = None) -> explicit.ExplicitSolver:
    """The explicit solver on a scene's mesh: the shell's material, and the charge's on its cells.

    Args:
        kernel: "C", "numba" or None (the C trial pass where it can be built).
    """
    mats = [setup.projectile_material(scene)]
    cellmat = np.zeros(pm.mesh.topology.index_map(3).size_local, dtype=np.int64)
    if pm.charge:  # material 1: the charge, tied through shared wall nodes or in contact (split)
        mats.append(setup.charge_material(scene))
        cellmat[fmesh.owned_cells_tagged(pm, tags.CHARGE)] = 1
    s = explicit.ExplicitSolver(pm.mesh, mats, cellmat, scene.run.safety_factor, kernel=kernel)
    if scene.run.stable_step == "eigenvalue":
        s.calibrate_step()
    return s


def build(scene, comm: MPI.Comm = MPI.COMM_WORLD) -> Model:
    """Mesh, solver, target or wall, contact and initial state of a deformable run."""
    t0 = time.perf_counter()
    pm = setup.mesh(scene, comm)
    mesh_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    s = solver(scene, pm)
    contact = None
    if pm.split:
        contact = shell_charge.ShellChargeContact(s, pm.facet_tags, scene.charge.friction)
        s.interface = contact
    tip = probes.node_at(s, pm.shape.tip)
    tail = probes.node_at(s, pm.shape.tail)
    R, v = setup.placement(scene)
    v0 = float(np.linalg.norm(v))
    surf = law = None
    if scene.target.kind == "concrete":
        law = setup.target_law(scene)
        surf = surface.outer_surface(s.V, pm.facet_tags, pm.shape)
        load = target_load.TargetLoad(s, surf, law, tip, tail, setup.crater(scene, law, s.total_mass, v0))
    else:
        load = rigid_wall.RigidWall(s)
    s.external = load
    eroding = receding = None
    if scene.effects.erosion:
        pe = scene.projectile.erosion
        eroding = erosion.Erosion(s, surf, pe.strain, pe.step_ratio)
    if scene.effects.wear and surf is not None:
        m = scene.projectile.material
        mu = scene.get("projectile.wear.friction")
        h = wear.melt_enthalpy(m.specific_heat, m.melt_temperature, m.room_temperature,
                               scene.projectile.wear.latent_heat)
        receding = recession.Recession(s, surf, scene.target.friction if mu is None else mu,
                                       scene.projectile.wear.efficiency, h, m.density)
        load.wear = receding
    s.set_initial(displacement=lambda X: X @ R.T - X, velocity=lambda X: np.tile(v, (len(X), 1)))
    return Model(pm, s, load, contact, tip, tail, v0, surf, law, mesh_s, time.perf_counter() - t0, eroding,
                 receding)
