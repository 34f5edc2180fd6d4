"""``fepen study ballistic-limit`` and ``fepen study ricochet`` (docs/studies.md): outcome boundaries found by
bisection, each a Study (fepen.studies.study) whose rounds of shots run on the one executor (so on any number of
ranks, and resumable: a round's records are kept in OUT/rounds/NNN, and the bisection replays them).

Ballistic limit: the striking speed v_bl below which the projectile does not perforate the slab (or layered
target), bracketed by [v_lo, v_hi] and bisected until v_hi − v_lo ≤ tol; v_bl is the bracket's middle. Above
it, the residual speeds of a set of shots are fitted by Recht & Ipson's (1963) curve
v_r = a (v^p − v_bl^p)^(1/p) (a, p by least squares; v_bl fixed).

Ricochet: for each striking speed, the obliquity above which the projectile ricochets, bisected in
[0, obliquity_max] to tol degrees, every speed's bisection in the same rounds; and the outcome map over an
obliquity × speed grid.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from fepen import scene as fscene
from fepen.errors import InputError
from fepen.studies.study import Round, Study, numbers, register, set_option

__all__ = ["BallisticLimit", "Ricochet", "ballistic_limit", "ricochet", "recht_ipson", "fit_recht_ipson",
           "check_ballistic_limit", "check_ricochet", "scene_line", "envelope_of", "base_keys"]


def recht_ipson(v, v_bl: float, a: float, p: float):
    """Recht–Ipson residual speed a (v^p − v_bl^p)^(1/p), zero at and below v_bl."""
    v = np.asarray(v, float)
    return a * np.maximum(v**p - v_bl**p, 0.0) ** (1.0 / p)


def fit_recht_ipson(v, vr, v_bl: float) -> tuple[float, float, float]:
    """(a, p, rms error (m/s)) of the Recht–Ipson curve through (v, vr) with v_bl fixed."""
    from scipy.optimize import curve_fit

    v, vr = np.asarray(v, float), np.asarray(vr, float)
    (a, p), _ = curve_fit(lambda x, a, p: recht_ipson(x, v_bl, a, p), v, vr, p0=(1.0, 2.0),
                          bounds=([0.1, 1.0], [1.5, 10.0]))
    return float(a), float(p), float(np.sqrt(np.mean((recht_ipson(v, v_bl, a, p) - vr) ** 2)))


def base_keys(scene_path, sets) -> dict:
    """A study's base scene as given keys: the file's, then the --set items, without impact.shot (the study
    sets the speed and the angles itself)."""
    given = fscene.read_toml(scene_path) if scene_path else {}
    for item in sets:
        k, v = fscene.parse_set(item)
        given[k] = v
    given.pop("impact.shot", None)
    return given


def check_ballistic_limit(scene_path, sets, v_low: float, v_high: float, tol: float) -> tuple[dict, fscene.Scene]:
    """The ballistic-limit study's inputs checked (InputError before anything is written): (base keys, scene)."""
    base = base_keys(scene_path, sets)
    probe = fscene.Scene(base)
    if probe.get("target.thickness") is None and not probe.get("target.layers"):
        raise InputError("target.thickness", "the ballistic limit needs a finite target: give target.thickness "
                                             "or target.layers")
    if not 0 < v_low < v_high <= 3000 or not tol > 0:
        raise InputError("--speeds", f"need 0 < v_low < v_high <= 3000 m/s and tol > 0, got {v_low:g}, "
                                     f"{v_high:g}, {tol:g}")
    return base, probe


def check_ricochet(scene_path, sets, speeds, obliquity_max: float, tol: float) -> tuple[dict, fscene.Scene, list]:
    """The ricochet study's inputs checked (InputError before anything is written): (base keys, scene, speeds)."""
    base = base_keys(scene_path, sets)
    probe = fscene.Scene(base)
    speeds = [float(v) for v in speeds]
    if not speeds or not all(0 < v <= 3000 for v in speeds) or not 0 < obliquity_max < 90 or not tol > 0:
        raise InputError("--speeds", "speeds in (0, 3000] m/s, obliquity_max in (0, 90) deg, tol > 0")
    return base, probe, speeds


