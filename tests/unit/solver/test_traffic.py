"""fepen.solver.traffic: the scaling model's arithmetic (bytes a step from the partition, the step's time, the
largest run an hour allows), the counters, and on 2 ranks (the MPI lane) the ghost plan against what dolfinx's own
scatters move and the counted bytes of a solver's steps against the model's."""

import math

import numpy as np
import pytest
from mpi4py import MPI

from fepen.solver import traffic


def test_step_bytes_is_the_sum_of_the_exchanges_payloads():
    """One step's bytes by hand: the volumes' reverse add and forward scatter (2 materials a node), the forces'
    reverse add, the accelerations' forward scatter (3 a node), the load points' terms (3 each)."""
    plan = traffic.GhostPlan(reverse=100, reverse_ranks=2, forward=90, forward_ranks=2)
    volumes = 8 * 2 * (100 + 90)
    forces, accelerations, load = 8 * 3 * 100, 8 * 3 * 90, 8 * 3 * 40
    assert traffic.step_bytes(plan, 2, 40, 4) == volumes + forces + accelerations + load == 8560
    assert traffic.step_bytes(plan, 2, 40, 1) == 0  # one rank sends nothing
    assert isinstance(traffic.step_bytes(plan, 1, 7, 2), int)


def test_rounds_and_imbalance():
    assert [traffic.rounds(p) for p in (1, 2, 3, 4, 8, 9, 64)] == [0, 1, 2, 2, 3, 4, 6]
    assert traffic.imbalance([100, 100]) == 1.0
    assert traffic.imbalance([150, 50, 100]) == pytest.approx(1.5)
    assert traffic.imbalance([]) == 1.0


def test_step_time_adds_the_busiest_ranks_cells_its_messages_and_the_reductions():
    m = traffic.Machine(t_cell_s=1e-7, alpha_s=2e-6, beta_B_s=1e9, t_step_s=5e-4, reductions=3.0)
    t = traffic.step_time(m, cells=1e6, ranks=8, imbalance_=1.1, messages=10, nbytes=5e5)
    assert t == pytest.approx(5e-4 + 1.1 * 1e6 / 8 * 1e-7 + 10 * 2e-6 + 5e5 / 1e9 + 3.0 * 3 * 2e-6, rel=1e-14)
    assert traffic.step_time(m, 1e6, 1, 1.0, 0, 0) == pytest.approx(0.1005, rel=1e-14)  # one rank: no messages


def test_largest_run_meets_the_budget():
    """Steps ∝ cells^(1/3), cells a step ∝ cells: a run's time ∝ cells^(4/3); the largest within an hour found
    to 1e-6."""
    def time_of(cells):
        return 1e-6 * cells ** (4.0 / 3.0)

    n = traffic.largest_run(time_of, 3600.0)
    assert n == pytest.approx((3600.0 / 1e-6) ** 0.75, rel=1e-6)
    assert time_of(n) <= 3600.0
    assert traffic.largest_run(time_of, 1e-9) == 0.0  # not even the smallest
    assert traffic.largest_run(lambda c: 0.0, 1.0) == 1e13  # any: the bracket's top


def test_counters_count_and_reset():
    traffic.reset()
    traffic.count("forces", 1, 240, 1, 0.0)
    traffic.count("forces", 1, 240, 1, 0.0)
    traffic.step_done()
    c = traffic.LEDGER["forces"]
    assert (c.calls, c.bytes, c.messages) == (2, 480, 2) and c.wait_s > 0.0
    assert traffic.LEDGER.steps == 1
    block = traffic.block(MPI.COMM_SELF, cells=10, load_points=5, ghosts=0, model_bytes=0)
    forces = next(e for e in block["exchanges"] if e["name"] == "forces")
    assert forces["calls"] == [2] and forces["bytes"] == [480]
    assert block["bytes_per_step"] == [480.0] and block["imbalance"] == 1.0
    assert [e["name"] for e in block["exchanges"]] == list(traffic.KINDS)
    traffic.reset()
    assert traffic.LEDGER["forces"].calls == 0 and traffic.LEDGER.steps == 0


def rod_solver(comm):
    from test_explicit import rod

    return rod("projectile.diameter=0.00762", "projectile.length=0.0254", "mesh.size=0.002", comm=comm)[2]


@pytest.mark.mpi
def test_ghost_plan_is_what_the_scatters_move_and_the_steps_count_it():
    """On 2 ranks: the plan's forward entries are the number of (owned node, ghosting rank) pairs, counted by a
    reverse add of ones from every ghost; its reverse entries are the ghosts; over the ranks they agree. Ten steps
    of a solver count, exchange by exchange, steps x the model's bytes."""
    comm = MPI.COMM_WORLD
    if comm.size < 2:
        pytest.skip("ghosts need 2 ranks: the MPI lane")
    from fepen import dolfinx_api as dx

    s = rod_solver(comm)
    imap = s.V.dofmap.index_map
    plan = traffic.GhostPlan.of(imap, comm)
    ones = dx.new_vector(imap, bs=1)
    ones.array[:] = 0.0
    ones.array[imap.size_local:] = 1.0
    dx.scatter_reverse_add(ones)
    assert plan.forward == int(round(ones.array[: imap.size_local].sum())) > 0
    assert plan.reverse == imap.num_ghosts > 0
    assert comm.allreduce(plan.forward) == comm.allreduce(plan.reverse)
    if comm.size == 2:
        assert plan.forward_ranks == plan.reverse_ranks == 1
    s.set_initial(velocity=lambda X: np.tile([0.0, -200.0, 0.0], (len(X), 1)))
    traffic.reset()
    for _ in range(10):
        s.step()
    led = traffic.LEDGER
    assert led.steps == 10
    assert led["volumes"].bytes == 10 * 8 * len(s.materials) * (plan.reverse + plan.forward)
    assert led["forces"].bytes == 10 * 24 * plan.reverse and led["accelerations"].bytes == 10 * 24 * plan.forward
    assert sum(led[k].bytes for k in traffic.STEP_KINDS) == 10 * traffic.step_bytes(plan, len(s.materials), 0,
                                                                                     comm.size)
    assert [led[k].calls for k in ("volumes", "forces", "accelerations", "inverted")] == [20, 10, 10, 10]
    assert led["stable_step"].calls == math.ceil(10 / 4)
