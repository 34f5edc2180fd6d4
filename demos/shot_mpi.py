"""One Table 1 shot on 2 MPI ranks, then the result opened in pyvista (run from the repository root).

    .venv/bin/python demos/shot_mpi.py [--shot C3] [--ranks 2] [--out results/demo] [--set KEY=VALUE ...]

Runs ``mpirun -n RANKS fepen run`` with the default scene and the shot, prints the summary, then reads
fields.h5 (mesh, last displacement and PEEQ) and writes demo.png: the deformed projectile coloured by PEEQ
beside its path from history.csv.
"""

import argparse
import json
import os
import sys
from pathlib import Path

import h5py
import numpy as np

from fepen.studies import processes


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--shot", default="C3")
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--out", default="results/demo")
    ap.add_argument("--set", dest="sets", action="append", default=[])
    args = ap.parse_args()
    out = Path(args.out)
    cmd = ["run", "scenes/default.toml", "--out", out.resolve(), "--force", "--set", f'impact.shot="{args.shot}"']
    for s in args.sets:
        cmd += ["--set", s]
    r = processes.run(cmd, args.ranks)
    if r.returncode:
        sys.exit(r.stderr)
    summary = json.loads((out / "summary.json").read_text())
    print({k: summary[k] for k in ("outcome", "Hx_mm", "Hy_mm", "Tx_mm", "Ty_mm", "max_peeq", "ranks", "wall_s")})

    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkOSOpenGLRenderWindow")
    import pyvista as pv

    with h5py.File(out / "fields.h5", "r") as h5:
        topo = h5["Mesh/mesh/topology"][:]
        geom = h5["Mesh/mesh/geometry"][:]
        last = sorted(h5["Function/displacement_m"].keys(), key=lambda k: float(k.replace('_', '.')))[-1]
        u = h5["Function/displacement_m"][last][:]
        peeq = h5["Function/peeq"][last][:].ravel()
    n = len(topo)
    cells = np.hstack([np.full((n, 1), 4), topo]).ravel()
    grid = pv.UnstructuredGrid(cells, np.full(n, pv.CellType.TETRA, dtype=np.uint8), (geom + u) * 1e3)
    grid.cell_data["PEEQ"] = peeq
    plotter = pv.Plotter(off_screen=True, window_size=(1000, 800))
    plotter.set_background("white")
    plotter.add_mesh(grid, scalars="PEEQ", cmap="inferno", show_scalar_bar=False)
    plotter.view_vector((0.0, 0.0, 1.0), viewup=(0.0, 1.0, 0.0))
    plotter.add_text(f"{args.shot}: t = {float(last.replace('_', '.')) * 1e6:.0f} us, "
                     f"PEEQ 0 ... {peeq.max():.3g} (black ... yellow)",
                     font_size=10, color="black")
    plotter.screenshot(str(out / "demo.png"))
    plotter.close()
    print(f"written: {out / 'demo.png'}")


if __name__ == "__main__":
    main()
