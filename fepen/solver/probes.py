"""Nodes of an ExplicitSolver's mesh followed through a run: located once in the initial reference body,
read every step on every rank (the nose tip and tail of fepen.runs, the target load's axis); the user's probes
([[output.probes]], fepen.runs.probes): the nearest node and the cell holding a point, chosen the same on any
partition, and their values, bit for bit the owner's on every rank."""

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


def node_values(solver, handles, *arrays: np.ndarray) -> np.ndarray:
    """The (3,) values of nodal arrays at several nodes located with node_at, as (k, 3 m) on every rank (m arrays
    side by side), in one reduction (each owner's value against −inf elsewhere: bit for bit the owner's)."""
    buf = np.full((len(handles), 3 * len(arrays)), -np.inf)
    for k, (owner, local) in enumerate(handles):
        if solver.comm.rank == owner:
            for j, array in enumerate(arrays):
                buf[k, 3 * j: 3 * j + 3] = array[local]
    if solver.comm.size > 1:
        solver.comm.Allreduce(MPI.IN_PLACE, buf, op=MPI.MAX)
    return buf


def node_value(solver, owner_local: tuple[int, int], array: np.ndarray) -> np.ndarray:
    """The (3,) value of a nodal array at a node located with node_at, on every rank."""
    owner, local = owner_local
    val = array[local].copy() if solver.comm.rank == owner else None
    return solver.comm.bcast(val, root=owner)


# ---------------------------------------------------------------------------------------------------------
# user-chosen probes ([[output.probes]]): the nearest node, the cell holding a point
# ---------------------------------------------------------------------------------------------------------
#: a point is inside a cell when each of its barycentric coordinates is at least minus this
INSIDE_TOLERANCE = 1e-9
#: node probe values: displacement, velocity, acceleration (3 each); cell probe values
NODE_QUANTITIES = 9
CELL_QUANTITIES = 5


def nearest_node(solver, point) -> tuple[tuple[int, int], float]:
    """The owned node nearest to a point of the initial reference body, chosen the same on any partition:
    the smallest distance, ties to the smallest input-mesh vertex number (collective).

    Args:
        solver: the ExplicitSolver. point: (3,) in the reference frame (m).

    Returns:
        ((owner rank, local index or -1 elsewhere), its distance (m), the same on every rank).
    """
    n = solver.n_owned
    d = np.sqrt(np.sum((solver.X0[:n] - np.asarray(point, dtype=float)) ** 2, axis=1))
    if n:
        k = int(np.lexsort((solver.node.input_index[:n], d))[0])
        mine = (float(d[k]), int(solver.node.input_index[k]), solver.comm.rank, k)
    else:
        mine = (np.inf, -1, solver.comm.rank, -1)
    dist, _, owner, local = min(solver.comm.allgather(mine))
    return (owner, local if solver.comm.rank == owner else -1), dist


def _barycentric(corners: np.ndarray, point: np.ndarray) -> np.ndarray:
    """Barycentric coordinates (n, 4) of a point in tetrahedra (n, 4, 3) (NaN for a degenerate one)."""
    T = np.transpose(corners[:, 1:] - corners[:, :1], (0, 2, 1))  # (n, 3, 3): columns the edges from corner 0
    with np.errstate(all="ignore"):
        lam = np.linalg.solve(T, (point - corners[:, 0])[:, :, None])[:, :, 0]
    return np.concatenate([1.0 - lam.sum(axis=1, keepdims=True), lam], axis=1)


def containing_cell(solver, point) -> tuple[int, int]:
    """The live owned cell of the initial reference body holding a point, chosen the same on any partition:
    its corners taken in their input-mesh order (the same arithmetic on every partition), ties (a point on a
    face, an edge or a node) to the smallest sorted input-mesh vertex numbers (collective).

    Args:
        solver: the ExplicitSolver. point: (3,) in the reference frame (m).

    Returns:
        (owner rank, local cell or -1 elsewhere), or (-1, -1) when no cell holds the point.
    """
    p = np.asarray(point, dtype=float)
    dofs = solver.dofs[: solver.n_cells]
    order = np.argsort(solver.node.input_index[dofs], axis=1, kind="stable")
    canonical = np.take_along_axis(dofs, order, axis=1)
    X = solver.X0[canonical]
    near = np.flatnonzero(np.all(X.min(axis=1) <= p + 1e-12, axis=1) & np.all(X.max(axis=1) >= p - 1e-12, axis=1)
                          & (solver.mat[: solver.n_cells] >= 0))
    best = None
    if len(near):
        lam = _barycentric(X[near], p)
        inside = near[np.all(lam >= -INSIDE_TOLERANCE, axis=1)]
        if len(inside):
            keys = solver.node.input_index[canonical[inside]]
            k = int(inside[np.lexsort(keys.T[::-1])[0]])
            best = (tuple(int(v) for v in solver.node.input_index[canonical[k]]), solver.comm.rank, k)
    found = [b for b in solver.comm.allgather(best) if b is not None]
    if not found:
        return (-1, -1)
    _, owner, local = min(found)
    return (owner, local if solver.comm.rank == owner else -1)


def cell_values(solver, handles, axis: np.ndarray) -> np.ndarray:
    """The cell probes' values (k, CELL_QUANTITIES) on every rank, bit for bit the owner's: von Mises and axial
    stress (as fepen.solver.diagnostics computes them for the fields), pressure (Pa, positive in compression),
    PEEQ, temperature (K).

    Args:
        solver: the ExplicitSolver. handles: (owner, local cell) of containing_cell. axis: the projectile's unit
            axis, tail to nose (world).
    """
    buf = np.full((len(handles), CELL_QUANTITIES), -np.inf)
    ax, ay, az = axis
    for k, (owner, c) in enumerate(handles):
        if solver.comm.rank != owner:
            continue
        sd = solver.s[c]
        vm = np.sqrt(1.5 * (sd[0] ** 2 + sd[1] ** 2 + sd[2] ** 2 + 2 * (sd[3] ** 2 + sd[4] ** 2 + sd[5] ** 2)))
        pm = mean_stress(solver, c)
        axial = (sd[0] * ax * ax + sd[1] * ay * ay + sd[2] * az * az
                 + 2 * (sd[3] * ax * ay + sd[4] * ay * az + sd[5] * ax * az)) + (pm if solver.passes.nodal else 0.0)
        buf[k] = (vm, axial, -pm, solver.eps_p[c], solver.temp[c])
    if solver.comm.size > 1:
        solver.comm.Allreduce(MPI.IN_PLACE, buf, op=MPI.MAX)
    return buf


def mean_stress(solver, c: int) -> float:
    """A cell's mean (Cauchy) stress (Pa, positive in tension): the average of its nodes' pressures with the
    averaged-nodal-pressure element, else the trace of its stress over 3."""
    if solver.passes.nodal:
        m = max(int(solver.mat[c]), 0)
        d = solver.dofs[c]
        return 0.25 * (solver.nodal_p[d[0], m] + solver.nodal_p[d[1], m] + solver.nodal_p[d[2], m]
                       + solver.nodal_p[d[3], m])
    return float(solver.s[c, 0] + solver.s[c, 1] + solver.s[c, 2]) / 3.0
