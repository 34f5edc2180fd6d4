"""make docs' blocks of docs/charge.md (the paper's charged shot, tied against frictional, and its safety verdict)
and docs/verification.md (the meshes, the Taylor impacts, the rigid checks).

Each generator takes a scratch directory and returns the block's Markdown; BLOCKS registers them with
tools/make_docs.py (which imports this module and merges BLOCKS into its own).
"""

from __future__ import annotations

import atexit
import csv
import json
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import make_docs as md  # (fepen, made, figure, took, version, Block)
import numpy as np

ROOT = md.ROOT
CHARGE_DEMO = "demos/charge/charge_800.py"
CHARGE_SCENE = "demos/charge/charge_800.toml"
CONTACTS = ("tied", "frictional")


# ---- running a script once per make docs ---------------------------------------------------------------------
_SCRIPTS: dict[tuple, tuple[Path, float, str]] = {}


def script(path: str, *args: str, ranks: int = 1, ranks_flag: bool = False) -> tuple[Path, float, str]:
    """A Python script run once per make docs from the project root with ``--out DIR``; its folder, wall time (s)
    and standard output. A failure stops make docs.

    Args:
        path: the script, from the project root.
        args: its arguments without --out (and without --ranks).
        ranks: the ranks it runs on (at most make_docs.RANKS).
        ranks_flag: the script starts its own MPI ranks (``--ranks N``); else it runs under mpirun when ranks > 1.

    Returns:
        (the --out folder, the seconds, its stdout).
    """
    r = min(ranks, md.RANKS)
    key = (path, args, r)
    if key not in _SCRIPTS:
        tmp = Path(tempfile.mkdtemp(prefix="fepen-docs-script-"))
        atexit.register(shutil.rmtree, tmp, True)
        cmd = [md.PY, path, *args, "--out", str(tmp / "out")]
        if ranks_flag:
            cmd += ["--ranks", str(r)]
        elif r > 1:
            cmd = ["mpirun", "-n", str(r), *cmd]
        t0 = time.perf_counter()
        path_ = os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH", "")) if p)
        p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True,  # this tree's fepen, as `python -m` has
                           env=dict(os.environ, PYTHONPATH=path_))
        if p.returncode != 0:
            raise SystemExit(f"make docs: {path} {' '.join(args)} failed (exit {p.returncode}):\n{p.stdout[-2000:]}\n"
                             f"{p.stderr[-2000:]}")
        _SCRIPTS[key] = (tmp / "out", time.perf_counter() - t0, p.stdout)
    return _SCRIPTS[key]


def _m(v: float, digits: int = 1) -> str:
    """A figure with a typographic minus."""
    return f"{v:.{digits}f}".replace("-", "−")


def _k(v: float) -> str:
    """A large figure with thousands separators and a typographic minus: −66,276."""
    return f"{v:,.0f}".replace("-", "−")


def _at(p) -> str:
    """A place in the x–y plane, mm: (42.4, −3.3)."""
    return "(" + ", ".join(_m(c) for c in p) + ")"


def _span(values: list[float], digits: int = 2) -> str:
    """A range as a page prints it, "0.23–0.24", or one figure where both ends print alike."""
    lo, hi = f"{min(values):.{digits}f}", f"{max(values):.{digits}f}"
    return lo if lo == hi else f"{lo}–{hi}"


def _pct(a: float, b: float) -> float:
    """|a/b − 1| in per cent."""
    return 100 * abs(a / b - 1)


# ---- docs/charge.md: 800 m/s, tied against frictional ---------------------------------------------------------
#: the paper's charged shot on its 2.5 mm mesh (both contacts, fields on: the maps)
CONTACT_ARGS: tuple[str, ...] = ()
#: the frictional shot on the 4 mm mesh (fepen run: the demo needs the fields for its maps)
COARSE_SETS = ("mesh.size=0.004",)
QUICK_ARGS = ("--quick",)


def charge_pair(*args: str) -> tuple[dict, dict, float]:
    """demos/charge/charge_800.py's comparison (its rows by contact), each contact's summary.json and its history's
    interface columns (under "interface"), and its wall time (s)."""
    out, seconds, _ = script(CHARGE_DEMO, *args, ranks=2, ranks_flag=True)
    rows = {r["contact"]: r for r in json.loads((out / "comparison.json").read_text())}
    summaries = {c: json.loads((out / c / "summary.json").read_text()) for c in CONTACTS}
    for c in CONTACTS:
        summaries[c]["folder"] = out / c
    return rows, summaries, seconds


