"""A frictionless rigid wall: the plane y = 0 (the target face), the projectile coming from y > 0.

Penalty contact on nodes: a node that has crossed the plane by δ = −y > 0 is pushed back by k_a δ along +y,
with k_a = κ m_a / Δt0² (m_a: the node's lumped mass, Δt0: the initial stable step). With κ = 0.5 the
node-on-spring period 2π Δt0/√κ ≈ 9 Δt0 keeps the step stable (κ < 4 − (ω_el Δt)² with ω_el Δt ≤ 1.6),
and the spring's compliance delays the contact by about 0.8 Δt0/κ per side, under 1 % of a bar's contact
time. The spring is conservative: its energy returns when the node leaves, and its work enters the
external work of the energy balance.
"""

from __future__ import annotations

import numpy as np
from mpi4py import MPI


class RigidWall:
    """Penalty wall y = 0 acting on the owned nodes of an ExplicitSolver.

    Args:
        solver: the ExplicitSolver (its initial stable step sets the penalty).
        kappa: dimensionless penalty κ.
    """

    def __init__(self, solver, kappa: float = 0.5):
        n = solver.n_owned
        self.k = kappa * solver.mass[:n] / solver.clock.dt0**2
        self.force = np.zeros(3)  # total force of the wall on the body (N), all ranks
        self.contact_nodes = 0
        self.area = 0.0  # a wall of nodes: no loaded area

    #: the wall's force on each node is not kept (its moment is not summed: diagnostics.rotation)
    nodal_force = None
    #: the fields it writes into fields.xdmf: none (fepen.solver.target_load.TargetLoad's: the target's load)
    field_names: tuple = ((), ())

    def surface_fields(self, solver) -> dict:
        """No surface fields: a wall's load is its nodes' springs."""
        return {}

    def angular_impulse_now(self, comm) -> np.ndarray:
        """The wall's angular impulse about O is not summed: zero."""
        return np.zeros(3)

    def stop_rule(self, run) -> str | None:
        """A body on the wall stops when it rebounds, checked every step (fepen.runs.events.StopRules.rebound)."""
        return run.rules.rebound(run.solver.t, self.contact_nodes)

    def __call__(self, solver, dt: float) -> None:
        n = solver.n_owned
        y = solver.X[:n, 1] + solver.U[:n, 1]
        inside = np.flatnonzero(y < 0.0)
        f = self.k[inside] * (-y[inside])
        solver.fext[inside, 1] += f
        total, count = solver.comm.allreduce(np.array([f.sum(), float(len(inside))]), op=MPI.SUM)
        self.force = np.array([0.0, total, 0.0])
        self.contact_nodes = int(count)
