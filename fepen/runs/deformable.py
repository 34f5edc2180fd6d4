"""The deformable run (``effects.fidelity = "elastic"`` or ``"plastic"``): a Shot in, a results directory out.

The skeleton (loop, stop, summary, history rows) is fepen.runs.run.Run's; the model comes from
fepen.runs.model, the outputs are the objects of fepen.runs.outputs, the closing analyses fepen.runs.closing's.
Reported frame (docs/theory.md §7): x along the target face in the direction of travel, y depth into the
target, both from the impact point, in mm.
"""

from __future__ import annotations

import numpy as np
from mpi4py import MPI

from fepen.errors import BeyondMethod, InputError, Interrupted, SimulationError
from fepen.geometry.frames import unit_axis
from fepen.io import results
from fepen.io.fields import FieldWriter
from fepen.post import analyses, paraview, signals
from fepen.runs import checkpoint, closing, events, model, outputs, shot
from fepen.runs import probes as run_probes
from fepen.runs.charge_safety import ChargeSafety
from fepen.runs.run import Removal, Run, Snapshot
from fepen.solver import diagnostics, explicit, probes, traffic

#: steps between two checks of the stop rules in the target (each costs a few reductions)
EVENT_EVERY = 20


#: a run whose energy balance is off by more than this fraction stops (it would report garbage)
ENERGY_LIMIT = 0.05


