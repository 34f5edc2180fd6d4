"""``fepen study charge-safety`` (docs/charge.md, docs/studies.md): the charge-safety verdict (summary.json's
``charge_safety``, fepen.runs.charge_safety) mapped over striking speed × obliquity (× angle of attack), one
deformable charged shot per point on the one executor (MPI groups, resumable from OUT/shots.jsonl), with the
speed at which the governing margin crosses 1 at each obliquity, the validated envelope's verdict on each point,
a table (charge_safety.csv, .md) and a map (charge_safety.png).
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass

from fepen import scene as fscene
from fepen.errors import InputError
from fepen.laws.explosive import CRITERIA
from fepen.runs.charge_safety import VERDICTS
from fepen.studies.limits import base_keys, envelope_of, scene_line
from fepen.studies.products import Picture, Table
from fepen.studies.study import Round, Study, numbers, register, set_option

__all__ = ["ChargeSafetyStudy", "SafetyPlan", "boundary", "table", "undecided_lines"]

#: the criteria's names, in the summary's order
NAMES = tuple(c for c, _, _ in CRITERIA)


@dataclass
class SafetyPlan:
    """The study's checked inputs: the base scene's keys, its points (speed, obliquity, attack) and their
    scenes, each point's envelope verdict."""

    base: dict
    probe: fscene.Scene
    points: list
    scenes: list
    envelopes: list

    @property
    def digest(self) -> str:
        text = json.dumps([self.base, self.points], sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def _angles(option: str, text: str | None, default: list[float]) -> list[float]:
    """Comma-separated angles in [0, 90) degrees (0 allowed); InputError naming the option else."""
    if text is None:
        return default
    try:
        values = [float(x) for x in str(text).split(",")]
    except ValueError:
        values = []
    if not values or not all(math.isfinite(v) and 0.0 <= v < 90.0 for v in values):
        raise InputError(option, f"comma-separated angles in [0, 90) deg, got {text!r}")
    return sorted(set(values))


def check(scene_path, sets, speeds, obliquities, attacks) -> SafetyPlan:
    """The study's inputs checked, every point's scene resolved (InputError before anything is written)."""
    base = base_keys(scene_path, sets)
    if base.get("effects.charge") is False:
        raise InputError("effects.charge", "the charge-safety study needs the charge: drop effects.charge = false")
    base["effects.charge"] = True
    probe = fscene.Scene(base)
    if probe.effects.fidelity == "rigid":
        raise InputError("effects.fidelity", "the charge's stresses need a meshed fidelity: 'elastic' or 'plastic'")
    if not speeds or not all(0.0 < v <= 3000.0 for v in speeds):
        raise InputError("--speeds", f"speeds in (0, 3000] m/s, got {speeds}")
    points = [(float(v), float(o), float(a)) for a in attacks for o in obliquities for v in sorted(set(speeds))]
    scenes, envelopes = [], []
    for i, (v, o, a) in enumerate(points):
        try:
            sc = fscene.Scene({**base, "impact.velocity": v, "impact.obliquity_deg": o, "impact.attack_deg": a})
        except InputError as err:
            raise InputError(f"point {i} ({v:g} m/s, {o:g} deg, attack {a:g} deg): {err.key}", err.message) from None
        scenes.append(sc)
        envelopes.append(envelope_of(sc))
    return SafetyPlan(base, probe, points, scenes, envelopes)


def boundary(speeds, margins) -> float | None:
    """The speed at which a margin crosses 1, between the first two neighbouring speeds that bracket it (the
    logarithm of the margin interpolated linearly in speed); None when no pair brackets it.

    Args:
        speeds: increasing striking speeds (m/s). margins: the governing margin at each (None: no result).
    """
    pts = [(v, m) for v, m in zip(speeds, margins) if m is not None and m > 0.0]
    for (v0, m0), (v1, m1) in zip(pts, pts[1:]):
        if (m0 - 1.0) * (m1 - 1.0) <= 0.0 and m0 != m1:
            l0, l1 = math.log(m0), math.log(m1)
            return v0 + (v1 - v0) * (0.0 - l0) / (l1 - l0)
    return None


def table(plan: SafetyPlan, records: dict) -> list[dict]:
    """One row per point: its speed, angles, status (ok, or why it has no result: bad-input, stopped, missing),
    the shot's outcome (its summary's, else the status), whether it finished, its verdict
    (fepen.runs.charge_safety.settled: an unfinished shot is never "safe") and why it has none, governing
    criterion and margin, every criterion's margin, the depth and final axis angle, whether it lies inside the
    validated envelope."""
    from fepen.runs.charge_safety import settled

    rows = []
    for i, (v, o, a) in enumerate(plan.points):
        r = records.get(i, {"status": "missing", "summary": None, "message": ""})
        s = r.get("summary") or {}
        cs = s.get("charge_safety") or {}
        end = settled(r.get("summary"), r["status"], r.get("message") or "")
        row = {"point": i, "velocity_m_s": v, "obliquity_deg": o, "attack_deg": a, "status": r["status"],
               "outcome": end["outcome"], "finished": end["finished"], "verdict": end["verdict"],
               "message": end["reason"] or None, "governing": cs.get("governing"), "margin": cs.get("margin")}
        for name in NAMES:
            c = cs.get(name) or {}
            row[f"{name}_margin"] = c.get("margin")
            row[f"{name}_demand"] = c.get("demand")
        row["depth_mm"] = s.get("depth_mm")
        row["final_axis_angle_deg"] = s.get("final_axis_angle_deg")
        row["inside_envelope"] = plan.envelopes[i]["inside"]
        rows.append(row)
    return rows


def undecided_lines(rows: list[dict]) -> list[str]:
    """One line per point whose shot did not finish and has nothing past a threshold: where, and why."""
    return [f"{r['velocity_m_s']:g} m/s, {r['obliquity_deg']:g} deg, attack {r['attack_deg']:g} deg: undecided "
            f"({r['outcome']}): {r['message']}" for r in rows if r["verdict"] == "undecided"]


@register
class ChargeSafetyStudy(Study):
    """``fepen study charge-safety``: the charge-safety verdict over speed × obliquity (× attack)."""

    name = "charge-safety"
    help = ("the charge-safety verdict over striking speed x obliquity (x attack), deformable charged shots: "
            "charge_safety.csv, .md, .png")
    names = ("shots.jsonl", "shots", "charge_safety.json", "charge_safety.csv", "charge_safety.md", "charge_safety.png")
    out = "results/charge-safety"

    @classmethod
    def add_arguments(cls, parser) -> None:
        parser.add_argument("scene", nargs="?", help="the base scene (absent: the default, with its charge)")
        parser.add_argument("--speeds", default="200,400,600,800,1000",
                            help="striking speeds, m/s (default 200,400,600,800,1000)")
        parser.add_argument("--obliquities", default="0,10,20", help="obliquities, deg (default 0,10,20)")
        parser.add_argument("--attacks", default="0", help="angles of attack, deg (default 0)")
        set_option(parser, "override a key of the base scene")

    @classmethod
    def options(cls, args) -> dict:
        return {"scene_path": args.scene, "sets": args.sets, "speeds": numbers("--speeds", args.speeds),
                "obliquities": _angles("--obliquities", args.obliquities, [0.0]),
                "attacks": _angles("--attacks", args.attacks, [0.0])}

    def plan(self, scene_path=None, sets=(), speeds=(200.0, 400.0, 600.0, 800.0, 1000.0), obliquities=(0.0, 10.0, 20.0),
             attacks=(0.0,)) -> SafetyPlan:
        return check(scene_path, sets, [float(v) for v in speeds], sorted({float(o) for o in obliquities}),
                     sorted({float(a) for a in attacks}))

    def digest(self, plan: SafetyPlan) -> str:
        return plan.digest

    def rounds(self, plan: SafetyPlan):
        yield Round(plan.scenes, keep=lambda sc: True, batch=False, label="charged shots")

    def result(self, plan: SafetyPlan, records: list[dict], info) -> dict:
        rows = table(plan, records[0])
        speeds = sorted({v for v, _, _ in plan.points})
        bounds = []
        for a in sorted({p[2] for p in plan.points}):
            for o in sorted({p[1] for p in plan.points}):
                ms = [next(r["margin"] if r["verdict"] != "undecided" else None for r in rows  # a lower bound
                           if (r["velocity_m_s"], r["obliquity_deg"], r["attack_deg"]) == (v, o, a)) for v in speeds]
                bounds.append({"obliquity_deg": o, "attack_deg": a, "boundary_speed_m_s": boundary(speeds, ms),
                               "margins": ms})
        govs = sorted({r["governing"] for r in rows if r["governing"]})
        return {"points": len(rows), "rows": rows, "boundary": bounds, "governing": govs,
                "explosive": plan.probe.charge.explosive, "scene": scene_line(plan.probe),
                "mesh_size_m": plan.probe.mesh.size,
                "statuses": {s: sum(r["status"] == s for r in rows) for s in sorted({r["status"] for r in rows})},
                "verdicts": {v: sum(r["verdict"] == v for r in rows) for v in VERDICTS if any(r["verdict"] == v
                                                                                            for r in rows)}}

    def tables(self, plan: SafetyPlan, result: dict, info) -> list:
        rows = result["rows"]
        return [Table("charge_safety.csv", list(rows[0]) if rows else [], rows)]

    def pictures(self, plan: SafetyPlan, result: dict, info) -> list:
        from fepen.post import study_figures

        return [Picture("charge_safety.png", (6.4, 4.6), lambda fig: study_figures.charge_safety(fig, result), 120)]

    def report(self, result: dict) -> str:
        lines = [f"# Charge safety: {result['explosive']}", "",
                 result["scene"] + f"; mesh {result['mesh_size_m'] * 1e3:g} mm", "",
                 "| speed (m/s) | obliquity (deg) | attack (deg) | governing | margin | " + " | ".join(NAMES)
                 + " | depth (mm) | envelope |",
                 "|" + "---|" * (7 + len(NAMES))]
        for r in result["rows"]:
            def f(x):
                return "–" if x is None else f"{x:.3g}"
            bound = "≤ " if r["verdict"] == "undecided" and r["margin"] is not None else ""  # the shot's is lower
            lines.append(f"| {r['velocity_m_s']:g} | {r['obliquity_deg']:g} | {r['attack_deg']:g} | "
                         f"{r['governing'] or r['status']} | {bound}{f(r['margin'])} | "
                         + " | ".join(f(r[f'{n}_margin']) for n in NAMES)
                         + f" | {'–' if r['depth_mm'] is None else format(r['depth_mm'], '.0f')} | "
                         + f"{'inside' if r['inside_envelope'] else 'outside'} |")
        undecided = [f"- {u}" for u in undecided_lines(result["rows"])]
        lines += [""] + undecided if undecided else []
        lines += ["", "Margin: threshold over demand (1 at the threshold, below 1 beyond it); – where the criterion "
                  "has no threshold; ≤: a shot that did not finish (undecided: its demands could still grow). The "
                  "boundary: the speed at which the governing margin crosses 1, of the finished shots.", "",
                  "Every criterion's demand (the largest over the shot; units: "
                  + ", ".join(f"{n} {u}" for n, u, _ in CRITERIA) + "):", "",
                  "| speed (m/s) | obliquity (deg) | attack (deg) | " + " | ".join(NAMES) + " |",
                  "|" + "---|" * (3 + len(NAMES))]
        for r in result["rows"]:
            lines.append(f"| {r['velocity_m_s']:g} | {r['obliquity_deg']:g} | {r['attack_deg']:g} | "
                         + " | ".join("–" if r[f"{n}_demand"] is None else f"{r[f'{n}_demand']:.4g}" for n in NAMES)
                         + " |")
        lines.append("")
        for b in result["boundary"]:
            v = b["boundary_speed_m_s"]
            lines.append(f"- obliquity {b['obliquity_deg']:g} deg, attack {b['attack_deg']:g} deg: "
                         + (f"margin 1 at {v:.0f} m/s" if v is not None else "no crossing in the speeds run"))
        return "\n".join(lines) + "\n"

    def lines(self, result: dict) -> list[str]:
        out = []
        for b in result["boundary"]:
            v = b["boundary_speed_m_s"]
            ms = ", ".join("–" if m is None else f"{m:.3g}" for m in b["margins"])
            out.append(f"obliquity {b['obliquity_deg']:g} deg, attack {b['attack_deg']:g} deg: governing margins "
                       f"{ms}; " + (f"margin 1 at {v:.0f} m/s" if v is not None else "no crossing"))
        out += undecided_lines(result["rows"])
        outside = [r for r in result["rows"] if not r["inside_envelope"]]
        out.append(f"governing: {', '.join(result['governing']) or 'none'}; {len(outside)} of {result['points']} "
                   "points outside the validated envelope")
        return out
