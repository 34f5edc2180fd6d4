"""The two stacks' speed in one run (docs/install.md): the same commands with Debian's dolfinx 0.5.2 (.venv) and the
current dolfinx 0.11 (.venv-current), taken in turn, each several times, and their ratios.

    .venv/bin/python benchmarks/stack_cost.py [--repeat 3] [--size 0.0025] [--end-time 3e-4]

The commands: ``fepen --version`` (the imports), Table 1's C3 rigid (no dolfinx) and C3 deformable at ``--size``
to ``--end-time`` on one rank (mesh from the cache, fields off). For each: the median wall of the whole process,
and for the deformable shot the time loop's and the ns per cell-step from its summary (the step itself, imports
and JIT left out). Ratios are current over Debian: above 1, the current stack is slower.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
from compare_stacks import STACKS  # noqa: E402


def timed(cmd: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, cwd=ROOT, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--size", type=float, default=2.5e-3)
    ap.add_argument("--end-time", type=float, default=3e-4)
    args = ap.parse_args(argv)
    missing = [str(p) for p in STACKS.values() if not p.is_file()]
    if missing:
        print(f"stack_cost: both stacks needed (make setup, make setup-current): missing {missing}")
        return 2
    tmp = Path(tempfile.mkdtemp(prefix="stack-cost-"))
    plastic = ["run", "--set", f"mesh.size={args.size}", "--set", f"run.end_time={args.end_time}", "--set",
               "run.fields=false", "--force"]
    cases = {"fepen --version": ["--version"], "C3 rigid": ["run", "--set", "effects.fidelity=rigid", "--force"],
             f"C3 plastic, {args.size * 1e3:g} mm, {args.end_time * 1e6:g} us": plastic}
    walls = {(c, s): [] for c in cases for s in STACKS}
    loops = {s: [] for s in STACKS}
    ns = {s: [] for s in STACKS}
    for stack, py in STACKS.items():  # warm the caches (numba, C kernels, the mesh) before timing
        subprocess.run([str(py), "-m", "fepen", *plastic, "--out", str(tmp / stack)], cwd=ROOT, check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    for _ in range(args.repeat):
        for case, a in cases.items():
            for stack, py in STACKS.items():
                out = ["--out", str(tmp / stack)] if a[0] == "run" else []
                walls[case, stack].append(timed([str(py), "-m", "fepen", *a, *out]))
                if a is plastic:
                    s = json.loads((tmp / stack / "summary.json").read_text())
                    loops[stack].append(s["time_split_s"]["time_loop"])
                    ns[stack].append(s["time_split_s"]["time_loop"] / (s["cells"] * s["steps"]) * 1e9)
    print(f"median of {args.repeat}, taken in turn (s); ratio = current / Debian")
    print("| command | Debian 0.5.2 | current 0.11 | ratio |\n|---|---|---|---|")
    for case in cases:
        a, b = (statistics.median(walls[case, s]) for s in STACKS)
        print(f"| {case}: whole process | {a:.2f} | {b:.2f} | {b / a:.2f} |")
    a, b = (statistics.median(loops[s]) for s in STACKS)
    print(f"| the plastic shot's time loop | {a:.2f} | {b:.2f} | {b / a:.2f} |")
    a, b = (statistics.median(ns[s]) for s in STACKS)
    print(f"| the plastic shot's ns per cell-step | {a:.0f} | {b:.0f} | {b / a:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
