"""The charge carried by the shell: no target, the projectile decelerated uniformly (run from the root).

    .venv/bin/python demos/charge/carried_charge.py [--size 0.004] [--accel-g 5000] [--json]
    mpirun -n 2 .venv/bin/python demos/charge/carried_charge.py

A body force on the shell alone, (m_shell + m_charge)/m_shell × ρ_shell × a, decelerates the whole
projectile at a (ramped up as sin² over 300 us, then held for 200 us); the charge is carried only by the
shell–charge contact (charge.contact = "frictional"). Its inertia must come back as the force of the
wall on it: m_charge × a, averaged over the hold (beyond the charge's ringing). Three cases: μ = 0 and
μ = 0.1 decelerating (the charge bears on the cavity's front end and on the ring where the narrow forward
section steps out), and μ = 0.1 under set-back (a gun's launch: the charge bears on the shell base).
Printed per case: the force over m_charge × a, how much of it the lateral (cylindrical) walls carry
(friction only), the largest interpenetration over the element size, the open gap at the far end, the
energy-balance error.
"""

import argparse
import json

import numpy as np
from mpi4py import MPI

from fepen import scene
from fepen.geometry import mesh as fmesh
from fepen.geometry import tags
from fepen.io.results import G0
from fepen.runs import setup
from fepen.solver import diagnostics, explicit
from fepen.solver.shell_charge import ShellChargeContact

CASES = [("decelerating, mu = 0", 0.0, 1.0), ("decelerating, mu = 0.1", 0.1, 1.0), ("set-back, mu = 0.1", 0.1, -1.0)]


def carry(friction: float, sign: float, size: float = 0.004, accel_g: float = 5000.0, ramp: float = 3e-4,
          hold: float = 2e-4, comm=MPI.COMM_WORLD) -> dict:
    """One case; returns its figures (every rank)."""
    sc = scene.load(None, ["effects.charge=true", "charge.contact=frictional", f"mesh.size={size}",
                           f"charge.friction={friction}"])
    pm = setup.mesh(sc, comm)
    cm = np.zeros(pm.mesh.topology.index_map(3).size_local, dtype=np.int64)
    cm[fmesh.owned_cells_tagged(pm, tags.CHARGE)] = 1
    s = explicit.ExplicitSolver(pm.mesh, [setup.projectile_material(sc), setup.charge_material(sc)], cm)
    contact = ShellChargeContact(s, pm.facet_tags, friction)
    s.interface = contact
    m_shell, m_charge = s.node.body_mass
    a0 = sign * accel_g * G0  # along +y, from the nose towards the tail: a deceleration of a nose-first flight
    n = s.n_owned
    share = s.node.mass_by_material[:n, 0] * (m_shell + m_charge) / m_shell

    def level(t):
        return a0 * (np.sin(0.5 * np.pi * t / ramp) ** 2 if t < ramp else 1.0)

    def body_force(solver, dt):
        solver.fext[:n, 1] += share * level(solver.t)

    s.external = body_force
    s.set_initial()
    yp = contact.X_pairs[:, 1]
    lo = comm.allreduce(float(yp.min(initial=np.inf)), op=MPI.MIN)  # the cavity's ends, over all ranks
    hi = comm.allreduce(float(yp.max(initial=-np.inf)), op=MPI.MAX)
    front, rear = yp < lo + 0.25 * size, yp > hi - 0.25 * size
    far = rear if sign > 0 else front
    lateral = np.abs(contact.normals()[:, 1]) < 0.3  # the cylindrical walls (not their edges)
    forces, on_lateral, worst = [], [], 0.0
    while s.t < ramp + hold:
        s.step()
        if s.t > ramp:
            m = contact.count
            forces.append(comm.allreduce(-contact.force[m].sum(axis=0), op=MPI.SUM))
            on_lateral.append(comm.allreduce(-float(contact.force[m & lateral, 1].sum()), op=MPI.SUM))
            worst = max(worst, contact.summary()["penetration_max_mm"] * 1e-3)
    f = np.mean(forces, axis=0)
    g, _ = contact.gap_and_slip()
    gaps = comm.gather(g[contact.count & far], root=0)
    far_gap = float(np.median(np.concatenate(gaps))) if comm.rank == 0 else None
    return {"friction": friction, "sign": sign, "ranks": comm.size, "m_charge_kg": float(m_charge),
            "accel_m_s2": a0, "force_N": [float(v) for v in f], "force_over_m_a": float(f[1] / (m_charge * a0)),
            "transverse_over_axial": float(np.hypot(f[0], f[2]) / abs(f[1])),
            "lateral_share": float(np.mean(on_lateral) / (m_charge * a0)),
            "penetration_over_h": worst / size, "far_end_gap_mm": comm.bcast(far_gap, root=0) * 1e3,
            "energy_error": diagnostics.energies(s).balance_error, "steps": s.step_count}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", type=float, default=0.004, help="element size (m)")
    ap.add_argument("--accel-g", type=float, default=5000.0)
    ap.add_argument("--json", action="store_true", help="print the figures as JSON lines")
    ap.add_argument("--case", type=int, action="append", choices=range(len(CASES)),
                    help="run only this case (0, 1, 2; repeatable; default: all three)")
    args = ap.parse_args()
    comm = MPI.COMM_WORLD
    if comm.rank == 0 and not args.json:
        print(f"{'case':24s} {'F/(m_c a)':>9} {'lateral':>8} {'max pen/h':>9} {'far gap mm':>10} {'energy err':>10}")
    for name, mu, sign in (CASES[k] for k in args.case) if args.case else CASES:
        r = carry(mu, sign, args.size, args.accel_g, comm=comm)
        if comm.rank:
            continue
        if args.json:
            print(json.dumps({"case": name, **r}))
        else:
            print(f"{name:24s} {r['force_over_m_a']:9.5f} {r['lateral_share']:8.4f} {r['penetration_over_h']:9.2e} "
                  f"{r['far_end_gap_mm']:10.4f} {r['energy_error']:10.2e}")


if __name__ == "__main__":
    main()
