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
from time import perf_counter

import numba
import numpy as np
from mpi4py import MPI

from fepen.solver import traffic

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
        self.sent_ranks = 0  # the ranks this rank sends terms to
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
            self.sent_ranks = len(dests)
            self._graph = comm.Create_dist_graph_adjacent([int(r) for r in sources], [int(d) for d in dests],
                                                          reorder=False)
            assert np.all((remote_node >= 0) & (remote_node < n_owned))
        # Nodes all of whose contributors are on this rank: a scatter over the contributors sorted by key adds
        # each node's terms in key order (the contributors' values are read in that order, the nodal sums
        # written in place). Nodes with terms from other ranks (the interface): their local and received
        # terms are merged by key into a node-major list (_place), and each node's run summed in order.
        self._conn = np.ascontiguousarray(conn)
        self._order = np.lexsort(tuple(keys[:, j] for j in range(keys.shape[1] - 1, -1, -1)))
        interface = np.zeros(n_owned, dtype=bool)
        interface[remote_node] = True
        mine = own.copy()
        mine[own] = interface[flat[own]]
        node = np.concatenate([flat[mine], remote_node])
        allkeys = np.concatenate([slot_keys[mine], remote_keys])
        order = np.lexsort(tuple(allkeys[:, j] for j in range(allkeys.shape[1] - 1, -1, -1)) + (node,))
        self._run_node = np.flatnonzero(interface)
        counts = np.bincount(node, minlength=n_owned)[self._run_node]
        self._ptr = np.zeros(len(self._run_node) + 1, dtype=np.int64)
        np.cumsum(counts, out=self._ptr[1:])
        # where each interface term goes: local slot s at _pos[s] (−1: not an interface term), received term r
        # at _pos_recv[r]
        where = np.empty(len(order), dtype=np.int64)
        where[order] = np.arange(len(order))
        n_local = int(mine.sum())
        self._pos = np.full(len(flat), -1, dtype=np.int64)
        self._pos[slots[mine]] = where[:n_local]
        self._pos_recv = where[n_local:]
        self.n_terms = len(order)
        self.n_recv = len(remote_node)
        self.sent = len(self._send)  # the terms this rank sends to other ranks' nodes, a call (times bs numbers)
        self._terms = {}

    def __call__(self, values: np.ndarray, out: np.ndarray) -> np.ndarray:
        """Write the owned nodes' sums of ``values`` into ``out`` (see the class); returns out."""
        values = np.asarray(values, dtype=float)
        per_node = values.ndim == 3
        bs = values.shape[-1]
        flat = values.reshape(-1, bs)
        recv = np.empty((self.n_recv, bs))
        if self._graph is not None:
            send = np.ascontiguousarray(flat[self._send if per_node else self._send // self.k])
            sc, rc = self._send_counts * bs, self._recv_counts * bs
            self._graph.Neighbor_alltoallv([send, (sc, _displs(sc)), MPI.DOUBLE],
                                           [recv, (rc, _displs(rc)), MPI.DOUBLE])
        out2 = out.reshape(len(out), -1)
        _sorted_scatter(self._order, self._conn, flat, per_node, self.n_owned, out2)
        if self.n_terms:
            terms = self._terms.get(bs)
            if terms is None:
                terms = self._terms[bs] = np.empty((self.n_terms, bs))
            _place(flat, self.k, per_node, self._pos, terms)
            terms[self._pos_recv] = recv
            _run_sums(self._ptr, self._run_node, terms, out2)
        return out


def _displs(counts: np.ndarray) -> np.ndarray:
    d = np.zeros_like(counts)
    if len(counts) > 1:
        np.cumsum(counts[:-1], out=d[1:])
    return d


@numba.njit(cache=True)
def _sorted_scatter(order, conn, values, per_node, n_owned, out):
    """out[:n_owned] = Σ over the contributors c in ``order`` of their values at their owned nodes (values
    (n_c k, bs) per node if per_node, else (n_c, bs) per contributor); ghost rows untouched. A contributor whose
    values are all zero is passed over (the target's unloaded facets, most of the surface): adding a zero
    leaves a sum's bits as they are (a sum that starts at +0 never becomes −0)."""
    bs = values.shape[1]
    k = conn.shape[1]
    out[:n_owned] = 0.0
    for i in range(len(order)):
        c = order[i]
        if not per_node:
            zero = True
            for q in range(bs):
                if values[c, q] != 0.0:
                    zero = False
                    break
            if zero:
                continue
        for j in range(k):
            a = conn[c, j]
            if a >= n_owned:
                continue
            r = c * k + j if per_node else c
            if bs == 3:
                out[a, 0] += values[r, 0]
                out[a, 1] += values[r, 1]
                out[a, 2] += values[r, 2]
            else:
                for q in range(bs):
                    out[a, q] += values[r, q]


@numba.njit(cache=True)
def _place(values, k, per_node, pos, terms):
    """terms[pos[s]] = the value of slot s = c k + j (values[s] if per_node, else values[c]) for every slot
    with pos[s] ≥ 0."""
    bs = values.shape[1]
    n_c = len(pos) // k
    for c in range(n_c):
        for j in range(k):
            s = c * k + j
            q = pos[s]
            if q < 0:
                continue
            r = s if per_node else c
            if bs == 3:
                terms[q, 0] = values[r, 0]
                terms[q, 1] = values[r, 1]
                terms[q, 2] = values[r, 2]
            else:
                for i in range(bs):
                    terms[q, i] = values[r, i]


@numba.njit(cache=True)
def _run_sums(ptr, run_node, terms, out):
    """out[run_node[r]] = Σ terms[ptr[r]:ptr[r + 1]], added in order."""
    bs = terms.shape[1]
    if bs == 3:
        for r in range(len(ptr) - 1):
            s0 = s1 = s2 = 0.0
            for q in range(ptr[r], ptr[r + 1]):
                s0 += terms[q, 0]
                s1 += terms[q, 1]
                s2 += terms[q, 2]
            a = run_node[r]
            out[a, 0] = s0
            out[a, 1] = s1
            out[a, 2] = s2
        return
    for r in range(len(ptr) - 1):
        a = run_node[r]
        for j in range(bs):
            acc = 0.0
            for q in range(ptr[r], ptr[r + 1]):
                acc += terms[q, j]
            out[a, j] = acc


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
    for j, row in enumerate(limbs.tolist()):  # Python integers: Σ row[k] 2^(LIMB_BITS k), exactly
        total = 0
        for v in reversed(row):
            total = (total << LIMB_BITS) + v
        out[j] = math.ldexp(float(total), -GRID_BITS) if total else 0.0  # one correct rounding
    out[bad > 0] = np.nan
    return out


def _reduced(limbs: np.ndarray, bad: np.ndarray, comm) -> tuple[np.ndarray, np.ndarray]:
    """limbs and bad counts summed over the ranks of comm, in one reduction."""
    if comm is None or comm.size == 1:
        return limbs, bad
    buf = np.concatenate([limbs.ravel(), bad])
    t0 = perf_counter()
    comm.Allreduce(MPI.IN_PLACE, buf, op=MPI.SUM)
    traffic.count("exact_sums", 1, buf.nbytes, traffic.rounds(comm.size), t0)
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
