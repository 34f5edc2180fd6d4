"""The rigid fidelity (``effects.fidelity = "rigid"``): the projectile as one rigid body in the concrete
target law (docs/theory.md §9). By default without any mesh: the mass properties of the exact solid of
revolution and load points in rings on its exact surface (fepen.geometry.revolution); the volume mesh's
(mesh_points) on request. Every rank integrates the same ODE on all the points. The
stop rules are fepen.runs.events'; a stop on V·a ≤ 0 is interpolated to where the speed along the axis
vanishes.
"""

from __future__ import annotations

import time

import numpy as np
from mpi4py import MPI

from fepen.errors import Interrupted, SimulationError
from fepen.geometry import mesh as fmesh
from fepen.geometry import revolution, tags
from fepen.geometry.cad import CadBody
from fepen.io import files, results, rundir
from fepen.laws import layers as fl
from fepen.laws import target as tg
from fepen.laws import wear
from fepen.laws.rigid_body import (
    RigidBody,
    RigidState,
    inertia_about_centre,
    matrix_to_quat,
    quat_to_matrix,
    tet_mass_properties,
)
from fepen.runs import events, interrupts, setup

#: default RK4 step: the time to travel this fraction of a diameter at the striking speed, and at most
#: 1/STOP_STEPS of the time the quasi-static force alone would take to stop the projectile
STEP_FRACTION = 0.2
STOP_STEPS = 150
#: load points per ring of the default (mesh-free) rigid body
RING_SECTORS = 12
#: steps between two looks at the signals (one reduction under MPI)
SIGNAL_EVERY = 64
#: a layered target's run without run.end_time lasts at least this many times the time to reach its last
#: face at the striking speed
LAYERED_TIME = 20.0


def mesh_points(scene, comm) -> tuple[dict, tuple, int]:
    """Load points and mass properties from the scene's volume mesh: its outer facets on the exact surface
    (fepen.solver.surface) and the exact integrals over its cells, summed in the cells' original (gmsh)
    order, so that the whole rigid trajectory is bitwise the same on any number of ranks.

    Returns:
        (points as fepen.geometry.revolution.load_points returns them, (mass, centre, inertia), cells).
    """
    from dolfinx import fem

    from fepen.solver import surface

    pm = setup.mesh(scene, comm)
    p = fmesh.cell_points(pm.mesh)
    rho = np.full(len(p), setup.projectile(scene).shell_density)
    if pm.charge:
        rho[fmesh.owned_cells_tagged(pm, tags.CHARGE)] = scene.charge.material.density
    key = pm.mesh.topology.original_cell_index[: len(p)]
    parts = comm.allgather((np.asarray(key), p, rho))
    order = np.argsort(np.concatenate([k for k, _, _ in parts]), kind="stable")
    p = np.concatenate([q for _, q, _ in parts])[order]
    rho = np.concatenate([r for _, _, r in parts])[order]
    m, first, second = tet_mass_properties(p, rho)
    c, inertia = inertia_about_centre(m, first, second)
    V = fem.VectorFunctionSpace(pm.mesh, ("CG", 1))
    points = surface.gather_global(surface.outer_surface(V, pm.facet_tags, pm.shape), comm)
    return points, (m, c, inertia), pm.mesh.topology.index_map(3).size_global


def ring_points(scene, shape) -> dict:
    """The default load points: rings on the exact surface (fepen.geometry.revolution.load_points), meridian
    panels of mesh.rigid_panel (absent: a sixth of the diameter) with two Gauss rings each, RING_SECTORS
    points per ring."""
    panel = scene.get("mesh.rigid_panel") or shape.diameter / 6.0
    return revolution.load_points(shape, panel, RING_SECTORS)


#: the default bodies built so far in this process, by their scene keys (a sweep's shots share a projectile)
_BODIES: dict = {}


def _body_key(scene) -> tuple:
    from fepen.scene import SCHEMA

    return tuple((k, repr(scene.get(k))) for k in SCHEMA
                 if k.startswith(("projectile.", "charge.")) or k in ("effects.charge", "mesh.rigid_panel"))


