"""The rigid fidelity: the default (a volume mesh at mesh.size for the mass properties, its outer facets as
load points) against the mesh-free set-up (the exact solid of revolution, rings of load points on its exact
surface; fepen.geometry.revolution), in one run: set-up and time-loop seconds, depth differences, sideways
drift; then the whole ``fepen run`` process of the default rigid shot.

    .venv/bin/python benchmarks/rigid_shot.py
"""

import time

from mpi4py import MPI

from fepen import scene
from fepen.geometry import revolution
from fepen.runs import setup
from fepen.runs.rigid import RigidRun
from fepen.studies import processes

CASES = {
    "C3": ["impact.shot=C3"],
    "30.5 mm x 305 mm solid, 800 m/s": ["projectile.diameter=0.0305", "projectile.length=0.305",
                                         "projectile.cavity_diameter=0", "impact.velocity=800",
                                         "impact.obliquity_deg=0", "impact.attack_deg=0",
                                         "target.compressive_strength=58.4e6"],
}


def timed(make):
    t0 = time.perf_counter()
    run = make()
    t1 = time.perf_counter()
    s = run.run()
    return s, t1 - t0, time.perf_counter() - t1, len(run.pts["area0"])


def main():
    print(f"{'case':34s} {'method':10s} {'points':>7s} {'setup_s':>8s} {'loop_s':>7s} {'Hy_mm':>9s} {'Hx_mm':>8s}")
    for name, sets in CASES.items():
        sc = scene.load(None, ["effects.fidelity=rigid", *sets])
        shape = setup.projectile_shape(sc)
        RigidRun(sc, None, MPI.COMM_SELF)  # warm: the mesh cache, imports
        rows = {}
        rows["mesh"] = timed(lambda sc=sc: RigidRun(sc, None, MPI.COMM_SELF))
        rows["exact"] = timed(lambda sc=sc, shape=shape: RigidRun(
            sc, None, MPI.COMM_SELF, revolution.load_points(shape, sc.mesh.size),
            revolution.mass_properties(shape, sc.projectile.material.density)))
        for method, (s, setup_s, loop_s, n) in rows.items():  # noqa: B007
            print(f"{name:34s} {method:10s} {n:7d} {setup_s:8.3f} {loop_s:7.3f} {s['Hy_mm']:9.3f} {s['Hx_mm']:8.4f}")
        a, b = rows["mesh"][0], rows["exact"][0]
        wall = (rows["exact"][1] + rows["exact"][2]) / (rows["mesh"][1] + rows["mesh"][2])
        print(f"{'':34s} exact/mesh: depth {b['depth_mm'] / a['depth_mm'] - 1:+.2%}, "
              f"Hx {b['Hx_mm'] - a['Hx_mm']:+.3f} mm, wall {wall:.3f}")
        t0 = time.perf_counter()
        r = processes.run(["run", "--set", "effects.fidelity=rigid", *[x for k in sets for x in ("--set", k)],
                           "--out", f"/tmp/fepen-bench-rigid-{len(sets)}"])
        print(f"{'':34s} whole `fepen run` process (default): {time.perf_counter() - t0:.2f} s, exit {r.returncode}")


if __name__ == "__main__":
    main()
