"""Cost of the field output per output time: the default shot C3 (2.5 mm cells) stepped from impact, its fields
written OUTPUTS times (DeformableRun.write_fields, as a run writes them), then consolidated. Prints the write
time per output time (best of the rounds) and the bytes per output time (fields.h5 + fields.xdmf after the
run, divided by the output times), in one run.

    .venv/bin/python benchmarks/field_output.py [mesh size in mm]        (any number of ranks)

The same script runs on releases before the one-grid-per-time layout (commit e70b094 and earlier), to compare
(PYTHONPATH=<a checkout of it>).
"""

import sys
import tempfile
import time
from pathlib import Path

from mpi4py import MPI

from fepen import scene
from fepen.runs.deformable import DeformableRun

OUTPUTS = 12
STEPS_BETWEEN = 10


def main():
    comm = MPI.COMM_WORLD
    h = float(sys.argv[1]) if len(sys.argv) > 1 else 2.5
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(comm.bcast(tmp, root=0)) / "run"
        run = DeformableRun(scene.load(None, [f"mesh.size={h * 1e-3}"]), out, comm)
        s = run.solver
        times = []
        for _ in range(OUTPUTS):
            for _ in range(STEPS_BETWEEN):
                s.step()
            comm.barrier()
            t0 = time.perf_counter()
            run.write_fields()
            comm.barrier()
            times.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        run.fields.consolidate()
        comm.barrier()
        t_cons = time.perf_counter() - t0
        if comm.rank == 0:
            n = len(run.fields.times)
            size = sum((out / f).stat().st_size for f in ("fields.h5", "fields.xdmf"))
            xdmf = (out / "fields.xdmf").stat().st_size
            print(f"h = {h} mm, {run.fields.n_nodes_global} nodes, {run.fields.n_cells_global} cells, "
                  f"{comm.size} rank(s), {n} output times: write {1e3 * min(times):.2f} ms (best), "
                  f"{1e3 * sorted(times)[n // 2]:.2f} ms (median) per output time; consolidate "
                  f"{1e3 * t_cons / n:.2f} ms per output time; {size / n / 1e3:.1f} kB per output time "
                  f"(of which fields.xdmf {xdmf / n / 1e3:.2f} kB)", flush=True)


if __name__ == "__main__":
    main()
