"""The closing figures shared over the ranks (fepen.runs.closing.shared): every job runs once, the heaviest
first, each on the rank with the least weight so far, and a failure is raised on every rank. On one process
(here) rank 0 runs them all; the MPI lane's whole runs draw them on 2 ranks (tests/system/test_rank_invariance.py,
test_paraview.py)."""

import pytest
from mpi4py import MPI

from fepen.runs.closing import shared


def test_every_job_runs_once_in_order_on_one_rank():
    done = []
    shared(MPI.COMM_SELF, None, [(lambda k=k: done.append(k), (), 1.0) for k in range(5)])
    assert done == [0, 1, 2, 3, 4]


class Two:
    """A two-rank communicator as seen from one rank (allgather answers for both)."""

    def __init__(self, rank, other_says=None):
        self.rank, self.size, self.other_says = rank, 2, other_says

    def allgather(self, value):
        return [value, self.other_says] if self.rank == 0 else [self.other_says, value]


def test_equal_jobs_alternate_over_the_ranks():
    done = {0: [], 1: []}
    for rank in (0, 1):
        shared(Two(rank), None, [(lambda k=k, r=rank: done[r].append(k), (), 1.0) for k in range(3)])
    assert done == {0: [0, 2], 1: [1]}


def test_the_weights_balance_the_ranks():
    """The closing's figures as they weigh (two stress maps 4, hazard 2, history 1.5, trajectory 1): each
    map on its own rank, then the lighter figures to the less loaded one; every job once."""
    weights = [4.0, 4.0, 1.0, 2.0, 1.5]
    done = {0: [], 1: []}
    for rank in (0, 1):
        shared(Two(rank), None, [(lambda k=k, r=rank: done[r].append(k), (), w) for k, w in enumerate(weights)])
    assert sorted(done[0] + done[1]) == [0, 1, 2, 3, 4]
    assert done == {0: [0, 3], 1: [1, 2, 4]}
    load = [sum(weights[k] for k in done[r]) for r in (0, 1)]
    assert abs(load[0] - load[1]) <= 0.5


def test_a_failure_is_raised_on_its_rank_and_named_on_the_others():
    def boom():
        raise ValueError("no fields.h5")

    with pytest.raises(ValueError, match="no fields.h5"):
        shared(MPI.COMM_SELF, None, [(boom, (), 1.0), (lambda: None, (), 1.0)])
    with pytest.raises(RuntimeError, match="rank 1: ValueError: no fields.h5"):
        shared(Two(0, other_says="ValueError: no fields.h5"), None, [(lambda: None, (), 1.0), (boom, (), 1.0)])


def test_rank_0_lists_what_the_other_ranks_write_in_the_manifest(tmp_path):
    """The run's manifest (rank 0's claim on its directory) names the files rank 1 draws, before it draws them;
    rank 0's own files are recorded by its own writes."""
    from fepen import atomic

    claim = atomic.claim(tmp_path)
    try:
        shared(Two(0), tmp_path, [(lambda: None, ("a.png",), 1.0), (lambda: None, ("b.png", "b.vtu"), 1.0),
                                  (lambda: None, ("c.png",), 1.0)])
        assert claim.added == ["b.png", "b.vtu"]
    finally:
        atomic.release(claim)
