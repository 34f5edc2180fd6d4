"""Will the charge survive? The charge-safety criteria (fepen.laws.explosive) watched over a charged deformable
run, its verdict in summary.json's ``charge_safety``, one console line and the margin fields (docs/charge.md,
docs/theory.md §20).

The interface's friction heat is accumulated at every step by the contact itself (fepen.solver.shell_charge,
per pair and per unit area); the charge's stresses, the end gaps and their closure are read at every history
row. Each criterion keeps its largest demand so far, where (the undeformed body's point: the cell's centre,
the pair's node) and when (the row), and the first row at which it passed its threshold. The same bits on any
number of ranks: each rank's candidates are compared by value, then by place.
"""

from __future__ import annotations

import math

import numpy as np

from fepen.laws import explosive

__all__ = ["ChargeSafety", "CELL_FIELDS", "line", "settled", "FINISHED", "VERDICTS"]

#: the criteria read in the charge's cells (their margins are fields.xdmf's cell fields)
CELL_CRITERIA = ("strength", "tension")
#: the criteria of the interface's pairs
PAIR_CRITERIA = ("friction_work", "friction_power", "gap", "closure_speed")
#: the cell fields of the criteria with a threshold: the smallest margin of each charge cell so far
CELL_FIELDS = {c: f"charge_{c}_margin" for c in CELL_CRITERIA}
#: the margin fields' cap: the value of a cell off the charge, or without demand, or whose margin is larger
#: (every field finite; a margin of 100 is no concern)
MARGIN_CAP = 100.0
#: a pair is at an end of the charge (its front or its base) when its reference normal leans this much along
#: the axis (cos of 45°)
END_COS = math.sqrt(0.5)


