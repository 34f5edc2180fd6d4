"""How a deformable run's step scales with ranks and cells (issue 62 item 4; docs/theory.md §11.1): the default C3
shot, short, at 1, 2, 4 and 8 ranks (4 and 8 oversubscribed on a 2-core machine: their counts are exact, their
times are not), each run's summary.json ``communication`` block and time split into a table; a ping-pong between
two ranks for the message latency and bandwidth; the model fitted; the largest run one node and 64 nodes can do
in an hour. Writes benchmarks/scaling_results.md.

    .venv/bin/python benchmarks/scaling.py [SIZES_MM...]        (default: 6 4 2.5 mm, 2.5 the default mesh)
    mpirun -n 2 .venv/bin/python benchmarks/scaling.py --pingpong   (what the first command runs itself)
    .venv/bin/python benchmarks/scaling.py --again      (the report again from the last measurements)

Run it on an idle machine: the counts are the same anywhere, the seconds are this machine's.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from fepen.solver import traffic
from fepen.studies import processes

ROOT = Path(__file__).resolve().parents[1]
RANKS = (1, 2, 4, 8)
#: simulated time per mesh size (mm): about 200 steps, the nose in the target
END_TIME = {6.0: 6e-5, 4.0: 5e-5, 2.5: 4e-5}
#: the default shot's whole run (docs/accuracy-cost.md, fepen 0.6.0): steps at the default 2.5 mm mesh, its cells
DEFAULT_STEPS, DEFAULT_CELLS, DEFAULT_H_MM = 7080, 14714, 2.5
#: one node's cores, and the interconnect between nodes (ASSUMED: HDR InfiniBand, 200 Gb/s, ~1.5 us a message)
NODE_CORES, IB_ALPHA_S, IB_BETA_B_S = 64, 1.5e-6, 25e9
#: the projectile's length (m): the band partition's bands cannot be thinner than a cell (ranks <= L / h)
LENGTH_M = 0.144
HOUR_S = 3600.0
#: whole default runs on an idle machine (docs/accuracy-cost.md, fepen 0.6.0): h (mm), ranks, cells, steps, loop (s)
IDLE_RUNS = ((2.5, 1, 14714, 7080, 13.4), (2.5, 2, 14714, 7080, 9.5), (1.6, 2, 50540, 9440, 27.6),
             (1.2, 2, 113892, 11760, 60.8))


def pingpong(reps: int = 2000) -> None:
    """Rank 0 prints {"alpha_s", "beta_B_s", "allreduce_s"}: half a round trip of 8 bytes, the bandwidth of 1 MiB
    messages, an 8-byte allreduce (two ranks)."""
    import numpy as np
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    other = 1 - comm.rank

    def trip(n: int, k: int) -> float:
        buf = np.zeros(n, dtype=np.uint8)
        comm.Barrier()
        t0 = time.perf_counter()
        for _ in range(k):
            if comm.rank == 0:
                comm.Send(buf, other)
                comm.Recv(buf, other)
            else:
                comm.Recv(buf, other)
                comm.Send(buf, other)
        return (time.perf_counter() - t0) / (2 * k)

    trip(8, 100)
    alpha = min(trip(8, reps) for _ in range(3))
    big = 1 << 20
    t_big = min(trip(big, 50) for _ in range(3))
    x = np.zeros(1)
    comm.Barrier()
    t0 = time.perf_counter()
    for _ in range(reps):
        comm.Allreduce(MPI.IN_PLACE, x, op=MPI.MAX)
    allreduce = (time.perf_counter() - t0) / reps
    if comm.rank == 0:
        print(json.dumps({"alpha_s": alpha, "beta_B_s": big / max(t_big - alpha, 1e-12), "allreduce_s": allreduce}))


def measure_link() -> dict:
    r = processes.run([str(Path(__file__).resolve()), "--pingpong"], 2, fepen=False, timeout=300,
                      check=True)
    return json.loads(r.stdout.strip().splitlines()[-1])


def one_run(h_mm: float, ranks: int, out: Path) -> dict:
    """summary.json of the default shot at h_mm on ``ranks`` ranks, END_TIME long."""
    sets = [f"mesh.size={h_mm / 1e3}", f"run.end_time={END_TIME.get(h_mm, 4e-5)}", "run.fields=false",
            "run.checkpoint_interval=0", "run.figures=false"]
    args = ["run", "--out", str(out), "--force", "--no-sensitivity"]
    for s in sets:
        args += ["--set", s]
    extra = {"OMPI_MCA_mpi_yield_when_idle": "1" if ranks > 2 else "0"}  # oversubscribed ranks yield their core
    r = subprocess.run(processes.command(args, ranks), cwd=ROOT, capture_output=True, text=True,
                                 env=processes.mpi_env(**extra), timeout=1800)
    if r.returncode:
        raise RuntimeError(r.stderr[-2000:])
    return json.loads((out / "summary.json").read_text())


def row(h_mm: float, s: dict) -> dict:
    """One table row from a run's summary."""
    c, ranks, steps = s["communication"], s["ranks"], s["steps"]
    loop = s["time_split_s"]["time_loop"]
    calls = sum(e["calls"][0] for e in c["exchanges"]) / steps
    messages_bytes = max(c["bytes_per_step"])
    return {"h_mm": h_mm, "ranks": ranks, "cells": s["cells"], "cells_per_rank": s["cells"] / ranks, "steps": steps,
            "ghosts_max": max(c["ghost_nodes"]), "bytes_step": messages_bytes,
            "model_bytes_step": max(c["model_bytes_per_step"]), "calls_step": calls,
            "wait_step_s": max(c["wait_s_per_step"]), "imbalance": c["imbalance"], "step_s": loop / steps,
            "ns_cell_step_core": 1e9 * loop * ranks / (steps * s["cells"])}


