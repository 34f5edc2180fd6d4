"""Cost of the deformable step in a real shot: the default scene (plastic C3 into the concrete target), one
run per stable-step estimate, and the split of its time loop.

    .venv/bin/python benchmarks/step_cost.py [--size 0.0012] [--end-time 3e-4] [--ranks 2]
        [--stable-step altitude eigenvalue] [--label TEXT]

With ``--ranks N > 1`` and started without mpirun, the script starts itself under ``mpirun -n N``
(or start it so: ``mpirun -n 2 .venv/bin/python benchmarks/step_cost.py``). Each run builds the shot in
the process (mesh from the cache, solver, target; the eigenvalue step's power iteration is part of the
set-up), runs it to ``run.end_time`` (3e-4 s: about a minute at 1.2 mm on 2 ranks, in the target from the
first step; ``--end-time 0`` runs the whole shot) with its ordinary outputs (history, fields every 50 µs,
checkpoints), and prints:

- cells, steps, the set-up, the time loop, the closing outputs and analyses (pictures), wall per step and
  ns per cell-step per core (loop × ranks / (cells × steps));
- the split of the step (ms per step, the slowest rank's): kinematics (current volumes, nodal volumes and
  their ghost sum, the inversion check), material (nodal pressures, stress update, P), assembly (the
  internal-force vector and its ghost sum), target (the target law on the surface points and its nodal
  forces) and, of it, target_comm (the target load's broadcasts of the nose and tail, its reduction, its
  ghost sum), update (central differences, energies' sums, the acceleration's ghost update), outputs
  (history, fields, checkpoints), rules (the stop rules every 20 steps) and the rest of the loop;
- the ratio of the step to one bare assembly of the internal-force form on the same mesh (dolfinx's
  assemble_vector of the compiled form, coefficients pre-packed, no ghost sum: the floor of the
  dolfinx-assembled step); Hy, the depth of the nose at the end; and, to tell a busy machine, cpu_share
  (the process's CPU time over the wall time of the run, the lowest rank's: below ~0.95 another process
  took the cores) and load (the 1-minute load average at the end, this run's ranks included).

Each run's row is appended to benchmarks/step_cost_results.csv, and benchmarks/step_cost_results.md is
rewritten from it (``--label`` names the row, e.g. "before"; the git commit is recorded).
"""

from __future__ import annotations

import argparse
import csv
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks"
SPLIT = ["kinematics", "material", "assembly", "target", "target_comm", "update", "outputs", "rules", "rest"]
COLUMNS = ["label", "commit", "date", "ranks", "size_mm", "stable_step", "end_time_us", "cells", "steps",
           "setup_s", "loop_s", "closing_s", "ms_per_step", "ns_cell_step_core", *SPLIT, "bare_ms", "step_over_bare",
           "Hy_mm", "cpu_share", "load"]


def _timed(fn, acc: dict, key: str):
    def wrapper(*a, **k):
        t0 = time.perf_counter()
        try:
            return fn(*a, **k)
        finally:
            acc[key] += time.perf_counter() - t0
    return wrapper


def measure(size: float, stable_step: str, end_time: float, comm) -> dict:
    from mpi4py import MPI

    from fepen import scene
    from fepen.runs.deformable import DeformableRun
    from fepen.solver import diagnostics, explicit

    sets = [f"mesh.size={size}", f"run.stable_step={stable_step}"]
    if end_time > 0:
        sets.append(f"run.end_time={end_time}")
    sc = scene.Scene(ROOT / "scenes/default.toml", sets)
    out = comm.bcast(tempfile.mkdtemp(prefix="fepen-step-") if comm.rank == 0 else None, root=0)
    comm.barrier()
    t0 = time.perf_counter()
    run = DeformableRun(sc, out, comm)
    setup_s = time.perf_counter() - t0
    s = run.solver
    acc = {"outputs": 0.0, "rules": 0.0}
    for o in run.outputs:
        o.write = _timed(o.write, acc, "outputs")
    run.stop_rules = _timed(run.stop_rules, acc, "rules")
    s.clock.times = explicit.StepTimes()
    steps0 = s.step_count
    comm.barrier()
    t0, c0 = time.perf_counter(), time.process_time()
    summary = run.run()
    whole = time.perf_counter() - t0
    cpu_share = comm.allreduce((time.process_time() - c0) / whole, op=MPI.MIN)
    load = os.getloadavg()[0]
    loop = summary["time_split_s"]["time_loop"]  # without the closing outputs and analyses
    steps = s.step_count - steps0
    tm = s.clock.times
    parts = {"kinematics": tm.kinematics, "material": tm.material, "assembly": tm.assembly,
             "target": tm.boundary, "target_comm": tm.target_comm, "update": tm.update, **acc}
    parts["rest"] = loop - sum(v for k, v in parts.items() if k != "target_comm")
    parts = {k: comm.allreduce(v, op=MPI.MAX) for k, v in parts.items()}
    # the bare assembly of the internal-force form, on the state at the end

    arr = s.node.fint_fn.x.array.copy()
    reps = 200
    for _ in range(10):
        diagnostics.assemble_form(s, arr)
    comm.barrier()
    t0 = time.perf_counter()
    for _ in range(reps):
        arr[:] = 0.0
        diagnostics.assemble_form(s, arr)
    bare = comm.allreduce((time.perf_counter() - t0) / reps, op=MPI.MAX)
    cells = summary["cells"]
    return dict(ranks=comm.size, size_mm=size * 1e3, stable_step=stable_step, end_time_us=s.t * 1e6, cells=cells,
                steps=steps, setup_s=comm.allreduce(setup_s, op=MPI.MAX), loop_s=loop, closing_s=whole - loop,
                ms_per_step=1e3 * loop / steps, ns_cell_step_core=1e9 * loop * comm.size / (cells * steps),
                **{k: 1e3 * v / steps for k, v in parts.items()}, bare_ms=1e3 * bare,
                step_over_bare=loop / steps / bare, Hy_mm=summary["Hy_mm"], cpu_share=cpu_share,
                load=load)


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.4g}" if abs(v) < 1e4 else f"{v:.0f}"
    return str(v)


