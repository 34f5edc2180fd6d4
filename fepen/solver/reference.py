"""Changes of an ExplicitSolver's reference body during a run: cells eroded (fepen.solver.erosion), a
surface receding (fepen.solver.recession), and the rebuild of the reference data after either (or after
restoring a checkpoint of a changed body). The removed mass and the energy it carried away are added to
the solver's ``_removed`` sums (docs/theory.md §15)."""

from __future__ import annotations

import numpy as np
from mpi4py import MPI

from fepen.solver import kernels


def remove_cells(solver, cells: np.ndarray) -> None:
    """Erode owned cells (collective; ``cells`` may be empty on some ranks): their stress and force go,
    their mass leaves their nodes, and a node left without a live cell stops (docs/theory.md §15).

    The removed mass, the kinetic energy it carried (½ Δm_a |v_a|² at the integer step) and the elastic
    energy stored in the removed cells are added to this rank's ``_removed`` sums.
    """
    s = solver
    cells = np.asarray(cells, dtype=np.int64)
    if len(cells):
        J = np.empty(s.n_cells)
        kernels.cell_jacobians(s.positions(), s.dofs, s.orient, s.vol0, s.mat, J)
        G = np.array([m.shear_modulus for m in s.materials])[s.mat[cells]]
        s.sums.removed[2] += kernels.deviatoric_energy(s.s[cells], J[cells], s.vol0[cells], G)
        s.mat[cells] = -1
        s.s[cells] = 0.0
        s.internal.P_packed[cells] = 0.0
        s.cell.sy0[cells] = np.inf
        s.cell.dt[cells] = np.inf
    rebuild(s, np.zeros(0, dtype=np.int64))


def change_reference(solver, dX: np.ndarray, rotation: np.ndarray | None = None) -> None:
    """Move the reference positions of nodes by dX (n_nodes, 3), ghosts included and equal on every rank
    that holds a node: material removed from a receding surface (fepen.solver.recession). The current
    positions move by R dX, the recession turned into the body's own frame (R: ``rotation``, the body's turn
    from its reference axis; None: the identity), so a worn node recedes along the turned body's surface, not
    along the reference frame's: the displacement gains (R − I) dX. The cells touched get their new reference
    gradients and volumes, the nodes their new masses (collective)."""
    moved = np.any(dX != 0.0, axis=1)
    cells = np.flatnonzero(moved[solver.dofs].any(axis=1))
    solver.X += dX
    if rotation is not None:
        solver.U += dX @ (np.asarray(rotation) - np.eye(3)).T
    rebuild(solver, cells)


def rebuild(solver, cells: np.ndarray) -> None:
    """Recompute the reference data of ``cells`` and every nodal mass and volume (collective)."""
    s = solver
    if len(cells):
        g, v, o = kernels.reference_gradients(s.X, s.dofs[cells])
        s.cell.grad0[cells], s.vol0[cells], s.orient[cells] = g, v, o
        if s.node.geometry_x is not None:
            s.node.geometry_x[s.node.geometry_node, :3] = s.X
    old = s.mass.copy()
    v = s.velocity_at_step()
    kernels.volumes_and_step(s.X, s.dofs, s.orient, s.vol0, s.mat, s.cell.speed, s.cell.vol, False)
    s.volumes_to_nodes(s.cell.vol, s.node.nvol0)
    nm = len(s.materials)
    s.lumped_mass(s.V.dofmap.index_map, nm, orphans_allowed=True)
    n = s.n_owned
    dm = old[:n] - s.mass[:n]
    s.sums.removed[0] += float(dm.sum())
    s.sums.removed[1] += 0.5 * float(np.sum(dm[:, None] * v[:n] ** 2))
    if np.any(s.node.orphans):
        for a in (s.Vel, s.acc):
            a[s.node.orphans] = 0.0


def removed_mass(solver) -> float:
    """Mass removed so far (kg), all ranks."""
    return solver.comm.allreduce(float(solver.sums.removed[0]), op=MPI.SUM)
