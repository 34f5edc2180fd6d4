"""``fepen study accuracy-cost``: what accuracy costs in time, over mesh and fidelity ladders of shots C3
and C7, each run a whole ``fepen run`` process; restartable (docs/accuracy-cost.md).
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np

from fepen import scene as fscene
from fepen.io import files
from fepen.studies import processes

SHOTS = ("C3", "C7")
MESH_SIZES = (0.006, 0.004, 0.0025, 0.0016, 0.0012)
FINEST = 0.0012
BASE_OFF = ["effects.separation=false", "effects.free_surface=false", "effects.friction=false"]


def configurations(quick: bool = False) -> list[dict]:
    """The study's runs: name, group, settings (without the shot), ranks offset."""
    runs = []
    sizes = (0.008, 0.006) if quick else MESH_SIZES
    for h in sizes:
        runs.append({"name": f"default-{h * 1e3:g}mm", "group": "mesh", "h": h, "sets": [f"mesh.size={h}"]})
    if quick:
        runs.append({"name": "rigid", "group": "fidelity", "h": 0.006,
                     "sets": ["mesh.size=0.006", "effects.fidelity=rigid"]})
        runs.append({"name": "altitude-step-6mm", "group": "costlier", "h": 0.006,
                     "sets": ["mesh.size=0.006", "run.stable_step=altitude"]})
        return runs
    h = 0.0025
    ladder = [
        ("rigid", ["effects.fidelity=rigid"]),
        ("elastic", ["effects.fidelity=elastic", *BASE_OFF]),
        ("plastic", ["effects.thermal=false", "effects.strain_rate=false", *BASE_OFF]),
        ("plastic+thermal+rate", BASE_OFF),
        ("+separation", ["effects.separation=true", "effects.free_surface=false", "effects.friction=false"]),
        ("+free surface", ["effects.separation=false", "effects.free_surface=true", "effects.friction=false"]),
        ("+friction", ["effects.separation=false", "effects.free_surface=false", "effects.friction=true"]),
        ("default+friction", ["effects.friction=true"]),
    ]
    for name, sets in ladder:
        runs.append({"name": name, "group": "fidelity", "h": h, "sets": [f"mesh.size={h}", *sets]})
    for hh in (0.0025, FINEST):
        runs.append({"name": f"altitude-step-{hh * 1e3:g}mm", "group": "costlier", "h": hh,
                     "sets": [f"mesh.size={hh}", "run.stable_step=altitude"]})
    runs.append({"name": "graded-4mm-nose1.6mm", "group": "cheaper", "h": 0.004,
                 "sets": ["mesh.size=0.004", "mesh.nose_size=0.0016"]})
    runs.append({"name": "default-2.5mm-1rank", "group": "ranks", "h": 0.0025, "sets": ["mesh.size=0.0025"],
                 "ranks": 1})
    return runs


def _run(cmd_sets: list[str], out: Path, ranks: int, fresh: bool) -> dict:
    """One ``fepen run`` process (reused when out already holds its result)."""
    sc = fscene.load(None, cmd_sets)
    want = sc.as_dict()
    summary_path = out / "summary.json"
    if not fresh and summary_path.exists():
        old = json.loads(summary_path.read_text())
        if old.get("scene") == want and old.get("ranks") == ranks and "process_s" in old:
            return old
    args = ["run", "--out", out, "--force"]
    for s in cmd_sets:
        args += ["--set", s]
    code, process_s, message = processes.run_fepen_process(args, ranks)
    if code != 0:
        return {"failed": message, "process_s": process_s}
    summary = json.loads(summary_path.read_text())
    summary["process_s"] = process_s
    summary_path.write_text(json.dumps(summary, indent=2) + "\n")
    return summary


def study(out: str | Path = "results/study", ranks: int = 2, quick: bool = False, fresh: bool = False,
          shots=SHOTS, say=print) -> list[dict]:
    """Run the study (rank 0 of COMM_WORLD only: each run is its own MPI job) and write its outputs.

    Returns:
        One row per run and shot.
    """
    out = Path(out)
    from mpi4py import MPI

    from fepen.io import rundir

    with rundir.study_directory(out, MPI.COMM_SELF, fresh, "accuracy-cost", STUDY_NAMES):
        return _study(out, ranks, quick, fresh, shots, say)


#: what the study writes into its folder (fepen.io.rundir.study_directory)
STUDY_NAMES = ("runs", "study.csv", "study.md", "study.json", "pareto.png")


