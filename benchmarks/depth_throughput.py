"""Throughput of the depth study's rigid predictions (fepen.studies.depth: ``fepen validate-depth``, and the
calibration's curves) on a synthetic set of varied projectiles, every row its own (12.9-203 mm, L/D 5-10,
CRH 2-6, about half the mass of a solid steel cylinder, 200-1200 m/s into 13-160 MPa), in one run:

1. in this process, each shot by the study's two rigid laws as rigid_depth runs them: shots per second, and a
   shot's time split between its set-up (the scene, the projectile built to its mass, its load points:
   fepen.runs.shot.resolve and RigidRun's construction) and its integration (RigidRun.run), the first law and
   the second apart (the second finds the projectile and its load points built);
2. the whole fepen.studies.depth.predict_sets with WORKERS processes (wall seconds, the pool's start and
   its workers' imports included).

    .venv/bin/python benchmarks/depth_throughput.py [SHOTS] [WORKERS]      (default: 40 shots, 2 workers)

The depths are the same bitwise whatever the machine's load; the seconds are not: run it on an idle machine.
"""

import math
import random
import sys
import time

from mpi4py import MPI

from fepen import scene
from fepen.runs import shot
from fepen.runs.rigid import RigidRun
from fepen.studies import depth


def synthetic_set(n: int, seed: int = 7) -> list:
    """n shots, calibres spread evenly in log between 12.9 and 203 mm, the rest drawn at random."""
    rng = random.Random(seed)
    rows = []
    for i in range(n):
        d = 12.9e-3 * (203.0 / 12.9) ** (i / max(n - 1, 1))
        L = d * rng.uniform(5.0, 10.0)
        m = 7850.0 * math.pi / 4.0 * d * d * L * rng.uniform(0.45, 0.6)
        fc = math.exp(rng.uniform(math.log(13.0), math.log(160.0))) * 1e6
        rows.append(depth.Row(f"S{i:02d}", d, L, m, rng.uniform(2.0, 6.0), rng.uniform(200.0, 1200.0), fc, 2400.0,
                              1.0))
    return rows


def in_process(rows) -> None:
    methods = [m for m, sets in depth.METHODS.items() if sets is not None]
    depth.rigid_depth(depth.table1_set()[0])  # the imports and the C kernels, once
    split = {m: [0.0, 0.0] for m in methods}
    steps = 0
    t_all = time.perf_counter()
    for row in rows:
        for m in methods:
            t0 = time.perf_counter()
            sc = scene.load(None, [*depth.scene_sets(row), *depth.METHODS[m]])
            run = RigidRun(shot.resolve(sc), None, MPI.COMM_SELF, history=False)
            t1 = time.perf_counter()
            run.run()
            split[m][0] += t1 - t0
            split[m][1] += time.perf_counter() - t1
            steps += run.step_count
    wall = time.perf_counter() - t_all
    runs = len(rows) * len(methods)
    print(f"in this process: {runs} rigid runs ({len(rows)} shots x {len(methods)} laws) in {wall:.2f} s: "
          f"{runs / wall:.1f} runs/s, {1e3 * wall / runs:.1f} ms a run, {steps / runs:.0f} steps a run")
    print(f"{'law':14s} {'setup_ms':>9s} {'integrate_ms':>13s} {'us/step':>8s}")
    for m, (setup_s, loop_s) in split.items():
        print(f"{m:14s} {1e3 * setup_s / len(rows):9.2f} {1e3 * loop_s / len(rows):13.2f} "
              f"{1e6 * loop_s * len(methods) / steps:8.1f}")


def pooled(rows, workers: int) -> None:
    t0 = time.perf_counter()
    depth.predict_sets({"synthetic": rows}, workers=workers)
    wall = time.perf_counter() - t0
    runs = 2 * len(rows)
    print(f"predict_sets, {workers} workers: {len(rows)} shots ({runs} rigid runs and the closed form) in "
          f"{wall:.2f} s wall: {runs / wall:.1f} rigid runs/s")


def main(n: int, workers: int) -> None:
    rows = synthetic_set(n)
    in_process(rows)
    pooled(rows, workers)


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 40, int(sys.argv[2]) if len(sys.argv) > 2 else 2)