def fit_cells(rows: list) -> tuple[float, float]:
    """(t_step_s, t_cell_s): the 1-rank runs' step time against their cells, a straight line (least squares)."""
    import numpy as np

    one = [r for r in rows if r["ranks"] == 1]
    A = np.array([[1.0, r["cells"]] for r in one])
    (t0, t1), *_ = np.linalg.lstsq(A, np.array([r["step_s"] for r in one]), rcond=None)
    return float(t0), float(t1)


def fit_ghosts(rows: list) -> tuple[float, float]:
    """Ghost nodes of the busiest rank against cells N and ranks P (bands of two halves): g = a N^(2/3) cuts(P) +
    b N^(2/3) / bands(P), cuts the cross-sections a band has inside the body (0, 1 or 2); least squares."""
    import numpy as np

    A, y = [], []
    for r in rows:
        if r["ranks"] < 2:
            continue
        bands = r["ranks"] // 2
        cuts = 0 if bands == 1 else (1 if bands == 2 else 2)
        n23 = r["cells"] ** (2.0 / 3.0)
        A.append([n23 * cuts, n23 / bands])
        y.append(r["ghosts_max"])
    (a, b), *_ = np.linalg.lstsq(np.array(A), np.array(y, dtype=float), rcond=None)
    return float(a), float(b)


