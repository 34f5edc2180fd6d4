"""make docs' blocks of the accuracy-cost ladder (docs/accuracy-cost.md), the hard cases (docs/hard-cases.md)
and wear's Table 1 (docs/wear.md).

Each generator takes a scratch directory and returns the block's Markdown; BLOCKS registers them with
tools/make_docs.py (which imports this module and merges BLOCKS into its own).
"""

from __future__ import annotations

import atexit
import csv
import json
import shutil
import tempfile
from pathlib import Path

import make_docs as md
import numpy as np

# ---- the accuracy-cost ladder (docs/accuracy-cost.md) --------------------------------------------------------
ACCURACY_COST = ("study", "accuracy-cost")
#: more options of the study: ("--quick",) runs its small subset (C3 on 8 and 6 mm meshes, 0.2 ms), which proves
#: the generators without the 25 minutes of the whole ladder
COST_OPTIONS: tuple = ()


def cost_study() -> Path:
    """The study's folder: `fepen study accuracy-cost`, each run on 2 ranks (its own mpirun; MAKE_DOCS_RANKS=1:
    on 1), run once per make docs and shared by the two blocks of the page."""
    return md.made(*ACCURACY_COST, "--ranks", str(min(2, md.RANKS)), *COST_OPTIONS)[0]


def accuracy_cost(tmp: Path) -> str:
    """The study's table (study.md: every run, then the cost exponents and the speed-ups of study.json)."""
    out = cost_study()
    md.figure(out / "pareto.png", "accuracy-cost.png")
    return (out / "study.md").read_text().strip()


def read_study_rows(path: Path) -> dict[tuple[str, str], dict]:
    """study.csv's runs that finished, by (shot, run name), their figures as floats where they are numbers."""
    out = {}
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            if r.get("failed"):
                continue
            row = dict(r)
            for k, v in r.items():
                try:
                    row[k] = float(v)
                except (TypeError, ValueError):
                    pass
            out[(r["shot"], r["name"])] = row
    return out


def _pair(rows: dict, shots: list[str], name: str, fmt) -> str:
    return " / ".join(fmt(rows[(s, name)]) for s in shots)


def _setting_row(rows, shots, question, setting, name, accuracy) -> str | None:
    if not all((s, name) in rows for s in shots):
        return None
    cost = _pair(rows, shots, name, lambda r: f"{r['process_s']:.{0 if r['process_s'] >= 20 else 1}f} s")
    return f"| {question} | {setting} | {cost} | {accuracy} |"


def settings_table(rows: dict[tuple[str, str], dict]) -> str:
    """"Which settings answer which question": each question's cheapest answering run, its cost (the whole
    process) and its accuracy (against the finest default run and Table 1), from study.csv's rows; a question
    whose runs are not in the study (--quick) is left out."""
    shots = sorted({s for s, _ in rows})
    ranks = {int(r["ranks"]) for (_, name), r in rows.items() if name.startswith("default-") and r["group"] == "mesh"}
    mesh = sorted({r["h_mm"] for r in rows.values() if r["group"] == "mesh"})
    finest = f"default-{mesh[0]:g}mm"
    pct = lambda key: lambda r: f"{100 * r[key]:.1f} %"  # noqa: E731
    peeq = lambda r: f"{r['max_peeq']:.4f}"  # noqa: E731
    lines = [f"| question | setting | cost ({' / '.join(shots)}, {'/'.join(map(str, sorted(ranks)))} "
             f"rank{'s' if max(ranks) > 1 else ''}) | accuracy |", "|---|---|---|---|"]
    acc = (f"within {_pair(rows, shots, 'rigid', pct('H_vs_finest'))} of the finest deformable run; Table 1 "
           f"nose error {_pair(rows, shots, 'rigid', pct('nose_error'))}") if all(
        (s, "rigid") in rows for s in shots) else ""
    found = [_setting_row(rows, shots, "depth only (Hy), a first trajectory", '`effects.fidelity = "rigid"` (any '
                          "mesh: it only carries the load points)", "rigid", acc)]
    for question, h in (("trajectory (Hx, Hy, Tx, Ty; curved paths)", 2.5), ("the same, converged", 1.6)):
        name = f"default-{h:g}mm"
        if all((s, name) in rows for s in shots):
            found.append(_setting_row(rows, shots, question, f"deformable at {h:g} mm", name,
                                      f"{_pair(rows, shots, name, pct('H_vs_finest'))} from the finest run"))
    altitude = f"altitude-step-{mesh[0]:g}mm"
    if all((s, finest) in rows and (s, altitude) in rows for s in shots):
        text = (f"max PEEQ {_pair(rows, shots, finest, peeq)} (altitude step: "
                f"{_pair(rows, shots, altitude, peeq)})")
        if all((s, "default-2.5mm") in rows for s in shots) and finest != "default-2.5mm":
            text += f"; at 2.5 mm {_pair(rows, shots, 'default-2.5mm', peeq)}"
        found.append(_setting_row(rows, shots, "deformation (max PEEQ, hazard map, gauges)",
                                  f"plastic at {mesh[0]:g} mm", finest, text))
    return "\n".join(lines + [r for r in found if r])


