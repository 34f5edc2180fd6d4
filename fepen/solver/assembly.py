"""Sums that do not depend on the partition: nodal sums over cells or facets in one canonical order, and
exactly rounded global sums (docs/theory.md §3.4).

A floating-point sum depends on the order of its terms. A node's internal force is the sum of its cells'
contributions: on one rank they are added in one order, on two in another (the cells are numbered otherwise,
and those of the other rank arrive as one partial sum), so the histories of one run on 1 and on 2 ranks part
at round-off, and the contact law's switches amplify the difference. Here

- each node adds its contributions in the order of its contributors' input-mesh vertex numbers, whichever
  rank holds them: the contributions of cells (or facets) on other ranks are sent to the node's owner, one per
  cell and node, not pre-summed (the idea of the "parallel arithmetic" options of explicit codes, e.g.
  OpenRadioss's /PARITH/ON);
- global sums of the quantities that feed the dynamics are exact: every term is rounded onto one fixed binary
  grid (2^-100, for terms below 2^70) and the terms are added as integers, so any grouping gives the same bits.

So a run gives the same numbers on any rank count, provided each contribution is computed from the same
inputs by the same code (per cell, per facet, per node), which is what the solver does.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from mpi4py import MPI

__all__ = ["NodalSum", "exact_sum", "ExactAccumulator", "input_keys"]

#: the exact sums' grid: terms are rounded to multiples of 2^-GRID_BITS and held in LIMBS integers of
#: LIMB_BITS bits each (the top one signed), so |term| < 2^(LIMBS * LIMB_BITS - GRID_BITS - 10) = 2^70
GRID_BITS = 100
LIMB_BITS = 30
LIMBS = 6


def input_keys(conn: np.ndarray, input_index: np.ndarray) -> np.ndarray:
    """Partition-independent keys of contributors (cells or facets): their vertices' input-mesh numbers,
    sorted ascending, one row per contributor.

    Args:
        conn: (n, k) local node indices of each contributor.
        input_index: (n_nodes,) the input-mesh number of each local node (owned and ghost).

    Returns:
        (n, k) int64.
    """
    return np.sort(np.asarray(input_index, dtype=np.int64)[conn], axis=1)


class NodalSum:
    """Σ over contributors of their values at their nodes, each node's terms added in one canonical order
    (by the contributors' keys), the same on any partition.

    Args:
        comm: the mesh's communicator.
        index_map: the nodes' dolfinx IndexMap (owned first, then ghosts).
        conn: (n_c, k) local node indices of this rank's contributors (each contributor on one rank only).
        keys: (n_c, kk) int64 partition-independent contributor keys (input_keys), unique per contributor.

    Calling it with values (n_c, k, bs) (one per contributor and node) or (n_c, bs) (the same at each of the
    contributor's nodes) writes the owned nodes' sums into ``out[:n_owned]`` (out (≥ n_owned, bs)); ghosts are
    left alone (refresh them with the vector's scatter_forward when they are needed).
    """

    def __init__(self, comm, index_map, conn: np.ndarray, keys: np.ndarray):
        conn = np.asarray(conn, dtype=np.int64)
        keys = np.asarray(keys, dtype=np.int64)
        self.comm = comm
        self.k = conn.shape[1]
        n_owned = index_map.size_local
        self.n_owned = n_owned
        flat = conn.ravel()
        slot_keys = np.repeat(keys, self.k, axis=0)
        slots = np.arange(len(flat), dtype=np.int64)
        own = flat < n_owned
        # the slots of ghost nodes go to the nodes' owners, with the owner's local index and the key
        ghost = ~own
        size = comm.size
        self._send = np.zeros(0, dtype=np.int64)
        self._graph = None
        remote_node = np.zeros(0, dtype=np.int64)
        remote_keys = np.zeros((0, keys.shape[1]), dtype=np.int64)
        if size > 1:
            g = flat[ghost] - n_owned
            owners = np.asarray(index_map.owners, dtype=np.int64)[g] if len(g) else np.zeros(0, dtype=np.int64)
            gidx = np.asarray(index_map.ghosts, dtype=np.int64)[g] if len(g) else np.zeros(0, dtype=np.int64)
            order = np.lexsort((slots[ghost], owners))
            self._send = slots[ghost][order]
            owners, gidx = owners[order], gidx[order]
            dests = np.unique(owners)
            counts = {int(d): int(np.sum(owners == d)) for d in dests}
            outgoing = [None] * size
            for d in dests:
                sel = owners == d
                outgoing[int(d)] = (gidx[sel], slot_keys[ghost][order][sel])
            incoming = comm.alltoall(outgoing)
            sources = [r for r in range(size) if incoming[r] is not None]
            lo = index_map.local_range[0]
            remote_node = np.concatenate([incoming[r][0] - lo for r in sources]) if sources else remote_node
            remote_keys = np.concatenate([incoming[r][1] for r in sources]) if sources else remote_keys
            self._recv_counts = np.array([len(incoming[r][0]) for r in sources], dtype=np.int64)
            self._send_counts = np.array([counts[int(d)] for d in dests], dtype=np.int64)
            self._graph = comm.Create_dist_graph_adjacent([int(r) for r in sources], [int(d) for d in dests],
                                                          reorder=False)
            assert np.all((remote_node >= 0) & (remote_node < n_owned))
        # every owned node's terms: local slots (src ≥ 0) and received ones (src = −1 − position), by key
        node = np.concatenate([flat[own], remote_node])
        src = np.concatenate([slots[own], -1 - np.arange(len(remote_node), dtype=np.int64)])
        allkeys = np.concatenate([slot_keys[own], remote_keys])
        order = np.lexsort(tuple(allkeys[:, j] for j in range(allkeys.shape[1] - 1, -1, -1)) + (node,))
        self._src = np.ascontiguousarray(src[order])
        self._ptr = np.zeros(n_owned + 1, dtype=np.int64)
        np.add.at(self._ptr, node[order] + 1, 1)
        np.cumsum(self._ptr, out=self._ptr)
        self.n_recv = len(remote_node)

    def __call__(self, values: np.ndarray, out: np.ndarray) -> np.ndarray:
        """Write the owned nodes' sums of ``values`` into ``out`` (see the class); returns out."""
        values = np.asarray(values, dtype=float)
        per_node = values.ndim == 3
        bs = values.shape[-1]
        flat = values.reshape(-1, bs)
        div = 1 if per_node else self.k
        recv = np.empty((self.n_recv, bs))
        if self._graph is not None:
            send = np.ascontiguousarray(flat[self._send // div])
            sc, rc = self._send_counts * bs, self._recv_counts * bs
            self._graph.Neighbor_alltoallv([send, (sc, _displs(sc)), MPI.DOUBLE],
                                           [recv, (rc, _displs(rc)), MPI.DOUBLE])
        _gather(self._ptr, self._src, div, flat, recv, out.reshape(len(out), -1))
        return out


def _displs(counts: np.ndarray) -> np.ndarray:
    d = np.zeros_like(counts)
    if len(counts) > 1:
        np.cumsum(counts[:-1], out=d[1:])
    return d


@numba.njit(cache=True)
def _gather(ptr, src, div, local, remote, out):
    bs = local.shape[1]
    acc = np.empty(bs)
    for a in range(len(ptr) - 1):
        acc[:] = 0.0
        for q in range(ptr[a], ptr[a + 1]):
            i = src[q]
            if i >= 0:
                r = i // div
                for j in range(bs):
                    acc[j] += local[r, j]
            else:
                r = -1 - i
                for j in range(bs):
                    acc[j] += remote[r, j]
        for j in range(bs):
            out[a, j] = acc[j]


# ------------------------------------------------------------------------------------------------------
# exact sums

@numba.njit(cache=True)
def _to_limbs(values, limbs, bad):
    """Add each column's terms, rounded to the grid, into limbs (m, LIMBS) int64 (not normalised); terms
    that are not finite or not below 2^70 are counted in bad (m,) instead (their sum is then NaN)."""
    scale = 2.0 ** GRID_BITS
    base = 2.0 ** LIMB_BITS
    top = 2.0 ** (LIMBS * LIMB_BITS - GRID_BITS - 10)
    n, m = values.shape
    for i in range(n):
        for j in range(m):
            v = values[i, j]
            if not (abs(v) < top):
                bad[j] += 1
                continue
            y = np.rint(v * scale)  # exact scaling by a power of two, one rounding
            for k in range(LIMBS - 1):
                q = np.floor(y / base)
                limbs[j, k] += np.int64(y - q * base)  # in [0, 2^30): exact
                y = q
            limbs[j, LIMBS - 1] += np.int64(y)


@numba.njit(cache=True)
def _carry(limbs):
    """Normalise limbs: every limb but the top one in [0, 2^30)."""
    for j in range(limbs.shape[0]):
        for k in range(LIMBS - 1):
            c = limbs[j, k] >> LIMB_BITS  # arithmetic shift: floor division by 2^30
            limbs[j, k] -= c << LIMB_BITS
            limbs[j, k + 1] += c


def _from_limbs(limbs: np.ndarray, bad: np.ndarray) -> np.ndarray:
    out = np.empty(limbs.shape[0])
    for j, row in enumerate(limbs):
        total = sum(int(v) << (LIMB_BITS * k) for k, v in enumerate(row))
        out[j] = math.ldexp(float(total), -GRID_BITS) if total else 0.0  # one correct rounding
    out[bad > 0] = np.nan
    return out


def _reduced(limbs: np.ndarray, bad: np.ndarray, comm) -> tuple[np.ndarray, np.ndarray]:
    """limbs and bad counts summed over the ranks of comm, in one reduction."""
    if comm is None or comm.size == 1:
        return limbs, bad
    buf = np.concatenate([limbs.ravel(), bad])
    comm.Allreduce(MPI.IN_PLACE, buf, op=MPI.SUM)
    limbs = buf[: limbs.size].reshape(limbs.shape)
    _carry(limbs)
    return limbs, buf[limbs.size:]


def exact_sum(values, comm=None):
    """Σ over the rows of ``values`` (n,) or (n, m), over all ranks of ``comm`` (if given), exactly (each
    term first rounded to a multiple of 2^-100), then rounded once: the same bits for any order or grouping
    of the terms. A column with a term that is not finite or not below 2^70 sums to NaN (on every rank).

    Args:
        values: this rank's terms, (n,) or (n, m).
        comm: an MPI communicator (a collective call), or None.

    Returns:
        (m,) sums (a float for 1-D values).
    """
    v = np.asarray(values, dtype=float)
    one = v.ndim == 1
    v = v.reshape(len(v), -1) if v.size else np.zeros((0, 1 if one else v.shape[-1]))
    m = v.shape[1]
    limbs, bad = np.zeros((m, LIMBS), dtype=np.int64), np.zeros(m, dtype=np.int64)
    _to_limbs(v, limbs, bad)
    _carry(limbs)
    out = _from_limbs(*_reduced(limbs, bad, comm))
    return float(out[0]) if one else out


class ExactAccumulator:
    """Running exact sums (m columns) of terms added step after step on each rank; ``total(comm)`` is the
    exact sum over steps and ranks, rounded once."""

    def __init__(self, m: int):
        self.limbs = np.zeros((m, LIMBS), dtype=np.int64)
        self.bad = np.zeros(m, dtype=np.int64)

    def add(self, values) -> None:
        """Add terms (n, m) (or (m,): one each)."""
        v = np.asarray(values, dtype=float).reshape(-1, self.limbs.shape[0])
        _to_limbs(v, self.limbs, self.bad)
        _carry(self.limbs)

    def total(self, comm=None) -> np.ndarray:
        """The sums (m,), over all ranks of comm (collective), or this rank's."""
        return _from_limbs(*_reduced(self.limbs.copy(), self.bad.copy(), comm))

    def clear(self) -> None:
        """Back to zero."""
        self.limbs[:] = 0
        self.bad[:] = 0
