"""Nodes of an ExplicitSolver's mesh followed through a run: located once in the initial reference body,
read every step on every rank (the nose tip and tail of fepen.runs, the target load's axis)."""

from __future__ import annotations

import numpy as np
from mpi4py import MPI


def node_at(solver, point) -> tuple[int, int]:
    """(owner rank, local index) of the owned node at a point of the initial reference body (exact match),
    or (-1, -1)."""
    d = np.linalg.norm(solver.X0[: solver.n_owned] - np.asarray(point), axis=1)
    local = int(np.argmin(d)) if len(d) else -1
    mine = local >= 0 and d[local] < 1e-12
    ranks = solver.comm.allgather(solver.comm.rank if mine else -1)
    owner = max(ranks)
    return owner, (local if solver.comm.rank == owner else -1)


def node_values(solver, handles, array: np.ndarray) -> np.ndarray:
    """The (3,) values of a nodal array at several nodes located with node_at, as (k, 3) on every rank, in
    one reduction (each owner's value against −inf elsewhere: bit for bit the owner's)."""
    buf = np.full((len(handles), 3), -np.inf)
    for k, (owner, local) in enumerate(handles):
        if solver.comm.rank == owner:
            buf[k] = array[local]
    if solver.comm.size > 1:
        solver.comm.Allreduce(MPI.IN_PLACE, buf, op=MPI.MAX)
    return buf


def node_value(solver, owner_local: tuple[int, int], array: np.ndarray) -> np.ndarray:
    """The (3,) value of a nodal array at a node located with node_at, on every rank."""
    owner, local = owner_local
    val = array[local].copy() if solver.comm.rank == owner else None
    return solver.comm.bcast(val, root=owner)