def accuracy_settings(tmp: Path) -> str:
    """The page's "which settings answer which question" table, from the same study's study.csv."""
    return settings_table(read_study_rows(cost_study() / "study.csv"))


# ---- the hard cases (docs/hard-cases.md) ---------------------------------------------------------------------
HARD = "demos/hard_cases"
HARD_SIZES = (0.0025, 0.004)
#: the refinement section's runs: mesh size -> cases
REFINED = {0.0016: ("attack_900_5", "oblique_900_45", "ricochet_250_75", "soft_bending"), 0.0012: ("oblique_900_45",)}
#: more --set of every hard-case run (a proof of the generators on short runs: ("run.end_time=1.5e-4",))
HARD_SETS: tuple = ()
#: exit 3: a case beyond the method stops with one line, which the table prints instead of figures
BEYOND = 3
_CASES: dict[tuple, dict] = {}


def hard_case(case: str, h: float, ranks: int = 2) -> dict:
    """One hard case at mesh size h (m), as demos/hard_cases/run_all.py runs it (no fields), once per make docs:
    its summary, or its stop line when it ends beyond the method (exit 3); any other failure stops make docs."""
    from fepen.studies.processes import run_fepen_process

    key = (case, h, min(ranks, md.RANKS))
    if key not in _CASES:
        out = Path(tempfile.mkdtemp(prefix="fepen-docs-hard-"))
        atexit.register(shutil.rmtree, out, True)
        code, wall, message = run_fepen_process(["run", f"{HARD}/{case}.toml", "--out", str(out / "run"), "--set",
                                                 f"mesh.size={h}", "--set", "run.fields=false",
                                                 *[a for s in HARD_SETS for a in ("--set", s)]], key[2])
        row = {"case": case, "h_mm": h * 1e3, "exit": code, "process_s": wall}
        if code == 0:
            row.update(json.loads((out / "run" / "summary.json").read_text()))
        elif code == BEYOND:
            row["message"] = message
        else:
            raise SystemExit(f"make docs: hard case {case} at {h * 1e3:g} mm failed (exit {code}): {message}")
        _CASES[key] = row
    return _CASES[key]


