"""Cost of one explicit step on the default projectile (plastic, hitting the rigid wall at 300 m/s).

For each mesh size: the per-step time split (kinematics and nodal volumes, material update, internal-force
assembly, boundary forces, vector updates), the full step over the bare internal-force assembly (the same
compiled form assembled alone, coefficients pre-packed), cell-steps per second, and the stable step over
(shortest altitude / dilatational speed); with the C trial pass of the stress update (fepen.solver.ckernel) and
with the numba reference kernel.

    .venv/bin/python benchmarks/wall_step_cost.py [sizes in mm ...]      (also under mpirun -n 2)
"""

import sys
import time

import numpy as np
from mpi4py import MPI

from fepen import scene
from fepen.geometry import tetra
from fepen.runs import model, setup
from fepen.solver import ckernel, explicit
from fepen.solver import rigid_wall as rigidwall

STEPS = 300


def measure(h_mm, comm, kernel):
    sc = scene.load(None, [f"mesh.size={h_mm * 1e-3}", "target.kind=rigid-wall", "impact.velocity=300",
                           "impact.obliquity_deg=0", "impact.attack_deg=0"])
    pm = setup.mesh(sc, comm)
    info = setup.mesh_metrics(pm, sc)
    s = model.solver(sc, pm, kernel=kernel)
    s.external = rigidwall.RigidWall(s)
    s.set_initial(velocity=lambda X: np.tile([0.0, -300.0, 0.0], (len(X), 1)))
    for _ in range(20):  # compile and warm up
        s.step()
    s.clock.times = explicit.StepTimes()
    comm.barrier()
    t0 = time.perf_counter()
    for _ in range(STEPS):
        s.step()
    comm.barrier()
    full = (time.perf_counter() - t0) / STEPS
    t0 = time.perf_counter()
    for _ in range(STEPS):
        s.assemble_internal_force()
    comm.barrier()
    bare = (time.perf_counter() - t0) / STEPS
    tm = s.clock.times
    split = {k: comm.allreduce(getattr(tm, k), op=MPI.MAX) / STEPS
             for k in ("kinematics", "material", "assembly", "boundary", "update")}
    mat = setup.projectile_material(sc)
    c = float(tetra.dilatational_speed(mat.E, mat.nu, mat.density))
    h_over_c = info["shortest_altitude_m"] / c
    return dict(kernel=kernel, h=h_mm, cells=info["cells"], full=full, bare=bare, split=split,
                cell_steps=info["cells"] / full, dt=s.clock.dt0, dt_ratio=s.clock.dt0 / h_over_c,
                plastic=comm.allreduce(int((s.eps_p > 0).sum()), op=MPI.SUM))


def main(sizes):
    comm = MPI.COMM_WORLD
    kernels = ["C", "numba"] if ckernel.library() is not None else ["numba"]
    rows = [measure(h, comm, k) for h in sizes for k in kernels]
    if comm.rank:
        return
    print(f"ranks: {comm.size}; {STEPS} steps after 20 warm-up steps; times per step in ms")
    print(f"{'kernel':>6} {'h_mm':>5} {'cells':>7} {'kinem':>6} {'mater':>6} {'assem':>6} {'bound':>6} {'update':>6} "
          f"{'full':>6} {'bare':>6} {'full/bare':>9} {'Mcell-steps/s':>13} {'dt_ns':>6} {'dt/(h/c)':>8} "
          f"{'plastic_cells':>13}")
    for r in rows:
        sp = r["split"]
        print(f"{r['kernel']:>6} {r['h']:5.2f} {r['cells']:7d} {sp['kinematics'] * 1e3:6.3f} "
              f"{sp['material'] * 1e3:6.3f} "
              f"{sp['assembly'] * 1e3:6.3f} {sp['boundary'] * 1e3:6.3f} {sp['update'] * 1e3:6.3f} "
              f"{r['full'] * 1e3:6.3f} {r['bare'] * 1e3:6.3f} {r['full'] / r['bare']:9.2f} "
              f"{r['cell_steps'] / 1e6:13.2f} {r['dt'] * 1e9:6.1f} {r['dt_ratio']:8.3f} {r['plastic']:13d}")


if __name__ == "__main__":
    main([float(a) for a in sys.argv[1:]] or [4.0, 2.5, 1.2])
