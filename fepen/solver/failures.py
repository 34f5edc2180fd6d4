"""Why an ExplicitSolver's step cannot go on, said where and when: an inverted element, a stable step that
collapsed. Each raises SimulationError on every rank (collective), naming the element's place in the
undeformed projectile (docs/theory.md §11)."""

from __future__ import annotations

import numpy as np
from mpi4py import MPI

from fepen.errors import SimulationError


def inverted(solver, x: np.ndarray, jmin: float, worst: int) -> None:
    """SimulationError naming the inverted element, where and when (collective)."""
    s = solver
    local = (0 if not (jmin > 0.0) else 1, s.comm.rank)
    _, owner = s.comm.allreduce(local, op=MPI.MIN)
    info = None
    if s.comm.rank == owner:
        c = x[s.dofs[worst]].mean(axis=0)
        c0 = s.X[s.dofs[worst]].mean(axis=0)
        info = (s.mesh.topology.index_map(3).local_range[0] + worst, jmin, c, c0)
    gidx, jw, c, c0 = s.comm.bcast(info, root=owner)
    raise SimulationError(
        f"element {gidx} inverted (J = {jw:.3g}) at step {s.step_count}, t = {s.t * 1e6:.3f} us, "
        f"centre ({c[0] * 1e3:.2f}, {c[1] * 1e3:.2f}, {c[2] * 1e3:.2f}) mm; in the undeformed projectile "
        f"{c0[1] * 1e3:.1f} mm behind the nose tip, radius {np.hypot(c0[0], c0[2]) * 1e3:.1f} mm")


def step_collapsed(solver, h_c: float, new: float) -> None:
    """SimulationError naming the nearly flat element (this rank's h/c: ``h_c``) that took the stable step
    down to ``new`` (collective)."""
    s = solver
    _, owner = s.comm.allreduce((h_c, s.comm.rank), op=MPI.MIN)
    c = s.X[s.dofs[s.cell.step_cell]].mean(axis=0) if s.comm.rank == owner else None
    c = s.comm.bcast(c, root=owner)
    raise SimulationError(
        f"stable step collapsed to {new:.3g} s (initial {s.clock.dt0:.3g} s) at step {s.step_count}, "
        f"t = {s.t * 1e6:.3f} us: an element is nearly flat, {c[1] * 1e3:.1f} mm behind the nose "
        f"tip (radius {np.hypot(c[0], c[2]) * 1e3:.1f} mm) in the undeformed projectile")