def envelope_of(sc: fscene.Scene) -> dict:
    """The validated envelope's verdict (fepen.stats.envelope) on a shot of the study, its printed line under
    "line": the study's boundary as far as fepen was checked there."""
    from fepen.runs import setup
    from fepen.stats import envelope

    v = envelope.verdict(setup.envelope_facts(sc, setup.check_supported(sc)))
    v["line"] = envelope.line(v)
    return v


def scene_line(sc) -> str:
    """What a study's figure says of its base scene: fidelity, projectile mass and calibre, the target."""
    layers = sc.get("target.layers")
    if layers:
        target = f"{len(layers)}-layer target"
    else:
        thick = sc.get("target.thickness")
        target = f"{sc.get('target.material')}" + (f", {thick * 1e3:g} mm thick" if thick else "")
        fc = sc.get("target.compressive_strength")
        from fepen.data import TARGETS

        if fc and TARGETS.get(sc.get("target.material"), {}).get("family") in ("concrete", "rock"):
            target += f", f_c {fc / 1e6:g} MPa"
    mass, diameter = sc.get("projectile.mass"), sc.get("projectile.diameter")
    drawn = sc.get("projectile.profile") or sc.get("projectile.cad")
    body = (f"{mass * 1e3:g} g, {diameter * 1e3:g} mm projectile" if mass and diameter
            else f"the projectile of {os.path.basename(drawn)}" if drawn else "the projectile")
    return f"{sc.get('effects.fidelity')} fidelity; {body}; {target}"


def _summaries(r: int, records: dict, n: int) -> list[dict]:
    """The summaries of a round's n shots, in order (InputError when one did not finish)."""
    recs = [records[i] for i in range(n)]
    for rec in recs:
        if rec["status"] != "ok":
            raise InputError("study", f"a shot of round {r} did not finish ({rec['status']}: {rec['message']})")
    return [rec["summary"] for rec in recs]


def _round(r: int, scenes: list) -> Round:
    """A bisection round: its records in rounds/NNN, every rank told its outcomes, rigid shots in batches."""
    return Round(scenes, folder=f"rounds/{r:03d}", label="", then=True,
                 batch=all(sc.effects.fidelity == "rigid" for sc in scenes))


@dataclass
class LimitPlan:
    """A limit study's checked inputs."""

    base: dict
    probe: fscene.Scene
    speeds: list
    tol: float
    extra: float = 0.0  #: the ricochet's obliquity_max; the ballistic limit's shots of the curve
    curve: int = 8


class _Limit(Study):
    """What the two limit studies share: the base scene and --set, the rounds' shots, the figure's title."""

    names = ("rounds",)

    @classmethod
    def add_arguments(cls, parser) -> None:
        parser.add_argument("scene", nargs="?", help="the base scene (absent: the default)")
        set_option(parser, "override a key of the base scene")

    def figure_size(self, result: dict) -> tuple[float, float]:
        return (6.4, 4.6)

    def scene(self, plan: LimitPlan, **keys) -> fscene.Scene:
        return fscene.Scene({**plan.base, **{k: float(v) for k, v in keys.items()}})

    def pictures(self, plan: LimitPlan, result: dict, info) -> list:
        from fepen.studies.products import Picture

        return [Picture(f"{self.json_name}.png", self.figure_size(result), lambda fig: self.draw(fig, result, plan),
                        120)]