def hard_table(rows: list[dict]) -> str:
    """run_all.py's table without its wall column (the machine's, not fepen's: the blocks say it once, masked)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("run_all", md.ROOT / "demos" / "hard_cases" / "run_all.py")
    run_all = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(run_all)
    return "\n".join(run_all.table(rows, wall=False))


def _cost_line(rows: list[dict], ranks: int) -> str:
    """The runs' wall time (masked by the drift test), the largest energy error of those that end, and how many
    stopped beyond the method."""
    ended = [r["energy_error"] for r in rows if r["exit"] == 0]
    stopped = sum(r["exit"] != 0 for r in rows)
    runs = "One run" if len(rows) == 1 else f"{len(rows)} runs"
    text = f"{runs} ({md.took(sum(r['process_s'] for r in rows), ranks)}, fepen {md.version()})"
    if ended:
        text += (f"; energy balance error {ended[0]:.1e}" if len(rows) == 1 else
                 f"; largest energy balance error of the {len(ended)} that end: {max(ended):.1e}") + " (goal 1 %)"
    return text + (f"; {stopped} stopped beyond the method (exit {BEYOND})." if stopped else ".")


def full_size_cases() -> list[str]:
    """The hard cases of the full-size table: every scene of demos/hard_cases but the coarse mesh (its own block)."""
    return sorted(p.stem for p in (md.ROOT / HARD).glob("*.toml") if p.stem != "coarse_mesh")


def _signed(v: float) -> str:
    """A change as the pages print it: its sign always, a true minus, no "−0.0"."""
    return f"{round(v, 1) or 0.0:+.1f}".replace("-", "−")


def hard_cases(tmp: Path) -> str:
    """The full-size table (2.5 and 4 mm, 2 ranks), its cost, and the charged shell against the empty one."""
    rows = [hard_case(c, h) for c in full_size_cases() for h in HARD_SIZES]
    text = [hard_table(rows), "", _cost_line(rows, 2)]
    h = HARD_SIZES[0]  # the default mesh
    c, o = hard_case("charged_oblique_900_45", h), hard_case("oblique_900_45", h)
    if c["exit"] == 0 and o["exit"] == 0:
        dy, dx = c["Hy_mm"] - o["Hy_mm"], c["Hx_mm"] - o["Hx_mm"]
        text += ["", f"At {h * 1e3:g} mm the charged projectile ends {abs(dy):.0f} mm "
                 f"({100 * abs(dy) / o['Hy_mm']:.0f} %) {'shallower' if dy < 0 else 'deeper'} than the empty shell, "
                 f"{c['Hy_mm']:.1f} against {o['Hy_mm']:.1f} mm, and {abs(dx):.0f} mm "
                 f"{'further' if dx > 0 else 'less far'} sideways."]
    return "\n".join(text)


def hard_coarse(tmp: Path) -> str:
    """The very coarse mesh (8 mm) on one rank: cheap, so the drift test keeps it honest."""
    row = hard_case("coarse_mesh", 0.008, ranks=1)
    return hard_table([row]) + "\n\n" + _cost_line([row], 1)


ENDPOINT_CASES = {"attack_900_5": "5° attack, 900 m/s", "oblique_900_45": "45° obliquity, 900 m/s",
                  "ricochet_250_75": "ricochet, 250 m/s at 75°"}


def endpoint_table(by_size: dict[float, dict[str, dict]]) -> str:
    """The nose tip's end point (Hx, Hy) of the cases that end on three meshes, coarsest first, and its changes."""
    sizes = sorted(by_size, reverse=True)[:3]
    mm = [f"{h * 1e3:g} mm" for h in sizes]
    lines = [f"| case | {' | '.join(mm)} | change {mm[0][:-3]} → {mm[1][:-3]} | change {mm[1][:-3]} → {mm[2][:-3]} |",
             "|---|---|---|---|---|---|"]
    for case, label in ENDPOINT_CASES.items():
        rs = [by_size[h][case] for h in sizes]
        if any(r["exit"] != 0 for r in rs):
            continue
        pts = [f"{r['Hx_mm']:.1f}, {r['Hy_mm']:.1f}" for r in rs]
        ch = [f"{_signed(b['Hx_mm'] - a['Hx_mm'])}, {_signed(b['Hy_mm'] - a['Hy_mm'])}" for a, b in zip(rs, rs[1:])]
        lines.append(f"| {label} | {' | '.join(pts)} | {' | '.join(ch)} |")
    return "\n".join(lines)


def _refined_notes(by_size: dict[float, dict[str, dict]]) -> list[str]:
    notes = []
    fine, finest = sorted(REFINED, reverse=True)
    a, b = by_size[fine]["oblique_900_45"], by_size[finest]["oblique_900_45"]
    if a["exit"] == 0 and b["exit"] == 0:
        dx = b["Hx_mm"] - a["Hx_mm"]
        notes.append(f"- 45° obliquity from {fine * 1e3:g} to {finest * 1e3:g} mm: sideways travel {_signed(dx)} mm "
                     f"({_signed(100 * dx / a['Hx_mm'])} %) to {b['Hx_mm']:.1f} mm; depth {b['Hy_mm']:.1f} mm "
                     f"({_signed(100 * (b['Hy_mm'] / a['Hy_mm'] - 1))} %).")
    soft = [(h, by_size[h]["soft_bending"]) for h in sorted(by_size, reverse=True) if "soft_bending" in by_size[h]]
    peaks = [f"{r['max_peeq']:.2f} at {h * 1e3:g} mm" for h, r in soft if r["exit"] == 0]
    stops = [f"stops beyond the method at {h * 1e3:g} mm" for h, r in soft if r["exit"] != 0]
    notes.append(f"- soft projectile: peak PEEQ {', '.join(peaks)}" + (f"; {', '.join(stops)}" if stops else "") + ".")
    return notes


