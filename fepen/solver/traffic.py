"""The communication of a deformable run's step, counted and modelled (issue 62; docs/theory.md §11.1).

Every exchange a step of the default deformable run makes between ranks goes through a counter here (a few integer
adds and two clock reads per call: nothing next to the step's milliseconds, and no number of the run changes):

========================  ==========================================================  ===============
exchange                  what                                                        calls per step
========================  ==========================================================  ===============
``volumes``               the nodal volumes' ghost sum: a reverse add, then a         2
                          forward scatter (block size = the number of materials)
``forces``                the internal forces' reverse add (block size 3)             1
``accelerations``         the accelerations' forward scatter (block size 3)           1
``load_points``           the target's point forces summed at their nodes: one        1
                          neighbourhood all-to-all (fepen.solver.assembly.NodalSum)
``inverted``              the inverted-cell flag, an allreduce of 1 number            1 (2+ ranks)
``nose_axis``             the nose tip and tail positions, an allreduce of 6 numbers  1 (2+ ranks)
``tunnel``                the tunnel wall's radii (effects.tunnel), an allreduce      1 (2+ ranks)
``stable_step``           the smallest h/c, an allreduce of 1 number                  1/STEP_EVERY
``exact_sums``            the exact sums' integer limbs (history rows, stop checks)   per row
========================  ==========================================================  ===============

Bytes are the payload this rank sends (8 per number): a reverse add sends each ghost entry to its owner; a forward
scatter sends each owned entry to every rank that ghosts it; an allreduce is counted as its payload once. The
ghost scatters' and the load points' bytes follow from the partition before the run (GhostPlan, step_bytes): the
model's exact count, which the run's counters must meet (tests/system/test_scaling_model.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from time import perf_counter

import numpy as np

__all__ = ["KINDS", "STEP_KINDS", "Counter", "Ledger", "LEDGER", "reset", "count", "rounds", "step_done", "GhostPlan",
           "step_bytes", "block", "of_run", "imbalance", "Machine", "step_time", "largest_run"]

#: the exchanges counted, in the order the summary lists them
KINDS = ("volumes", "forces", "accelerations", "load_points", "inverted", "nose_axis", "tunnel", "stable_step",
         "exact_sums")
#: those whose bytes per step the partition fixes before the run (step_bytes)
STEP_KINDS = ("volumes", "forces", "accelerations", "load_points")
#: bytes per number (float64 or int64)
WORD = 8


class Counter:
    """One exchange's totals on this rank: calls, bytes sent, messages sent, wall seconds inside the calls."""

    __slots__ = ("calls", "bytes", "messages", "wait_s")

    def __init__(self):
        self.calls = self.bytes = self.messages = 0
        self.wait_s = 0.0


class Ledger(dict):
    """{exchange: Counter} and ``steps``, the solver steps counted since the last reset."""

    steps = 0


#: this process's counters by exchange, and the steps taken since the last reset
LEDGER = Ledger((k, Counter()) for k in KINDS)


def reset() -> None:
    """Every counter back to zero (a run calls it before its time loop)."""
    for k in KINDS:
        LEDGER[k] = Counter()
    LEDGER.steps = 0


def count(kind: str, calls: int, nbytes: int, messages: int, t0: float) -> None:
    """Count ``calls`` calls of an exchange that began at perf_counter() ``t0`` and has just ended.

    Args:
        kind: one of KINDS. calls: calls made. nbytes: bytes this rank sent. messages: messages it sent.
        t0: perf_counter() when the calls began.
    """
    c = LEDGER[kind]
    c.calls += calls
    c.bytes += nbytes
    c.messages += messages
    c.wait_s += perf_counter() - t0


def rounds(ranks: int) -> int:
    """The messages a rank sends in an allreduce of the model (recursive doubling): ceil(log2 ranks)."""
    return math.ceil(math.log2(ranks)) if ranks > 1 else 0


def step_done() -> None:
    """One solver step taken."""
    LEDGER.steps += 1


@dataclass(frozen=True)
class GhostPlan:
    """The ghost entries of a nodal index map, as its scatters move them (entries are nodes; times the block size
    for numbers).

    Attributes:
        reverse: this rank's ghosts (a reverse add sends each to its owner).
        reverse_ranks: the ranks owning them (messages of a reverse add).
        forward: this rank's owned nodes ghosted elsewhere, once per rank ghosting each (a forward scatter's).
        forward_ranks: the ranks ghosting them (messages of a forward scatter).
    """

    reverse: int = 0
    reverse_ranks: int = 0
    forward: int = 0
    forward_ranks: int = 0

    @classmethod
    def of(cls, index_map, comm) -> GhostPlan:
        """The plan of a dolfinx IndexMap (num_ghosts and owners: dolfinx 0.5 and 0.11 alike); collective (one
        all-to-all of counts at set-up)."""
        if comm.size == 1:
            return cls()
        owners = np.asarray(index_map.owners, dtype=np.int64)[: index_map.num_ghosts]
        per_owner = np.bincount(owners, minlength=comm.size)
        ghosted = np.asarray(comm.alltoall([int(n) for n in per_owner]), dtype=np.int64)
        return cls(int(index_map.num_ghosts), int(np.count_nonzero(per_owner)), int(ghosted.sum()),
                   int(np.count_nonzero(ghosted)))


