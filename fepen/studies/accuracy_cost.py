"""``fepen study accuracy-cost``: what accuracy costs in time, over mesh and fidelity ladders of shots C3
and C7, each run a whole ``fepen run`` process on the one executor; restartable (docs/accuracy-cost.md).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fepen import scene as fscene
from fepen.studies.products import Picture, Table
from fepen.studies.study import Round, Study, register

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


@dataclass
class CostPlan:
    """The study's runs: (shot, configuration) pairs, their scenes, and the ranks."""

    runs: list
    scenes: list
    ranks: int
    quick: bool


def _folder(run: tuple) -> str:
    shot, c = run
    return f"{shot}-{c['name'].replace(' ', '_').replace('+', 'with_')}"


@register
class AccuracyCost(Study):
    """``fepen study accuracy-cost``: each configuration of each shot a whole ``fepen run`` process (the wall
    time a user waits), its folder OUT/runs/SHOT-NAME; the table, the exponents and speed-ups, the Pareto front."""

    name = "accuracy-cost"
    help = "what accuracy costs in time: study.csv, study.md, pareto.png"
    names = ("runs", "rounds", "shots.jsonl", "study.csv", "study.md", "study.json", "pareto.png")
    out = "results/study"

    @classmethod
    def add_arguments(cls, parser) -> None:
        parser.add_argument("--ranks", type=int, default=2, help="MPI ranks of each run (default 2)")
        parser.add_argument("--quick", action="store_true", help="a small subset on coarse meshes")

    @classmethod
    def options(cls, args) -> dict:
        from mpi4py import MPI

        from fepen.errors import InputError

        if MPI.COMM_WORLD.size > 1:
            raise InputError("fepen study", "run it without mpirun: it starts its own MPI jobs (--ranks)")
        return {"ranks": args.ranks, "quick": args.quick}

    def plan(self, ranks: int = 2, quick: bool = False, shots=SHOTS) -> CostPlan:
        from fepen.errors import InputError

        if ranks < 1:
            raise InputError("--ranks", f"must be at least 1, got {ranks}")
        runs = [(shot, c) for shot in (shots[:1] if quick else shots) for c in configurations(quick)]
        scenes = [fscene.load(None, [f'impact.shot="{shot}"', "run.fields=false", *c["sets"],
                                     *(["run.end_time=2e-4"] if quick else [])]) for shot, c in runs]
        return CostPlan(runs, scenes, ranks, quick)

    def digest(self, plan: CostPlan) -> str:
        import hashlib

        return hashlib.sha256(json.dumps([[s, c] for s, c in plan.runs] + [plan.ranks], sort_keys=True,
                                         default=str).encode()).hexdigest()[:16]

    def rounds(self, plan: CostPlan):
        names = [_folder(r) for r in plan.runs]
        ranks = [c.get("ranks", plan.ranks) for _, c in plan.runs]
        if len(set(ranks)) == 1:
            yield Round(plan.scenes, shot_folder=lambda out, i: out / "runs" / names[i], batch=False,
                        label="runs", process=ranks[0])
            return
        for rk in sorted(set(ranks)):  # one round per rank count (the 1-rank run of the speed-up)
            idx = [i for i, r in enumerate(ranks) if r == rk]
            yield Round([plan.scenes[i] for i in idx], folder=f"rounds/ranks-{rk}",
                        shot_folder=lambda out, j, idx=idx: out.parent.parent / "runs" / names[idx[j]], batch=False,
                        label=f"runs on {rk} rank{'s' if rk > 1 else ''}", process=rk)

    def result(self, plan: CostPlan, records: list, info) -> dict:
        ranks = [c.get("ranks", plan.ranks) for _, c in plan.runs]
        order = sorted(set(ranks))
        recs = {}
        for rk, round_records in zip(order, records):
            idx = [i for i, r in enumerate(ranks) if r == rk]
            recs.update({idx[j]: rec for j, rec in round_records.items()})
        rows = []
        for i, (shot, c) in enumerate(plan.runs):
            rec = recs[i]
            row = {"shot": shot, "name": c["name"], "group": c["group"], "h_mm": c["h"] * 1e3, "ranks": ranks[i]}
            s = rec.get("summary")
            if rec["status"] != "ok" or s is None:
                row["failed"] = rec.get("message") or rec["status"]
            else:
                row.update({"process_s": rec["wall_s"], "wall_s": s["wall_s"],
                            "loop_s": s.get("time_split_s", {}).get("time_loop", np.nan), "steps": s["steps"],
                            "dt_s": s["dt_s"], "peak_memory_mb": s.get("peak_memory_bytes", 0) / 2 ** 20,
                            "cells": s["cells"], "Hx_mm": s["Hx_mm"], "Hy_mm": s["Hy_mm"], "Tx_mm": s["Tx_mm"],
                            "Ty_mm": s["Ty_mm"], "max_peeq": s["max_peeq"], "energy_error": s["energy_error"],
                            "outcome": s["outcome"], "nose_error": s["experiment"]["nose_error"],
                            "tail_error": s["experiment"]["tail_error"]})
            rows.append(row)
            info.say(_line(row))
        _against_finest(rows, plan.quick)
        return {"exponents": cost_exponents(rows), "speedups": rank_speedups(rows), "_rows": rows}

    @property
    def json_name(self) -> str:
        """Its files' stem: study.json, study.csv, study.md."""
        return "study"

    def document(self, plan: CostPlan, result: dict, info) -> dict:
        return {"exponents": result["exponents"], "speedups": result["speedups"]}

    def tables(self, plan: CostPlan, result: dict, info) -> list:
        return [Table("study.csv", COLUMNS, result["_rows"])]

    def texts(self, plan: CostPlan, result: dict, info) -> dict:
        return {"study.md": _report(result["_rows"], result["exponents"], result["speedups"])}

    def pictures(self, plan: CostPlan, result: dict, info) -> list:
        from fepen.post import study_figures

        return [Picture("pareto.png", (12, 5), lambda fig: study_figures.pareto(fig, result["_rows"]), 120)]


def study(out: str | Path = "results/study", ranks: int = 2, quick: bool = False, fresh: bool = False,
          shots=SHOTS, say=print) -> dict:
    """Run the study (AccuracyCost; rank 0 of COMM_WORLD only: each run is its own MPI job) and write its
    outputs. Returns its result: the exponents and the speed-ups."""
    from mpi4py import MPI

    from fepen.studies import study as fstudy

    st = AccuracyCost()
    return fstudy.run(st, st.plan(ranks, quick, shots), out, MPI.COMM_SELF, 1, fresh, say, progress=False)


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


def _report(rows, exponents, speedups) -> str:
    """study.md: the runs' table, then the cost exponents and the speed-ups."""
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
    return "\n".join(lines) + "\n"
