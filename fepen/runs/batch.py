"""Rigid shots in batches: many shots of one projectile integrated by one compiled call (fepen/runs/rigid_batch.c)
instead of one ``RigidRun.run()`` each, for the studies that run thousands of them (``fepen sweep``, the limit
studies, ``fepen validate-depth``).

Each shot is set up by ``RigidRun`` as usual (its projectile, load points, law, crater, step, initial state);
the kernel then advances every shot of a projectile with the single path's own compiled RK4 step (rk4, which
RigidRun.step calls through rigid_step: Step), its stop rules (perforated, ricochet, embedded with its
interpolation back to V·a = 0, the hard end) and its history clock (the largest nose depth and energy error of
the rows the single path would record); the final row and the summary are then made by
``RigidRun`` itself from the final state. The single path (``RigidRun.run``) stays the reference: the batch
gives its summaries bitwise (tests/unit/runs/test_batch.py), and falls back to it, shot by shot and
automatically, for what the kernel does not cover:

- wear (``effects.wear``) and layered targets (``fepen.laws.layers``): the single path runs the shot;
- a results directory (the batch writes no history.csv), a target that is not a ``TargetLaw``;
- FEPEN_KERNEL=numpy or a machine where the C kernels do not build;
- a shot whose state or history row turns non-finite (the single path runs it again and stops it with its own
  error).
"""

from __future__ import annotations

import time

import numpy as np
from mpi4py import MPI

from fepen import native
from fepen.errors import InputError, SimulationError
from fepen.laws import target as tg
from fepen.laws import tunnel
from fepen.runs import events
from fepen.runs.rigid import SHOT_NUMBERS, RigidRun, kernel, point_arrays, shot_numbers

__all__ = ["summaries", "reason", "kernel", "SHOT_NUMBERS", "RESULTS", "OUTCOMES"]

#: the per-shot results it writes: its R_ members and their names here (checked as fepen.runs.rigid's shot numbers are)
_RESULT_LAYOUT = (("R_T", "t"), ("R_STEPS", "steps"), ("R_OUTCOME", "outcome"), ("R_WORK", "work"),
                  ("R_ENTERED", "entered"), ("R_MAX_NOSE", "max_nose_mm"), ("R_MAX_ERROR", "max_error"),
                  ("R_ROWS", "rows"), ("R_STATUS", "status"))
RESULTS = tuple(name for _, name in _RESULT_LAYOUT)
native.shares("rigid_batch", "R_", [(member, 1) for member, _ in _RESULT_LAYOUT])
#: outcome codes of the kernel (events_kernel.h's, which rigid_batch.c includes: checked with the events kernel)
OUTCOMES = events.OUTCOMES
_R = {k: i for i, k in enumerate(RESULTS)}


def reason(run) -> str | None:
    """Why a RigidRun (set up, not run) cannot go in a batch, or None when it can."""
    if kernel() is None:
        return "the C kernels are not built"
    if run.out is not None:
        return "it writes a results directory"
    if run.wear is not None:
        return "wear"
    why = run.shot.target.not_batched()
    if why is not None:
        return why
    if run.crossings is not None or len(run.outputs) != 1 or run.history.clock.next != 0.0:
        return "layer crossings or outputs"
    if run.t != 0.0 or run.step_count != 0:
        return "not at its start"
    return None


def summaries(scenes, comm=None, history: bool = True) -> list:
    """The summaries of rigid shots, as ``RigidRun(scene, None, comm, history=history).run()`` returns them:
    in batches per projectile where the kernel covers the shot, else by the single path.

    Args:
        scenes: the shots (Scenes or resolved Shots), rigid fidelity. comm: the communicator of every shot
            (None: COMM_SELF). history: as RigidRun's (False: the final row alone).

    Returns:
        One item per shot, in order: its summary, or the InputError or SimulationError it raised.
    """
    from fepen.runs import shot

    comm = MPI.COMM_SELF if comm is None else comm
    out: list = [None] * len(scenes)
    groups: dict = {}
    for i, sc in enumerate(scenes):
        try:
            sh = sc if isinstance(sc, shot.Shot) else shot.resolve(sc, toml=False)  # no results directory
            run = RigidRun(sh, None, comm, history=history)
        except (InputError, SimulationError) as err:
            out[i] = err
            continue
        if reason(run) is not None:
            out[i] = _single(run)
            continue
        groups.setdefault((id(run.pts), run.body.centre0.tobytes(), run.body.r0.shape), []).append((i, run))
    for members in groups.values():
        for (i, _run), summary in zip(members, _integrate([run for _, run in members])):
            out[i] = summary if summary is not None else _single(RigidRun(scenes[i], None, comm, history=history))
    return out