def predict(m: traffic.Machine, ghosts: tuple, cells: float, ranks: int, imbalance: float, steps: float | None = None,
            parts: bool = False):
    """Wall seconds of the whole default run of ``cells`` cells on ``ranks`` ranks (fewer if the bands would be
    thinner than a cell): steps x step_time; parts: (that, the ranks that work, the step's s, its exchanges' s)."""
    h = DEFAULT_H_MM * 1e-3 * (DEFAULT_CELLS / cells) ** (1.0 / 3.0)
    usable = max(1, min(ranks, 2 * int(LENGTH_M / (2.0 * h))))
    bands = max(usable // 2, 1)
    cuts = 0 if bands == 1 else (1 if bands == 2 else 2)
    g = ghosts[0] * cells ** (2.0 / 3.0) * cuts + ghosts[1] * cells ** (2.0 / 3.0) / bands if usable > 1 else 0.0
    nbytes = 2 * g * 8 * (1 + 3)  # reverse and forward entries alike; the volumes' 1 and the 3 of forces/accelerations
    messages = 5 * min(usable - 1, 5)  # 5 exchanges a step, each to the rank's other half and the bands' 4 beside
    steps = DEFAULT_STEPS * (cells / DEFAULT_CELLS) ** (1.0 / 3.0) if steps is None else steps
    step = traffic.step_time(m, cells, usable, imbalance, messages, nbytes)
    if not parts:
        return steps * step
    alone = traffic.step_time(m, cells, usable, imbalance, 0, 0) - m.reductions * traffic.rounds(usable) * m.alpha_s
    exchanges = step - alone
    return steps * step, usable, step, exchanges


def report(rows: list, link: dict) -> str:
    """benchmarks/scaling_results.md's text."""
    t_step, t_cell = fit_cells(rows)
    ghosts = fit_ghosts(rows)
    imb = max(r["imbalance"] for r in rows)
    short = traffic.Machine(t_cell, link["alpha_s"], link["beta_B_s"], t_step)
    h0, ranks0, cells0, steps0, loop0 = IDLE_RUNS[0]
    whole = loop0 / predict(short, ghosts, cells0, ranks0, 1.0, steps=steps0)  # a whole run's step against a short
    node = traffic.Machine(whole * t_cell, link["alpha_s"], link["beta_B_s"], whole * t_step)
    cluster = traffic.Machine(whole * t_cell, IB_ALPHA_S, IB_BETA_B_S, whole * t_step)
    lines = ["# How a deformable run's step scales (`benchmarks/scaling.py`)", "",
             f"Made by `.venv/bin/python benchmarks/scaling.py` on {time.strftime('%Y-%m-%d')}, this machine: "
             "2 cores; 4 and 8 ranks oversubscribed (their counts exact, their times not). The default C3 shot, "
             "each run about 200 steps.", "",
             "| h (mm) | ranks | cells | cells/rank | ghost nodes (max) | bytes/step/rank (max) | model bytes/step "
             "(max) | calls/step | wait/step (ms, max) | imbalance | step (ms) | loop ns per cell-step·core |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['h_mm']:g} | {r['ranks']} | {r['cells']} | {r['cells_per_rank']:.0f} | {r['ghosts_max']} "
                     f"| {r['bytes_step']:.0f} | {r['model_bytes_step']} | {r['calls_step']:.2f} "
                     f"| {1e3 * r['wait_step_s']:.3f} | {r['imbalance']:.4f} | {1e3 * r['step_s']:.3f} "
                     f"| {r['ns_cell_step_core']:.0f} |")
    lines += ["", "Measured here:", "",
              f"- a step on one rank: {1e3 * t_step:.3f} ms + {1e9 * t_cell:.0f} ns a cell (least squares over the "
              "1-rank runs' loop time a step against their cells)",
              f"- α = {1e6 * link['alpha_s']:.2f} µs a message, β = {link['beta_B_s'] / 1e9:.2f} GB/s (ping-pong "
              f"between 2 ranks, shared memory); an 8-byte allreduce on 2 ranks {1e6 * link['allreduce_s']:.2f} µs",
              f"- ghost nodes of the busiest rank: {ghosts[0]:.3f} N^(2/3) per cross-section cut + "
              f"{ghosts[1]:.3f} N^(2/3) / bands for the mid-plane (least squares over the 2-8-rank runs)",
              f"- imbalance at most {imb:.4f} ((cells + load points) of the busiest rank over the mean)",
              f"- a whole run's step costs {whole:.2f} x a short run's (the default 2.5 mm run on 1 rank, "
              f"docs/accuracy-cost.md: {loop0:g} s of time loop in {steps0} steps, the nose deeper and more of the "
              "surface loaded than in the first 40 µs): t_step and t_cell times this below", "",
              f"Assumed: a node of {NODE_CORES} cores like these (t_cell, α, β carry over within a node); between "
              f"nodes HDR InfiniBand, α = {1e6 * IB_ALPHA_S:.1f} µs and β = {IB_BETA_B_S / 1e9:.0f} GB/s (not "
              f"measurable here); steps ∝ 1/h ∝ cells^(1/3) from the default run's {DEFAULT_STEPS} steps at "
              f"{DEFAULT_CELLS} cells; the imbalance stays at {imb:.4f}; ranks beyond L/h (bands thinner than a cell)"
              " do no work.", "",
              "| machine | ranks | largest run in an hour (cells) | h (mm) | its steps | ranks that work | step (ms) "
              "| of which exchanges (ms) |", "|---|---|---|---|---|---|---|---|"]
    for name, m, ranks in (("one core", node, 1), ("one node", node, NODE_CORES),
                           ("64 nodes", cluster, 64 * NODE_CORES)):
        n = traffic.largest_run(lambda c, m=m, p=ranks: predict(m, ghosts, c, p, imb), HOUR_S)
        h = DEFAULT_H_MM * (DEFAULT_CELLS / n) ** (1.0 / 3.0)
        steps = DEFAULT_STEPS * (n / DEFAULT_CELLS) ** (1.0 / 3.0)
        _, usable, step, ex = predict(m, ghosts, n, ranks, imb, parts=True)
        lines.append(f"| {name} | {ranks} | {n:.3g} | {h:.3f} | {steps:.0f} | {usable} | {1e3 * step:.2f} "
                     f"| {1e3 * ex:.3f} |")
    lines += ["", "The model against whole runs of the default shot on an idle machine (docs/accuracy-cost.md, "
              "fepen 0.6.0; the model with this machine's constants, times the whole-run factor from the first row, "
              "and the imbalance 1):", "",
              "| h (mm) | ranks | cells | steps | time loop (s) | model (s) |", "|---|---|---|---|---|---|"]
    for h, ranks, cells, steps, loop in IDLE_RUNS:
        model = predict(node, ghosts, cells, ranks, 1.0, steps=steps)
        lines.append(f"| {h:g} | {ranks} | {cells} | {steps} | {loop:.1f} | {model:.1f} |")
    return "\n".join(lines) + "\n"


#: the last measurements (``--again`` writes the report again from them, without running)
KEPT = Path(tempfile.gettempdir()) / "fepen-scaling-rows.json"


def main(sizes: list) -> None:
    if sizes == ["--again"]:
        kept = json.loads(KEPT.read_text())
        link, rows = kept["link"], kept["rows"]
        text = report(rows, link)
        (ROOT / "benchmarks" / "scaling_results.md").write_text(text)
        print(text)
        return
    link = measure_link()
    rows = []
    with tempfile.TemporaryDirectory(prefix="fepen-scaling-") as tmp:
        for h in sizes:
            for p in RANKS:
                s = one_run(h, p, Path(tmp) / f"h{h}-p{p}")
                rows.append(row(h, s))
                r = rows[-1]
                print(f"h = {h:g} mm, ranks = {p}: cells/rank {r['cells_per_rank']:.0f}, bytes/step/rank "
                      f"{r['bytes_step']:.0f} (model {r['model_bytes_step']}), calls/step {r['calls_step']:.2f}, "
                      f"wait/step {1e3 * r['wait_step_s']:.3f} ms, imbalance {r['imbalance']:.4f}, "
                      f"{r['ns_cell_step_core']:.0f} ns per cell-step-core", flush=True)
    KEPT.write_text(json.dumps({"link": link, "rows": rows}))
    text = report(rows, link)
    (ROOT / "benchmarks" / "scaling_results.md").write_text(text)
    print(text)


if __name__ == "__main__":
    if "--pingpong" in sys.argv:
        pingpong()
    else:
        main(sys.argv[1:] if sys.argv[1:] == ["--again"] else [float(a) for a in sys.argv[1:]] or [6.0, 4.0, 2.5])
