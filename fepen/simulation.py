"""The time loop of ``fepen run``: scene in, results directory out.

Initial state (docs/theory.md, "Striking conditions"): the stress-free projectile is turned about the nose
tip (the impact point O) by θ = α + ϑ about +z, and moves at v0 (sin α, −cos α, 0): α is the obliquity
(velocity from the target normal −y towards +x), ϑ the angle of attack (axis from the velocity, same sense).

Reported frame (contract): x along the target face in the direction of travel, y depth into the target,
both from the impact point, in mm.
"""

from __future__ import annotations

import math
import time

import numpy as np
from mpi4py import MPI

from fepen import explicit, materials as M, mesh as fmesh, output, results
from fepen.errors import InputError


def placement(scene):
    """Rotation (3x3) of the body and its velocity (3,) at impact."""
    a = math.radians(scene.impact.obliquity_deg)
    th = a + math.radians(scene.impact.attack_deg)
    R = np.array([[math.cos(th), -math.sin(th), 0.0], [math.sin(th), math.cos(th), 0.0], [0.0, 0.0, 1.0]])
    v = scene.impact.velocity * np.array([math.sin(a), -math.cos(a), 0.0])
    return R, v


def check_supported(scene) -> None:
    """Raise InputError for scene settings this version cannot simulate yet."""
    rigid = scene.effects.fidelity == "rigid"
    if rigid and scene.target.kind != "concrete":
        raise InputError("effects.fidelity", "'rigid' runs against target.kind = 'concrete'; a rigid "
                                             "projectile on a rigid wall has nothing to compute")