class DeformableRun(Run):
    """One deformable run.

    Args:
        shot_: the resolved shot (fepen.runs.shot.Shot; a Scene is resolved).
        out: results directory (created).
        comm: MPI communicator.
        progress_end: the expected end (s) of a tqdm bar on rank 0 (fepen.runs.expected_end), or None.
        resume: the state.json of a checkpoint in ``out`` to continue from, or None.
    """

    check_every = EVENT_EVERY

    def __init__(self, shot_, out, comm=MPI.COMM_WORLD, progress_end: float | None = None,
                 resume: dict | None = None):
        sh = shot.of(shot_)
        self.fidelity = sh.fidelity
        self.model = m = model.build(sh, comm)
        if sh.probes:  # located before any step: a point outside the mesh is an input error
            self.probes = run_probes.MeshProbes(sh.probes, m.solver, sh.mesh.options.size)
        super().__init__(sh, out, comm)
        self.pm, self.solver, self.load, self.contact = m.pm, m.solver, m.load, m.contact
        self.initial_mass = self.solver.initial_mass
        self.gauges = analyses.Gauges(self.solver, self.pm)
        self.sections = analyses.ChargeSections(self.solver, self.pm) if self.pm.charge else None
        self.safety = (ChargeSafety(self.solver, self.contact, sh.safety, sh.outputs.acceleration_filter_hz)
                       if self.pm.charge and sh.safety is not None else None)
        self.closing = closing.Closing()
        o = sh.outputs
        self.fields_out = outputs.Fields(o.output_interval, grid=True) if o.fields else None
        self.checkpoints = outputs.Checkpoint(o.checkpoint_interval, o.checkpoint_interval, grid=True)
        field_times = self.restore(resume) if resume is not None else []
        self.fields = self._field_writer(field_times) if self.fields_out is not None else None
        self.outputs += [x for x in (self.fields_out, self.checkpoints) if x is not None]
        if progress_end is not None and comm.rank == 0:
            self.outputs.append(outputs.Progress(progress_end, self.t))
        traffic.reset()  # the communication block counts the time loop's exchanges

    @property
    def t(self) -> float:
        return self.solver.t

    @property
    def step_count(self) -> int:
        return self.solver.step_count

    @property
    def charged(self) -> bool:
        return bool(self.pm.charge)

    @property
    def frictional(self) -> bool:
        return self.contact is not None

    def load_split(self) -> list[float]:
        return self.load.split(self.comm)

    # ---- the step and the rules ---------------------------------------------------------------------------
    def step(self) -> None:
        """One explicit step, then the nose's recession and the erosion."""
        s, m = self.solver, self.model
        s.step()
        if m.recession is not None and s.step_count % m.recession.every == 0:
            m.recession.apply()
        if m.erosion is not None:
            inside = m.erosion.take_pending()  # cells that inverted within the step, eroded
            if (s.step_count % explicit.STEP_EVERY == 1 and m.erosion.check()) or inside:
                self._after_erosion()

    def stop_rules(self) -> str | None:
        """The load's own rules: on the rigid wall every step ("rebound", fepen.solver.rigid_wall); in a target
        target_rules."""
        return self.load.stop_rule(self)

    def target_rules(self) -> str | None:
        """In a target: Run's rules every EVENT_EVERY steps, after "eroded" and the failure strain
        (BeyondMethod)."""
        s, m = self.solver, self.model
        if s.step_count % self.check_every:
            return None
        if m.erosion is not None and s.total_mass < events.ERODED_FRACTION * s.initial_mass:
            return "eroded"
        if events.beyond_method(diagnostics.max_peeq(s), self.shot.failure_strain):
            self._beyond_method()
        return super().stop_rules()

    def _y_extent(self, x: np.ndarray) -> tuple[float, float]:
        """The lowest and highest y of the load points (collective)."""
        pts = self.model.surface.kinematics(x, self.solver.Vel)[0]
        y_min = self.comm.allreduce(float(pts[:, 1].min()) if len(pts) else np.inf, op=MPI.MIN)
        y_max = self.comm.allreduce(float(pts[:, 1].max()) if len(pts) else -np.inf, op=MPI.MAX)
        return y_min, y_max

    def extent(self):
        s, m = self.solver, self.model
        x = s.positions()
        y_min, y_max = self._y_extent(x)
        if not (self.rules.entered or y_min < 0.0):
            return None  # not in the target yet
        axis = unit_axis(probes.node_value(s, m.tip, x), probes.node_value(s, m.tail, x))
        return y_min, y_max, diagnostics.momentum_velocity(s), axis, s.total_mass, s.sums.ke0

    def _after_erosion(self) -> None:
        """If the nose-tip (tail) node lost its last cell, the foremost (rearmost) live node along the axis
        takes its place (collective)."""
        s, m = self.solver, self.model
        x = s.positions()
        axis = unit_axis(probes.node_value(s, m.tip, x), probes.node_value(s, m.tail, x))
        for name, sign in (("tip", 1.0), ("tail", -1.0)):
            owner, local = getattr(m, name)
            dead = self.comm.bcast(bool(s.node.orphans[local]) if self.comm.rank == owner else None, root=owner)
            if not dead:
                continue
            ahead = np.where(s.node.orphans[: s.n_owned], -np.inf, sign * (x[: s.n_owned] @ axis))
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
            f"{self.shot.failure_strain:g}, {where[1] * 1e3:.1f} mm behind the nose tip "
            f"(radius {np.hypot(where[0], where[2]) * 1e3:.1f} mm), at t = {s.t * 1e6:.1f} us, step "
            f"{s.step_count}: the projectile would fracture or erode, which projectile-target separation "
            "does not model; no result is reported")

    def interrupt(self, name: str) -> None:
        """A signal: write a checkpoint of this step and history.csv, then raise Interrupted (collective)."""
        s = self.solver
        self.write_history()
        self.write_checkpoint()
        raise Interrupted(f"{name} at step {s.step_count}, t = {s.t * 1e6:.3f} us: a checkpoint of that step is "
                          f"written; `fepen run --resume {self.out}` finishes the run with the same results")

    # ---- rows, fields, summary ----------------------------------------------------------------------------
    def snapshot(self) -> Snapshot:
        """The state of a history row (collective); the strain gauges' and charge sections' rows are recorded
        with it."""
        s, m = self.solver, self.model
        x = s.positions()
        e = diagnostics.energies(s)
        en = dict(kinetic=e.kinetic, internal_work=e.internal_work, external_work=e.external_work,
                  elastic=e.elastic, plastic=e.plastic, heat=e.heat, energy_error=e.balance_error,
                  total_energy=e.total, energy_ratio=e.ratio)
        if e.balance_error > ENERGY_LIMIT:
            raise SimulationError(
                f"energy balance lost: error {e.balance_error:.1%} at step {s.step_count}, t = {s.t * 1e6:.3f} us "
                f"(kinetic energy {e.kinetic:.4g} J, carried off by removed material {e.removed_kinetic:.4g} J, "
                f"internal work {e.internal_work:.4g} J): the explicit step is unstable in distorted or eroding "
                "cells; the rows written so far are kept")
        tip, tail = probes.node_value(s, m.tip, x), probes.node_value(s, m.tail, x)
        extra = {}  # the body's own history columns, by their declared names (fepen.io.columns)
        if self.pm.charge:
            extra.update(zip(("shell_acc_g", "charge_acc_g"),
                             diagnostics.body_accelerations(s, unit_axis(tip, tail)) / results.G0))
            b = diagnostics.bodies(s, e)
            for k, body in enumerate(("shell", "charge")):  # reported frame: y is depth
                extra.update({f"{body}_kinetic_J": b.kinetic[k], f"{body}_internal_J": b.internal[k],
                              f"{body}_px_N_s": b.momentum[k, 0], f"{body}_py_N_s": -b.momentum[k, 1]})
            f = self.contact.resultant() if self.contact is not None else diagnostics.tied_interface_force(s)
            extra.update(contact_fx_N=f[0], contact_fy_N=-f[1], contact_force_N=float(np.linalg.norm(f)))
            self.sections.record(tip, tail)
            if self.safety is not None:
                self.safety.record(s.t)
        if self.contact is not None:
            i = self.contact.summary()
            extra.update(friction_J=e.friction, **{f"interface_{k}": i[k] for k in (
                "gap_max_mm", "penetration_max_mm", "slip_max_mm", "free_fraction", "sliding_fraction")})
        self.gauges.record()
        rear = -self._y_extent(x)[1] if self.crossings is not None else np.nan
        xc, w, M, H, vc = diagnostics.rotation(s, x, self.load.nodal_force)  # a rigid wall: None
        return Snapshot(tip, tail, vc, self.load.force, s.total_mass, en,
                        self.load.contact_nodes, s.dt, diagnostics.max_peeq(s), self.load.area, rear, extra,
                        self._removal(e) if self.removing else None, w, M, H,
                        self.load.angular_impulse_now(self.comm), xc)

    def removal(self) -> Removal:
        return self._removal(diagnostics.energies(self.solver))

    def _removal(self, e) -> Removal:
        """Removal from the step's energies ``e`` (collective: the wear heat's sum)."""
        s, m = self.solver, self.model
        heat = self.comm.allreduce(m.recession.heat_total, op=MPI.SUM) if m.recession is not None else 0.0
        return Removal(s.initial_mass - s.total_mass, heat, m.erosion.count if m.erosion is not None else 0,
                       e.removed_kinetic, e.removed_internal, remaining_kg=s.total_mass)

    def finish_loop(self) -> None:
        self.record()
        if self.fields is not None:
            self.write_fields()

    def _field_writer(self, times) -> FieldWriter:
        scalars = ["interface_gap_m", "interface_slip_m"] if self.contact is not None else []
        nodal = ["displacement_m", "velocity_m_s", *self.load.field_names[0]]  # the target's load (a wall: none)
        scalars += list(self.load.field_names[1])
        if self.model.recession is not None:
            scalars.append("wear_depth_m")
        if self.safety is not None and self.contact is not None:
            scalars.append("interface_friction_work_J_m2")
        if self.comm.rank == 0:
            paraview.write_view_script(self.out)
        names = list(self.shot.outputs.field_names) + (self.safety.field_names() if self.safety is not None else [])
        return FieldWriter(self.out, self.solver, nodal, names, times, scalars,
                           integer=("cell_tag",))

    def write_fields(self) -> None:
        s, m = self.solver, self.model
        x = s.positions()
        axis = unit_axis(probes.node_value(s, m.tip, x), probes.node_value(s, m.tail, x))
        values = {"displacement_m": x - s.X0, "velocity_m_s": s.velocity_at_step(),
                  "von_mises_Pa": diagnostics.von_mises(s), "axial_stress_Pa": diagnostics.axial_stress(s, axis),
                  "peeq": diagnostics.live_peeq(s), "temperature_K": s.temp, "cell_tag": s.mat + 1.0}
        stress = diagnostics.stress_fields(s)
        values.update(zip(shot.STRESS_TENSOR_FIELDS, stress.pop("stress_Pa").T), **stress)
        values.update(self.load.surface_fields(s))  # the target's load (a rigid wall has none)
        if self.contact is not None:
            values.update(self.contact.nodal_gap_and_slip())
        if m.recession is not None:
            values["wear_depth_m"] = m.recession.depth
        if self.safety is not None:
            values.update(self.safety.cell_fields())
            if self.contact is not None:
                values.update(self.safety.nodal_fields())
        self.fields.write(s.t, values)

    def write_closing(self) -> None:
        self.closing.write(self)

    def summary_extra(self, loop_s: float) -> dict:
        s, m, o = self.solver, self.model, self.shot.outputs
        return {"dt_s": s.clock.dt_min,
                "time_split_s": {"mesh": m.mesh_s, "setup_jit": m.setup_s,
                                 "time_loop": loop_s - self.output_s, "output": self.output_s},
                "mass_kg": s.total_mass, "cells": self.pm.mesh.topology.index_map(3).size_global,
                "stress_kernel": s.kernel, "step_gain": s.clock.step_gain, **self.closing.summary(),
                "acceleration_filter": o.acceleration_filter,
                "acceleration_filter_hz": signals.corner_hz(o.acceleration_filter, o.acceleration_filter_hz),
                "communication": traffic.of_run(self.comm, self.solver, self.load)}

    def stop_extra(self) -> dict:
        return {"mass_kg": self.solver.total_mass}

    # ---- checkpoints: the dict of the components' states ----------------------------------------------------
    def components(self) -> tuple[dict, dict]:
        """(the components whose state is arrays, per rank; those whose state is small, kept in state.json)."""
        m = self.model
        arrays = {"solver": self.solver, "load": self.load, "gauges": self.gauges, "sections": self.sections,
                  "contact": self.contact, "safety": self.safety,
                  "surface": m.surface if self.removing else None, "recession": m.recession, "probes": self.probes}
        small = {"rules": self.rules, "crossings": self.crossings, "erosion": m.erosion, "history": self.history,
                 "fields": self.fields_out, "checkpoints": self.checkpoints}
        return ({k: c for k, c in arrays.items() if c is not None}, {k: c for k, c in small.items() if c is not None})

    def write_checkpoint(self) -> None:
        """A checkpoint of the state between two steps (collective)."""
        big, small = self.components()
        arrays = {f"{name}.{k}": v for name, c in big.items() for k, v in c.state().items()}
        arrays["rows"] = np.array(self.rows, dtype=float)
        meta = {"wall_s": self.wall_s, "inputs_sha256": self.shot.inputs.get("sha256"),
                "components": {name: c.state() for name, c in small.items()},
                "tip": self._tip_reference(),
                "field_times_s": list(self.fields.times) if self.fields is not None else []}
        checkpoint.write(self.out, self.comm, self.solver.step_count, self.solver.t, arrays, meta)

    def restore(self, state: dict) -> list[float]:
        """Put a checkpoint back into this freshly built run (collective). Returns the field output times."""
        z = checkpoint.read_arrays(self.out, self.comm, state, ())
        X0 = z.get("solver.X0", z.get("solver.X"))
        same = X0 is not None and X0.shape == self.solver.X0.shape and np.array_equal(X0, self.solver.X0)
        if not self.comm.allreduce(same, op=MPI.LAND):
            raise InputError("--resume", "the mesh rebuilt from scene.toml differs from the checkpointed one "
                                         "(another fepen or gmsh version, or another partition)")
        big, small = self.components()
        for name, c in big.items():
            c.restore({k.split(".", 1)[1]: v for k, v in z.items() if k.startswith(f"{name}.")})
        for name, c in small.items():
            c.restore(state["components"][name])
        self.rows = [list(r) for r in z["rows"]]
        self.model.tip = self.load.tip = probes.node_at(self.solver, state["tip"])
        self.wall_before = float(state["wall_s"])
        return state["field_times_s"]

    def _tip_reference(self) -> list[float]:
        """The initial reference position of the current nose-tip node (to find it again on resume)."""
        owner, local = self.model.tip
        return self.comm.bcast([float(c) for c in self.solver.X0[local]] if self.comm.rank == owner else None,
                               root=owner)

    def drop_checkpoints(self) -> None:
        checkpoint.drop(self.out, self.comm)