def contact_table(rows: dict, summaries: dict) -> str:
    """The page's table of what the contact changes (tied | frictional)."""
    t, f = rows["tied"], rows["frictional"]
    bold = abs(f["charge_peak_g"]) > abs(t["charge_peak_g"])

    def both(fn, strong: bool = False) -> str:
        a, b = fn(t), fn(f)
        return f"{a} | **{b}**" if strong else f"{a} | {b}"

    def where_vm(r, part):
        return f"{r[f'{part}_vm_max_MPa']:.1f} at {_at(r[f'{part}_vm_at_mm'])}"

    lines = [
        "| | tied | frictional |", "|---|---|---|",
        "| depth of penetration (mm) | " + both(lambda r: f"{r['depth_mm']:.1f}") + " |",
        f"| shell: peak acceleration, filtered (g) | {both(lambda r: _k(r['shell_peak_g']))} |",
        "| &nbsp;&nbsp;at t (µs), nose depth (mm) | "
        + both(lambda r: f"{r['shell_peak_t_us']:.1f}, {r['shell_peak_depth_mm']:.1f}") + " |",
        f"| &nbsp;&nbsp;raw peak (g) | {both(lambda r: _k(r['shell_raw_peak_g']))} |",
        f"| charge: peak acceleration, filtered (g) | {both(lambda r: _k(r['charge_peak_g']), bold)} |",
        "| &nbsp;&nbsp;at t (µs), nose depth (mm) | "
        + both(lambda r: f"{r['charge_peak_t_us']:.1f}, {r['charge_peak_depth_mm']:.1f}") + " |",
        f"| &nbsp;&nbsp;raw peak (g) | {both(lambda r: _k(r['charge_raw_peak_g']), bold)} |",
        "| charge: largest equivalent stress at the maps' time (MPa), where* | "
        + both(lambda r: f"{where_vm(r, 'charge')}, {r['maps_t_us']:.0f} µs") + " |",
        "| charge: largest PEEQ then, where* | "
        + both(lambda r: f"{r['charge_peeq_max']:.2g} at {_at(r['charge_peeq_at_mm'])}") + " |",
        "| shell: largest equivalent stress then (MPa), where* | "
        + both(lambda r: f"{r['shell_vm_max_MPa']:.0f} at {_at(r['shell_vm_at_mm'])}") + " |",
        "| charge axis, front point: most compressive axial stress (MPa) | "
        + both(lambda r: _m(r['axis_front_min_MPa'])) + " |",
        "| charge axis, middle point: most compressive axial stress (MPa) | "
        + both(lambda r: _m(r['axis_mid_min_MPa'])) + " |",
        f"| friction dissipation (J) | – | {f['friction_J']:.2f} |",
        f"| largest slip / gap / interpenetration (mm) | – | {f['slip_max_mm']:.3f} / {f['gap_max_mm']:.3f} / "
        f"{f['penetration_max_mm']:.1e} |",
        "| energy-balance error | " + both(lambda r: f"{r['energy_error']:.1e}") + " |",
        f"| wall time | {both(lambda r: md.took(r['wall_s'], 2))} |"]
    return "\n".join(lines)


