"""Mesh cost and explicit-step figures of the default projectile at several element sizes.

Prints, for each size: cells, nodes, meshing wall time (from a cold cache), the shortest altitude over the
nominal size, and the stable step; and the ratios between sizes (how cells and steps grow with 1/h).

    .venv/bin/python benchmarks/mesh_cost.py [sizes in mm ...]
"""

import sys
import tempfile
import time

from mpi4py import MPI

from fepen import scene
from fepen.runs import setup


def main(sizes_mm):
    rows = []
    with tempfile.TemporaryDirectory() as cache:
        import os

        os.environ["FEPEN_MESH_CACHE"] = cache  # cold: measure meshing itself
        for h in sizes_mm:
            sc = scene.load(None, [f"mesh.size={h * 1e-3}"])
            t0 = time.perf_counter()
            pm = setup.mesh(sc, MPI.COMM_SELF)
            wall = time.perf_counter() - t0
            info = setup.mesh_metrics(pm, sc)
            rows.append((h, info, wall))
    print(f"{'h_mm':>6} {'cells':>8} {'nodes':>7} {'mesh_s':>7} {'alt/h':>6} {'dt_ns':>7} {'mass_g':>8}")
    for h, i, wall in rows:
        print(f"{h:6.2f} {i['cells']:8d} {i['nodes']:7d} {wall:7.1f} {i['altitude_over_size']:6.3f} "
              f"{i['stable_dt_s'] * 1e9:7.1f} {i['mass_kg'] * 1e3:8.2f}")
    (h0, i0, _), (h1, i1, _) = rows[0], rows[-1]
    import math

    r = math.log(h0 / h1)
    print(f"cells grow as h^-{math.log(i1['cells'] / i0['cells']) / r:.2f}; stable step as "
          f"h^{math.log(i1['stable_dt_s'] / i0['stable_dt_s']) / r * -1:.2f}; "
          f"cell-steps per unit time as h^-"
          f"{math.log(i1['cells'] / i0['cells'] * i0['stable_dt_s'] / i1['stable_dt_s']) / r:.2f}")


if __name__ == "__main__":
    main([float(a) for a in sys.argv[1:]] or [4.0, 2.5, 1.6, 1.2])
