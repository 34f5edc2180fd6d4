"""The concrete target acting on the deformable projectile: the nodal external force of each step.

Each step: current load points from the deformed surface (fepen.surface: positions, mean nodal velocities,
exact normals turned with their facets, areas stretched with them) → the target law (fepen.target) →
forces shared to the facets' nodes, accumulated across ranks (scatter-reverse), added to the owned nodes'
external force. The axis (tail to nose) for the wake rule and the linear crater comes from the tracked tip
and tail nodes.
"""

from __future__ import annotations

import numpy as np
from dolfinx import la
from mpi4py import MPI

from fepen import surface as fsurface, target as tg


class ConcreteLoad:
    """External force of the concrete target on an ExplicitSolver.

    Args:
        solver: the ExplicitSolver.
        surf: its fepen.surface.Surface (owned outer facets).
        law: the TargetLaw.
        tip, tail: (owner, local) node handles of the nose tip and tail centre (ExplicitSolver.node_at).
        crater: a fepen.target.ForrestalCrater for the linear crater, else None.
    """

    def __init__(self, solver, surf: fsurface.Surface, law: tg.TargetLaw, tip, tail, crater=None):
        self.surf, self.law, self.tip, self.tail, self.crater = surf, law, tip, tail, crater
        self.buf = la.vector(solver.V.dofmap.index_map, bs=3)
        self.force = np.zeros(3)
        self.contact_nodes = 0
        self.area = 0.0

    def __call__(self, solver) -> None:
        x_all = solver.positions()
        tip = solver.node_value(self.tip, x_all)
        tail = solver.node_value(self.tail, x_all)
        axis = (tip - tail) / np.linalg.norm(tip - tail)
        x, v, area, n = self.surf.kinematics(x_all, solver.Vel)
        f = np.zeros_like(x)
        idx = np.flatnonzero(tg.immersion(self.law, x, area) > 0.0)
        sig = np.zeros(0)
        if len(idx):
            st = tg.SurfaceState(x[idx], v[idx], n[idx], area[idx], self.surf.radius[idx],
                                 self.surf.R_meridian[idx], self.surf.sin_phi0[idx], axis)
            f[idx], sig = tg.forces(self.law, st)
        total = solver.comm.allreduce(f.sum(axis=0), op=MPI.SUM)
        if self.crater is not None:
            scale = self.crater.scale(-tip[1], -float(total @ axis))
            f *= scale
            total = total * scale
        arr = self.buf.array.reshape(-1, 3)
        arr[:] = 0.0
        self.surf.to_nodes(f, arr)
        self.buf.scatter_reverse(la.ScatterMode.add)
        n_own = solver.n_owned
        solver.fext[:n_own] += arr[:n_own]
        self.force = total
        loaded = sig > 0.0
        self.contact_nodes = int(solver.comm.allreduce(int(loaded.sum()), op=MPI.SUM))
        self.area = solver.comm.allreduce(float(area[idx][loaded].sum()) if len(idx) else 0.0, op=MPI.SUM)