def _study(out: Path, ranks: int, quick: bool, fresh: bool, shots, say) -> list[dict]:
    """study's body, in its claimed folder."""
    from mpi4py import MPI

    out = files.prepare(out, MPI.COMM_SELF)  # a file or a place that cannot be made: bad input, one line
    rows = []
    confs = configurations(quick)
    if quick:
        shots = shots[:1]
    for shot in shots:
        for c in confs:
            sets = [f'impact.shot="{shot}"', "run.fields=false", *c["sets"]]
            if quick:
                sets.append("run.end_time=2e-4")
            rk = c.get("ranks", ranks)
            s = _run(sets, out / "runs" / f"{shot}-{c['name'].replace(' ', '_').replace('+', 'with_')}", rk,
                     fresh)
            row = {"shot": shot, "name": c["name"], "group": c["group"], "h_mm": c["h"] * 1e3, "ranks": rk}
            if "failed" in s:
                row["failed"] = s["failed"]
            else:
                row.update({"process_s": s["process_s"], "wall_s": s["wall_s"],
                            "loop_s": s.get("time_split_s", {}).get("time_loop", np.nan), "steps": s["steps"],
                            "dt_s": s["dt_s"], "peak_memory_mb": s.get("peak_memory_bytes", 0) / 2 ** 20,
                            "cells": s["cells"], "Hx_mm": s["Hx_mm"], "Hy_mm": s["Hy_mm"], "Tx_mm": s["Tx_mm"],
                            "Ty_mm": s["Ty_mm"], "max_peeq": s["max_peeq"], "energy_error": s["energy_error"],
                            "outcome": s["outcome"], "nose_error": s["experiment"]["nose_error"],
                            "tail_error": s["experiment"]["tail_error"]})
            rows.append(row)
            say(_line(row))
    _against_finest(rows, quick)
    exponents = cost_exponents(rows)
    speedups = rank_speedups(rows)
    _write(rows, exponents, speedups, out)
    pareto(rows, out / "pareto.png")
    return rows


def _line(r: dict) -> str:
    if "failed" in r:
        return f"{r['shot']} {r['name']}: FAILED {r['failed']}"
    return (f"{r['shot']} {r['name']:>22}: {r['process_s']:7.1f} s, {r['steps']:6d} steps, Hy {r['Hy_mm']:.1f} mm, "
            f"nose error {100 * r['nose_error']:.1f} %")


def _against_finest(rows: list[dict], quick: bool) -> None:
    """Differences from the finest default run of the same shot: Hy, the nose 2-vector, max PEEQ."""
    finest = min((r["h_mm"] for r in rows if r["group"] == "mesh"), default=None)
    for shot in {r["shot"] for r in rows}:
        ref = [r for r in rows if r["shot"] == shot and r["group"] == "mesh" and r["h_mm"] == finest
               and "failed" not in r]
        if not ref:
            continue
        ref = ref[0]
        for r in rows:
            if r["shot"] != shot or "failed" in r:
                continue
            r["Hy_vs_finest"] = abs(r["Hy_mm"] - ref["Hy_mm"]) / ref["Hy_mm"]
            r["H_vs_finest"] = float(np.hypot(r["Hx_mm"] - ref["Hx_mm"], r["Hy_mm"] - ref["Hy_mm"])
                                     / np.hypot(ref["Hx_mm"], ref["Hy_mm"]))
            r["peeq_vs_finest"] = abs(r["max_peeq"] - ref["max_peeq"])


def cost_exponents(rows: list[dict]) -> dict:
    """Least-squares exponents over the mesh ladder per shot: wall ~ h^-q and wall ~ cells^p (time loop
    and whole process), and steps ~ h^-s."""
    out = {}
    for shot in sorted({r["shot"] for r in rows}):
        m = [r for r in rows if r["shot"] == shot and r["group"] == "mesh" and "failed" not in r]
        if len(m) < 2:
            continue
        h = np.log([r["h_mm"] for r in m])
        cells = np.log([r["cells"] for r in m])
        loop = np.log([r["loop_s"] for r in m])
        proc = np.log([r["process_s"] for r in m])
        steps = np.log([r["steps"] for r in m])
        order = np.argsort(h)
        q_fine = -(loop[order[1]] - loop[order[0]]) / (h[order[1]] - h[order[0]])
        out[shot] = {"q_loop": -np.polyfit(h, loop, 1)[0], "q_process": -np.polyfit(h, proc, 1)[0],
                     "p_loop": np.polyfit(cells, loop, 1)[0], "s_steps": -np.polyfit(h, steps, 1)[0],
                     "q_loop_finest_pair": q_fine}
    return out


def rank_speedups(rows: list[dict]) -> dict:
    """Process and time-loop speed-up from 1 rank to the study's ranks, default run at 2.5 mm."""
    out = {}
    for shot in sorted({r["shot"] for r in rows}):
        one = [r for r in rows if r["shot"] == shot and r["group"] == "ranks" and "failed" not in r]
        many = [r for r in rows if r["shot"] == shot and r["group"] == "mesh" and r["h_mm"] == 2.5
                and "failed" not in r]
        if one and many:
            out[shot] = {"ranks": many[0]["ranks"], "process": one[0]["process_s"] / many[0]["process_s"],
                         "loop": one[0]["loop_s"] / many[0]["loop_s"]}
    return out