def hard_refinement(tmp: Path) -> str:
    """The refinement section: the cases at 1.6 mm and the 45° shot at 1.2 mm (2 ranks), the end points on the
    4, 2.5 and 1.6 mm meshes (the full-size runs shared with that block) and what changes."""
    fine, finest = sorted(REFINED, reverse=True)
    rows = [hard_case(c, h) for h, cases in REFINED.items() for c in cases]
    three = sorted((*HARD_SIZES, fine), reverse=True)
    by_size = {h: {c: hard_case(c, h) for c in (*ENDPOINT_CASES, "soft_bending")} for h in three}
    by_size[finest] = {c: hard_case(c, finest) for c in REFINED[finest]}
    mm = ", ".join(f"{h * 1e3:g}" for h in three[:-1]) + f" and {three[-1] * 1e3:g}"
    return "\n".join([hard_table(rows), "", _cost_line(rows, 2), "", f"Nose-tip end point on the {mm} mm meshes "
                      "(Hx, Hy in mm):", "", endpoint_table({h: by_size[h] for h in three}), "",
                      *_refined_notes(by_size)])


# ---- Table 1 with the calibrated wear (docs/wear.md §2.4) --------------------------------------------------------
WEAR_RIGID = ("validate", *md.RIGID, "--set", "effects.wear=true")
WEAR_PLASTIC = ("validate", "--set", "effects.wear=true", "--set", "run.fields=false")
#: the rule of §2.5: wear on by default only if no mean error grows by more than this (points of %, degrees)
RULE = 1.0


def read_wear(folder: Path) -> dict[str, dict]:
    """validation.csv's rows by shot, each with its run's summary (mass loss, length change) under "summary"."""
    rows = md.read_validation(folder / "validation.csv")
    for shot, r in rows.items():
        r["summary"] = json.loads((folder / shot / "summary.json").read_text())
    return rows


def _means(rows: dict) -> tuple[float, float, float]:
    """Mean nose and tail errors (%) and mean final-axis error (degrees, absolute), as Table 1's lines."""
    return (100 * np.mean([float(r["nose_error"]) for r in rows.values()]),
            100 * np.mean([float(r["tail_error"]) for r in rows.values()]),
            np.mean([abs(float(r["axis_error_deg"])) for r in rows.values()]))


def wear_table(label: str, off: dict, on: dict) -> str:
    """One fidelity's Table 1 with and without wear: the losses, the errors off → on, the means and the verdict
    of §2.5's rule."""
    lines = ["| shot | V (m/s) | mass loss (%) | length change (mm) | nose error: off → on | tail error: off → on |",
             "|---|---|---|---|---|---|"]
    for shot, r in on.items():
        s, o = r["summary"], off[shot]
        lines.append(f"| {shot} | {float(r['v0_m_s']):.0f} | {s['mass_loss_percent']:.2f} | "
                     f"{s['length_change_mm']:.2f} | {100 * float(o['nose_error']):.1f} → "
                     f"{100 * float(r['nose_error']):.1f} % | {100 * float(o['tail_error']):.1f} → "
                     f"{100 * float(r['tail_error']):.1f} % |")
    m0, m1 = _means(off), _means(on)
    d = [b - a for a, b in zip(m0, m1)]
    worse = [k for k, v in zip(("nose", "tail", "final axis"), d) if v > RULE]
    verdict = "within the rule" if not worse else f"beyond the rule ({', '.join(worse)})"
    means = (f"Means, {label}: nose {m0[0]:.1f} → {m1[0]:.1f} %, tail {m0[1]:.1f} → {m1[1]:.1f} %, final axis "
             f"{m0[2]:.1f} → {m1[2]:.1f}° ({_signed(d[0])} and {_signed(d[1])} points, {_signed(d[2])}°: {verdict}).")
    return "\n".join([*lines, "", means])