class ChargeSafety:
    """The criteria of one charged deformable run (module docstring).

    Args:
        solver: the ExplicitSolver (material 1 the charge). contact: the ShellChargeContact, or None (a tied
            charge: no friction, no gap). thresholds: fepen.runs.shot.SafetyThresholds.

    Attributes:
        charge_length: the charge's length along the axis (m; its nodes' extent), for the set-forward pressure.
    """

    def __init__(self, solver, contact, thresholds, filter_hz: float = 0.0):
        from mpi4py import MPI

        s = solver
        self.solver, self.contact, self.th = s, contact, thresholds
        self.cells = np.flatnonzero(s.mat[: s.n_cells] == 1)
        y = s.X[s.dofs[self.cells], 1]
        lo = s.comm.allreduce(float(y.min()) if y.size else np.inf, op=MPI.MIN)
        hi = s.comm.allreduce(float(y.max()) if y.size else -np.inf, op=MPI.MAX)
        self.charge_length = max(hi - lo, 0.0)
        self.centres = s.X[s.dofs[self.cells]].mean(axis=1) if len(self.cells) else np.zeros((0, 3))
        self.peak = np.zeros((len(CELL_CRITERIA), len(self.cells)))  # each cell's largest demand so far
        self.peak_raw = np.zeros(1)  # this rank's largest unfiltered von Mises stress
        self._demand = np.empty((2, len(self.cells)))
        self._cand = np.empty((len(explosive.CRITERIA), 4))
        self.tau = 1.0 / (2.0 * math.pi * filter_hz) if filter_hz > 0.0 else 0.0
        self.filtered = np.zeros((len(self.cells), 6))  # each cell's low-passed stress
        self.t_last = 0.0
        if contact is not None:
            n_ref = contact.normals(s.X)  # out of the charge, in the undeformed body (axis +y, tail at +y)
            self.ends = np.flatnonzero((np.abs(n_ref[:, 1]) > END_COS) & contact.count)
            self.counted = np.flatnonzero(contact.count)
        # per criterion: [largest demand, t (s), x, y, z (m, the undeformed body), first time past the threshold]
        names = [c for c, _, _ in explosive.CRITERIA]
        self.names = names
        self.best = np.full((len(names), 6), np.nan)
        self.best[:, 0] = 0.0

    # ---- the rows -----------------------------------------------------------------------------------------
    def record(self, t: float) -> None:
        """Read the criteria at a history row (collective)."""
        s = self.solver
        cand = self._cand
        cand[:, 0] = -np.inf
        cand[:, 1:] = np.nan
        cells = self.cells
        if len(cells):
            alpha = -math.expm1(-(t - self.t_last) / self.tau) if self.tau > 0.0 else 1.0
            explosive.cell_demands(s.s, s.nodal_p, s.dofs, s.mat, cells, bool(s.passes.nodal), alpha, self.filtered,
                                   self._demand, self.peak, self.peak_raw)
            cand[0] = _largest(self._demand[0], self.centres)  # strength
            cand[1] = _largest(self._demand[1], self.centres)  # tension
        c = self.contact
        if c is not None:
            counted, ends = self.counted, self.ends
            cand[2] = _largest(c.friction_work[counted], c.X_pairs[counted])
            cand[3] = _largest(c.friction_power_peak[counted], c.X_pairs[counted])
            if len(ends):
                a, b = c.pa[ends], c.pb[ends]
                n = c.normal[ends]
                x = s.positions()
                gap = np.einsum("ij,ij->i", x[a] - x[b], n)
                closing = -np.einsum("ij,ij->i", s.Vel[a] - s.Vel[b], n)  # > 0: the gap shrinks
                pts = c.X_pairs[ends]
                cand[4] = _largest(np.maximum(gap, 0.0), pts)
                cand[5] = _largest(np.where(gap > 0.0, np.maximum(closing, 0.0), 0.0), pts)
        self.t_last = t
        everyone = s.comm.allgather(cand) if s.comm.size > 1 else [cand]
        for k, name in enumerate(self.names[:6]):  # the acceleration's is the closing's filtered peak
            rows = [tuple(r[k]) for r in everyone if r[k, 0] > -np.inf]
            if not rows:
                continue
            top = min(rows, key=lambda r: (-r[0], r[1], r[2], r[3]))  # the largest; a tie: the first place
            if top[0] > self.best[k, 0]:
                self.best[k, :5] = [top[0], t, *top[1:]]
            limit = self.th.values.get(name)
            if limit is not None and np.isnan(self.best[k, 5]) and top[0] >= limit:
                self.best[k, 5] = t

    # ---- the results --------------------------------------------------------------------------------------
    def summary(self, charge_peak: dict | None) -> dict:
        """summary.json's ``charge_safety`` (collective): per criterion its margin, demand, threshold, where and
        when; the governing criterion (the smallest margin among those with a threshold) and its margin.

        Args:
            charge_peak: the charge's filtered peak acceleration (fepen.runs.closing.accelerations' "charge_acc":
                filtered_g, t_s), or None.
        """
        out: dict = {"explosive": self.th.explosive}
        for k, (name, unit, what) in enumerate(explosive.CRITERIA):
            limit = self.th.values.get(name)
            demand, t, x, y, z, first = self.best[k]
            where = None
            if name == "acceleration_g":
                if charge_peak is None:
                    continue
                demand, t = abs(float(charge_peak["filtered_g"])), float(charge_peak["t_s"])
                first = t if limit is not None and demand >= limit else math.nan
                where = {"part": "charge (mass average)"}
            elif name in PAIR_CRITERIA and self.contact is None:
                continue  # a tied charge: no interface
            elif np.isfinite(x):
                where = {"part": "charge" if name in CELL_CRITERIA else "interface",
                         "behind_tip_mm": float(y) * 1e3, "radius_mm": float(np.hypot(x, z)) * 1e3,
                         "x_mm": float(x) * 1e3, "z_mm": float(z) * 1e3}
            m = explosive.margin(limit, float(demand))
            verdict = ("no threshold" if m is None else "no demand" if not math.isfinite(m)
                       else "beyond" if m < 1.0 else "within")
            out[name] = {"margin": m if m is not None and math.isfinite(m) else None, "verdict": verdict,
                         "demand": float(demand), "threshold": limit, "unit": unit,
                         "what": what, "where": where, "time_s": float(t) if np.isfinite(t) else None,
                         "first_beyond_s": float(first) if np.isfinite(first) else None,
                         "source": self.th.sources.get(name)}
        from mpi4py import MPI

        raw = self.solver.comm.allreduce(float(self.peak_raw[0]), op=MPI.MAX)
        if "strength" in out:  # the unfiltered peak beside: the mesh's ringing the low-pass takes off
            out["strength"]["demand_unfiltered"] = raw
        if charge_peak is not None:
            a = abs(float(charge_peak["filtered_g"])) * 9.80665
            out["acceleration_g"]["set_forward_pressure_Pa"] = explosive.set_forward_pressure(
                self.th.density, self.charge_length, a)
        judged = [(v["margin"], name) for name, v in out.items()
                  if isinstance(v, dict) and v.get("margin") is not None]
        gov = min(judged) if judged else None
        out["governing"] = gov[1] if gov else None
        out["margin"] = gov[0] if gov else None
        out["unjudged"] = [name for name, v in out.items() if isinstance(v, dict) and v["verdict"] == "no threshold"]
        return out

    def cell_fields(self) -> dict[str, np.ndarray]:
        """The margin fields of the cell criteria with a threshold: each charge cell's smallest margin so far
        (threshold over its largest demand), at most MARGIN_CAP, which is also the value off the charge and
        where there was no demand."""
        s = self.solver
        out = {}
        for k, name in enumerate(CELL_CRITERIA):
            limit = self.th.values.get(name)
            if limit is None:
                continue
            a = np.full(s.n_cells, MARGIN_CAP)
            peak = self.peak[k]
            a[self.cells] = np.minimum(limit / np.maximum(peak, limit / MARGIN_CAP), MARGIN_CAP)
            out[CELL_FIELDS[name]] = a
        return out

    def field_names(self) -> list[str]:
        """The cell fields cell_fields() writes."""
        return [CELL_FIELDS[c] for c in CELL_CRITERIA if self.th.values.get(c) is not None]

    def nodal_fields(self) -> dict[str, np.ndarray]:
        """``interface_friction_work_J_m2``: the friction heat per unit area so far at both nodes of each pair (0
        off the wall)."""
        c = self.contact
        a = np.zeros(self.solver.n_nodes)
        a[c.pa] = c.friction_work
        a[c.pb] = c.friction_work
        return {"interface_friction_work_J_m2": a}

    # ---- checkpoints ----------------------------------------------------------------------------------------
    def state(self) -> dict:
        return {"peak": self.peak, "best": self.best, "peak_raw": self.peak_raw, "filtered": self.filtered,
                "t_last": np.array([self.t_last])}

    def restore(self, state: dict) -> None:
        self.peak[:] = state["peak"]
        self.best[:] = state["best"]
        self.peak_raw[:] = state["peak_raw"]
        self.filtered[:] = state["filtered"]
        self.t_last = float(state["t_last"][0])