def write_results(rows: list[dict]) -> None:
    path = RESULTS / "step_cost_results.csv"
    new = not path.exists()
    with path.open("a", newline="") as f:
        w = csv.DictWriter(f, COLUMNS)
        if new:
            w.writeheader()
        for r in rows:
            w.writerow({k: _fmt(r[k]) for k in COLUMNS})
    write_table()


def write_table() -> None:
    """benchmarks/step_cost_results.md from the CSV; the notes written below the table are kept."""
    path = RESULTS / "step_cost_results.csv"
    md = RESULTS / "step_cost_results.md"
    old = md.read_text().splitlines() if md.is_file() else []
    rows_end = max((i for i, ln in enumerate(old) if ln.startswith("|")), default=len(old) - 1)
    notes = old[rows_end + 1:]
    with path.open() as f:
        table = list(csv.DictReader(f))
    lines = ["# Cost of the deformable step (benchmarks/step_cost.py)", "",
             "The default scene (plastic C3 into the concrete target) to `end_time_us`; ms per step, the split "
             "per step (ms, slowest rank; `target_comm` is part of `target`), `bare_ms` one bare dolfinx "
             "assembly of the internal-force form, `step_over_bare` the whole step over it. One run each, "
             "appended by each call of the benchmark. A `cpu_share` well below 1 means another process "
             "shared the two cores (its times are inflated, ratios less so).", "",
             "| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    lines += ["| " + " | ".join(r.get(k) or "" for k in COLUMNS) + " |" for r in table]
    md.write_text("\n".join(lines + notes) + "\n")


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--size", type=float, default=0.0012, help="mesh.size (m)")
    p.add_argument("--end-time", type=float, default=3e-4, help="run.end_time (s); 0: the whole shot")
    p.add_argument("--ranks", type=int, default=2)
    p.add_argument("--stable-step", nargs="+", default=["altitude", "eigenvalue"])
    p.add_argument("--label", default="")
    a = p.parse_args(argv)
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    if comm.size == 1 and a.ranks > 1:  # start again under mpirun
        sys.path.insert(0, str(ROOT))
        from fepen.studies import processes

        r = processes.run([Path(__file__).resolve(), *(argv if argv is not None else sys.argv[1:])], a.ranks,
                          fepen=False)
        print(r.stdout, end="")
        if r.returncode:
            print(r.stderr, file=sys.stderr)
        sys.exit(r.returncode)
    rows = [measure(a.size, ss, a.end_time, comm) for ss in a.stable_step]
    if comm.rank:
        return
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                            text=True).stdout.strip()
    dirty = subprocess.run(["git", "status", "--porcelain", "fepen/solver", "fepen/runs/model.py",
                            "fepen/runs/deformable.py"], cwd=ROOT, capture_output=True,
                           text=True).stdout.strip()
    for r in rows:
        r.update(label=a.label, commit=commit + ("+" if dirty else ""), date=time.strftime("%Y-%m-%d %H:%M"))
    print(f"ranks {comm.size}, mesh {a.size * 1e3:g} mm; split in ms per step (slowest rank)")
    print(" ".join(f"{k:>{max(len(k), 8)}}" for k in COLUMNS[4:]))
    for r in rows:
        print(" ".join(f"{_fmt(r[k]):>{max(len(k), 8)}}" for k in COLUMNS[4:]))
    write_results(rows)
    print(f"appended to {RESULTS / 'step_cost_results.csv'}; table in {RESULTS / 'step_cost_results.md'}")


if __name__ == "__main__":
    main()