def contact_words(rows: dict, summaries: dict, h_mm: float) -> str:
    """What the contact changes, in figures: the sentence the page's reading refers to."""
    t, f = rows["tied"], rows["frictional"]
    bonded = _pct(t["charge_peak_g"], t["shell_peak_g"])
    return (f"Bonded, the charge's filtered peak is the shell's to {bonded:.2g} %, "
            f"at {t['charge_peak_t_us']:.0f} µs (the shell's at {t['shell_peak_t_us']:.0f} µs), nose "
            f"{t['charge_peak_depth_mm']:.0f} mm deep; its raw peak {_k(t['charge_raw_peak_g'])} g; the axial "
            f"stress on its axis {_m(t['axis_front_min_MPa'], 0)} MPa at the front, "
            f"{_m(t['axis_mid_min_MPa'], 0)} MPa at mid-length. Sliding, its filtered peak comes at "
            f"{f['charge_peak_t_us']:.0f} µs (nose "
            f"{f['charge_peak_depth_mm']:.0f} mm deep), {_pct(f['charge_peak_g'], f['shell_peak_g']):.1f} % "
            f"{'above' if abs(f['charge_peak_g']) > abs(f['shell_peak_g']) else 'below'} the shell's; its raw peak "
            f"{_pct(f['charge_raw_peak_g'], t['charge_raw_peak_g']):.0f} % "
            f"{'above' if abs(f['charge_raw_peak_g']) > abs(t['charge_raw_peak_g']) else 'below'} the bonded charge's; "
            f"the axial stress at mid-length is {f['axis_mid_min_MPa'] / t['axis_mid_min_MPa']:.1f} times the bonded "
            f"charge's; the rear end opens by up to {f['gap_max_mm']:.2f} mm and the largest slip, "
            f"{f['slip_max_mm']:.2f} mm, is {f['slip_max_mm'] / h_mm:.2f} of the {h_mm:g} mm element. The charge's "
            f"filtered peak over the shell's: {f['charge_peak_g'] / f['shell_peak_g']:.2f} sliding, "
            f"{t['charge_peak_g'] / t['shell_peak_g']:.2f} bonded; the depths differ by "
            f"{_pct(f['depth_mm'], t['depth_mm']):.1f} %." + _pictures_words(summaries))


def _pictures_words(summaries: dict) -> str:
    """What the pictures show, in figures: the mid-length section's axial strain and when the slip is set."""
    mid = {c: summaries[c]["charge"]["cross_sections"]["mid"] for c in CONTACTS}
    with open(summaries["frictional"]["folder"] / "history.csv", newline="") as f:
        hist = [(float(r["t_s"]), float(r["interface_slip_max_mm"]), float(r["interface_gap_max_mm"]))
                for r in csv.DictReader(f)]
    slip = max(h[1] for h in hist)
    t_slip = next(t for t, a, _ in hist if a >= 0.95 * slip)
    return (f" At mid-length, at the maps' time, the sliding charge's mean axial strain is "
            f"{_m(mid['frictional']['charge_mean'] * 1e3, 1)}e-3, the least compressive in the section "
            f"{_m(mid['frictional']['max'] * 1e3, 1)}e-3; bonded {_m(mid['tied']['charge_mean'] * 1e3, 1)}e-3 and "
            f"{_m(mid['tied']['max'] * 1e3, 1)}e-3. The slip reaches 95 % of its largest at {t_slip * 1e6:.0f} µs and "
            f"ends at {hist[-1][1]:.2f} mm, the gap at {hist[-1][2]:.2f} mm.")


PICTURES = (("stress_maps", "stress-maps"), ("cross_sections", "cross-sections"),
            ("charge_histories", "charge-histories"))


def charge_contact(tmp: Path) -> str:
    """The paper's charged shot tied against frictional: the table, the figures in a sentence, the pictures."""
    rows, summaries, _ = charge_pair(*CONTACT_ARGS)
    out = summaries["tied"]["folder"].parent
    md.figure(out / "tied_vs_frictional.png", "charge-tied-vs-frictional.png")
    for c in CONTACTS:
        for src, name in PICTURES:
            md.figure(out / c / f"{src}.png", f"charge-{c}-{name}.png")
    md.figure(out / "frictional" / "interface.png", "charge-frictional-interface.png")
    cells = summaries["frictional"]["cells"]
    h = float(summaries["frictional"]["scene"]["mesh"]["size"]) * 1e3
    return "\n".join([
        f"`demos/charge/charge_800.py --ranks 2`: {h:g} mm mesh ({cells:,} cells), to embedment, fepen "
        f"{md.version()}:", "", contact_table(rows, summaries), "",
        "\\* in the x–y plane of the deformed projectile: (mm behind the nose tip along the axis, mm across it); the "
        "maps are drawn at the field output nearest the charge's peak.", "",
        contact_words(rows, summaries, h)])


def _interface(folder: Path) -> dict:
    """The largest slip and gap (mm) and the friction dissipation (J) of a frictional run's history."""
    with open(folder / "history.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    return {"slip": max(float(r["interface_slip_max_mm"]) for r in rows),
            "gap": max(float(r["interface_gap_max_mm"]) for r in rows), "friction": float(rows[-1]["friction_J"])}


