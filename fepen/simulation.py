"""The time loop of ``fepen run``: scene in, results directory out.

Initial state (docs/theory.md, "Striking conditions"): the stress-free projectile is turned about the nose
tip (the impact point O) by θ = α + ϑ about +z, and moves at v0 (sin α, −cos α, 0): α is the obliquity
(velocity from the target normal −y towards +x), ϑ the angle of attack (axis from the velocity, same sense).

Reported frame (contract): x along the target face in the direction of travel, y depth into the target,
both from the impact point, in mm.
"""

from __future__ import annotations

import csv
import io
import math
import time
from pathlib import Path

import numpy as np
from mpi4py import MPI

from fepen import explicit, materials as M, mesh as fmesh, output
from fepen.errors import InputError, SimulationError

G0 = 9.80665  # m/s^2, for accelerations in g

HISTORY_COLUMNS = ["t_s", "nose_x_mm", "nose_y_mm", "tail_x_mm", "tail_y_mm", "speed_m_s", "decel_g",
                   "vx_m_s", "vy_m_s", "force_x_N", "force_y_N", "length_mm", "kinetic_J", "internal_work_J",
                   "external_work_J", "elastic_J", "plastic_J", "heat_J", "energy_error", "contact_nodes",
                   "dt_s", "max_peeq"]


def placement(scene):
    """Rotation (3x3) of the body and its velocity (3,) at impact."""
    a = math.radians(scene.impact.obliquity_deg)
    th = a + math.radians(scene.impact.attack_deg)
    R = np.array([[math.cos(th), -math.sin(th), 0.0], [math.sin(th), math.cos(th), 0.0], [0.0, 0.0, 1.0]])
    v = scene.impact.velocity * np.array([math.sin(a), -math.cos(a), 0.0])
    return R, v


def check_supported(scene) -> None:
    """Raise InputError for scene settings this version cannot simulate yet."""
    if scene.target.kind != "rigid-wall":
        raise InputError("target.kind", "only 'rigid-wall' can be simulated in this version; the concrete "
                                        "cavity-expansion target is the next milestone")
    if scene.effects.fidelity == "rigid":
        raise InputError("effects.fidelity", "'rigid' needs the concrete target (next milestone); allowed "
                                             "here: 'elastic', 'plastic'")
    if scene.effects.charge:
        raise InputError("effects.charge", "the charged projectile is not available in this version")