def default_body(scene):
    """(the built projectile, its ring load points, its exact mass properties), built once per projectile in
    a process (the arrays are shared: read them, never write)."""
    key = _body_key(scene)
    hit = _BODIES.get(key)
    if hit is None:
        built = setup.projectile(scene)
        rho_c = scene.charge.material.density if scene.effects.charge else None
        hit = (built, ring_points(scene, built.shape),
               revolution.mass_properties(built.shape, built.shell_density, rho_c))
        if len(_BODIES) >= 16:
            _BODIES.clear()
        _BODIES[key] = hit
    return hit


class RigidRun:
    """One rigid-projectile penetration.

    Args:
        scene: resolved Scene (fidelity rigid, concrete target).
        out: results directory (None: write nothing, for sweeps and tests).
        comm: MPI communicator.
        points: load points (dict as fepen.geometry.revolution.load_points returns); default: the rings on
            the exact surface (ring_points); "mesh": the volume mesh's outer facets and its mass properties
            (mesh_points).
        mass_properties: (mass, centre, inertia); default: the exact solid of revolution's.
    """

    def __init__(self, scene, out, comm=MPI.COMM_WORLD, points: dict | None = None,
                 mass_properties: tuple | None = None):
        self.scene, self.comm = scene, comm
        self.t0 = time.perf_counter()
        self.cells = 0  # no volume mesh unless asked for
        if points is None and mass_properties is None and not scene.get("projectile.cad"):
            built, points, mass_properties = default_body(scene)
        else:
            built = setup.projectile(scene)
        if points == "mesh" or (points is None and isinstance(built.shape, CadBody)):  # a CAD body: only its mesh
            points, mass_properties, self.cells = mesh_points(scene, comm)
        if points is None:
            points = ring_points(scene, built.shape)
        if mass_properties is None:
            rho_c = scene.charge.material.density if scene.effects.charge else None
            mass_properties = revolution.mass_properties(built.shape, built.shell_density, rho_c)
        self.shape = built.shape
        self.mass, c0, inertia = mass_properties
        self.pts = g = points
        self.setup_s = time.perf_counter() - self.t0
        self.out = files.prepare(out, comm) if out is not None else None
        self.body = RigidBody(self.mass, c0, inertia, g["X"], g["N"])
        self.law = setup.target_law(scene)
        R, v = setup.placement(scene)
        self.v0 = float(np.linalg.norm(v))
        self.state = RigidState(R @ c0, matrix_to_quat(R), v.copy(), np.zeros(3))
        self.crater = setup.crater(scene, self.law, self.mass, self.v0)
        a = 0.5 * scene.projectile.diameter
        t_stop = self.mass * self.v0 / (self.law.sigma_s * np.pi * a * a)
        self.dt = scene.get("run.rigid_step") or min(STEP_FRACTION * scene.projectile.diameter / self.v0,
                                                      t_stop / STOP_STEPS)
        self.tip_ref = np.zeros(3)
        self.tail_ref = np.array([0.0, self.shape.length, 0.0])
        self.rows = []
        self.w_ext = 0.0
        self.ke0 = self.body.kinetic_energy(self.state)
        self.loaded = 0
        self.area = 0.0
        self.wear = Wear(scene) if scene.effects.wear else None
        self.crossings = fl.Crossings(self.law.faces()) if getattr(self.law, "layered", False) else None

    # ------------------------------------------------------------------------------------------------
    def force_fn(self, s: RigidState, x, v, n):
        """Target forces on the load points (zero outside the target)."""
        g = self.pts
        R = self.body.frame[0]  # s's rotation (RigidBody.derivative)
        tip = s.c + R @ (self.tip_ref - self.body.centre0)
        load = tg.load_on_points(self.law, x, v, n, g["area0"], g["radius"], g["R_meridian"], g["sin_phi0"],
                                 -R[:, 1], self.crater, -tip[1])
        self.loaded, self.area = load.loaded, load.area
        if self.wear is not None:
            self.wear.stage(load.force, n, v)
        return load.force

    def axis(self, s: RigidState) -> np.ndarray:
        """World unit vector of the projectile axis, tail to nose."""
        return quat_to_matrix(s.q) @ np.array([0.0, -1.0, 0.0])

    def record(self, s: RigidState, force):
        tip = self.body.to_world(s, self.tip_ref[None])[0]
        tail = self.body.to_world(s, self.tail_ref[None])[0]
        ke = self.body.kinetic_energy(s)
        removed = self.wear.kinetic_removed if self.wear is not None else 0.0
        err = abs(ke + removed - self.ke0 - self.w_ext) / self.ke0
        en = dict(kinetic=ke, internal_work=0.0, external_work=self.w_ext, elastic=0.0, plastic=0.0, heat=0.0,
                  energy_error=err)
        row = results.history_row(self.t, tip, tail, s.V, force, self.body.mass, en, self.loaded, self.dt, 0.0,
                                  self.area)
        if self.wear is not None:
            row += [self.body.mass, self.wear.heat]
        results.finite_row(row, self.steps, self.t)
        self.rows.append(row)

    def run(self) -> dict:
        """Integrate to a stop event or run.end_time; write the outputs; return the summary. A stop (a signal,
        a non-finite state, a full disk) writes summary.json with the stop (when the run has a directory) and
        raises again."""
        try:
            with interrupts.Interrupts(self.comm) as signals:
                outcome, t_loop = self.integrate(signals)
            return self.finish(outcome, t_loop)
        except BaseException as err:
            if self.out is not None:
                self.write_stop(err)
            raise

    def integrate(self, signals) -> tuple[str | None, float]:
        """The RK4 loop to a stop event or the end time (a caught signal: Interrupted). Returns (the outcome
        or None, the loop's start on the wall clock)."""
        end = self.scene.get("run.end_time")
        hard_end = end if end is not None else 0.05
        hist_every = max(1, round(1e-6 / self.dt))
        body, s = self.body, self.state
        self.t, self.steps = 0.0, 0
        self.rules = events.StopRules(self.law.thickness, end is None)
        outcome = None
        t_loop = time.perf_counter()
        if self.crossings is not None:
            hard_end = end if end is not None else max(hard_end, LAYERED_TIME * self.law.faces()[-1][0] / self.v0)
            y0 = body.points(s)[0][:, 1]
            self.crossings.update(0.0, -body.to_world(s, self.tip_ref[None])[0][1], -float(y0.max()),
                                  float(np.linalg.norm(s.V)))
        _, F, M = body.derivative(s, self.force_fn)
        self.record(s, F)
        while self.t < hard_end:
            prev = s
            s, F, M, work = body.rk4_step(s, self.dt, self.force_fn)  # F, M: at the start of the step
            self.w_ext += work
            if self.wear is not None:
                s = self.wear.step(body, s, self.dt)
            self.t += self.dt
            self.steps += 1
            y = body.points(s)[0][:, 1]
            if self.crossings is not None:
                tip_y = body.to_world(s, self.tip_ref[None])[0][1]
                self.crossings.update(self.t, -tip_y, -float(y.max()), float(np.linalg.norm(s.V)))
            outcome = self.rules.penetration(float(y.min()), float(y.max()), s.V, self.axis(s), self.mass, self.ke0)
            if outcome == "embedded" and float(s.V @ self.axis(s)) <= 0.0:
                # stopped advancing: interpolate to where the speed along the axis vanishes
                a0, a1 = float(prev.V @ self.axis(prev)), float(s.V @ self.axis(s))
                lam = a0 / (a0 - a1) if a0 - a1 > 0.0 else 1.0
                s = RigidState.from_array(prev.as_array() + lam * (s.as_array() - prev.as_array()))
                s.q /= np.linalg.norm(s.q)
                self.t -= (1.0 - lam) * self.dt
            if outcome is not None:
                break
            if self.steps % hist_every == 0:
                self.record(s, F)
            if self.steps % SIGNAL_EVERY == 0 and (name := signals.stop()) is not None:
                raise Interrupted(f"{name} at step {self.steps}, t = {self.t * 1e6:.3f} us: a rigid run keeps no "
                                  "checkpoint (it takes seconds); `fepen run --resume DIR` runs it again")
        _, F, M = body.derivative(s, self.force_fn)
        self.record(s, F)
        self.state = s
        return outcome, t_loop

    def finish(self, outcome: str | None, t_loop: float) -> dict:
        """The summary; history.csv and summary.json when the run has a directory."""
        body = self.body
        loop_s = time.perf_counter() - t_loop
        extra = {"steps": self.steps, "dt_s": self.dt, "end_time_s": self.t,
                 "wall_s": time.perf_counter() - self.t0,
                 "time_split_s": {"mesh": self.setup_s, "time_loop": loop_s}, "mass_kg": self.mass,
                 "cells": self.cells, "ranks": self.comm.size,
                 "peak_memory_bytes": files.peak_memory_bytes(self.comm),
                 "load_points": len(self.pts["area0"]), "fidelity": "rigid"}
        if self.wear is not None:
            extra.update(self.wear.summary(self.mass, body.mass))
        summary = results.summary(self.scene, self.rows, outcome or "ended", extra)
        if self.crossings is not None:
            summary.update(self.crossings.summary(self.law, 1e-3 * summary["depth_mm"]))
        if self.out is not None:
            results.write_history(self.rows, self.out, self.comm, self.columns)
            results.write_summary(self.out, summary, self.comm)
        return summary

    @property
    def columns(self) -> list[str]:
        return results.HISTORY_COLUMNS + (results.WEAR_COLUMNS if self.wear is not None else [])

    def write_stop(self, err: BaseException) -> None:
        """history.csv so far and summary.json of the stop (rank 0, no collective; best effort)."""
        if isinstance(err, (Interrupted, KeyboardInterrupt)):
            outcome = "interrupted"
        elif isinstance(err, OSError):
            outcome = "fault"
        else:
            outcome = "stopped" if isinstance(err, SimulationError) else "error"
        steps, t = getattr(self, "steps", 0), getattr(self, "t", 0.0)
        reason = str(err).splitlines()[0] if str(err) else type(err).__name__
        summary = results.stop_summary(self.scene, self.rows, outcome, reason, {"step": steps, "t_s": t},
                                       {"steps": steps, "ranks": self.comm.size, "fidelity": "rigid"})
        if self.comm.rank == 0:
            rundir.release_reserve()
            try:
                if self.rows:
                    results.write_history(self.rows, self.out, MPI.COMM_SELF, self.columns)
                files.write_json(self.out / "summary.json", summary, MPI.COMM_SELF)
            except OSError:
                pass


