"""``fepen study ballistic-limit`` and ``fepen study ricochet`` (docs/studies.md): outcome boundaries found
by bisection, each round of shots run on fepen.studies.engine (so on any number of ranks, and resumable: a
round's records are kept in OUT/rounds/NNN, and the bisection replays them).

Ballistic limit: the striking speed v_bl below which the projectile does not perforate the slab (or layered
target), bracketed by [v_lo, v_hi] and bisected until v_hi − v_lo ≤ tol; v_bl is the bracket's middle. Above
it, the residual speeds of a set of shots are fitted by Recht & Ipson's (1963) curve
v_r = a (v^p − v_bl^p)^(1/p) (a, p by least squares; v_bl fixed).

Ricochet: for each striking speed, the obliquity above which the projectile ricochets, bisected in
[0, obliquity_max] to tol degrees, every speed's bisection in the same rounds; and the outcome map over an
obliquity × speed grid.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from mpi4py import MPI

from fepen import scene as fscene
from fepen.atomic import make_dir
from fepen.errors import InputError
from fepen.io import files
from fepen.studies import engine

__all__ = ["ballistic_limit", "ricochet", "recht_ipson", "fit_recht_ipson"]


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


def _round(out: Path, r: int, scenes: list, comm, k: int) -> list[dict]:
    """Run a round of shots (resumable) and return their summaries (every rank), in order."""
    d = out / "rounds" / f"{r:03d}"
    if comm.rank == 0:
        make_dir(d)  # fepen's or new in the study's folder, never a link
    comm.barrier()
    rigid = all(sc.effects.fidelity == "rigid" for sc in scenes)
    records, _ = engine.execute(len(scenes), lambda i: scenes[i], d, comm, k,
                                batch=engine.BATCH if rigid else 1)  # rigid shots in batches
    recs = comm.bcast([records[i] for i in range(len(scenes))] if comm.rank == 0 else None, root=0)
    for rec in recs:
        if rec["status"] != "ok":
            raise InputError("study", f"a shot of round {r} did not finish ({rec['status']}: {rec['message']})")
    return [rec["summary"] for rec in recs]


#: what the limit studies write into their folders (fepen.io.rundir.study_directory)
BALLISTIC_NAMES = ("rounds", "ballistic_limit.json", "ballistic_limit.png")
RICOCHET_NAMES = ("rounds", "ricochet.json", "ricochet.png")


def _base(scene_path, sets) -> dict:
    given = fscene.read_toml(scene_path) if scene_path else {}
    for item in sets:
        k, v = fscene.parse_set(item)
        given[k] = v
    given.pop("impact.shot", None)
    return given


def check_ballistic_limit(scene_path, sets, v_low: float, v_high: float, tol: float) -> tuple[dict, fscene.Scene]:
    """The ballistic-limit study's inputs checked (InputError before anything is written): (base keys, scene)."""
    base = _base(scene_path, sets)
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
    base = _base(scene_path, sets)
    probe = fscene.Scene(base)
    speeds = [float(v) for v in speeds]
    if not speeds or not all(0 < v <= 3000 for v in speeds) or not 0 < obliquity_max < 90 or not tol > 0:
        raise InputError("--speeds", "speeds in (0, 3000] m/s, obliquity_max in (0, 90) deg, tol > 0")
    return base, probe, speeds


