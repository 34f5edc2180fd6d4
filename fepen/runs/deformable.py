"""The deformable run (``effects.fidelity = "elastic"`` or ``"plastic"``): scene in, results directory out.

The model comes from fepen.runs.model, the stop rules from fepen.runs.events, the outputs are the objects
of fepen.runs.outputs. Reported frame (docs/theory.md §7): x along the target face in the direction of
travel, y depth into the target, both from the impact point, in mm.
"""

from __future__ import annotations

import time

import numpy as np
from mpi4py import MPI

from fepen.errors import BeyondMethod, InputError, Interrupted, MachineFault, SimulationError
from fepen.experiments import shot
from fepen.geometry.frames import unit_axis
from fepen.io import files, results, rundir
from fepen.io.fields import FieldWriter
from fepen.laws import layers as fl
from fepen.post import analyses, paraview, signals, slices
from fepen.runs import checkpoint, events, interrupts, model, outputs, rigid
from fepen.solver import diagnostics, explicit, probes

#: steps between two checks of the stop rules in the target (each costs a few reductions)
EVENT_EVERY = 20
#: the longest a run without run.end_time may last (s)
MAX_TIME = 5e-3


class DeformableRun:
    """One deformable run.

    Args:
        scene: resolved Scene.
        out: results directory (created).
        comm: MPI communicator.
        progress: show a tqdm bar on rank 0.
        resume: the state.json of a checkpoint in ``out`` to continue from, or None.
    """

    def __init__(self, scene, out, comm=MPI.COMM_WORLD, progress: bool = False, resume: dict | None = None):
        self.scene, self.comm = scene, comm
        self.wall_t0 = time.perf_counter()
        self.model = model.build(scene, comm)
        self.out = files.prepare(out, comm)
        m = self.model
        self.pm, self.solver, self.load, self.contact = m.pm, m.solver, m.load, m.contact
        self.gauges = analyses.Gauges(self.solver, self.pm)
        self.sections = analyses.ChargeSections(self.solver, self.pm) if self.pm.charge else None
        self.removal = m.erosion is not None or m.recession is not None
        self.columns = (results.HISTORY_COLUMNS + (results.CHARGE_COLUMNS if self.pm.charge else [])
                        + (results.INTERFACE_COLUMNS if self.contact is not None else [])
                        + (results.REMOVAL_COLUMNS if self.removal else []))
        self.rows: list[list[float]] = []
        self.end = scene.get("run.end_time")
        self.rules = events.StopRules(m.law.thickness if m.law is not None else None, self.end is None)
        self.crossings = fl.Crossings(m.law.faces()) if getattr(m.law, "layered", False) else None
        self.peaks: dict | None = None
        self.charge: dict | None = None
        self.profile: dict | None = None
        self.output_s = 0.0
        self.wall_before = 0.0
        self.stop: BaseException | None = None  # what stopped the run before its end
        sc = scene.run
        self.history = outputs.History(min(sc.output_interval / 10.0, 1e-6))
        self.fields_out = outputs.Fields(sc.output_interval) if sc.fields else None
        self.checkpoints = outputs.Checkpoint(sc.checkpoint_interval, sc.checkpoint_interval)
        self.fields = None
        field_times = []
        if resume is not None:
            field_times = self.restore(resume)
        if self.fields_out is not None:
            self.fields = self._field_writer(field_times)
        self.outputs = [o for o in (self.history, self.fields_out, self.checkpoints) if o is not None]
        if progress and comm.rank == 0:
            self.outputs.append(outputs.Progress(self.expected_end(), self.solver.t))

    @property
    def hard_end(self) -> float:
        if self.end is not None:
            return self.end
        if self.crossings is not None:  # long enough to reach the last layer
            return max(MAX_TIME, rigid.LAYERED_TIME * self.model.law.faces()[-1][0] / self.model.v0)
        return MAX_TIME

    def expected_end(self) -> float:
        """The time the run is expected to end at, for the progress bar: run.end_time, else the end of the same
        shot with the rigid projectile (a fraction of a second to compute; rank 0), else hard_end."""
        if self.end is not None or self.model.law is None:
            return self.hard_end
        try:
            quick = rigid.RigidRun(self.scene.with_sets(["effects.fidelity=rigid", "effects.erosion=false"]), None,
                                   MPI.COMM_SELF).run()
            return min(self.hard_end, 1.05 * float(quick["end_time_s"]))
        except Exception:  # noqa: BLE001 - only the bar's length depends on it
            return self.hard_end

    # ------------------------------------------------------------------------------------------------
    def run(self) -> dict:
        """Advance to run.end_time or a stop event; write the outputs; return the summary. A stop (SimulationError,
        a signal, a full disk) closes the outputs, writes summary.json with the stop and raises again."""
        t_loop = time.perf_counter()
        outcome, completed = None, False
        try:
            with interrupts.Interrupts(self.comm) as signals:
                outcome = self.advance(signals)
            self.record()  # the final state
            if self.fields is not None:
                self.write_fields()
            completed = True
        except BaseException as err:
            self.stop = err
            raise
        finally:
            t_out = time.perf_counter()
            self.close_outputs(completed)
            if completed:
                self.write_analyses()
            self.output_s += time.perf_counter() - t_out
            if self.stop is not None:
                self.write_stop(self.stop)
        return self.write_summary(outcome or "ended", time.perf_counter() - t_loop)

    def advance(self, signals) -> str | None:
        """The time loop: outputs, a step, wear and erosion, the stop rules, and every EVENT_EVERY steps the
        signals (a caught SIGTERM or SIGINT: interrupt after the next outputs, as a timed checkpoint would).
        Returns the outcome of a stop rule, or None at the end of time."""
        s, m = self.solver, self.model
        outcome = caught = None
        while outcome is None and s.t < self.hard_end:
            for o in self.outputs:
                if o.due(self):
                    o.write(self)
            if caught is not None:  # where a checkpoint of the outputs' clock would be taken
                self.interrupt(caught)
            s.step()
            if m.recession is not None and s.step_count % m.recession.every == 0:
                m.recession.apply()
            if m.erosion is not None:
                inside = m.erosion.take_pending()  # cells that inverted within the step, eroded
                if (s.step_count % explicit.STEP_EVERY == 1 and m.erosion.check()) or inside:
                    self._after_erosion()
            outcome = self.stop_rules()
            if s.step_count % EVENT_EVERY == 0:
                caught = signals.stop()
        return outcome

    def interrupt(self, name: str) -> None:
        """A signal: write a checkpoint of this step and history.csv, then raise Interrupted (collective)."""
        s = self.solver
        self.write_history()
        self.write_checkpoint()
        raise Interrupted(f"{name} at step {s.step_count}, t = {s.t * 1e6:.3f} us: a checkpoint of that step is "
                          f"written; `fepen run --resume {self.out}` finishes the run with the same results")

    def close_outputs(self, completed: bool) -> None:
        """Close every output (history.csv, the fields, the checkpoints, the bar); while stopping, a failing
        close is logged, not raised (the stop's own error is the one to report)."""
        for o in reversed(self.outputs):
            if self.stop is None:
                o.close(self, completed)
                continue
            try:
                o.close(self, completed)
            except (OSError, SimulationError) as err:  # into fepen.log: the console says only the stop
                rundir.log_line(f"fepen: while stopping, {type(o).__name__.lower()} output: {err}")

    def write_stop(self, err: BaseException) -> None:
        """summary.json of a stopped run: outcome, stop_reason, stop_time_s, where (rank 0, no collective; a
        full disk leaves the previous one)."""
        s = self.solver
        if isinstance(err, (Interrupted, KeyboardInterrupt)):
            outcome = "interrupted"
        elif isinstance(err, (MachineFault, OSError)):
            outcome = "fault"
        elif isinstance(err, SimulationError):
            outcome = "stopped"
        else:
            outcome = "error"
        where = {"step": s.step_count, "t_s": s.t}
        reason = str(err).splitlines()[0] if str(err) else type(err).__name__
        extra = {"steps": s.step_count, "end_time_s": s.t, "ranks": self.comm.size, "mass_kg": s.total_mass,
                 "wall_s": self.wall_before + time.perf_counter() - self.wall_t0}
        summary = results.stop_summary(self.scene, self.rows, outcome, reason, where, extra)
        if self.comm.rank == 0:
            rundir.release_reserve()
            try:
                files.write_json(self.out / "summary.json", summary, self.comm)
            except OSError as e:
                rundir.log_line(f"fepen: summary.json of the stop not written: {e}")

    def stop_rules(self) -> str | None:
        """The outcome if a stop rule fires (fepen.runs.events), else None; BeyondMethod past the failure
        strain. In the target the rules are checked every EVENT_EVERY steps, on the rigid wall every step."""
        s, m = self.solver, self.model
        if m.law is None:
            return self.rules.rebound(s.t, self.load.contact_nodes)
        if s.step_count % EVENT_EVERY:
            return None
        if m.erosion is not None and s.total_mass < events.ERODED_FRACTION * s.initial_mass:
            return "eroded"
        if events.beyond_method(diagnostics.max_peeq(s), self.scene.get("projectile.failure_strain")):
            self._beyond_method()
        x = s.positions()
        pts = m.surface.kinematics(x, s.Vel)[0]
        y_min = self.comm.allreduce(float(pts[:, 1].min()) if len(pts) else np.inf, op=MPI.MIN)
        y_max = self.comm.allreduce(float(pts[:, 1].max()) if len(pts) else -np.inf, op=MPI.MAX)
        if self.crossings is not None:
            self.crossings.update(s.t, -float(probes.node_value(s, m.tip, x)[1]), -y_max,
                                  float(np.linalg.norm(diagnostics.momentum_velocity(s))))
        if not (self.rules.entered or y_min < 0.0):
            return None  # not in the target yet
        axis = unit_axis(probes.node_value(s, m.tip, x), probes.node_value(s, m.tail, x))
        return self.rules.penetration(y_min, y_max, diagnostics.momentum_velocity(s), axis, s.total_mass, s.ke0)

    def _after_erosion(self) -> None:
        """If the nose-tip (tail) node lost its last cell, the foremost (rearmost) live node along the axis
        takes its place (collective)."""
        s, m = self.solver, self.model
        x = s.positions()
        axis = unit_axis(probes.node_value(s, m.tip, x), probes.node_value(s, m.tail, x))
        for name, sign in (("tip", 1.0), ("tail", -1.0)):
            owner, local = getattr(m, name)
            dead = self.comm.bcast(bool(s.orphans[local]) if self.comm.rank == owner else None, root=owner)
            if not dead:
                continue
            ahead = np.where(s.orphans[: s.n_owned], -np.inf, sign * (x[: s.n_owned] @ axis))
            k = int(np.argmax(ahead)) if len(ahead) else -1
            best = float(ahead[k]) if k >= 0 else -np.inf
            _, owner = self.comm.allreduce((best, self.comm.rank), op=MPI.MAXLOC)
            setattr(m, name, (owner, k if self.comm.rank == owner else -1))
        self.load.tip, self.load.tail = m.tip, m.tail

    def _beyond_method(self):
        """Stop: the equivalent plastic strain passed projectile.failure_strain (where, when)."""
        s = self.solver
        peeq, where = diagnostics.max_peeq_where(s)
        raise BeyondMethod(
            f"the equivalent plastic strain reached {peeq:.3g} > projectile.failure_strain = "
            f"{self.scene.get('projectile.failure_strain'):g}, {where[1] * 1e3:.1f} mm behind the nose tip "
            f"(radius {np.hypot(where[0], where[2]) * 1e3:.1f} mm), at t = {s.t * 1e6:.1f} us, step "
            f"{s.step_count}: the projectile would fracture or erode, which projectile-target separation "
            "does not model; no result is reported")

    # ------------------------------------------------------------------------------------------------
    def record(self) -> list[float]:
        """Append one history row (and the gauges' and sections' rows); return the row."""
        s, m = self.solver, self.model
        x = s.positions()
        e = diagnostics.energies(s)
        en = dict(kinetic=e.kinetic, internal_work=e.internal_work, external_work=e.external_work,
                  elastic=e.elastic, plastic=e.plastic, heat=e.heat, energy_error=e.balance_error)
        tip, tail = probes.node_value(s, m.tip, x), probes.node_value(s, m.tail, x)
        row = results.history_row(s.t, tip, tail, diagnostics.momentum_velocity(s), self.load.force, s.total_mass,
                                  en, self.load.contact_nodes, s.dt, diagnostics.max_peeq(s), self.load.area)
        if self.pm.charge:
            row += list(diagnostics.body_accelerations(s, unit_axis(tip, tail)) / results.G0)
            self.sections.record(tip, tail)
        if self.contact is not None:
            i = self.contact.summary()
            row += [e.friction, i["gap_max_mm"], i["penetration_max_mm"], i["slip_max_mm"], i["free_fraction"],
                    i["sliding_fraction"]]
        if self.removal:
            heat = self.comm.allreduce(m.recession.heat_total, op=MPI.SUM) if m.recession is not None else 0.0
            row += [s.total_mass, heat, m.erosion.count if m.erosion is not None else 0, e.removed_kinetic]
        results.finite_row(row, s.step_count, s.t)
        self.rows.append(row)
        self.gauges.record()
        return row

    def write_history(self) -> None:
        results.write_history(self.rows, self.out, self.comm, self.columns)

    def _field_writer(self, times) -> FieldWriter:
        names = ["von_mises_Pa", "axial_stress_Pa"]  # fields of switched-off physics are not written
        if self.scene.effects.fidelity == "plastic":
            names.append("peeq")
            if self.scene.effects.thermal:
                names.append("temperature_K")
        names.append("cell_tag")  # 1 shell, 2 charge, 0 eroded: for ParaView's Threshold
        scalars = ["interface_gap_m", "interface_slip_m"] if self.contact is not None else []
        if self.model.recession is not None:
            scalars.append("wear_depth_m")
        if self.comm.rank == 0:
            paraview.write_view_script(self.out)
        return FieldWriter(self.out, self.solver, ["displacement_m", "velocity_m_s"], names, times, scalars,
                           integer=("cell_tag",))

    def write_fields(self) -> None:
        s, m = self.solver, self.model
        x = s.positions()
        axis = unit_axis(probes.node_value(s, m.tip, x), probes.node_value(s, m.tail, x))
        values = {"displacement_m": x - s.X0, "velocity_m_s": s.velocity_at_step(),
                  "von_mises_Pa": diagnostics.von_mises(s), "axial_stress_Pa": diagnostics.axial_stress(s, axis),
                  "peeq": diagnostics.live_peeq(s), "temperature_K": s.temp,
                  "cell_tag": s.mat + 1.0}
        if self.contact is not None:
            values.update(self.contact.nodal_gap_and_slip())
        if m.recession is not None:
            values["wear_depth_m"] = m.recession.depth
        self.fields.write(s.t, values)

    def write_analyses(self) -> None:
        """The closing analyses of a completed run: gauges and hazard map, charge sections, accelerations,
        the charge's pictures, the deformed picture."""
        self.gauges.write(self.out)
        if self.sections is not None:
            self.sections.write(self.out)
        self.peaks = self._write_accelerations()
        if self.pm.charge:
            report = None
            if self.comm.rank == 0:
                report = slices.charge_report(self.out, self.sections.sections, self.peaks["charge_acc"]["t_s"])
            self.charge = self.comm.bcast(report, root=0)
        s = self.solver
        if self.fields is not None:  # the cut planes at peak load and at the end, and the shot (Figs. 18, 20-21)
            if self.comm.rank == 0:
                name = self.scene.get("impact.shot")
                slices.stress_maps(self.out, self.out / "stress_maps_peak.png", self.peaks["decel"]["t_s"])
                slices.stress_maps(self.out, self.out / "stress_maps_end.png")
                slices.trajectory_figure(self.out, self.out / "trajectory.png", shot(name) if name else None)
        else:
            analyses.deformed_picture(s, self.out / "deformed.png",
                                      f"t = {s.t * 1e6:.0f} us, max PEEQ {diagnostics.max_peeq(s):.3g}")
        if self.model.surface is not None:
            self.profile = analyses.nose_profile(s, self.model, self.out)

    def _write_accelerations(self) -> dict:
        """accelerations.csv: the target deceleration (and with a charge each body's axial acceleration),
        raw and low-pass filtered (run.acceleration_filter_hz). Returns the peaks."""
        rows = np.array(self.rows)
        t = rows[:, 0]
        names = ["decel_g"] + (results.CHARGE_COLUMNS if self.pm.charge else [])
        cut = self.scene.run.acceleration_filter_hz
        cols, header, peaks = [t], ["t_s"], {}
        for name in names:
            raw = rows[:, self.columns.index(name)]
            filt = signals.lowpass(t, raw, cut)
            cols += [raw, filt]
            header += [name, name.replace("_g", "_filtered_g")]
            k = int(np.argmax(np.abs(filt)))
            depth = rows[k, self.columns.index("nose_y_mm")]
            peaks[name.replace("_g", "")] = {"filtered_g": float(filt[k]), "t_s": float(t[k]),
                                             "nose_depth_mm": float(depth),
                                             "raw_peak_g": float(raw[np.argmax(np.abs(raw))])}
        body = "\n".join(",".join(f"{v:.9g}" for v in r) for r in np.column_stack(cols))
        files.write_text(self.out / "accelerations.csv", ",".join(header) + "\n" + body + "\n", self.comm)
        return peaks

    def write_summary(self, outcome: str, loop_s: float) -> dict:
        s, m = self.solver, self.model
        extra = {"steps": s.step_count, "dt_s": s.dt_min, "end_time_s": s.t,
                 "wall_s": self.wall_before + time.perf_counter() - self.wall_t0,
                 "time_split_s": {"mesh": m.mesh_s, "setup_jit": m.setup_s,
                                  "time_loop": loop_s - self.output_s, "output": self.output_s},
                 "mass_kg": s.total_mass, "cells": self.pm.mesh.topology.index_map(3).size_global,
                 "ranks": self.comm.size, "stress_kernel": s.kernel, "step_gain": s.step_gain,
                 "peak_memory_bytes": files.peak_memory_bytes(self.comm),
                 "peak_accelerations": self.peaks, "charge": self.charge,
                 "acceleration_filter_hz": self.scene.run.acceleration_filter_hz}
        extra.update(self.removal_summary())
        extra["nose_profile"] = self.profile
        summary = results.summary(self.scene, self.rows, outcome, extra)
        if self.crossings is not None:
            summary.update(self.crossings.summary(self.model.law, 1e-3 * summary["depth_mm"]))
        results.write_summary(self.out, summary, self.comm)
        return summary

    def removal_summary(self) -> dict:
        """Mass loss, length change, eroded cells, the wear heat and the removed energies (every deformable
        run; zero when wear and erosion are off)."""
        s, m = self.solver, self.model
        e = diagnostics.energies(s)
        lost = s.initial_mass - s.total_mass
        length = self.rows[-1][results.COL["length_mm"]] if self.rows else self.pm.shape.length * 1e3
        heat = self.comm.allreduce(m.recession.heat_total, op=MPI.SUM) if m.recession is not None else 0.0
        return {"mass_loss_kg": lost, "mass_loss_percent": 100.0 * lost / s.initial_mass,
                "remaining_mass_kg": s.total_mass, "length_change_mm": length - self.pm.shape.length * 1e3,
                "eroded_cells": m.erosion.count if m.erosion is not None else 0,
                "crossings": self.crossings.state() if self.crossings is not None else None, "wear_heat_J": heat,
                "removed_kinetic_J": e.removed_kinetic, "removed_elastic_J": e.removed_internal}

    # ------------------------------------------------------------------------------------------------
    #: arrays held by rank 0 only in a checkpoint: the run's tables and the load's last state
    ROOT_ARRAYS = ("rows", "gauge_rows", "section_rows", "load")

    def write_checkpoint(self) -> None:
        """A checkpoint of the state between two steps (collective)."""
        s = self.solver
        arrays = dict(s.state())
        m = self.model
        if m.surface is not None and (m.erosion is not None or m.recession is not None):
            arrays.update({f"surface_{k}": getattr(m.surface, k) for k in m.surface.FIELDS})
        if m.recession is not None:
            arrays.update(wear_heat_nodes=m.recession.heat_nodes, wear_depth=m.recession.depth,
                          wear_heat=np.array([m.recession.heat_total]))
        if self.comm.rank == 0:
            arrays["rows"] = np.array(self.rows, dtype=float)
            arrays["gauge_rows"] = np.array(self.gauges.rows, dtype=float)
            if self.sections is not None:
                arrays["section_rows"] = np.array(self.sections.rows, dtype=float)
            arrays["load"] = np.array([*self.load.force, self.load.contact_nodes, self.load.area])
        loop = {"next_hist": self.history.clock.next,
                "next_out": self.fields_out.clock.next if self.fields_out is not None else 0.0,
                "next_ckpt": self.checkpoints.clock.next, **self.rules.state(),
                "eroded_cells": m.erosion.count if m.erosion is not None else 0,
                "crossings": self.crossings.state() if self.crossings is not None else None,
                "tip": self._tip_reference()}
        meta = {"wall_s": self.wall_before + time.perf_counter() - self.wall_t0, "loop": loop,
                "field_times_s": list(self.fields.times) if self.fields is not None else []}
        checkpoint.write(self.out, self.comm, s.step_count, s.t, arrays, meta)

    def restore(self, state: dict) -> list[float]:
        """Put a checkpoint back into this freshly built run (collective). Returns the field output times."""
        z = checkpoint.read_arrays(self.out, self.comm, state, self.ROOT_ARRAYS)
        X0 = z["X0"] if "X0" in z else z["X"]
        same = X0.shape == self.solver.X0.shape and np.array_equal(X0, self.solver.X0)
        if not self.comm.allreduce(same, op=MPI.LAND):
            raise InputError("--resume", "the mesh rebuilt from scene.toml differs from the checkpointed one "
                                         "(another fepen or gmsh version, or another partition)")
        self.solver.restore(z)
        m = self.model
        if "surface_tri" in z:
            for k in m.surface.FIELDS:
                setattr(m.surface, k, np.ascontiguousarray(z[f"surface_{k}"]))
        if m.recession is not None:
            m.recession.heat_nodes[:] = z["wear_heat_nodes"]
            m.recession.depth[:] = z["wear_depth"]
            m.recession.heat_total = float(z["wear_heat"][0])
        self.rows = [list(r) for r in z["rows"]]
        self.gauges.rows = [list(r) for r in z["gauge_rows"]]
        if self.sections is not None and "section_rows" in z:
            self.sections.rows = [list(r) for r in z["section_rows"]]
        load = z["load"]
        self.load.force, self.load.contact_nodes, self.load.area = np.array(load[:3]), int(load[3]), float(load[4])
        loop = state["loop"]
        self.history.clock.next = loop["next_hist"]
        if self.fields_out is not None:
            self.fields_out.clock.next = loop["next_out"]
        self.checkpoints.clock.next = loop["next_ckpt"]
        self.rules.restore(loop)
        if self.crossings is not None and loop.get("crossings"):
            self.crossings.restore(loop["crossings"])
        if m.erosion is not None:
            m.erosion.count = int(loop.get("eroded_cells", 0))
        if "tip" in loop:
            m.tip = probes.node_at(self.solver, loop["tip"])
            self.load.tip = m.tip
        self.wall_before = float(state["wall_s"])
        return state["field_times_s"]

    def _tip_reference(self) -> list[float]:
        """The initial reference position of the current nose-tip node (to find it again on resume)."""
        owner, local = self.model.tip
        return self.comm.bcast([float(c) for c in self.solver.X0[local]] if self.comm.rank == owner else None,
                               root=owner)

    def drop_checkpoints(self) -> None:
        checkpoint.drop(self.out, self.comm)