class Wear:
    """The scalar nose wear of the rigid fidelity (docs/theory.md §14): the interface heat μ σ_n |v_t| summed
    over the load points with the RK4 weights of the step's four stages, and the mass η Q/h it melts, taken
    off the body after each step (fepen.laws.wear)."""

    def __init__(self, scene):
        m = scene.projectile.material
        mu = scene.get("projectile.wear.friction")
        self.mu = scene.target.friction if mu is None else mu
        self.efficiency = scene.projectile.wear.efficiency
        self.enthalpy = wear.melt_enthalpy(m.specific_heat, m.melt_temperature, m.room_temperature,
                                           scene.projectile.wear.latent_heat)
        self.stages: list[float] = []
        self.heat = self.mass_lost = self.kinetic_removed = 0.0

    def stage(self, force, n, v) -> None:
        """Record one RK4 stage's heat rate (W)."""
        self.stages.append(wear.heat_rate(force, n, v, self.mu))

    def step(self, body, s, dt: float):
        """Add the step's heat (its four RK4 stages, the last recorded), take its melted mass off the body; the
        state after."""
        q = self.stages[-4:]
        self.stages.clear()
        heat = dt / 6.0 * (q[0] + 2.0 * q[1] + 2.0 * q[2] + q[3])
        dm = wear.melted_mass(heat, self.efficiency, self.enthalpy)
        self.heat += heat
        if dm <= 0.0:
            return s
        s, ke = body.remove_mass(s, dm)
        self.mass_lost += dm
        self.kinetic_removed += ke
        return s

    def summary(self, mass0: float, remaining: float) -> dict:
        return {"mass_loss_kg": self.mass_lost, "mass_loss_percent": 100.0 * self.mass_lost / mass0,
                "remaining_mass_kg": remaining,
                "wear_heat_J": self.heat, "removed_kinetic_J": self.kinetic_removed}