def ballistic_limit(scene_path, sets, out, comm=None, ranks_per_shot: int = 1, v_low: float = 100.0,
                    v_high: float = 1500.0, tol: float = 2.0, curve: int = 8, say=print) -> dict:
    """The ballistic limit of the scene's target by bisection on perforation, the check one tolerance either
    side, and the Recht–Ipson fit of the residual speeds above it.

    Args:
        scene_path, sets: the base scene (a finite target.thickness or target.layers) and --set overrides.
        out: results directory. comm: communicator. ranks_per_shot: ranks per shot.
        v_low, v_high: the initial bracket (m/s): v_low must not perforate, v_high must.
        tol: the bracket's final width (m/s). curve: shots of the residual-speed curve.
        say: prints a line (rank 0).

    Returns:
        {"v_bl_m_s", "bracket_m_s", "tol_m_s", "check": {below, above}, "a", "p", "rms_m_s", "curve": [...]}.
    """
    comm = MPI.COMM_WORLD if comm is None else comm
    base, probe = check_ballistic_limit(scene_path, sets, v_low, v_high, tol)
    out = files.prepare(out, comm)

    def scene(v):
        return fscene.Scene({**base, "impact.velocity": float(v)})

    def perforates(s):
        return s["outcome"] == "perforated"

    lo, hi = float(v_low), float(v_high)
    r = 0
    ends = _round(out, r, [scene(lo), scene(hi)], comm, ranks_per_shot)
    if perforates(ends[0]) or not perforates(ends[1]):
        raise InputError("--speeds", f"{lo:g} m/s must not perforate and {hi:g} m/s must "
                                     f"({ends[0]['outcome']}, {ends[1]['outcome']})")
    steps = [(lo, ends[0]["outcome"], ends[0]["residual_speed_m_s"]),
             (hi, ends[1]["outcome"], ends[1]["residual_speed_m_s"])]
    while hi - lo > tol:
        r += 1
        mid = 0.5 * (lo + hi)
        s = _round(out, r, [scene(mid)], comm, ranks_per_shot)[0]
        steps.append((mid, s["outcome"], s["residual_speed_m_s"]))
        if perforates(s):
            hi = mid
        else:
            lo = mid
    v_bl = 0.5 * (lo + hi)
    speeds = [v_bl * (1.0 + 0.04 * (j + 1)) for j in range(curve)] if curve else []
    r += 1
    shots = _round(out, r, [scene(v_bl - tol), scene(v_bl + tol), *map(scene, speeds)], comm, ranks_per_shot)
    check = {"below": {"v_m_s": v_bl - tol, "outcome": shots[0]["outcome"]},
             "above": {"v_m_s": v_bl + tol, "outcome": shots[1]["outcome"],
                       "residual_speed_m_s": shots[1]["residual_speed_m_s"]}}
    pts = [(v, s["residual_speed_m_s"]) for v, s in zip(speeds, shots[2:]) if perforates(s)]
    result = {"v_bl_m_s": v_bl, "bracket_m_s": [lo, hi], "tol_m_s": tol, "check": check,
              "bisection": [{"v_m_s": v, "outcome": o, "residual_speed_m_s": vr} for v, o, vr in steps],
              "curve": [{"v_m_s": v, "residual_speed_m_s": vr} for v, vr in pts]}
    if len(pts) >= 3:
        a, p, rms = fit_recht_ipson([v for v, _ in pts], [vr for _, vr in pts], v_bl)
        result.update(a=a, p=p, rms_m_s=rms)
    if comm.rank == 0:
        files.write_json(out / "ballistic_limit.json", result, MPI.COMM_SELF)
        _limit_figure(result, out / "ballistic_limit.png", probe)
        say(f"ballistic limit {v_bl:.1f} m/s (bracket {lo:.2f}-{hi:.2f}, tol {tol:g}); "
            f"{v_bl - tol:.1f} m/s: {check['below']['outcome']}, {v_bl + tol:.1f} m/s: {check['above']['outcome']}"
            + (f"; Recht-Ipson a = {result['a']:.3f}, p = {result['p']:.2f}, rms {result['rms_m_s']:.1f} m/s"
               if "a" in result else ""))
    return result


def _scene_line(sc) -> str:
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
    return (f"{sc.get('effects.fidelity')} fidelity; {sc.get('projectile.mass') * 1e3:g} g, "
            f"{sc.get('projectile.diameter') * 1e3:g} mm projectile; {target}")


def _limit_figure(res: dict, path: Path, sc=None) -> None:
    """ballistic_limit.png: residual against striking speed, the shots that did not perforate on the axis,
    the Recht–Ipson fit and the limit (dotted). sc: the base Scene (for the title), or None."""
    from fepen.post.figures import new_figure, save_figure

    fig = new_figure((6.4, 4.6))
    ax = fig.subplots()
    pts = res["curve"] + [{"v_m_s": b["v_m_s"], "residual_speed_m_s": b["residual_speed_m_s"]}
                          for b in res["bisection"] if b["outcome"] == "perforated"]
    v = np.array([p["v_m_s"] for p in pts])
    vr = np.array([p["residual_speed_m_s"] for p in pts])
    ax.plot(v, vr, "o", label="fepen shots (perforated)")
    stuck = [b["v_m_s"] for b in res["bisection"] if b["outcome"] != "perforated"]
    ax.plot(stuck, np.zeros(len(stuck)), "x", color="tab:red", label="fepen shots (not perforated)")
    if "a" in res:
        x = np.linspace(res["v_bl_m_s"], max(v.max(), res["v_bl_m_s"] * 1.4), 200)
        ax.plot(x, recht_ipson(x, res["v_bl_m_s"], res["a"], res["p"]), "-", color="k",
                label=f"Recht–Ipson fit: a = {res['a']:.3f}, p = {res['p']:.2f}")
    ax.axvline(res["v_bl_m_s"], ls=":", color="k", label=f"ballistic limit {res['v_bl_m_s']:.1f} m/s")
    ax.set_xlabel("striking speed (m/s)")
    ax.set_ylabel("residual speed (m/s)")
    title = f"ballistic limit {res['v_bl_m_s']:.1f} m/s (± {res['tol_m_s'] / 2:g} m/s)"
    ax.set_title(title + (f"\n{_scene_line(sc)}" if sc is not None else ""), fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path, dpi=120)