COLUMNS = ["shot", "group", "name", "h_mm", "ranks", "cells", "process_s", "wall_s", "loop_s", "steps", "dt_s",
           "peak_memory_mb", "Hx_mm", "Hy_mm", "Tx_mm", "Ty_mm", "max_peeq", "energy_error", "outcome",
           "nose_error", "tail_error", "Hy_vs_finest", "H_vs_finest", "peeq_vs_finest", "failed"]


def _write(rows, exponents, speedups, out: Path) -> None:
    buf = io.StringIO()
    w = csv.DictWriter(buf, COLUMNS)
    w.writeheader()
    for r in rows:
        w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items() if k in COLUMNS})
    files.write_text(out / "study.csv", buf.getvalue())
    lines = ["| shot | run | h (mm) | ranks | cells | wall (s) | time loop (s) | steps | smallest step (ns) | "
             "peak memory (MiB) | Hy (mm) | nose error vs Table 1 | tail error vs Table 1 | "
             "H vs finest | max PEEQ | PEEQ vs finest |", "|" + "---|" * 16]
    for r in rows:
        if "failed" in r:
            lines.append(f"| {r['shot']} | {r['name']} | {r['h_mm']:g} | {r['ranks']} | failed: {r['failed']} |"
                         + " |" * 11)
            continue
        lines.append(
            f"| {r['shot']} | {r['name']} | {r['h_mm']:g} | {r['ranks']} | {r['cells']} | {r['process_s']:.1f} | "
            f"{r['loop_s']:.1f} | {r['steps']} | {r['dt_s'] * 1e9:.1f} | {r['peak_memory_mb']:.0f} | "
            f"{r['Hy_mm']:.1f} | {100 * r['nose_error']:.1f} % | {100 * r['tail_error']:.1f} % | "
            f"{100 * r.get('H_vs_finest', np.nan):.2f} % | {r['max_peeq']:.4f} | "
            f"{r.get('peeq_vs_finest', np.nan):.4f} |")
    lines.append("")
    for shot, e in exponents.items():
        lines.append(f"- {shot}: time loop ~ h^-{e['q_loop']:.2f} ~ cells^{e['p_loop']:.2f} over the mesh ladder, "
                     f"h^-{e['q_loop_finest_pair']:.2f} between its two finest meshes; whole process "
                     f"~ h^-{e['q_process']:.2f}; steps ~ h^-{e['s_steps']:.2f}")
    for shot, s in speedups.items():
        lines.append(f"- {shot}: 1 -> {s['ranks']} ranks at 2.5 mm: process {s['process']:.2f} x, time loop "
                     f"{s['loop']:.2f} x")
    files.write_text(out / "study.md", "\n".join(lines) + "\n")
    files.write_json(out / "study.json", {"exponents": exponents, "speedups": speedups})


def pareto(rows, path: Path) -> None:
    """Error against Table 1 (nose) and against the finest run, against wall time, log-log."""
    from matplotlib.lines import Line2D

    from fepen.post.figures import new_figure, save_figure

    fig = new_figure((12, 5))
    axes = fig.subplots(1, 2)
    marks = {"mesh": "o", "fidelity": "s", "cheaper": "^", "costlier": "v", "ranks": "D"}
    colours = {"C3": "tab:blue", "C7": "tab:red"}
    for ax, key, label in ((axes[0], "nose_error", "nose error against Table 1's test"),
                           (axes[1], "H_vs_finest", "nose position against the finest run")):
        for r in rows:
            if "failed" in r or not np.isfinite(r.get(key, np.nan)) or r.get(key, 0) <= 0:
                continue
            ax.loglog(r["process_s"], 100 * r[key], marks[r["group"]], color=colours.get(r["shot"], "k"),
                      alpha=0.8)
            ax.annotate(r["name"], (r["process_s"], 100 * r[key]), fontsize=6, alpha=0.7,
                        xytext=(3, 2), textcoords="offset points")
        ax.set(xlabel="wall time of the run (s)", ylabel=f"{label} (%)")
        ax.grid(True, which="both", alpha=0.3)
    handles = [Line2D([], [], marker=m, ls="", color="gray", label=f"varied: {g}") for g, m in marks.items()]
    handles += [Line2D([], [], marker="o", ls="", color=c, label=f"shot {s}") for s, c in colours.items()]
    axes[0].legend(handles=handles, fontsize=8)
    fig.suptitle("fepen: accuracy against time (shots C3 and C7)")
    fig.tight_layout()
    save_figure(fig, path, dpi=120)