def cell_stress(solver, cells: np.ndarray) -> np.ndarray:
    """The Cauchy stress (k, 6: xx, yy, zz, xy, yz, xz; Pa, tension positive) of the owned cells ``cells``,
    as fepen.solver.diagnostics.stress_fields gives it for all."""
    s = solver
    stress = np.array(s.s[cells], dtype=float)
    if s.passes.nodal:  # the deviator with the nodal pressure's mean stress
        mat = np.maximum(s.mat[cells], 0)
        stress[:, :3] += s.nodal_p[s.dofs[cells], mat[:, None]].mean(axis=1)[:, None]
    return stress


def _largest(values: np.ndarray, points: np.ndarray) -> np.ndarray:
    """[largest value, x, y, z] of one rank's candidates: among equal values the point first in (x, y, z)
    order (any partition picks the same); [-inf, nan...] when there is none."""
    if not len(values):
        return np.array([-np.inf, np.nan, np.nan, np.nan])
    top = values.max()
    at = np.flatnonzero(values == top)
    if len(at) == 1:
        return np.array([top, *points[at[0]]])
    p = points[at]
    j = at[np.lexsort((p[:, 2], p[:, 1], p[:, 0]))[0]]
    return np.array([top, *points[j]])


#: the outcomes of a shot that ended by its own physics (fepen.errors.OUTCOMES): its demands are whole. "ended"
#: (run.end_time reached first) is not one: the projectile still moved, and a demand could still grow
FINISHED = ("embedded", "perforated", "ricochet", "rebound", "eroded")
#: a shot's verdict on its charge: "safe" (finished, every threshold's margin at least 1), "unsafe" (a demand
#: past its threshold, finished or not: it stays past it), "undecided" (not finished and nothing past a
#: threshold yet, or no result: a margin so far is only an upper bound of the shot's), "no threshold" (finished,
#: but no criterion has one)
VERDICTS = ("safe", "unsafe", "undecided", "no threshold")