def ricochet(scene_path, sets, out, comm=None, ranks_per_shot: int = 1, speeds=(300, 400, 500, 600, 700, 800, 900),
             obliquity_max: float = 85.0, tol: float = 0.5, map_step: float = 10.0, say=print) -> dict:
    """The ricochet boundary (critical obliquity) at each speed by bisection, and the outcome map.

    Args:
        scene_path, sets: the base scene and --set overrides (its obliquity is what varies).
        speeds: striking speeds (m/s). obliquity_max: the bracket's top (deg): must ricochet.
        tol: the bisection's final width (deg). map_step: the outcome map's obliquity step (deg).

    Returns:
        {"speeds_m_s", "critical_obliquity_deg", "brackets", "map": [{v, obliquity, outcome}], "tol_deg"}.
    """
    comm = MPI.COMM_WORLD if comm is None else comm
    base, probe, speeds = check_ricochet(scene_path, sets, speeds, obliquity_max, tol)
    out = files.prepare(out, comm)

    def scene(v, ob):
        return fscene.Scene({**base, "impact.velocity": v, "impact.obliquity_deg": float(ob)})

    grid = [float(x) for x in np.arange(0.0, obliquity_max + 1e-9, map_step)]
    if grid[-1] < obliquity_max:
        grid.append(obliquity_max)
    pairs = [(v, ob) for v in speeds for ob in grid]
    r = 0
    shots = _round(out, r, [scene(v, ob) for v, ob in pairs], comm, ranks_per_shot)
    cells = [{"v_m_s": v, "obliquity_deg": ob, "outcome": s["outcome"]} for (v, ob), s in zip(pairs, shots)]
    brackets = []
    for v in speeds:  # the bracket: the last grid obliquity that does not ricochet, the next that does
        row = [c for c in cells if c["v_m_s"] == v]
        rico = [c["obliquity_deg"] for c in row if c["outcome"] == "ricochet"]
        if not rico:
            raise InputError("--obliquity-max", f"no ricochet at {v:g} m/s up to {obliquity_max:g} deg")
        hi = min(rico)
        lower = [c["obliquity_deg"] for c in row if c["obliquity_deg"] < hi]
        brackets.append([max(lower) if lower else 0.0, hi])
    while any(hi - lo > tol for lo, hi in brackets):
        r += 1
        open_ = [j for j, (lo, hi) in enumerate(brackets) if hi - lo > tol]
        mids = [0.5 * sum(brackets[j]) for j in open_]
        res = _round(out, r, [scene(speeds[j], m) for j, m in zip(open_, mids)], comm, ranks_per_shot)
        for j, m, s in zip(open_, mids, res):
            cells.append({"v_m_s": speeds[j], "obliquity_deg": m, "outcome": s["outcome"]})
            brackets[j][1 if s["outcome"] == "ricochet" else 0] = m
    critical = [0.5 * (lo + hi) for lo, hi in brackets]
    result = {"speeds_m_s": speeds, "critical_obliquity_deg": critical, "brackets": brackets, "tol_deg": tol,
              "map": cells}
    if comm.rank == 0:
        files.write_json(out / "ricochet.json", result, MPI.COMM_SELF)
        _ricochet_figure(result, out / "ricochet.png", probe)
        say("critical obliquity: " + ", ".join(f"{v:g} m/s {c:.1f} deg" for v, c in zip(speeds, critical)))
    return result


def _ricochet_figure(res: dict, path: Path, sc=None) -> None:
    """ricochet.png: the outcome of every shot over striking speed and obliquity, and the bisected ricochet
    boundary. sc: the base Scene (for the title), or None."""
    from fepen.post.figures import new_figure, save_figure
    from fepen.studies.sweep_figures import OUTCOME_COLOURS

    fig = new_figure((6.4, 4.8))
    ax = fig.subplots()
    for name in sorted({c["outcome"] for c in res["map"]}):
        c = [m for m in res["map"] if m["outcome"] == name]
        ax.plot([m["v_m_s"] for m in c], [m["obliquity_deg"] for m in c], "s", ms=5,
                color=OUTCOME_COLOURS.get(name, "k"), label=f"fepen shots: {name}", alpha=0.8)
    ax.plot(res["speeds_m_s"], res["critical_obliquity_deg"], "-k", lw=1.5,
            label=f"ricochet boundary (± {res['tol_deg'] / 2:g}°)")
    ax.set_xlabel("striking speed (m/s)")
    ax.set_ylabel("obliquity from the face normal (°)")
    ax.set_title("critical obliquity of ricochet" + (f"\n{_scene_line(sc)}" if sc is not None else ""), fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path, dpi=120)