class Simulation:
    """One run: mesh, solver, loads, time loop, outputs.

    Args:
        scene: resolved Scene.
        out: results directory (created).
        comm: MPI communicator.
        progress: show a tqdm bar on rank 0.
        resume: the state.json of a checkpoint in ``out`` to continue from (fepen.checkpoint), or None.
    """

    def __init__(self, scene, out, comm=MPI.COMM_WORLD, progress: bool = False, resume: dict | None = None):
        from fepen import rigidwall

        self.scene, self.comm, self.progress = scene, comm, progress
        self.wall_t0 = time.perf_counter()
        self.pm = fmesh.create(scene, comm)
        self.mesh_s = time.perf_counter() - self.wall_t0
        self.out = output.prepare(out, comm)
        mats = [M.from_scene(scene)]
        cellmat = np.zeros(self.pm.mesh.topology.index_map(3).size_local, dtype=np.int64)
        if self.pm.charge:  # material 1: the charge, tied through shared wall nodes or in contact (split)
            from fepen import geometry

            mats.append(M.charge_from_scene(scene))
            cellmat[fmesh.owned_cells_tagged(self.pm, geometry.CHARGE)] = 1
        t0 = time.perf_counter()
        self.solver = explicit.ExplicitSolver(self.pm.mesh, mats, cellmat, scene.run.safety_factor)
        if scene.run.stable_step == "eigenvalue":
            self.solver.calibrate_step()
        self.contact = None
        if self.pm.split:
            from fepen.interface import ShellChargeContact

            self.contact = ShellChargeContact(self.solver, self.pm.facet_tags, scene.charge.friction)
            self.solver.interface = self.contact
        self.tip = self.solver.node_at((0.0, 0.0, 0.0))
        self.tail = self.solver.node_at((0.0, self.pm.shape.length, 0.0))
        R, v = placement(scene)
        self.v0 = float(np.linalg.norm(v))
        self.concrete = scene.target.kind == "concrete"
        if self.concrete:
            from fepen import concrete, surface, target as tg

            law = tg.law_from_scene(scene)
            crater = (tg.ForrestalCrater(law, self.solver.total_mass, self.v0, scene.projectile.crh)
                      if law.crater == "linear" else None)
            surf = surface.outer_surface(self.solver.V, self.pm.facet_tags, self.pm.shape)
            self.load = concrete.ConcreteLoad(self.solver, surf, law, self.tip, self.tail, crater)
            self.surf, self.law = surf, law
        else:
            self.load = rigidwall.RigidWall(self.solver)
        self.solver.external = self.load
        self.solver.set_initial(displacement=lambda X: X @ R.T - X, velocity=lambda X: np.tile(v, (len(X), 1)))
        self.jit_s = time.perf_counter() - t0
        from fepen import analyses

        self.gauges = analyses.Gauges(self.solver, self.pm)
        self.sections = analyses.ChargeSections(self.solver, self.pm) if self.pm.charge else None
        self.output_s = 0.0
        self.columns = (results.HISTORY_COLUMNS + (results.CHARGE_COLUMNS if self.pm.charge else [])
                        + (results.INTERFACE_COLUMNS if self.contact is not None else []))
        self.rows: list[list[float]] = []
        self.fields = None
        # the loop's clocks and event memory (checkpointed)
        self.next_hist = self.next_out = self.next_ckpt = 0.0
        self.touched, self.free_since, self._entered = False, None, False
        self.wall_before = 0.0
        self._resume = resume
        if resume is not None:
            from fepen import checkpoint

            checkpoint.restore(self, resume)
            self.wall_before = float(resume["wall_s"])

    def loop_state(self) -> dict:
        """The time loop's clocks and event memory (for checkpoints)."""
        return {"next_hist": self.next_hist, "next_out": self.next_out, "next_ckpt": self.next_ckpt,
                "touched": self.touched, "free_since": self.free_since, "entered": self._entered}

    def set_loop_state(self, state: dict) -> None:
        """Restore what loop_state returned."""
        self.next_hist, self.next_out, self.next_ckpt = state["next_hist"], state["next_out"], state["next_ckpt"]
        self.touched, self.free_since, self._entered = state["touched"], state["free_since"], state["entered"]

    # ------------------------------------------------------------------------------------------------
    def _momentum(self):
        s = self.solver
        n = s.n_owned
        vel = s.velocity_at_step()
        p = np.sum(s.mass[:n, None] * vel[:n], axis=0)
        return self.comm.allreduce(p, op=MPI.SUM) / s.total_mass

    def _body_accelerations(self, axis) -> np.ndarray:
        """Mass-averaged acceleration of the shell and of the charge along the axis (tail to nose), in g:
        Σ_a m_a^(body) a_a · axis / m_body, with m_a^(body) the lumped mass node a takes from that body's
        cells (interface nodes share theirs)."""
        s = self.solver
        n = s.n_owned
        along = s.acc[:n] @ axis
        local = np.array([float(s.mass_by_material[:n, k] @ along) for k in range(2)])
        total = self.comm.allreduce(local, op=MPI.SUM)
        return total / s.body_mass / results.G0

    def _max_peeq(self) -> float:
        s = self.solver
        return self.comm.allreduce(float(s.eps_p.max()) if s.n_cells else 0.0, op=MPI.MAX)

    def record(self) -> list[float]:
        """Append one history row (and return it)."""
        s = self.solver
        x = s.positions()
        e = s.energies()
        en = dict(kinetic=e.kinetic, internal_work=e.internal_work, external_work=e.external_work,
                  elastic=e.elastic, plastic=e.plastic, heat=e.heat, energy_error=e.balance_error)
        tip, tail = s.node_value(self.tip, x), s.node_value(self.tail, x)
        row = results.history_row(s.t, tip, tail, self._momentum(), self.load.force, s.total_mass, en,
                                  self.load.contact_nodes, s.dt, self._max_peeq(), getattr(self.load, "area", 0.0))
        if self.pm.charge:
            row += list(self._body_accelerations((tip - tail) / np.linalg.norm(tip - tail)))
            self.sections.record(tip, tail)
        if self.contact is not None:
            i = self.contact.summary()
            row += [e.friction, i["gap_max_mm"], i["penetration_max_mm"], i["slip_max_mm"], i["free_fraction"],
                    i["sliding_fraction"]]
        results.finite_row(row, s.step_count, s.t)
        self.rows.append(row)
        if self.concrete and row[results.HISTORY_COLUMNS.index("max_peeq")] > self.scene.projectile.failure_strain:
            self._beyond_method()
        self.gauges.record()
        return row

    def _write_accelerations(self):
        """accelerations.csv: the target deceleration (and with a charge each body's axial acceleration),
        raw and low-pass filtered (fepen.signals, run.acceleration_filter_hz); peaks into self.peaks."""
        from fepen import signals

        rows = np.array(self.rows)
        t = rows[:, 0]
        names = ["decel_g"] + (results.CHARGE_COLUMNS if self.pm.charge else [])
        cut = self.scene.run.acceleration_filter_hz
        cols, header = [t], ["t_s"]
        self.peaks = {}
        for name in names:
            raw = rows[:, self.columns.index(name)]
            filt = signals.lowpass(t, raw, cut)
            cols += [raw, filt]
            header += [name, name.replace("_g", "_filtered_g")]
            k = int(np.argmax(np.abs(filt)))
            depth = rows[k, self.columns.index("nose_y_mm")]
            self.peaks[name.replace("_g", "")] = {"filtered_g": float(filt[k]), "t_s": float(t[k]),
                                                   "nose_depth_mm": float(depth),
                                                   "raw_peak_g": float(raw[np.argmax(np.abs(raw))])}
        body = "\n".join(",".join(f"{v:.9g}" for v in r) for r in np.column_stack(cols))
        output.write_text(self.out / "accelerations.csv", ",".join(header) + "\n" + body + "\n", self.comm)

    def _charge_report(self):
        """The charge's pictures (fepen.slices), maps and cross-sections at the output time nearest the
        charge's peak (filtered) acceleration; what they show goes into summary.json ("charge")."""
        from fepen import slices

        report = None
        if self.comm.rank == 0:
            report = slices.charge_report(self.out, self.sections.sections, self.peaks["charge_acc"]["t_s"])
        self.charge = self.comm.bcast(report, root=0)

    def _beyond_method(self):
        """Stop: the equivalent plastic strain passed projectile.failure_strain (where, when)."""
        from fepen.errors import BeyondMethod

        s = self.solver
        local = (float(s.eps_p.max()), self.comm.rank, int(np.argmax(s.eps_p))) if s.n_cells else (-1.0, 0, -1)
        peeq, owner, cell = self.comm.allreduce(local, op=MPI.MAX)
        where = s.X[s.dofs[cell]].mean(axis=0) if self.comm.rank == owner else None
        where = self.comm.bcast(where, root=owner)
        raise BeyondMethod(
            f"the equivalent plastic strain reached {peeq:.3g} > projectile.failure_strain = "
            f"{self.scene.projectile.failure_strain:g}, {where[1] * 1e3:.1f} mm behind the nose tip "
            f"(radius {np.hypot(where[0], where[2]) * 1e3:.1f} mm), at t = {s.t * 1e6:.1f} us, step "
            f"{s.step_count}: the projectile would fracture or erode, which projectile-target separation "
            "does not model; no result is reported")

    def run(self) -> dict:
        """Advance to the end (run.end_time, or a stop event) and write the outputs.

        history.csv is rewritten (atomically) at every field output and checkpoint, fields as they come
        (fepen.fields), a checkpoint every run.checkpoint_interval of simulated time (fepen.checkpoint)."""
        from fepen import checkpoint

        s, sc = self.solver, self.scene
        end = sc.get("run.end_time")
        hard_end = end if end is not None else 5e-3
        hist_dt = min(sc.run.output_interval / 10.0, 1e-6)
        out_dt = sc.run.output_interval
        ckpt_dt = sc.run.checkpoint_interval
        if self._resume is None:
            self.next_ckpt = ckpt_dt
        bar = None
        if self.progress and self.comm.rank == 0:
            from tqdm import tqdm

            bar = tqdm(total=round(hard_end * 1e6), initial=round(s.t * 1e6), unit="us", desc="fepen",
                       leave=False)
        t_loop = time.perf_counter()
        outcome = "ended"
        completed = False
        try:
            if sc.run.fields:
                self._open_fields(self._resume["field_times_s"] if self._resume is not None else [])
            while s.t < hard_end:
                if s.t >= self.next_hist:
                    self.record()
                    self.next_hist += hist_dt
                if self.fields is not None and s.t >= self.next_out:
                    t_out = time.perf_counter()
                    self._write_fields()
                    results.write_history(self.rows, self.out, self.comm, self.columns)
                    self.output_s += time.perf_counter() - t_out
                    self.next_out += out_dt
                if ckpt_dt > 0.0 and s.t >= self.next_ckpt:
                    t_out = time.perf_counter()
                    while self.next_ckpt <= s.t:
                        self.next_ckpt += ckpt_dt
                    results.write_history(self.rows, self.out, self.comm, self.columns)
                    checkpoint.write(self, self.wall_before + time.perf_counter() - self.wall_t0)
                    self.output_s += time.perf_counter() - t_out
                s.step()
                if bar is not None and s.step_count % 200 == 0:
                    bar.n = round(s.t * 1e6)
                    bar.refresh()
                if self.concrete:
                    outcome = self._penetration_event(s, end)
                    if outcome != "running":
                        break
                    outcome = "ended"
                    continue
                if self.load.contact_nodes > 0:
                    self.touched, self.free_since = True, None
                elif self.touched and self.free_since is None:
                    self.free_since = s.t
                if end is None and self.free_since is not None and s.t - self.free_since > 20e-6:
                    outcome = "rebound"
                    break
            self.record()
            if self.fields is not None:
                self._write_fields()
            completed = True
        finally:
            if bar is not None:
                bar.close()
            t_out = time.perf_counter()
            if self.fields is not None:
                self.fields.consolidate()
            results.write_history(self.rows, self.out, self.comm, self.columns)  # kept even when the run failed
            if completed:
                from fepen import analyses

                self.gauges.write(self.out)
                if self.sections is not None:
                    self.sections.write(self.out)
                self._write_accelerations()
                if self.pm.charge:
                    self._charge_report()
                analyses.deformed_picture(self.solver, self.out / "deformed.png",
                                          f"t = {self.solver.t * 1e6:.0f} us, max PEEQ {self._max_peeq():.3g}")
            self.output_s += time.perf_counter() - t_out
        loop_s = time.perf_counter() - t_loop
        summary = self._summary(outcome, loop_s)
        if self.comm.rank == 0 and (self.out / "checkpoint").exists():
            import shutil

            shutil.rmtree(self.out / "checkpoint")  # the run is complete: nothing left to resume
        return summary

    def _penetration_event(self, s, end) -> str:
        """Stop events in the concrete target, checked every 20 steps: "embedded" (the centre of mass has
        stopped advancing along the axis, or its kinetic energy is below 1e-5 of the initial),
        "perforated" (every load point beyond the rear face), "ricochet" (back above the face, moving away),
        else "running"."""
        if s.step_count % 20:
            return "running"
        x_all = s.positions()
        pts = self.surf.kinematics(x_all, s.Vel)[0]
        ymin = self.comm.allreduce(float(pts[:, 1].min()) if len(pts) else np.inf, op=MPI.MIN)
        ymax = self.comm.allreduce(float(pts[:, 1].max()) if len(pts) else -np.inf, op=MPI.MAX)
        self._entered = self._entered or ymin < 0.0
        if not self._entered:
            return "running"
        vcm = self._momentum()
        if self.law.thickness is not None and ymax < -self.law.thickness:
            return "perforated"
        if ymin > 0.0 and vcm[1] > 0.0:
            return "ricochet"
        if end is None:
            tip, tail = s.node_value(self.tip, x_all), s.node_value(self.tail, x_all)
            axis = (tip - tail) / np.linalg.norm(tip - tail)
            if float(vcm @ axis) <= 0.0 or 0.5 * s.total_mass * float(vcm @ vcm) < 1e-5 * s.ke0:
                return "embedded"
        return "running"

    # ------------------------------------------------------------------------------------------------
    def _open_fields(self, times):
        names = ["von_mises_Pa", "axial_stress_Pa"]  # fields of switched-off physics are not written
        if self.scene.effects.fidelity == "plastic":
            names.append("peeq")
            if self.scene.effects.thermal:
                names.append("temperature_K")
        if self.pm.charge:
            names.append("body")  # 1 shell, 2 charge: for ParaView's Threshold
        scalars = ["interface_gap_m", "interface_slip_m"] if self.contact is not None else []
        from fepen.fields import FieldWriter

        self.fields = FieldWriter(self.out, self.solver, ["displacement", "velocity"], names, times, scalars)

    def _write_fields(self):
        s = self.solver
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
        values = {"displacement": s.U, "velocity": s.Vel, "von_mises_Pa": vm, "axial_stress_Pa": axial,
                  "peeq": s.eps_p, "temperature_K": s.temp, "body": s.mat + 1.0}
        if self.contact is not None:
            values.update(self.contact.nodal_gap_and_slip())
        self.fields.write(s.t, values)

    def _summary(self, outcome: str, loop_s: float) -> dict:
        s = self.solver
        extra = {"steps": s.step_count, "dt_s": s.dt_min, "end_time_s": s.t,
                 "wall_s": self.wall_before + time.perf_counter() - self.wall_t0,
                 "time_split_s": {"mesh": self.mesh_s, "setup_jit": self.jit_s,
                                  "time_loop": loop_s - self.output_s, "output": self.output_s},
                 "mass_kg": s.total_mass, "cells": self.pm.mesh.topology.index_map(3).size_global,
                 "ranks": self.comm.size, "stress_kernel": s.kernel, "step_gain": s.step_gain,
                 "peak_memory_bytes": output.peak_memory_bytes(self.comm),
                 "peak_accelerations": getattr(self, "peaks", None),
                 "charge": getattr(self, "charge", None),
                 "acceleration_filter_hz": self.scene.run.acceleration_filter_hz}
        summary = results.summary(self.scene, self.rows, outcome, extra)
        output.write_json(self.out / "summary.json", summary, self.comm)
        return summary


def run_scene(scene, out, comm=MPI.COMM_WORLD, progress=False, resume: dict | None = None) -> dict:
    """Run one scene into a results directory (the rigid or the deformable projectile); returns the summary.

    resume: a checkpoint's state (fepen.checkpoint.read_state) to continue from (deformable runs)."""
    check_supported(scene)
    if scene.effects.fidelity == "rigid":
        from fepen.rigidrun import RigidRun

        return RigidRun(scene, out, comm).run()
    return Simulation(scene, out, comm, progress, resume).run()