def mesh_row(label: str, s: dict, contact: str) -> list:
    """One row of the refinement table: mesh, cells, depth, the peaks with their times, slip / gap, friction."""
    pk = s["peak_accelerations"]
    cols = [label, f"{s['cells']:,}", f"{s['Hy_mm']:.1f}",
            f"{_k(pk['shell_acc']['filtered_g'])} at {pk['shell_acc']['t_s'] * 1e6:.1f} µs",
            f"{_k(pk['charge_acc']['filtered_g'])} at {pk['charge_acc']['t_s'] * 1e6:.1f} µs",
            _k(pk["charge_acc"]["raw_peak_g"])]
    if contact == "frictional":
        i = _interface(s["folder"])
        cols += [f"{i['slip']:.3f} / {i['gap']:.3f}", f"{i['friction']:.2f}"]
    else:
        cols += ["–", "–"]
    return cols


def charge_mesh(tmp: Path) -> str:
    """The charged shot on the 4 and 2.5 mm meshes: the peaks, slip and friction, and how much they move."""
    coarse = _scene_run(*COARSE_SETS)
    _, fine, _ = charge_pair(*CONTACT_ARGS)
    lines = ["| mesh | cells | depth (mm) | shell peak, filtered (g) | charge peak, filtered (g) | charge raw peak (g) "
             "| largest slip / gap (mm) | friction (J) |", "|---|---|---|---|---|---|---|---|"]
    for label, s, c in (("4 mm, frictional", coarse, "frictional"), ("2.5 mm, frictional", fine["frictional"],
                                                                        "frictional"),
                        ("2.5 mm, tied", fine["tied"], "tied")):
        lines.append("| " + " | ".join(mesh_row(label, s, c)) + " |")
    a, b = coarse["peak_accelerations"], fine["frictional"]["peak_accelerations"]
    ia, ib = _interface(coarse["folder"]), _interface(fine["frictional"]["folder"])
    return "\n".join(lines) + "\n\n" + (
        f"Frictional, from 4 to 2.5 mm: the filtered peaks change by "
        f"{_pct(b['shell_acc']['filtered_g'], a['shell_acc']['filtered_g']):.1f} % (shell) and "
        f"{_pct(b['charge_acc']['filtered_g'], a['charge_acc']['filtered_g']):.1f} % (charge), the charge's raw peak "
        f"by {_pct(b['charge_acc']['raw_peak_g'], a['charge_acc']['raw_peak_g']):.1f} %, the slip by "
        f"{_pct(ib['slip'], ia['slip']):.0f} %, the depth by "
        f"{_pct(fine['frictional']['Hy_mm'], coarse['Hy_mm']):.1f} %;"
        f" the largest slip is {ia['slip'] / 4.0:.2f} of the element at 4 mm and {ib['slip'] / 2.5:.2f} at 2.5 mm.")


# ---- docs/charge.md: the safety verdict ------------------------------------------------------------------------
def console_line(tmp: Path) -> str:
    """The frictional shot's console line of its charge's safety verdict, and its reading in figures."""
    from fepen.runs.charge_safety import line

    _, summaries, _ = charge_pair(*CONTACT_ARGS)
    cs = summaries["frictional"]["charge_safety"]
    st = cs["strength"]
    d, th = st["demand"], st["threshold"]
    w = st["where"]
    return "\n".join(["```", line(cs), "```", "",
                      f"The charge's equivalent stress reaches {d * 1e-6:.1f} MPa, {_pct(d, th):.0f} % "
                      f"{'above' if d > th else 'below'} the {th * 1e-6:g} MPa at which its law starts to flow, "
                      f"{st['time_s'] * 1e6:.0f} µs after impact, {w['behind_tip_mm']:.1f} mm behind the nose tip at "
                      f"radius {w['radius_mm']:.1f} mm"
                      + (f" (first beyond it at {st['first_beyond_s'] * 1e6:.0f} µs)" if st["first_beyond_s"] else "")
                      + f"; governing: {cs['governing']}, margin {cs['margin']:.3g}."])


def quick_verdict(tmp: Path) -> str:
    """demos/charge/charge_800.py --quick: each contact's governing criterion and its strength and tension margins."""
    rows, _, _ = charge_pair(*QUICK_ARGS)

    def one(label, r):
        return (f"{label}: {r['safety_governing']} governs, margin {r['safety_margin']:.3g} (strength "
                f"{r['strength_margin']:.3g}, tension {r['tension_margin']:.3g})")

    return one("Bonded", rows["tied"]) + "; " + one("sliding", rows["frictional"]) + "."


