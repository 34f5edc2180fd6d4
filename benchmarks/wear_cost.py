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

STEPS = 200
REPEATS = 8


def build(h_mm, variant, comm):
    sets = [f"mesh.size={h_mm * 1e-3}", "run.fields=false"]
    if "wear" in variant:
        sets.append("effects.wear=true")
    if "erosion" in variant:
        sets.append("effects.erosion=true")
    m = model.build(scene.load(None, sets), comm)
    for _ in range(20):  # compile and warm up
        m.solver.step()
    return m


def loop(m, comm) -> float:
    """STEPS steps as a run takes them (the recession every Recession.every, the erosion check every 4)."""
    s = m.solver
    rec, ero = getattr(m, "recession", None), getattr(m, "erosion", None)
    comm.barrier()
    t0 = time.perf_counter()
    for _ in range(STEPS):
        s.step()
        if rec is not None and s.step_count % rec.every == 0:
            rec.apply()
        if ero is not None and s.step_count % 4 == 1:
            ero.check()
    comm.barrier()
    return (time.perf_counter() - t0) / STEPS


def main():
    """The variants are built first and their loops interleaved, REPEATS rounds, the best of each kept: a
    machine whose speed drifts slows every variant alike."""
    comm = MPI.COMM_WORLD
    h = float(sys.argv[1]) if len(sys.argv) > 1 else 2.5
    variants = sys.argv[2:] or ["off", "wear", "wear+erosion"]
    models = [build(h, v, comm) for v in variants]
    best = [float("inf")] * len(variants)
    for _ in range(REPEATS):
        for i, m in enumerate(models):
            best[i] = min(best[i], loop(m, comm))
    for v, t, m in zip(variants, best, models):
        if comm.rank == 0:
            print(f"{v:14s} h = {h} mm, {m.solver.n_cells} cells on rank 0, {comm.size} rank(s): step "
                  f"{t * 1e3:.3f} ms, ratio to {variants[0]} {t / best[0]:.3f}", flush=True)


if __name__ == "__main__":
    main()