@register
class BallisticLimit(_Limit):
    """``fepen study ballistic-limit``: bisection on perforation, the check one tolerance either side, the
    Recht–Ipson fit of the residual speeds above the limit."""

    name = "ballistic-limit"
    help = "the speed below which the target is not perforated, by bisection: ballistic_limit.json, .png"
    names = ("rounds", "ballistic_limit.json", "ballistic_limit.png")
    out = "results/ballistic-limit"

    @classmethod
    def add_arguments(cls, parser) -> None:
        super().add_arguments(parser)
        parser.add_argument("--speeds", default="100,1500", help="the bracket 'LOW,HIGH' (default 100,1500 m/s)")
        parser.add_argument("--tol", type=float, default=2.0, help="the bisection's final width in m/s (default 2)")

    @classmethod
    def options(cls, args) -> dict:
        bracket = numbers("--speeds", args.speeds)
        if len(bracket) != 2:
            raise InputError("--speeds", f"two speeds LOW,HIGH (m/s), got {args.speeds!r}")
        return {"scene_path": args.scene, "sets": args.sets, "v_low": bracket[0], "v_high": bracket[1],
                "tol": args.tol}

    def plan(self, scene_path=None, sets=(), v_low: float = 100.0, v_high: float = 1500.0, tol: float = 2.0,
             curve: int = 8) -> LimitPlan:
        base, probe = check_ballistic_limit(scene_path, sets, v_low, v_high, tol)
        return LimitPlan(base, probe, [float(v_low), float(v_high)], tol, curve=curve)

    def rounds(self, plan: LimitPlan):
        lo, hi = plan.speeds
        tol = plan.tol
        r = 0
        ends = _summaries(r, (yield _round(r, [self.scene(plan, **{"impact.velocity": v}) for v in (lo, hi)])), 2)
        if _perforates(ends[0]) or not _perforates(ends[1]):
            raise InputError("--speeds", f"{lo:g} m/s must not perforate and {hi:g} m/s must "
                                         f"({ends[0]['outcome']}, {ends[1]['outcome']})")
        bisection = [(lo, ends[0]["outcome"], ends[0]["residual_speed_m_s"]),
                     (hi, ends[1]["outcome"], ends[1]["residual_speed_m_s"])]
        while hi - lo > tol:
            r += 1
            mid = 0.5 * (lo + hi)
            s = _summaries(r, (yield _round(r, [self.scene(plan, **{"impact.velocity": mid})])), 1)[0]
            bisection.append((mid, s["outcome"], s["residual_speed_m_s"]))
            lo, hi = (lo, mid) if _perforates(s) else (mid, hi)
        bracket = (lo, hi)
        v_bl = 0.5 * (lo + hi)
        speeds = [v_bl * (1.0 + 0.04 * (j + 1)) for j in range(plan.curve)] if plan.curve else []
        vs = [v_bl - tol, v_bl + tol, *speeds]
        last = _summaries(r + 1, (yield _round(r + 1, [self.scene(plan, **{"impact.velocity": v}) for v in vs])),
                          len(vs))
        return {"bisection": bisection, "bracket": bracket, "speeds": speeds, "last": last}

    def result(self, plan: LimitPlan, records: list[dict], info) -> dict:
        found = info.found
        lo, hi = found["bracket"]
        v_bl, tol, shots = 0.5 * (lo + hi), plan.tol, found["last"]
        check = {"below": {"v_m_s": v_bl - tol, "outcome": shots[0]["outcome"]},
                 "above": {"v_m_s": v_bl + tol, "outcome": shots[1]["outcome"],
                           "residual_speed_m_s": shots[1]["residual_speed_m_s"]}}
        pts = [(v, s["residual_speed_m_s"]) for v, s in zip(found["speeds"], shots[2:]) if _perforates(s)]
        result = {"v_bl_m_s": v_bl, "bracket_m_s": [lo, hi], "tol_m_s": tol, "check": check,
                  "bisection": [{"v_m_s": v, "outcome": o, "residual_speed_m_s": vr}
                                for v, o, vr in found["bisection"]],
                  "curve": [{"v_m_s": v, "residual_speed_m_s": vr} for v, vr in pts]}
        if len(pts) >= 3:
            a, p, rms = fit_recht_ipson([v for v, _ in pts], [vr for _, vr in pts], v_bl)
            result.update(a=a, p=p, rms_m_s=rms)
        result["envelope"] = envelope_of(fscene.Scene({**plan.base, "impact.velocity": v_bl}))
        return result

    def draw(self, fig, res: dict, plan: LimitPlan) -> None:
        from fepen.post import study_figures

        fit = None
        if "a" in res:
            v = [p["v_m_s"] for p in res["curve"]] + [b["v_m_s"] for b in res["bisection"]
                                                       if b["outcome"] == "perforated"]
            x = np.linspace(res["v_bl_m_s"], max(max(v), res["v_bl_m_s"] * 1.4), 200)
            fit = (x, recht_ipson(x, res["v_bl_m_s"], res["a"], res["p"]))
        study_figures.limit(fig, res, scene_line(plan.probe), fit)

    def lines(self, res: dict) -> list[str]:
        v_bl, tol, check = res["v_bl_m_s"], res["tol_m_s"], res["check"]
        lo, hi = res["bracket_m_s"]
        return [f"ballistic limit {v_bl:.1f} m/s (bracket {lo:.2f}-{hi:.2f}, tol {tol:g}); "
                f"{v_bl - tol:.1f} m/s: {check['below']['outcome']}, {v_bl + tol:.1f} m/s: {check['above']['outcome']}"
                + (f"; Recht-Ipson a = {res['a']:.3f}, p = {res['p']:.2f}, rms {res['rms_m_s']:.1f} m/s"
                   if "a" in res else ""), f"at the limit: {res['envelope']['line']}"]


