"""The explicit step's length (docs/theory.md §3): the stable step, safety x the calibrated gain x min over
cells of h/c on the current mesh; its calibration by power iteration on M⁻¹K of the undeformed body; the coming
step, evened out before an output time so that the last one lands on it; the collapse of the step stopped.
Functions of an ExplicitSolver ``s`` (fepen.solver.explicit), which calls them.
"""

from __future__ import annotations

import math
from time import perf_counter

import numpy as np
from mpi4py import MPI

from fepen.solver import failures, kernels, traffic

__all__ = ["stable", "new_stable", "choose", "calibrate", "LANDING_SLIVER", "GAIN_QUANTUM"]

#: a landing time closer than this fraction of the stable step is not landed on (the output it is for is
#: written at the step after, as without landing): no step that short
LANDING_SLIVER = 1e-6
#: the eigenvalue step's gain over the altitude estimate is rounded down to a multiple of this (calibrate_step)
GAIN_QUANTUM = 0.005


def stable(s) -> float:
    """Safety x min over cells of (shortest altitude / dilatational speed), current mesh, all ranks."""
    # a scratch array: nodal_vol must keep the ghost-summed volumes of the last step (energies use them)
    _, _, h_c, _ = kernels.volumes_and_step(s.positions(), s.dofs, s.orient, s.vol0, s.mat, s.cell.speed,
                                            np.empty(s.n_cells))
    return s.clock.safety * s.clock.step_gain * s.comm.allreduce(h_c, op=MPI.MIN)


def new_stable(s, h_c: float) -> None:
    """The next stable Δt from this rank's h/c (all ranks agree), or SimulationError if it collapsed."""
    t0 = perf_counter()
    new = s.clock.safety * s.clock.step_gain * s.comm.allreduce(h_c, op=MPI.MIN)
    traffic.count("stable_step", 1, traffic.WORD if s.comm.size > 1 else 0, traffic.rounds(s.comm.size), t0)
    if not (new > 1e-3 * s.clock.dt0):
        failures.step_collapsed(s, h_c, new)
    s.clock.dt_stable = new
    s.clock.dt_min = min(s.clock.dt_min, new)


def choose(s) -> None:
    """The coming step ``s.dt``: the stable step, or, with a landing time ahead (``s.landing``), the time to it
    (of the outputs whose interval is at least the stable step) cut into the fewest equal steps no longer than
    the stable step, the last of which ends on it (central
    differences take any shorter step; the stable step bounds it from above). Equal steps, not one short one
    before each landing: a step that changes every interval pumps energy into the highest modes (a C3 run at
    300 m/s, elastic: an energy error of 2.6e-3 with one short step per microsecond, 1.2e-5 without landing)."""
    dt, s.clock.land_at = s.clock.dt_stable, -1.0
    if s.landing is not None:
        target = s.landing(s.t, dt)
        r = target - s.t
        if LANDING_SLIVER * dt < r < math.inf:
            n = max(1, math.ceil(r / dt * (1.0 - 1e-12)))
            dt = r / n
            if n == 1:
                s.clock.land_at = target
    s.dt = dt


def calibrate(s, iterations: int = 400, rtol: float = 1e-5) -> tuple[float, float]:
    """The critical step 2/ω_max of the undeformed, unstressed body, by power iteration on M⁻¹K.

    K d is the internal force of a tiny displacement ε d from the reference state (the solver's own
    element, nodal pressure included), so ω_max is that of the discrete system actually integrated.
    Sets ``step_gain`` = (2/ω_max) / min(h/c) (rounded down to a multiple of GAIN_QUANTUM), by which the
    altitude estimate is multiplied from then
    on (it keeps tracking the deformed mesh). Call before set_initial: the state is zeroed after.
    The start vector is a smooth-free oscillating field of the reference positions, the same on any
    partition. The Rayleigh quotient approaches ω_max² from below, so the safety factor keeps a margin.

    Returns:
        (critical step of the undeformed body (s), step_gain).
    """
    n = s.n_owned
    X = s.X
    L = float(np.ptp(X, axis=0).max())
    d = np.stack([np.sin(X @ np.array(w) / L * 977.0 + k) for k, w in
                  enumerate(([1.0, 0.31, 0.57], [0.23, 1.0, 0.71], [0.61, 0.43, 1.0]))], axis=1)
    external, s.external = s.external, None
    eps = 1e-9 * L
    lam = lam_prev = 0.0
    for it in range(iterations):
        if s.node.fixed is not None:
            d[s.node.fixed] = 0.0
        norm = np.sqrt(s.comm.allreduce(float(np.sum(s.mass[:n, None] * d[:n] ** 2)), op=MPI.SUM))
        d /= norm
        s.U[:] = eps * d
        s.Vel[:] = eps * d
        s.s[:] = 0.0
        s._forces(1.0)  # increment v dt = eps d from the reference: f_int = K eps d
        Kd = s.node.fint[:n] / eps
        lam = s.comm.allreduce(float(np.sum(d[:n] * Kd)), op=MPI.SUM)
        s.Vel[:n] = Kd / s.mass[:n, None]
        s.node.v.x.scatter_forward()
        d = s.Vel.copy()
        if it > 30 and abs(lam - lam_prev) < rtol * lam:
            break
        lam_prev = lam
    s.external = external
    for a in (s.U, s.Vel, s.s, s.node.fint, s.fext, s.acc):
        a[:] = 0.0
    s.eps_p[:] = 0.0
    _, _, h_c, _ = kernels.volumes_and_step(s.positions(), s.dofs, s.orient, s.vol0, s.mat,
                                               s.cell.speed, np.empty(s.n_cells))
    h_c = s.comm.allreduce(h_c, op=MPI.MIN)
    dt_crit = 2.0 / np.sqrt(lam)
    # rounded down to a multiple of GAIN_QUANTUM: the Rayleigh quotient of a 1e-9 L displacement carries
    # round-off of ~1e-6 that depends on the partition; rounded, the step is the same on any number of
    # ranks (unless the gain falls within ~1e-6 of a multiple), and at most GAIN_QUANTUM / 2 smaller
    s.clock.step_gain = max(math.floor(dt_crit / h_c / GAIN_QUANTUM) * GAIN_QUANTUM, GAIN_QUANTUM)
    s.dt = s.clock.dt_stable = s.clock.dt0 = s.clock.dt_min = s.stable_step()
    return dt_crit, s.clock.step_gain