def settled(summary: dict | None, status: str = "ok", message: str = "") -> dict:
    """A shot's outcome, whether it finished and its verdict on the charge (VERDICTS), from its own end state.

    Args:
        summary: its summary.json (None: no result). status: the study's record of it ("ok", "stopped",
            "bad-input", "failed", "missing"). message: the record's message (why it stopped).

    Returns:
        {"outcome": the summary's outcome (OUTCOMES' name) or, without a result, the status; "finished": bool;
        "verdict": one of VERDICTS; "reason": why a shot that did not finish has no verdict ("" else)}.
    """
    s = summary or {}
    outcome = s.get("outcome") or status
    finished = status == "ok" and outcome in FINISHED and "Hx_mm" in s
    margin = (s.get("charge_safety") or {}).get("margin")
    if margin is not None and margin < 1.0:
        verdict = "unsafe"
    elif finished:
        verdict = "safe" if margin is not None else "no threshold"
    else:
        verdict = "undecided"
    reason = ""
    if not finished:
        from fepen.errors import OUTCOMES

        if outcome == "ended":
            reason = (f"reached run.end_time = {s.get('end_time_s', float('nan')):.4g} s with the projectile still "
                      f"at {s.get('residual_speed_m_s', float('nan')):.4g} m/s: its demands so far are lower bounds")
        else:
            reason = message or s.get("stop_reason") or (OUTCOMES[outcome].meaning if outcome in OUTCOMES else
                                                         f"no result ({outcome})")
    return {"outcome": outcome, "finished": finished, "verdict": verdict, "reason": reason}


def line(block: dict) -> str:
    """The console's one line of a charge_safety block."""
    gov = block.get("governing")
    unjudged = ", ".join(block.get("unjudged", []))
    tail = f"; no threshold for {unjudged}" if unjudged else ""
    if gov is None:
        return f"charge safety ({block['explosive']}): no criterion has a threshold{tail}"
    c = block[gov]
    scale, unit = {"Pa": (1e-6, "MPa"), "m": (1e3, "mm"), "J/m^2": (1.0, "J/m^2"), "W/m^2": (1.0, "W/m^2"),
                   "m/s": (1.0, "m/s"), "g": (1.0, "g")}[c["unit"]]
    verdict = "beyond its threshold" if c["verdict"] == "beyond" else "within its threshold"
    w = c.get("where") or {}
    place = (f" {w['behind_tip_mm']:.1f} mm behind the nose tip, radius {w['radius_mm']:.1f} mm"
             if "behind_tip_mm" in w else f" ({w['part']})" if w else "")
    when = f", t = {c['time_s'] * 1e6:.1f} us" if c.get("time_s") is not None else ""
    others = ", ".join(f"{n} {block[n]['margin']:.3g}" for n in block
                       if isinstance(block[n], dict) and n != gov and block[n].get("margin") is not None)
    return (f"charge safety ({block['explosive']}): margin {c['margin']:.3g}, {gov} {verdict} "
            f"({c['demand'] * scale:.4g} against {c['threshold'] * scale:.4g} {unit}{place}{when})"
            + (f"; {others}" if others else "") + tail)
