"""The rigid fidelity before and after issue 13, in one run: the volume mesh at mesh.size for the mass
properties and its outer facets as load points (before; ``points="mesh"``) against the default without a
mesh (the exact solid of revolution, rings of load points on its exact surface; after): set-up and
time-loop seconds, wall_s, depth difference, sideways travel; then the whole ``fepen run`` process of each
case (the default, mesh-free) with its wall seconds.

    .venv/bin/python benchmarks/rigid_shot.py
"""

import time

from mpi4py import MPI

from fepen import scene
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
    print(f"{'case':34s} {'method':10s} {'points':>7s} {'setup_s':>8s} {'loop_s':>7s} {'wall_s':>7s} "
          f"{'Hy_mm':>9s} {'Hx_mm':>8s}")
    for name, sets in CASES.items():
        sc = scene.load(None, ["effects.fidelity=rigid", *sets])
        RigidRun(sc, None, MPI.COMM_SELF, points="mesh")  # warm: the mesh cache, imports
        rows = {"mesh": timed(lambda sc=sc: RigidRun(sc, None, MPI.COMM_SELF, points="mesh")),
                "rings": timed(lambda sc=sc: RigidRun(sc, None, MPI.COMM_SELF))}
        for method, (s, setup_s, loop_s, n) in rows.items():
            print(f"{name:34s} {method:10s} {n:7d} {setup_s:8.3f} {loop_s:7.3f} {s['wall_s']:7.3f} "
                  f"{s['Hy_mm']:9.3f} {s['Hx_mm']:8.4f}")
        a, b = rows["mesh"][0], rows["rings"][0]
        print(f"{'':34s} rings/mesh: depth {b['depth_mm'] / a['depth_mm'] - 1:+.3%}, "
              f"Hx {b['Hx_mm'] - a['Hx_mm']:+.3f} mm, wall_s {b['wall_s'] / a['wall_s']:.3f}")
        walls = []
        for _ in range(3):
            t0 = time.perf_counter()
            r = processes.run(["run", "--set", "effects.fidelity=rigid", *[x for k in sets for x in ("--set", k)],
                               "--out", f"/tmp/fepen-bench-rigid-{len(sets)}"])
            walls.append(time.perf_counter() - t0)
        print(f"{'':34s} whole `fepen run` process (default, mesh-free): min {min(walls):.2f} s, "
              f"median {sorted(walls)[1]:.2f} s of 3, exit {r.returncode}")


if __name__ == "__main__":
    main()