def step_bytes(plan: GhostPlan, materials: int, load_sent: int, ranks: int) -> int:
    """The bytes a rank sends in one step's STEP_KINDS exchanges (the model, exact): the volumes' reverse add and
    forward scatter (``materials`` numbers a node), the forces' reverse add and the accelerations' forward scatter
    (3), the load points' forces to other ranks' nodes (``load_sent`` entries of 3); 0 on one rank.

    Args:
        plan: the rank's GhostPlan. materials: the nodal volumes' block size. load_sent: the target load's nodal sum
            entries this rank sends (NodalSum.sent). ranks: the communicator's size.
    """
    if ranks == 1:
        return 0
    return WORD * ((plan.reverse + plan.forward) * (materials + 3) + 3 * load_sent)


def imbalance(work: list) -> float:
    """The load's imbalance: the largest rank's work over the mean (1: balanced)."""
    w = np.asarray(work, dtype=float)
    return float(w.max() / w.mean()) if len(w) and w.mean() > 0 else 1.0


def block(comm, cells: int, load_points: int, ghosts: int, model_bytes: int) -> dict:
    """summary.json's ``communication`` block (collective; docs/results.md): the counters since the last reset,
    per rank, with each rank's cells, load points, ghost nodes and the model's bytes per step.

    Args:
        comm: the run's communicator. cells, load_points, ghosts: this rank's owned cells, load points and ghost
            nodes. model_bytes: step_bytes of this rank.
    """
    mine = (cells, load_points, ghosts, model_bytes, [(LEDGER[k].calls, LEDGER[k].bytes, LEDGER[k].wait_s)
                                                      for k in KINDS])
    ranks = comm.allgather(mine)
    steps = max(LEDGER.steps, 1)
    total_bytes = [sum(b for _, b, _ in r[4]) for r in ranks]
    total_wait = [sum(w for _, _, w in r[4]) for r in ranks]
    return {"steps": LEDGER.steps,
            "cells": [r[0] for r in ranks], "load_points": [r[1] for r in ranks], "ghost_nodes": [r[2] for r in ranks],
            "imbalance": imbalance([r[0] + r[1] for r in ranks]),
            "bytes_per_step": [b / steps for b in total_bytes],
            "model_bytes_per_step": [r[3] for r in ranks],
            "wait_s_per_step": [w / steps for w in total_wait],
            "exchanges": [{"name": k, "calls": [r[4][i][0] for r in ranks], "bytes": [r[4][i][1] for r in ranks],
                           "wait_s": [r[4][i][2] for r in ranks]} for i, k in enumerate(KINDS)]}


def of_run(comm, solver, load) -> dict:
    """summary.json's ``communication`` block of a deformable run (collective): ``block`` with the solver's
    cells and ghosts, the load's points (a rigid wall: none) and the model's bytes a step from this partition.

    Args:
        comm: the run's communicator. solver: its ExplicitSolver. load: its external load.
    """
    sent = getattr(load, "sent_terms", 0)
    model_bytes = step_bytes(solver.ghosts, len(solver.materials), sent, comm.size)
    return block(comm, solver.n_cells, len(getattr(load, "last_X", ())), solver.ghosts.reverse, model_bytes)


# -----------------------------------------------------------------------------------------------------------
# the step's time against ranks and cells (docs/theory.md §11.1)

@dataclass(frozen=True)
class Machine:
    """The model's constants.

    Attributes:
        t_cell_s: wall seconds of one cell's step on one core (its share of the load points included).
        alpha_s: a message's latency (s). beta_B_s: the bandwidth (bytes/s).
        t_step_s: a step's fixed wall seconds on every rank, whatever its cells (the interpreter's dispatch of the
            step's passes, the load's and the clock's arithmetic).
        reductions: allreduces per step (each ceil(log2 ranks) latencies): the inverted flag, the nose axis, the
            tunnel, a quarter of the stable step's.
    """

    t_cell_s: float
    alpha_s: float
    beta_B_s: float
    t_step_s: float = 0.0
    reductions: float = 3.25


def step_time(m: Machine, cells: float, ranks: int, imbalance_: float, messages: float, nbytes: float) -> float:
    """Wall seconds of a step: the fixed part, the busiest rank's cells, its messages and bytes, the allreduces'
    rounds.

    Args:
        m: the Machine. cells: all cells. ranks: ranks. imbalance_: the busiest rank's work over the mean.
        messages, nbytes: the busiest rank's messages and bytes a step.
    """
    return (m.t_step_s + imbalance_ * cells / ranks * m.t_cell_s + messages * m.alpha_s + nbytes / m.beta_B_s
            + m.reductions * rounds(ranks) * m.alpha_s)


def largest_run(time_of, budget_s: float, lo: float = 1e3, hi: float = 1e13) -> float:
    """The most cells whose whole run takes at most ``budget_s`` (bisection on log cells).

    Args:
        time_of: cells -> wall seconds of the whole run (increasing). budget_s: the wall time allowed.
        lo, hi: the bracket (cells).
    """
    if time_of(lo) > budget_s:
        return 0.0
    if time_of(hi) <= budget_s:
        return hi
    for _ in range(200):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if time_of(mid) <= budget_s else (lo, mid)
        if hi / lo < 1 + 1e-9:
            break
    return lo
