"""Cost of wear and erosion per step: the default shot C3 (plastic, in the target) stepped from impact with
wear and erosion off, wear on, and wear and erosion on; the same loop as a run (the recession applied every
``Recession.every`` steps, the erosion checked every 4). Prints the step time of each and its ratio to "off",
in one run.

    .venv/bin/python benchmarks/wear_cost.py [mesh size in mm] [variants: off wear wear+erosion]

"off" runs on releases without wear too (to compare the step with the code before it).
"""

import sys
import time

from mpi4py import MPI

from fepen import scene
from fepen.runs import model

STEPS = 400
REPEATS = 3


def measure(h_mm, variant, comm):
    sets = [f"mesh.size={h_mm * 1e-3}", "run.fields=false"]
    if "wear" in variant:
        sets.append("effects.wear=true")
    if "erosion" in variant:
        sets.append("effects.erosion=true")
    m = model.build(scene.load(None, sets), comm)
    s = m.solver
    rec, ero = getattr(m, "recession", None), getattr(m, "erosion", None)
    for _ in range(20):  # compile and warm up
        s.step()
    best = float("inf")
    for _ in range(REPEATS):
        comm.barrier()
        t0 = time.perf_counter()
        for _ in range(STEPS):
            s.step()
            if rec is not None and s.step_count % rec.every == 0:
                rec.apply()
            if ero is not None and s.step_count % 4 == 1:
                ero.check()
        comm.barrier()
        best = min(best, (time.perf_counter() - t0) / STEPS)
    return best, s.n_cells


def main():
    comm = MPI.COMM_WORLD
    h = float(sys.argv[1]) if len(sys.argv) > 1 else 2.5
    variants = sys.argv[2:] or ["off", "wear", "wear+erosion"]
    base = None
    for v in variants:
        t, cells = measure(h, v, comm)
        base = base or t
        if comm.rank == 0:
            print(f"{v:14s} h = {h} mm, {cells} cells on rank 0, {comm.size} rank(s): step {t * 1e3:.3f} ms, "
                  f"ratio to {variants[0]} {t / base:.3f}", flush=True)


if __name__ == "__main__":
    main()
