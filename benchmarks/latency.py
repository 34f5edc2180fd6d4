"""Where a user waits: the whole `fepen run` process of the default C3 shot against its time loop, with every
cache empty (a fresh machine) and with every cache warm, for this tree and a baseline revision in one run.

    .venv/bin/python benchmarks/latency.py [--baseline REV] [--ranks 2] [--repeats 2] [--set KEY=VALUE ...]
        [--warm-only]

The rigid shot (issue 62's second figure, a rigid C3 process): ``--ranks 1 --set effects.fidelity=rigid --set
run.fields=false --set run.figures=false``: one rank is started as a user starts it, without mpirun.

Each run is a whole ``mpirun -n RANKS python -m fepen run scenes/default.toml`` process, timed from outside,
with the settings given (``--set mesh.size=0.0012 --set run.fields=false --warm-only``: issue 48's second
figure, the loop in ns per cell-step·core, loop × ranks / (cells × steps), beside the baseline). The ranks
run as a user's shell starts them: the Makefile's OMPI_MCA_mpi_yield_when_idle (for the tests, whose
2-rank runs share the cores) is left out, since a waiting rank that yields its core costs a step 15-25 %;
its split (mesh, set-up and compilation, time loop, output, the rest) is the run's summary.json
``time_split_s``. "cold": empty caches of its own (FEPEN_MESH_CACHE, FEPEN_KERNEL_CACHE, NUMBA_CACHE_DIR,
XDG_CACHE_HOME and MPLCONFIGDIR in a new temporary folder); "warm": the same folder again, after the cold run
filled it. The baseline is a git worktree of REV run from this tree's .venv with its own source first on
PYTHONPATH (its meshes and kernels built in its own temporary caches, as a fresh machine would). The ratio
whole / time_loop is issue 48's first acceptance figure (≤ 2.5 cold, ≤ 1.5 warm).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import baseline  # benchmarks/baseline.py: this tree and a baseline worktree

ROOT = Path(__file__).resolve().parents[1]


def one(tree: Path, caches: Path, ranks: int, sets: list[str] = ()) -> dict:
    """One whole process of the default shot (with ``sets``) from source tree ``tree`` with its caches in
    ``caches``."""
    out = Path(tempfile.mkdtemp(prefix="fepen-latency-"))
    env = dict(os.environ, PYTHONPATH=str(tree), FEPEN_MESH_CACHE=str(caches / "meshes"),
               FEPEN_KERNEL_CACHE=str(caches / "kernels"), NUMBA_CACHE_DIR=str(caches / "numba"),
               XDG_CACHE_HOME=str(caches / "xdg"), MPLCONFIGDIR=str(caches / "mpl"), FEPEN_PROGRESS="0")
    env.pop("OMPI_MCA_mpi_yield_when_idle", None)
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # a user's Python keeps its compiled modules
    launcher = ["mpirun", "-n", str(ranks)] if ranks > 1 else []  # one rank: started as a user starts a rigid shot
    cmd = [*launcher, sys.executable, "-m", "fepen", "run", str(tree / "scenes" / "default.toml"),
           "--out", str(out), "--force", *[a for kv in sets for a in ("--set", kv)]]
    t0 = time.perf_counter()
    r = subprocess.run(cmd, cwd=tree, env=env, capture_output=True, text=True)
    whole = time.perf_counter() - t0
    if r.returncode != 0:
        raise SystemExit(f"latency: the run in {tree} failed (exit {r.returncode}):\n{r.stderr[-2000:]}")
    s = json.loads((out / "summary.json").read_text())
    shutil.rmtree(out, ignore_errors=True)
    split = s.get("time_split_s", {})
    return {"whole_s": whole, "loop_s": split.get("time_loop", float("nan")), "mesh_s": split.get("mesh", 0.0),
            "setup_s": split.get("setup_jit", 0.0), "output_s": split.get("output", 0.0), "Hy_mm": s["Hy_mm"],
            "steps": s["steps"], "ns": (1e9 * split.get("time_loop", float("nan")) * ranks / (s["cells"] * s["steps"])
                                        if s["cells"] > 1 else float("nan"))}


def measure(tree: Path, label: str, ranks: int, repeats: int, sets: list[str] = (), warm_only: bool = False
            ) -> list[dict]:
    """Each repeat: a cold run in new empty caches, then a warm one in them (warm_only: the cold run is made
    to fill the caches and not reported)."""
    rows = []
    for _ in range(repeats):
        caches = Path(tempfile.mkdtemp(prefix="fepen-latency-caches-"))
        try:
            cold = {"tree": label, "caches": "cold", **one(tree, caches, ranks, sets)}
            if not warm_only:
                rows.append(cold)
            rows.append({"tree": label, "caches": "warm", **one(tree, caches, ranks, sets)})
        finally:
            shutil.rmtree(caches, ignore_errors=True)
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baseline", help="a git revision measured beside this tree (a worktree of it)")
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE",
                    help="a scene setting for every run (repeatable)")
    ap.add_argument("--warm-only", action="store_true", help="report the warm runs only")
    args = ap.parse_args(argv)
    with baseline.trees(args.baseline) as trees:
        rows = [r for tree, label in trees for r in measure(tree, label, args.ranks, args.repeats, args.sets,
                                                                args.warm_only)]
    print(f"default C3 shot{' with ' + ', '.join(args.sets) if args.sets else ''}, {args.ranks} ranks, whole "
          "process against its time loop")
    print(f"{'tree':24s} {'caches':6s} {'whole_s':>8} {'loop_s':>7} {'ratio':>6} {'mesh_s':>7} {'setup_s':>8} "
          f"{'output_s':>8} {'steps':>6} {'ns/cell-step-core':>17} {'Hy_mm':>8}")
    for r in rows:
        print(f"{r['tree']:24s} {r['caches']:6s} {r['whole_s']:8.3f} {r['loop_s']:7.3f} "
              f"{r['whole_s'] / r['loop_s']:6.2f} {r['mesh_s']:7.2f} {r['setup_s']:8.2f} {r['output_s']:8.2f} "
              f"{r['steps']:6d} {r['ns']:17.1f} {r['Hy_mm']:8.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
