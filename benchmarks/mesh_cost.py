"""Mesh cost and explicit-step figures of the default projectile at several element sizes, for each meshing route.

Prints, for each size and route (mesh.optimize): cells, nodes, meshing wall time from an empty cache, the
shortest altitude over the nominal size, the smallest mean-ratio quality, the altitude step, the mass; then how
cells and steps grow with 1/h for the first route. The routes run side by side in one process, so their times
are comparable.

    .venv/bin/python benchmarks/mesh_cost.py [sizes in mm ...] [--routes hxt,netgen] [--scene FILE]
"""

import argparse
import math
import os
import tempfile
import time

from mpi4py import MPI

from fepen import scene
from fepen.runs import setup


def one(path, sets):
    """One mesh from an empty cache: (wall seconds, fepen.geometry.mesh.metrics)."""
    with tempfile.TemporaryDirectory() as cache:
        os.environ["FEPEN_MESH_CACHE"] = cache  # empty: measure meshing itself
        sc = scene.load(path, sets)
        t0 = time.perf_counter()
        pm = setup.mesh(sc, MPI.COMM_SELF)
        wall = time.perf_counter() - t0
        return wall, setup.mesh_metrics(pm, sc)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sizes", nargs="*", type=float, default=[4.0, 2.5, 1.6, 1.2], help="element sizes (mm)")
    ap.add_argument("--routes", default="hxt,netgen", help="mesh.optimize values, comma-separated")
    ap.add_argument("--scene", default=None, help="a scene file (default: the default scene)")
    a = ap.parse_args()
    routes = a.routes.split(",")
    rows = []
    print(f"{'h_mm':>6} {'route':>7} {'cells':>8} {'nodes':>7} {'mesh_s':>7} {'alt/h':>6} {'min_q':>6} "
          f"{'dt_ns':>7} {'mass_g':>8}")
    for h in a.sizes:
        for route in routes:
            wall, i = one(a.scene, [f"mesh.size={h * 1e-3}", f"mesh.optimize={route}"])
            rows.append((h, route, i, wall))
            print(f"{h:6.2f} {route:>7} {i['cells']:8d} {i['nodes']:7d} {wall:7.1f} {i['altitude_over_size']:6.3f} "
                  f"{i['min_quality']:6.3f} {i['stable_dt_s'] * 1e9:7.1f} {i['mass_kg'] * 1e3:8.2f}", flush=True)
    first = [r for r in rows if r[1] == routes[0]]
    if len(first) > 1:
        (h0, _, i0, _), (h1, _, i1, _) = first[0], first[-1]
        r = math.log(h0 / h1)
        print(f"{routes[0]}: cells grow as h^-{math.log(i1['cells'] / i0['cells']) / r:.2f}; altitude step as "
              f"h^{math.log(i1['stable_dt_s'] / i0['stable_dt_s']) / r * -1:.2f}")
    for h in a.sizes:
        t = {route: wall for hh, route, _, wall in rows if hh == h}
        if len(t) > 1:
            print(f"{h:.2f} mm: " + ", ".join(f"{k} {v / t[routes[0]]:.2f}x" for k, v in t.items()) +
                  f" the time of {routes[0]}")


if __name__ == "__main__":
    main()
