"""Wall time of one rigid-fidelity shot (Table 1 C3 by default), split into mesh/setup and time loop.

    .venv/bin/python benchmarks/rigid_shot.py [SHOT]      (also under mpirun -n 2)
"""

import sys
import time

from mpi4py import MPI

from fepen import scene
from fepen.runs.rigid import RigidRun


def main(name="C3", repeats=3):
    comm = MPI.COMM_WORLD
    sc = scene.load(None, ["effects.fidelity=rigid", f'impact.shot="{name}"'])
    RigidRun(sc, None, comm).run()  # warm: mesh cache, imports
    best = None
    for _ in range(repeats):
        t0 = time.perf_counter()
        run = RigidRun(sc, None, comm)
        t1 = time.perf_counter()
        s = run.run()
        t2 = time.perf_counter()
        row = (t1 - t0, s["time_split_s"]["time_loop"], t2 - t0, s["steps"], s["load_points"])
        best = row if best is None or row[2] < best[2] else best
    if comm.rank == 0:
        print(f"shot {name}, {comm.size} rank(s), best of {repeats}: setup (mesh from cache, surface, mass) "
              f"{best[0]:.3f} s, time loop {best[1]:.3f} s, total {best[2]:.3f} s; {best[3]} RK4 steps, "
              f"{best[4]} load points, {best[1] / best[3] * 1e3:.2f} ms per step")


if __name__ == "__main__":
    main(*sys.argv[1:2])
