"""Wall time of one deformable shot (default scene: plastic, Table 1 C3, default mesh) and its split.

    .venv/bin/python benchmarks/shot_cost.py [RANKS ...]       (default: 1 2)

Each run is a whole ``mpirun -n RANKS fepen run`` process (fields written, as a user would); the split
(mesh, set-up and compilation, time loop, output) comes from the run's summary.json; the whole-process time
includes Python start-up and imports.
"""

import json
import sys
import tempfile
import time
from pathlib import Path

from fepen.studies import processes

ROOT = Path(__file__).resolve().parents[1]


def run(ranks: int) -> dict:
    out = Path(tempfile.mkdtemp(prefix="fepen-shot-"))
    t0 = time.perf_counter()
    processes.run(["run", ROOT / "scenes/default.toml", "--out", out, "--force"], ranks, check=True)
    whole = time.perf_counter() - t0
    s = json.loads((out / "summary.json").read_text())
    return dict(ranks=ranks, whole=whole, **s["time_split_s"], steps=s["steps"], Hy=s["Hy_mm"])


def main(ranks):
    rows = [run(r) for r in ranks]
    print(f"{'ranks':>5} {'whole_s':>8} {'mesh_s':>7} {'setup_jit_s':>11} {'loop_s':>7} {'output_s':>8} "
          f"{'steps':>6} {'Hy_mm':>7}")
    for r in rows:
        print(f"{r['ranks']:5d} {r['whole']:8.1f} {r['mesh']:7.2f} {r['setup_jit']:11.2f} {r['time_loop']:7.1f} "
              f"{r['output']:8.2f} {r['steps']:6d} {r['Hy']:7.1f}")
    if len(rows) > 1:
        print(f"speed-up of the time loop, {rows[0]['ranks']} -> {rows[-1]['ranks']} ranks: "
              f"{rows[0]['time_loop'] / rows[-1]['time_loop']:.2f}")


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [1, 2])