@register
class Ricochet(_Limit):
    """``fepen study ricochet``: the outcome map over obliquity and speed, and at each speed the critical
    obliquity by bisection (every speed's in the same rounds)."""

    name = "ricochet"
    help = "the outcome map over obliquity and speed, the critical obliquity at each speed: ricochet.json, .png"
    names = ("rounds", "ricochet.json", "ricochet.png")
    out = "results/ricochet"

    def figure_size(self, result: dict) -> tuple[float, float]:
        return (6.4, 4.8)

    @classmethod
    def add_arguments(cls, parser) -> None:
        super().add_arguments(parser)
        parser.add_argument("--speeds", default="300,400,500,600,700,800,900", help="the speeds (default "
                                                                                    "300,400,...,900 m/s)")
        parser.add_argument("--tol", type=float, default=0.5, help="the bisection's final width in deg (default 0.5)")
        parser.add_argument("--obliquity-max", type=float, default=85.0, help="top of the bracket (deg)")

    @classmethod
    def options(cls, args) -> dict:
        import math

        if not (math.isfinite(args.obliquity_max) and 0.0 < args.obliquity_max < 90.0):
            raise InputError("--obliquity-max", f"in (0, 90) deg, got {args.obliquity_max!r}")
        return {"scene_path": args.scene, "sets": args.sets, "speeds": numbers("--speeds", args.speeds),
                "obliquity_max": args.obliquity_max, "tol": args.tol}

    def plan(self, scene_path=None, sets=(), speeds=(300, 400, 500, 600, 700, 800, 900), obliquity_max: float = 85.0,
             tol: float = 0.5, map_step: float = 10.0) -> LimitPlan:
        base, probe, speeds = check_ricochet(scene_path, sets, speeds, obliquity_max, tol)
        return LimitPlan(base, probe, speeds, tol, extra=obliquity_max, curve=map_step)

    def rounds(self, plan: LimitPlan):
        speeds, tol, top, step = plan.speeds, plan.tol, plan.extra, plan.curve
        grid = [float(x) for x in np.arange(0.0, top + 1e-9, step)]
        if grid[-1] < top:
            grid.append(top)
        pairs = [(v, ob) for v in speeds for ob in grid]
        shots = _summaries(0, (yield _round(0, [self._at(plan, v, ob) for v, ob in pairs])), len(pairs))
        cells = [{"v_m_s": v, "obliquity_deg": ob, "outcome": s["outcome"]} for (v, ob), s in zip(pairs, shots)]
        brackets = []
        for v in speeds:  # the bracket: the last grid obliquity that does not ricochet, the next that does
            row = [c for c in cells if c["v_m_s"] == v]
            rico = [c["obliquity_deg"] for c in row if c["outcome"] == "ricochet"]
            if not rico:
                raise InputError("--obliquity-max", f"no ricochet at {v:g} m/s up to {top:g} deg")
            hi = min(rico)
            lower = [c["obliquity_deg"] for c in row if c["obliquity_deg"] < hi]
            brackets.append([max(lower) if lower else 0.0, hi])
        r = 0
        while any(hi - lo > tol for lo, hi in brackets):
            r += 1
            open_ = [j for j, (lo, hi) in enumerate(brackets) if hi - lo > tol]
            mids = [0.5 * sum(brackets[j]) for j in open_]
            res = _summaries(r, (yield _round(r, [self._at(plan, speeds[j], m) for j, m in zip(open_, mids)])),
                             len(open_))
            for j, m, s in zip(open_, mids, res):
                cells.append({"v_m_s": speeds[j], "obliquity_deg": m, "outcome": s["outcome"]})
                brackets[j][1 if s["outcome"] == "ricochet" else 0] = m
        return {"cells": cells, "brackets": brackets}

    def _at(self, plan: LimitPlan, v: float, ob: float) -> fscene.Scene:
        return fscene.Scene({**plan.base, "impact.velocity": v, "impact.obliquity_deg": float(ob)})

    def result(self, plan: LimitPlan, records: list[dict], info) -> dict:
        cells, brackets = info.found["cells"], info.found["brackets"]
        critical = [0.5 * (lo + hi) for lo, hi in brackets]
        # the envelope at the boundary's ends: the slowest and the fastest speed at its critical obliquity
        ends = {f"{v:g}": envelope_of(self._at(plan, v, c))
                for v, c in ((plan.speeds[0], critical[0]), (plan.speeds[-1], critical[-1]))}
        return {"speeds_m_s": plan.speeds, "critical_obliquity_deg": critical, "brackets": brackets,
                "tol_deg": plan.tol, "map": cells, "envelope": ends}

    def draw(self, fig, res: dict, plan: LimitPlan) -> None:
        from fepen.post import study_figures

        study_figures.ricochet(fig, res, scene_line(plan.probe))

    def lines(self, res: dict) -> list[str]:
        return ["critical obliquity: " + ", ".join(f"{v:g} m/s {c:.1f} deg" for v, c in
                                                   zip(res["speeds_m_s"], res["critical_obliquity_deg"])),
                *(f"at {v} m/s on the boundary: {e['line']}" for v, e in res["envelope"].items())]


def _perforates(s: dict) -> bool:
    return s["outcome"] == "perforated"


def ballistic_limit(scene_path, sets, out, comm=None, ranks_per_shot: int = 1, v_low: float = 100.0,
                    v_high: float = 1500.0, tol: float = 2.0, curve: int = 8, say=print, fresh: bool = False) -> dict:
    """The ballistic limit study (BallisticLimit) run into OUT; its result (every rank)."""
    from fepen.studies import study

    st = BallisticLimit()
    return study.run(st, st.plan(scene_path, sets, v_low, v_high, tol, curve), out, comm, ranks_per_shot, fresh, say)


def ricochet(scene_path, sets, out, comm=None, ranks_per_shot: int = 1, speeds=(300, 400, 500, 600, 700, 800, 900),
             obliquity_max: float = 85.0, tol: float = 0.5, map_step: float = 10.0, say=print,
             fresh: bool = False) -> dict:
    """The ricochet study (Ricochet) run into OUT; its result (every rank)."""
    from fepen.studies import study

    st = Ricochet()
    return study.run(st, st.plan(scene_path, sets, speeds, obliquity_max, tol, map_step), out, comm, ranks_per_shot,
                     fresh, say)
