"""Sums that do not depend on the partition (fepen.solver.assembly): exact sums against math.fsum and under
any order or grouping; nodal sums the same bits whatever the order of the contributors and on any number of
ranks."""

import math

import numpy as np
import pytest
from dolfinx import mesh as dmesh
from hypothesis import given, settings
from hypothesis import strategies as st
from mpi4py import MPI

from fepen import dolfinx_api as dx
from fepen.solver import assembly as A


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(min_value=-1e15, max_value=1e15, allow_nan=False), min_size=1, max_size=200),
       st.randoms(use_true_random=False))
def test_exact_sum_is_fsum_in_any_order(terms, rnd):
    """The sum of terms on the grid is exactly rounded: math.fsum's value for terms that are multiples of
    2^-100 (these are: |x| > 2^-47 or 0 here, whose ulp is a multiple), whatever the order."""
    terms = [t for t in terms if t == 0.0 or abs(t) > 2.0 ** -40]
    shuffled = terms[:]
    rnd.shuffle(shuffled)
    assert A.exact_sum(np.array(terms)) == math.fsum(terms) == A.exact_sum(np.array(shuffled))


def test_exact_sum_of_cancelling_terms():
    """1e16 + 1 - 1e16 is 1 exactly (a float sum in that order gives 0 or 2)."""
    assert A.exact_sum(np.array([1e16, 1.0, -1e16])) == 1.0
    assert A.exact_sum(np.array([[1e16, 3.0], [1.0, -3.0], [-1e16, 0.5]])).tolist() == [1.0, 0.5]


def test_exact_sum_flags_terms_out_of_range():
    """A NaN, an infinity or a term over 2^70 makes its column NaN, not a wrong number."""
    out = A.exact_sum(np.array([[1.0, np.nan, 2.0 ** 71], [2.0, 1.0, 1.0]]))
    assert out[0] == 3.0 and np.isnan(out[1]) and np.isnan(out[2])


def test_accumulator_is_the_exact_sum_of_all_its_terms():
    rng = np.random.default_rng(3)
    steps = [rng.standard_normal((50, 2)) * 10.0 ** rng.integers(-8, 8) for _ in range(40)]
    acc = A.ExactAccumulator(2)
    for s in steps:
        acc.add(s)
    every = np.concatenate(steps)
    assert acc.total().tolist() == [math.fsum(every[:, 0]), math.fsum(every[:, 1])]


class _Map:
    """A serial IndexMap: all nodes owned."""

    def __init__(self, n):
        self.size_local, self.num_ghosts = n, 0


def test_nodal_sum_does_not_depend_on_the_contributors_order():
    """The same contributors listed in another order give the same bits at every node, and the plain
    scatter's values to round-off."""
    rng = np.random.default_rng(7)
    n_nodes, n_c = 60, 400
    conn = np.array([rng.choice(n_nodes, 4, replace=False) for _ in range(n_c)])
    keys = A.input_keys(conn, np.arange(n_nodes) * 7 + 3)
    vals = rng.standard_normal((n_c, 4, 3)) * 10.0 ** rng.integers(-3, 6, (n_c, 1, 1))
    out = np.zeros((n_nodes, 3))
    A.NodalSum(MPI.COMM_SELF, _Map(n_nodes), conn, keys)(vals, out)
    perm = rng.permutation(n_c)
    out2 = np.zeros((n_nodes, 3))
    A.NodalSum(MPI.COMM_SELF, _Map(n_nodes), conn[perm], keys[perm])(vals[perm], out2)
    assert np.array_equal(out, out2)
    ref = np.zeros((n_nodes, 3))
    np.add.at(ref, conn.ravel(), vals.reshape(-1, 3))
    np.testing.assert_allclose(out, ref, rtol=1e-12, atol=1e-12 * np.abs(vals).max())
    per_cell = np.zeros((n_nodes, 3))  # one value per contributor, the same at its four nodes
    A.NodalSum(MPI.COMM_SELF, _Map(n_nodes), conn, keys)(vals[:, 0], per_cell)
    ref = np.zeros((n_nodes, 3))
    np.add.at(ref, conn.ravel(), np.repeat(vals[:, 0], 4, axis=0))
    np.testing.assert_allclose(per_cell, ref, rtol=1e-12, atol=1e-12 * np.abs(vals).max())


@pytest.mark.mpi
def test_nodal_sum_is_the_same_on_any_partition():
    """Per-cell values that depend only on the cell's input vertices, summed at the nodes on COMM_WORLD and on
    one rank: the same bits at every node (compared by input node number)."""
    def run(comm):
        m = dmesh.create_box(comm, [[0, 0, 0], [1, 1, 2]], [4, 4, 8], dmesh.CellType.tetrahedron)
        imap = m.geometry.index_map()
        dofs = dx.geometry_dofs(m)[: m.topology.index_map(3).size_local].astype(np.int64)
        inp = np.asarray(m.geometry.input_global_indices, dtype=np.int64)
        keys = A.input_keys(dofs, inp)
        vals = np.sin(keys[:, :, None] * np.array([0.37, 1.1, 2.3]) + keys.sum(axis=1)[:, None, None]) * 1e3
        out = np.zeros((imap.size_local + imap.num_ghosts, 3))
        A.NodalSum(comm, imap, dofs, keys)(_by_node(vals, dofs, inp), out)
        n = imap.size_local
        return _gathered(comm, inp[:n], out[:n])

    world = run(MPI.COMM_WORLD)
    alone = run(MPI.COMM_SELF)
    if MPI.COMM_WORLD.rank == 0:
        assert np.array_equal(world, alone)


def _by_node(vals, dofs, inp):
    """The value of a cell at its node j taken from the node's rank in the cell's sorted keys, so that each
    (cell, node) term is the same on any partition."""
    rank = np.argsort(np.argsort(inp[dofs], axis=1), axis=1)
    return np.take_along_axis(vals, rank[:, :, None], axis=1)


def _gathered(comm, idx, values):
    parts = comm.allgather((idx, values))
    i = np.concatenate([p[0] for p in parts])
    v = np.concatenate([p[1] for p in parts])
    return v[np.argsort(i)]