#: the paper's shot at 20° and at 1000 m/s (frictional, to embedment, fields off); 800 m/s, 0° is charge_contact's
ANGLES = {"800 m/s, 20°": ["impact.obliquity_deg=20"], "1000 m/s, 0°": ["impact.velocity=1000"]}


def _scene_run(*sets: str, ranks: int = 2) -> dict:
    """`fepen run demos/charge/charge_800.toml --set ...` (shared), its summary with its folder."""
    out, seconds = md.made("run", CHARGE_SCENE, *md._sets([*sets, "run.fields=false"]), ranks=ranks)
    s = json.loads((out / "summary.json").read_text())
    s["folder"], s["demo_wall_s"] = out, seconds
    return s


def _strength(c: dict) -> str:
    w = c["where"]
    return (f"{c['margin']:.3g} ({c['demand'] * 1e-6:.1f} MPa, {w['behind_tip_mm']:.1f} mm, r {w['radius_mm']:.1f} mm, "
            f"{c['time_s'] * 1e6:.0f} µs)")


def _tension(c: dict, end_s: float) -> str:
    stop = ", at the stop" if c["time_s"] >= 0.98 * end_s else ""
    return (f"{c['margin']:.3g} ({c['demand'] * 1e-6:.2f} MPa at {c['where']['behind_tip_mm']:.1f} mm{stop}, "
            f"{c['time_s'] * 1e6:.0f} µs)")


def safety_angles(tmp: Path) -> str:
    """The verdict at 800 m/s normal, at 20° and at 1000 m/s: each criterion's demand and margin."""
    runs = {"800 m/s, 0°": charge_pair(*CONTACT_ARGS)[1]["frictional"]}
    runs.update({k: _scene_run(*v) for k, v in ANGLES.items()})
    cs = {k: s["charge_safety"] for k, s in runs.items()}

    def row(label, fn):
        return f"| {label} | " + " | ".join(fn(k) for k in runs) + " |"

    lines = ["| | " + " | ".join(runs) + " |", "|---" * (len(runs) + 1) + "|",
             row("depth (mm)", lambda k: f"{runs[k]['Hy_mm']:.1f}"),
             row("governing", lambda k: str(cs[k]["governing"])),
             row("governing margin", lambda k: f"{cs[k]['margin']:.3g}"),
             row("strength margin (demand, where, when)", lambda k: _strength(cs[k]["strength"])),
             row("tension margin (demand, where, when)", lambda k: _tension(cs[k]["tension"], runs[k]["end_time_s"])),
             row("friction work, largest (J/m²)", lambda k: _k(cs[k]["friction_work"]["demand"])),
             row("friction power μ p v, largest (W/m²)", lambda k: f"{cs[k]['friction_power']['demand']:.2e}"),
             row("largest end gap (mm), closure speed (m/s)",
                 lambda k: f"{cs[k]['gap']['demand'] * 1e3:.2f}, {cs[k]['closure_speed']['demand']:.1f}"),
             row("charge's filtered peak acceleration (g)", lambda k: _k(cs[k]["acceleration_g"]["demand"]))]
    base, obl, fast = cs.values()

    def change(c, name):
        a, b = c[name]["demand"], base[name]["demand"]
        return f"{_pct(a, b):.0f} % {'more' if a > b else 'less'}"

    def moved(c):
        way = "lowers" if c["margin"] < base["margin"] else "raises"
        return f"{way} it by {_pct(c['margin'], base['margin']):.1f} %"

    words = (f"Against 800 m/s at 0°: 20° {moved(obl)}, 1000 m/s {moved(fast)} (the governing margin). At 1000 m/s "
             + ", ".join(f"{n.replace('_', ' ')} {change(fast, n)}" for n in ("strength", "tension", "friction_work",
                                                                           "friction_power", "acceleration_g"))
             + "; at 20° " + ", ".join(f"{n.replace('_', ' ')} {change(obl, n)}"
                                        for n in ("strength", "friction_work", "friction_power", "closure_speed"))
             + ".")
    return "\n".join(lines) + "\n\n" + words


#: the same shot to 300 µs on six meshes (frictional, fields off)
SAFETY_MESHES = ("0.006", "0.005", "0.004", "0.003", "0.0025", "0.002")
SAFETY_MESH_SETS = ("run.end_time=3e-4",)