def _losses(label: str, on: dict) -> str:
    by_speed = sorted(on.values(), key=lambda r: float(r["v0_m_s"]))
    loss = {r["shot"]: r["summary"]["mass_loss_percent"] for r in by_speed}
    short = [-r["summary"]["length_change_mm"] for r in by_speed]
    top = max(loss, key=loss.get)
    return (f"{label}: the loss goes from {loss[by_speed[0]['shot']]:.2f} % at {by_speed[0]['shot']} "
            f"({float(by_speed[0]['v0_m_s']):.0f} m/s) to {loss[by_speed[-1]['shot']]:.2f} % at "
            f"{by_speed[-1]['shot']} ({float(by_speed[-1]['v0_m_s']):.0f} m/s), the largest {loss[top]:.2f} % "
            f"({top}); the bodies shorten by {min(short):.1f}–{max(short):.1f} mm (C7 {short_of(on, 'C7')}, C8 "
            f"{short_of(on, 'C8')} mm).")


def short_of(rows: dict, shot: str) -> str:
    return f"{-rows[shot]['summary']['length_change_mm']:.1f}"


def wear_rigid(tmp: Path) -> str:
    """§2.4's rigid half: two rigid Table 1 sweeps (8 s each), without wear (shared with the table1 block) and
    with it."""
    off, on = md.read_validation(md.made(*md.VALIDATE_RIGID)[0] / "validation.csv"), read_wear(md.made(*WEAR_RIGID)[0])
    return wear_table("rigid", off, on) + "\n\n" + _losses("Rigid", on)


def wear_plastic(tmp: Path) -> str:
    """§2.4's plastic half (2.5 mm cells: minutes), and the two fidelities with wear against each other."""
    off = md.read_validation(md.made(*md.VALIDATE_PLASTIC)[0] / "validation.csv")
    on, rigid = read_wear(md.made(*WEAR_PLASTIC)[0]), read_wear(md.made(*WEAR_RIGID)[0])
    gap = max(abs(on[s]["summary"]["mass_loss_percent"] / rigid[s]["summary"]["mass_loss_percent"] - 1) for s in on)
    return "\n\n".join([
        wear_table("plastic", off, on), _losses("Plastic", on),
        f"The two fidelities' mass losses differ by at most {100 * gap:.0f} %. With wear the plastic C7 ends at "
        f"{float(on['C7']['axis_deg']):.1f}° against the rigid {float(rigid['C7']['axis_deg']):.1f}°, and the "
        f"plastic C8 at {float(on['C8']['axis_deg']):.1f}° ({float(off['C8']['axis_deg']):.1f}° without)."])


BLOCKS = {
    "accuracy-cost": md.Block("docs/accuracy-cost.md", accuracy_cost, 1500, "fepen study accuracy-cost"),
    "accuracy-settings": md.Block("docs/accuracy-cost.md", accuracy_settings, 0,
                                  "fepen study accuracy-cost (its study.csv)"),
    "hard-cases": md.Block("docs/hard-cases.md", hard_cases, 300,
                           f"mpirun -n 2 fepen run {HARD}/CASE.toml --set mesh.size=0.0025 (and 0.004) "
                           "--set run.fields=false, each case"),
    "hard-coarse": md.Block("docs/hard-cases.md", hard_coarse, 15,
                            f"fepen run {HARD}/coarse_mesh.toml --set mesh.size=0.008 --set run.fields=false", True),
    "hard-refinement": md.Block("docs/hard-cases.md", hard_refinement, 800,
                                f"mpirun -n 2 fepen run {HARD}/CASE.toml --set mesh.size=0.0016 (and 0.0012) "
                                "--set run.fields=false, the cases below"),
    "wear-rigid": md.Block("docs/wear.md", wear_rigid, 20,
                           "fepen validate --set effects.fidelity=rigid [--set effects.wear=true]"),
    "wear-plastic": md.Block("docs/wear.md", wear_plastic, 360,
                             "fepen validate --set run.fields=false [--set effects.wear=true]"),
}