class Simulation:
    """One run: mesh, solver, loads, time loop, outputs.

    Args:
        scene: resolved Scene.
        out: results directory (created).
        comm: MPI communicator.
        progress: show a tqdm bar on rank 0.
    """

    def __init__(self, scene, out, comm=MPI.COMM_WORLD, progress: bool = False):
        from fepen import rigidwall

        check_supported(scene)
        self.scene, self.comm, self.progress = scene, comm, progress
        self.wall_t0 = time.perf_counter()
        self.pm = fmesh.create(scene, comm)
        self.mesh_s = time.perf_counter() - self.wall_t0
        self.out = output.prepare(out, comm)
        mats = [M.from_scene(scene)]
        cellmat = np.zeros(self.pm.mesh.topology.index_map(3).size_local, dtype=np.int64)
        t0 = time.perf_counter()
        self.solver = explicit.ExplicitSolver(self.pm.mesh, mats, cellmat, scene.run.safety_factor)
        self.wall = rigidwall.RigidWall(self.solver)
        self.solver.external = self.wall
        R, v = placement(scene)
        self.R = R
        self.solver.set_initial(displacement=lambda X: X @ R.T - X, velocity=lambda X: np.tile(v, (len(X), 1)))
        self.jit_s = time.perf_counter() - t0
        self.tip = self.solver.node_at((0.0, 0.0, 0.0))
        self.tail = self.solver.node_at((0.0, self.pm.shape.length, 0.0))
        self.rows: list[list[float]] = []
        self.fields = None

    # ------------------------------------------------------------------------------------------------
    def _momentum(self):
        s = self.solver
        n = s.n_owned
        vel = s.velocity_at_step()
        p = np.sum(s.mass[:n, None] * vel[:n], axis=0)
        return self.comm.allreduce(p, op=MPI.SUM) / s.total_mass

    def _max_peeq(self) -> float:
        s = self.solver
        return self.comm.allreduce(float(s.eps_p.max()) if s.n_cells else 0.0, op=MPI.MAX)

    def record(self) -> list[float]:
        """Append one history row (and return it)."""
        s = self.solver
        x = s.positions()
        tip = s.node_value(self.tip, x)
        tail = s.node_value(self.tail, x)
        vel = self._momentum()
        e = s.energies()
        axis = (tip - tail) / np.linalg.norm(tip - tail)
        force = self.wall.force
        decel = -float(force @ axis) / s.total_mass / G0
        row = [s.t, tip[0] * 1e3, -tip[1] * 1e3, tail[0] * 1e3, -tail[1] * 1e3, float(np.linalg.norm(vel)),
               decel, vel[0], -vel[1], force[0], -force[1], float(np.linalg.norm(tip - tail)) * 1e3, e.kinetic,
               e.internal_work, e.external_work, e.elastic, e.plastic, e.heat, e.balance_error,
               self.wall.contact_nodes, s.dt, self._max_peeq()]
        if not all(math.isfinite(v) for v in row):
            raise SimulationError(f"non-finite state at step {s.step_count}, t = {s.t * 1e6:.3f} us")
        self.rows.append(row)
        return row

    def run(self) -> dict:
        """Advance to the end (run.end_time, or the rebound from the wall) and write the outputs."""
        s, sc = self.solver, self.scene
        end = sc.get("run.end_time")
        hard_end = end if end is not None else 5e-3
        hist_dt = min(sc.run.output_interval / 10.0, 1e-6)
        out_dt = sc.run.output_interval
        next_hist, next_out = 0.0, 0.0
        touched, free_since = False, None
        bar = None
        if self.progress and self.comm.rank == 0:
            from tqdm import tqdm

            bar = tqdm(total=round(hard_end * 1e6), unit="us", desc="fepen", leave=False)
        t_loop = time.perf_counter()
        outcome = "ended"
        try:
            if sc.run.fields:
                self._open_fields()
            while s.t < hard_end:
                if s.t >= next_hist:
                    self.record()
                    next_hist += hist_dt
                if self.fields is not None and s.t >= next_out:
                    self._write_fields()
                    next_out += out_dt
                s.step()
                if bar is not None and s.step_count % 200 == 0:
                    bar.n = round(s.t * 1e6)
                    bar.refresh()
                if self.wall.contact_nodes > 0:
                    touched, free_since = True, None
                elif touched and free_since is None:
                    free_since = s.t
                if end is None and free_since is not None and s.t - free_since > 20e-6:
                    outcome = "rebound"
                    break
            self.record()
            if self.fields is not None:
                self._write_fields()
        finally:
            if bar is not None:
                bar.close()
            if self.fields is not None:
                self.fields.close()
            self._write_history()
        loop_s = time.perf_counter() - t_loop
        return self._summary(outcome, loop_s)

    # ------------------------------------------------------------------------------------------------
    def _open_fields(self):
        from dolfinx import fem
        from dolfinx.io import XDMFFile

        self.fields = XDMFFile(self.comm, str(self.out / "fields.xdmf"), "w")
        self.fields.write_mesh(self.pm.mesh)
        W = fem.FunctionSpace(self.pm.mesh, ("DG", 0))
        self._dg = {name: fem.Function(W, name=name) for name in
                    ("von_mises_Pa", "axial_stress_Pa", "peeq", "temperature_K")}
        self._dg_cells = W.dofmap.list.array[: self.solver.n_cells]

    def _write_fields(self):
        s = self.solver
        t = s.t
        x = s.positions()
        tip, tail = s.node_value(self.tip, x), s.node_value(self.tail, x)
        axis = (tip - tail) / np.linalg.norm(tip - tail)
        sd = s.s
        vm = np.sqrt(1.5 * (sd[:, 0] ** 2 + sd[:, 1] ** 2 + sd[:, 2] ** 2
                            + 2 * (sd[:, 3] ** 2 + sd[:, 4] ** 2 + sd[:, 5] ** 2)))
        pm = s.nodal_p[s.dofs, s.mat[:, None]].mean(axis=1) if s.nodal else 0.0
        ax, ay, az = axis
        axial = (sd[:, 0] * ax * ax + sd[:, 1] * ay * ay + sd[:, 2] * az * az
                 + 2 * (sd[:, 3] * ax * ay + sd[:, 4] * ay * az + sd[:, 5] * ax * az)) + pm
        for name, values in (("von_mises_Pa", vm), ("axial_stress_Pa", axial), ("peeq", s.eps_p),
                             ("temperature_K", s.temp)):
            f = self._dg[name]
            f.x.array[self._dg_cells] = values
            f.x.scatter_forward()
            self.fields.write_function(f, t)
        self.fields.write_function(s.u, t)
        self.fields.write_function(s.v, t)

    def _write_history(self):
        if self.comm.rank != 0:
            return
        buf = io.StringIO()
        w = csv.writer(buf)
        w.writerow(HISTORY_COLUMNS)
        for r in self.rows:
            w.writerow([f"{v:.9g}" for v in r])
        output.write_text(self.out / "history.csv", buf.getvalue(), self.comm)

    def _summary(self, outcome: str, loop_s: float) -> dict:
        s = self.solver
        last = self.rows[-1]
        col = {k: i for i, k in enumerate(HISTORY_COLUMNS)}
        depth = max(r[col["nose_y_mm"]] for r in self.rows)
        summary = {
            "Hx_mm": abs(last[col["nose_x_mm"]]), "Hy_mm": abs(last[col["nose_y_mm"]]),
            "Tx_mm": abs(last[col["tail_x_mm"]]), "Ty_mm": abs(last[col["tail_y_mm"]]),
            "depth_mm": depth, "length_mm": last[col["length_mm"]],
            "residual_speed_m_s": last[col["speed_m_s"]], "outcome": outcome,
            "steps": s.step_count, "dt_s": s.dt_min, "end_time_s": s.t,
            "wall_s": time.perf_counter() - self.wall_t0,
            "time_split_s": {"mesh": self.mesh_s, "setup_jit": self.jit_s, "time_loop": loop_s},
            "energy_error": last[col["energy_error"]], "max_peeq": last[col["max_peeq"]],
            "mass_kg": s.total_mass, "cells": self.pm.mesh.topology.index_map(3).size_global,
            "ranks": self.comm.size, "scene": self.scene.as_dict(), "versions": output.versions(),
        }
        output.write_json(self.out / "summary.json", summary, self.comm)
        return summary


def run_scene(scene, out, comm=MPI.COMM_WORLD, progress=False) -> dict:
    """Run one scene into a results directory; returns the summary."""
    sim = Simulation(scene, out, comm, progress)
    return sim.run()


def figures(out: Path, comm=MPI.COMM_WORLD) -> None:
    """History figures of a rigid-wall run (rank 0)."""
    if comm.rank != 0:
        return
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    data = np.genfromtxt(Path(out) / "history.csv", delimiter=",", names=True)
    fig, ax = plt.subplots(1, 3, figsize=(13, 3.6))
    t = data["t_s"] * 1e6
    ax[0].plot(t, -data["force_y_N"] * 1e-3)
    ax[0].set(xlabel="t (us)", ylabel="wall force (kN)")
    ax[1].plot(t, data["length_mm"])
    ax[1].set(xlabel="t (us)", ylabel="nose-tail length (mm)")
    for k in ("kinetic_J", "internal_work_J", "plastic_J", "external_work_J"):
        ax[2].plot(t, data[k], label=k)
    ax[2].set(xlabel="t (us)", ylabel="energy (J)")
    ax[2].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(Path(out) / "history.png", dpi=110)
    plt.close(fig)