def safety_mesh(tmp: Path) -> str:
    """Each criterion's demand on six meshes, to 300 µs, and what converges."""
    runs = {float(h) * 1e3: _scene_run(f"mesh.size={h}", *SAFETY_MESH_SETS) for h in SAFETY_MESHES}
    lines = ["| mesh | cells | strength margin (filtered σ_eq, raw) | tension margin (σ₁) | friction work (J/m²) | "
             "friction power (W/m²) | end gap (mm) | closure (m/s) | charge peak (g) | strength's place (mm behind "
             "the tip) |", "|---|---|---|---|---|---|---|---|---|---|"]
    for h, s in runs.items():
        c = s["charge_safety"]
        st = c["strength"]
        lines.append(f"| {h:g} mm | {s['cells']:,} | {st['margin']:.3g} ({st['demand'] * 1e-6:.1f}, "
                     f"{st['demand_unfiltered'] * 1e-6:.1f} MPa) | {c['tension']['margin']:.3g} "
                     f"({c['tension']['demand'] * 1e-6:.2f} MPa) | {c['friction_work']['demand']:.0f} | "
                     f"{c['friction_power']['demand']:.2e} | {c['gap']['demand'] * 1e3:.3f} | "
                     f"{c['closure_speed']['demand']:.1f} | {_k(c['acceleration_g']['demand'])} | "
                     f"{st['where']['behind_tip_mm']:.1f} |")
    fine = [s["charge_safety"] for h, s in runs.items() if h <= 4.0]
    finer = [s["charge_safety"] for h, s in runs.items() if h <= 3.0]

    def spread(cs, name, key="demand"):
        v = np.array([c[name][key] for c in cs])
        return 100 * (v.max() / v.min() - 1)

    sm = [c["strength"]["margin"] for c in finer]
    return "\n".join(lines) + "\n\n" + (
        f"From 4 mm on, the largest over the smallest: the charge's peak acceleration "
        f"{spread(fine, 'acceleration_g'):.1f} %, the end gap {spread(fine, 'gap'):.0f} %, the friction power "
        f"{spread(fine, 'friction_power'):.0f} %, the "
        f"strength's demand {spread(fine, 'strength'):.0f} %, the tension's {spread(fine, 'tension'):.0f} %, the "
        f"friction work's {spread(fine, 'friction_work'):.0f} %; from 3 mm on the strength margin lies in "
        f"{min(sm):.3g}–{max(sm):.3g}.")


# ---- docs/verification.md ----------------------------------------------------------------------------------------
MESH_SIZES = ("4.0", "3.0", "2.5", "2.0", "1.6", "1.2")


def mesh_quality(tmp: Path) -> str:
    """`fepen mesh --set mesh.size=H` at six sizes: cells, mass, volume error, shortest altitude, stable step."""
    lines = ["| h (mm) | cells | mass (g) | volume error vs exact solid | shortest altitude / h | stable step (ns) |",
             "|---|---|---|---|---|---|"]
    met, short = [], []
    for h in MESH_SIZES:
        out = tmp / f"mesh-{h}"
        md.fepen("mesh", "--set", f"mesh.size={float(h) * 1e-3:g}", "--out", str(out))
        m = json.loads((out / "mesh.json").read_text())
        lines.append(f"| {h} | {m['cells']:,} | {m['mass_kg'] * 1e3:.2f} | {_m(100 * m['volume_error'], 2)} % | "
                     f"{m['altitude_over_size']:.3f} | {m['stable_dt_s'] * 1e9:.1f} |")
        (met if m["altitude_over_size"] >= 0.25 else short).append((h, m["altitude_over_size"]))
    words = f"The 0.25 h altitude goal is met at {', '.join(h for h, _ in met) or 'no size'} mm"
    if short:
        words += (f"; at {', '.join(h for h, _ in short)} mm the 2 mm wide cavity step is narrower than an element and "
                  f"the mesh reaches {_span([a for _, a in short])} h")
    return "\n".join(lines) + f"\n\n{words} (fepen {md.version()})."


def taylor(tmp: Path) -> str:
    """demos/verification/taylor.py's table: final length against the tests on three meshes, energy error."""
    _, seconds, text = script("demos/verification/taylor.py")
    return taylor_block(text, seconds)