def _single(run):
    try:
        return run.run()
    except (InputError, SimulationError) as err:
        return err


def _tunnel_room(runs) -> int:
    """Stations a batch's tunnels need at most: the shoulder's path within the hard end, at most twice the
    striking speed times it (speed only falls; the turning adds the arm's sweep), over the spacing."""
    need = [2.0 * r.v0 * r.end / r.tunnel.buf[tunnel.T_SPACING] + 2.0 for r in runs if r.tunnel is not None]
    return int(min(tunnel.CAPACITY, max(need))) if need else 0


def _integrate(runs: list) -> list:
    """The summaries of runs that share their load points (None for a shot the single path must run)."""
    from fepen.io import results

    lib, (points, moment), gauss = kernel()
    g, body = runs[0].pts, runs[0].body
    n, k = len(runs), len(body.r0)
    const = point_arrays(runs[0])
    sp = np.ascontiguousarray([shot_numbers(r) for r in runs], dtype=float)
    numbers = [tg._law_numbers(r.law) for r in runs]  # padded to the longest (the random fields' modes)
    laws = np.zeros((n, max(len(a) for a in numbers)))
    for row, a in zip(laws, numbers):
        row[:len(a)] = a
    y = np.ascontiguousarray([r.state.as_array() for r in runs], dtype=float)
    res = np.zeros((n, len(RESULTS)))
    cap = _tunnel_room(runs)
    tlen = tunnel.HEADER + cap * (tunnel.STATION + tunnel.SECTORS)
    tunnels = np.zeros((n, tlen)) if cap else None
    xi = np.ascontiguousarray(g["X"][:, 1], dtype=float)
    t0 = time.perf_counter()
    check = lib.rigid_batch(n, k, *[a.ctypes.data for a in const], gauss.ctypes.data, len(gauss) // 2, points, moment,
                            sp.ctypes.data, laws.ctypes.data, laws.shape[1], y.ctypes.data, res.ctypes.data,
                            xi.ctypes.data, cap, tunnel.SECTORS, None if tunnels is None else tunnels.ctypes.data)
    loop_s = (time.perf_counter() - t0) / n
    if check < 0:
        raise MemoryError("rigid_batch: no memory for its scratch arrays (or a law of another length)")
    assert check == len(SHOT_NUMBERS) * 10000 + len(RESULTS) * 100 + laws.shape[1], \
        "rigid_batch.c and fepen.runs.batch (or target.py's _law_numbers) disagree on a layout"
    from fepen.laws.rigid_body import RigidState

    out = []
    for run, yi, ri in zip(runs, y, res):
        if ri[_R["status"]] != 0.0:
            out.append(None)
            continue
        run.state = RigidState.from_array(yi)
        if run.tunnel is not None:  # the shot's tunnel as it ended (its room: the batch's, all it needed)
            ti = tunnels[len(out)]
            if ti[tunnel.T_M] >= cap:  # full: the single path, whose room is larger, runs the shot
                out.append(None)
                continue
            m = int(ti[tunnel.T_M])
            run.tunnel.buf[:tunnel.HEADER + m * (tunnel.STATION + tunnel.SECTORS)] = ti[:tunnel.HEADER + m * (
                tunnel.STATION + tunnel.SECTORS)]
            run.tunnel.buf[tunnel.T_CAP] = tunnel.CAPACITY
        run.t, run.step_count, run.w_ext = float(ri[_R["t"]]), int(ri[_R["steps"]]), float(ri[_R["work"]])
        run.rules.entered = bool(ri[_R["entered"]])
        try:
            run.finish_loop()  # the final row, with the force at the final state, as the single path makes it
        except SimulationError:  # a non-finite final row: the single path stops the shot with its own error
            out.append(None)
            continue
        if ri[_R["rows"]] > 0:  # the recorded rows' largest depth and energy error, as one row before it
            top = list(run.rows[-1])
            top[results.COL["nose_y_mm"]] = float(ri[_R["max_nose_mm"]])
            top[results.COL["energy_error"]] = float(ri[_R["max_error"]])
            run.rows.insert(0, top)
        outcome = OUTCOMES[int(ri[_R["outcome"]])]
        out.append(run.write_summary(outcome or "ended", loop_s))
    return out
