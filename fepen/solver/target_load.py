"""The concrete target acting on the deformable projectile: the nodal external force of each step
(docs/theory.md §10).

Each step: the load points of the deformed surface (fepen.solver.surface) → the target law on them
(fepen.laws.target.load_on_points) → forces shared to the facets' nodes, summed across ranks, added to
the owned nodes' external force.
"""

from __future__ import annotations

from time import perf_counter

import numpy as np
from dolfinx import la
from mpi4py import MPI

from fepen.geometry.frames import unit_axis
from fepen.laws import target as tg
from fepen.solver import probes
from fepen.solver.surface import Surface


class TargetLoad:
    """External force of the concrete target on an ExplicitSolver (an explicit.Load).

    Args:
        solver: the ExplicitSolver.
        surf: its Surface (owned outer facets).
        law: the TargetLaw.
        tip, tail: (owner, local) node handles of the nose tip and tail centre (probes.node_at).
        crater: a ForrestalCrater for the linear crater, else None.
    """

    def __init__(self, solver, surf: Surface, law: tg.TargetLaw, tip, tail, crater=None):
        self.surf, self.law, self.tip, self.tail, self.crater = surf, law, tip, tail, crater
        self.buf = la.vector(solver.V.dofmap.index_map, bs=3)
        self.force = np.zeros(3)
        self.contact_nodes = 0
        self.area = 0.0
        self.wear = None  # a fepen.solver.recession.Recession fed each step's point loads, or None

    def __call__(self, solver, dt: float) -> None:
        x_all = solver.positions()  # from X and U: a load may be evaluated on a state set by hand (wear playback)
        t0 = perf_counter()
        tip, tail = probes.node_values(solver, (self.tip, self.tail), x_all)  # one reduction for both
        comm_s = perf_counter() - t0
        axis = unit_axis(tip, tail)

        def reduce(a):
            nonlocal comm_s
            t1 = perf_counter()
            a = np.array(a, dtype=float)
            if solver.comm.size > 1:
                solver.comm.Allreduce(MPI.IN_PLACE, a, op=MPI.SUM)
            comm_s += perf_counter() - t1
            return a

        x, v, area, n = self.surf.kinematics(x_all, solver.Vel)
        s = self.surf
        load = tg.load_on_points(self.law, x, v, n, area, s.radius, s.R_meridian, s.sin_phi0, axis, self.crater,
                                 -tip[1], reduce)
        arr = self.buf.array.reshape(-1, 3)
        arr[:] = 0.0
        self.surf.to_nodes(load.force, arr)
        if self.wear is not None:
            self.wear.add(load.force, n, v, dt)
        t1 = perf_counter()
        self.buf.scatter_reverse(la.ScatterMode.add)
        comm_s += perf_counter() - t1
        n_own = solver.n_owned
        solver.fext[:n_own] += arr[:n_own]
        self.force, self.contact_nodes, self.area = load.total, load.loaded, load.area
        solver.times.target_comm += comm_s

    def state(self) -> dict[str, np.ndarray]:
        """The load's last totals (for checkpoints; the same on every rank)."""
        return {"force": np.asarray(self.force, dtype=float), "totals": np.array([self.contact_nodes, self.area])}

    def restore(self, state: dict) -> None:
        """Put back what state() returned."""
        self.force = np.array(state["force"][:3])
        self.contact_nodes, self.area = int(state["totals"][0]), float(state["totals"][1])
