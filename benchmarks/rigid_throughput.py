"""Rigid shots as a sweep, a study and a user run them, for this tree and a baseline revision in one run (issue 62's
first acceptance): each figure measured for both trees back to back, so that their ratio holds whatever else the
machine does.

    .venv/bin/python benchmarks/rigid_throughput.py [--baseline REV] [--shots 4000] [--ranks 2] [--repeats 3]

- the Monte Carlo sweep of ``demos/studies/c3_scatter.toml`` resized to SHOTS (v0 ± 20 m/s, obliquity ± 1°, yaw
  ± 0.5°, f_c ± 10 %, seed 2026; the tunnel on) as ``mpirun -n RANKS python -m fepen sweep``, timed from outside:
  ms per shot·core = wall × ranks / shots (start-up, the table and its figures included);
- the same shots in-process, batched (``fepen.runs.batch.summaries``, warm): CPU ms per shot;
- one rigid C3 as a user starts it (``python -m fepen run scenes/default.toml --set effects.fidelity=rigid --set
  run.fields=false --set run.figures=false``, no mpirun, caches warm): its wall time, the best of REPEATS.

Prints a table and writes benchmarks/rigid_throughput_results.md. The baseline is a git worktree of REV run from
this tree's .venv with its own source first on PYTHONPATH; the sweep tables of both trees are compared (the
tunnel's location changed in issue 62: the shots agree to the tunnel's bound, not bit for bit).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import baseline  # benchmarks/baseline.py: this tree and a baseline worktree

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "demos" / "studies" / "c3_scatter.toml"
IN_PROCESS = 400  # shots of the in-process figure

_BATCH = """
import sys, time
from fepen.runs import batch
from fepen.studies import sweep
sw = sweep.read(sys.argv[1])
scenes = [sw.scene(i) for i in range(int(sys.argv[2]))]
batch.summaries(scenes[:2])
c = time.process_time()
batch.summaries(scenes)
print((time.process_time() - c) / len(scenes))
"""


def _env(tree: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree), FEPEN_PROGRESS="0")
    env.pop("OMPI_MCA_mpi_yield_when_idle", None)
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # a user's Python keeps its compiled modules
    return env


def _timed(cmd: list, tree: Path) -> tuple[float, str]:
    t0 = time.perf_counter()
    r = subprocess.run(cmd, cwd=tree, env=_env(tree), capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        raise SystemExit(f"rigid_throughput: {' '.join(map(str, cmd))} in {tree} failed (exit {r.returncode}):\n"
                         f"{r.stderr[-2000:]}")
    return wall, r.stdout


def measure(tree: Path, shots: int, ranks: int, repeats: int, work: Path) -> dict:
    """The three figures for the source tree ``tree`` (its sweep's folder kept in ``work``)."""
    py = sys.executable
    spec = work / "mc.toml"
    resize = ("from fepen.studies import sweep; import sys; "
              "print(sweep.resized(sys.argv[1], int(sys.argv[2])), end='')")
    spec.write_text(_timed([py, "-c", resize, str(DEMO), str(shots)], tree)[1])
    cpu = float(_timed([py, "-c", _BATCH, str(spec), str(min(shots, IN_PROCESS))], tree)[1].split()[-1])
    one = [py, "-m", "fepen", "run", "scenes/default.toml", "--set", "effects.fidelity=rigid", "--set",
           "run.fields=false", "--set", "run.figures=false", "--out", str(work / "one"), "--force"]
    _timed(one, tree)  # caches warm
    process = min(_timed(one, tree)[0] for _ in range(repeats))
    wall, _ = _timed(["mpirun", "-n", str(ranks), py, "-m", "fepen", "sweep", str(spec), "--out",
                      str(work / "sweep"), "--fresh"], tree)
    return {"sweep_ms": 1e3 * wall * ranks / shots, "sweep_s": wall, "batched_ms": 1e3 * cpu,
            "process_s": process, "table": (work / "sweep" / "sweep.csv").read_text()}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baseline", help="a git revision measured beside this tree (a worktree of it)")
    ap.add_argument("--shots", type=int, default=4000)
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    rows = []
    with baseline.trees(args.baseline) as trees:
        for tree, label in trees:
            work = Path(tempfile.mkdtemp(prefix="fepen-rigid-throughput-"))
            try:
                rows.append((label, measure(tree, args.shots, args.ranks, args.repeats, work)))
            finally:
                shutil.rmtree(work, ignore_errors=True)
    lines = [f"`benchmarks/rigid_throughput.py --shots {args.shots} --ranks {args.ranks}"
             + (f" --baseline {args.baseline}`" if args.baseline else "`") + ", one run, this machine's 2 cores.", "",
             f"| tree | {args.shots}-shot sweep on {args.ranks} ranks: wall (s) | per shot·core (ms, whole process) "
             f"| batched in-process, CPU per shot (ms) | one rigid C3 process (s, best of {args.repeats}) |",
             "|---|---|---|---|---|"]
    for label, r in rows:
        lines.append(f"| {label} | {r['sweep_s']:.1f} | {r['sweep_ms']:.1f} | {r['batched_ms']:.1f} | "
                     f"{r['process_s']:.2f} |")
    if len(rows) == 2:
        a, b = rows[0][1], rows[1][1]
        lines += ["", f"Ratios (this tree over the baseline): sweep {a['sweep_ms'] / b['sweep_ms']:.2f}, batched "
                  f"{a['batched_ms'] / b['batched_ms']:.2f}, process {a['process_s'] / b['process_s']:.2f}; the sweep "
                  f"tables {'identical' if a['table'] == b['table'] else 'differ (the tunnel located by rings)'}."]
    text = "\n".join(lines)
    print(text)
    Path(__file__).with_name("rigid_throughput_results.md").write_text("# Rigid shots: throughput\n\n" + text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