def read_taylor(text: str) -> list[dict]:
    """taylor.py's printed rows: case, h (mm), cells, final and measured length (mm), error (%), energy error,
    wall time (s)."""
    rows = []
    for ln in text.splitlines()[1:]:
        if not ln.strip():
            continue
        h, cells, final, measured, err, energy, wall = ln[24:].split()
        rows.append({"case": ln[:24].strip(), "h": float(h), "cells": int(cells), "final": float(final),
                     "measured": float(measured), "error": float(err), "energy": float(energy), "wall": float(wall)})
    return rows


def taylor_block(text: str, seconds: float) -> str:
    """The Taylor table from taylor.py's printed rows, and how far each case moves between its two finest meshes."""
    rows = read_taylor(text)
    lines = ["| case | h (mm) | cells | final length (mm) | measured (mm) | error | energy error | wall |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['case']} | {r['h']:g} | {r['cells']:,} | {r['final']:.3f} | {r['measured']:.2f} | "
                     f"{r['error']:+.2f} % | {r['energy']:.1e} | {md.took(r['wall'], 1)} |")
    words = []
    for case in dict.fromkeys(r["case"] for r in rows):
        c = sorted((r for r in rows if r["case"] == case), key=lambda r: -r["h"])
        e = [r["error"] for r in c]
        words.append(f"{case}: {min(e):+.2f} to {max(e):+.2f} % over the meshes, "
                     f"{_pct(c[-1]['final'], c[-2]['final']):.2f} % between the two finest")
    return "\n".join(lines) + "\n\n" + "; ".join(words) + f" (fepen {md.version()}; {md.took(seconds, 1)} in all)."


RICOCHET = ["effects.fidelity=rigid", "impact.velocity=250", "impact.obliquity_deg=75", "impact.attack_deg=0"]
SLAB = ["effects.fidelity=rigid", "impact.velocity=800", "impact.obliquity_deg=0", "impact.attack_deg=0",
        "target.thickness=0.15"]


def rigid_checks(tmp: Path) -> str:
    """The rigid fidelity's outcomes: a ricochet at 75° and a perforated 150 mm slab, each with its residual speed."""
    lines = ["| check | result | goal |", "|---|---|---|"]
    for label, sets, goal in (("250 m/s at 75°", RICOCHET, "ricochet"),
                              ("800 m/s into a 150 mm slab", SLAB, "perforated, residual speed reported")):
        out = tmp / goal.split(",")[0]
        md.fepen("run", *md._sets(sets), "--out", str(out))
        s = json.loads((out / "summary.json").read_text())
        lines.append(f"| {label} | {s['outcome']}, leaving at {s['residual_speed_m_s']:.0f} m/s | {goal} |")
    return "\n".join(lines)


B = md.Block
_DEMO = f"python {CHARGE_DEMO} --ranks 2"
#: name -> make_docs.Block
BLOCKS: dict = {
    "charge-contact": B("docs/charge.md", charge_contact, 150, _DEMO),
    "charge-mesh": B("docs/charge.md", charge_mesh, 60,
                     f"{_DEMO}; mpirun -n 2 fepen run {CHARGE_SCENE} --set mesh.size=0.004 --set run.fields=false"),
    "charge-console": B("docs/charge.md", console_line, 150, _DEMO),
    "charge-quick": B("docs/charge.md", quick_verdict, 30, f"{_DEMO} --quick"),
    "charge-angles": B("docs/charge.md", safety_angles, 200,
                       f"{_DEMO}; mpirun -n 2 fepen run {CHARGE_SCENE} --set run.fields=false "
                       "[--set impact.obliquity_deg=20 | --set impact.velocity=1000]"),
    "charge-safety-mesh": B("docs/charge.md", safety_mesh, 200,
                            f"mpirun -n 2 fepen run {CHARGE_SCENE} --set mesh.size=H --set run.end_time=3e-4 "
                            f"--set run.fields=false (H = {', '.join(SAFETY_MESHES)})"),
    "mesh-quality": B("docs/verification.md", mesh_quality, 150,
                      f"fepen mesh --set mesh.size=H (H = {', '.join(MESH_SIZES)} mm)"),
    "taylor": B("docs/verification.md", taylor, 130, "python demos/verification/taylor.py"),
    "rigid-checks": B("docs/verification.md", rigid_checks, 4,
                      f"fepen run {' '.join(md._sets(RICOCHET))}; fepen run {' '.join(md._sets(SLAB))}", True),
}
