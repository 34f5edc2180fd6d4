"""The rigid fidelity (``effects.fidelity = "rigid"``): the projectile as one rigid body in the concrete
target law (docs/theory.md §9). By default without any mesh: the mass properties of the exact solid of
revolution and load points in rings on its exact surface (fepen.geometry.revolution); the volume mesh's
(mesh_points) on request. Every rank integrates the same ODE on all the points, by the compiled step
(fepen/runs/rigid_batch.c's rigid_step, the batch's own) where the C kernels build and the target is one
material, else by the numpy step (fepen.laws.rigid_body.RigidBody.rk4_step, its oracle). The stop rules are
fepen.runs.events'; a stop on V·a ≤ 0 is interpolated to where the speed along the axis vanishes.
"""

from __future__ import annotations

import ctypes
import functools
import time

import numpy as np
from mpi4py import MPI

from fepen import native
from fepen.errors import Interrupted, SimulationError
from fepen.geometry import mesh as fmesh
from fepen.geometry import revolution, tags
from fepen.geometry.cad import CadBody
from fepen.geometry.shape import Shape
from fepen.io import results
from fepen.laws import energy, wear
from fepen.laws import target as tg
from fepen.laws import tunnel as tunnel_zones
from fepen.laws.rigid_body import (
    RigidBody,
    RigidState,
    inertia_about_centre,
    matrix_to_quat,
    tet_mass_properties,
)
from fepen.laws.tunnel import Tunnel
from fepen.runs import budget, events, outputs, setup, shot
from fepen.runs import probes as run_probes
from fepen.runs.run import Removal, Run, Snapshot

#: load points per ring of the default (mesh-free) rigid body
RING_SECTORS = 12


def mesh_points(sh, comm) -> tuple[dict, tuple, int]:
    """Load points and mass properties from the shot's volume mesh: its outer facets on the exact surface
    (fepen.solver.surface) and the exact integrals over its cells, summed in the cells' original (gmsh)
    order, so that the whole rigid trajectory is bitwise the same on any number of ranks.

    Args:
        sh: the Shot (a Scene is resolved). comm: the communicator.

    Returns:
        (points as fepen.geometry.revolution.load_points returns them, (mass, centre, inertia), cells).
    """
    from fepen import dolfinx_api as dx
    from fepen.solver import surface

    sh = shot.of(sh)

    pm = setup.build_mesh(sh.built, sh.mesh, comm)
    p = fmesh.cell_points(pm.mesh)
    rho = np.full(len(p), sh.built.shell_density)
    if pm.charge:
        rho[fmesh.owned_cells_tagged(pm, tags.CHARGE)] = sh.mesh.charge_density
    key = pm.mesh.topology.original_cell_index[: len(p)]
    parts = comm.allgather((np.asarray(key), p, rho))
    order = np.argsort(np.concatenate([k for k, _, _ in parts]), kind="stable")
    p = np.concatenate([q for _, q, _ in parts])[order]
    rho = np.concatenate([r for _, _, r in parts])[order]
    m, first, second = tet_mass_properties(p, rho)
    c, inertia = inertia_about_centre(m, first, second)
    V = dx.vector_space(pm.mesh)
    points = surface.gather_global(surface.outer_surface(V, pm.facet_tags, pm.shape), comm)
    return points, (m, c, inertia), pm.mesh.topology.index_map(3).size_global


def ring_points(shape, panel: float | None = None) -> dict:
    """The default load points: rings on the exact surface (fepen.geometry.revolution.load_points), meridian
    panels of ``panel`` (mesh.rigid_panel; None: a sixth of the diameter) with two Gauss rings each,
    RING_SECTORS points per ring."""
    return revolution.load_points(shape, panel or shape.diameter / 6.0, RING_SECTORS)


#: the default bodies built so far in this process, by their scene keys (a sweep's shots share a projectile)
_BODIES: dict = {}


def _charge_density(sh: shot.Shot) -> float | None:
    return sh.mesh.charge_density if sh.mesh.charge else None


def default_body(sh: shot.Shot):
    """(its ring load points, its exact mass properties), built once per projectile in a process (the arrays
    are shared: read them, never write)."""
    hit = _BODIES.get(sh.body_key)
    if hit is None:
        shape = sh.built.shape
        hit = (ring_points(shape, sh.mesh.rigid_panel),
               revolution.mass_properties(shape, sh.built.shell_density, _charge_density(sh)))
        if len(_BODIES) >= 16:
            _BODIES.clear()
        _BODIES[sh.body_key] = hit
    return hit


#: the energy balance error (theory.md §6) beyond which a rigid run is unstable: a stable one stays under 1e-2
UNSTABLE_ENERGY_ERROR = 0.1


@functools.singledispatch
def body_points(shape, sh, comm, points: dict | None, mass_properties: tuple | None) -> tuple[dict, tuple, int]:
    """The rigid body's load points and mass properties where not given, by the body's kind.

    Args:
        shape: the built body (a Shape or a CadBody). sh: the Shot. comm: the communicator.
        points, mass_properties: as RigidRun takes them (None: the kind's own).

    Returns:
        (points, (mass, centre, inertia), the volume mesh's cells: 0 without one).
    """
    raise TypeError(f"no rigid body for a {type(shape).__name__}")


@body_points.register(Shape)
def _exact_body_points(shape, sh, comm, points, mass_properties):
    """The exact solid of revolution: rings on its surface and its exact mass properties, no mesh."""
    if points is None and mass_properties is None:
        points, mass_properties = default_body(sh)
    if points is None:
        points = ring_points(shape, sh.mesh.rigid_panel)
    if mass_properties is None:
        mass_properties = revolution.mass_properties(shape, sh.built.shell_density, _charge_density(sh))
    return points, mass_properties, 0


@body_points.register(CadBody)
def _cad_body_points(shape, sh, comm, points, mass_properties):
    """A CAD body: only its mesh knows its surface and mass (mesh_points, its mass properties too when no
    points are given)."""
    if points is None:
        return mesh_points(sh, comm)
    if mass_properties is None:
        _, mass_properties, cells = mesh_points(sh, comm)
        return points, mass_properties, cells
    return points, mass_properties, 0


class RigidRun(Run):
    """One rigid-projectile penetration.

    Args:
        shot: the resolved shot (fepen.runs.shot.Shot; a Scene is resolved), rigid fidelity, concrete target.
        out: results directory (None: write nothing, for sweeps and tests).
        comm: MPI communicator.
        points: load points (dict as fepen.geometry.revolution.load_points returns); default: the rings on
            the exact surface (ring_points); "mesh": the volume mesh's outer facets and its mass properties
            (mesh_points).
        mass_properties: (mass, centre, inertia); default: the exact solid of revolution's.
        history: False keeps only the final state's history row (a study that reads the final depth alone,
            fepen.studies.depth: the trajectory is the same, the summary's maxima are that row's, and every
            step's state is checked finite instead).
    """

    fidelity = "rigid"

    def __init__(self, shot_, out, comm=MPI.COMM_WORLD, points: dict | None = None,
                 mass_properties: tuple | None = None, history: bool = True, progress: bool = False):
        sh = shot.of(shot_)
        super().__init__(sh, out, comm)
        if progress and comm.rank == 0:  # a terminal's bar (a slow shot's thousands of steps take seconds)
            self.outputs.append(outputs.Progress(sh.end_time or sh.hard_end, 0.0))
        if not history:
            self.history.clock.interval = 0.0  # never due: finish_loop records the final row
        self.check_finite = not history
        if points == "mesh":
            points, mass_properties, self.cells = mesh_points(sh, comm)
        else:  # what the body's kind gives where not given
            points, mass_properties, self.cells = body_points(sh.built.shape, sh, comm, points, mass_properties)
        self.shape = sh.built.shape
        self.mass, c0, inertia = mass_properties
        self.initial_mass = self.mass
        self.pts = g = points
        self.setup_s = time.perf_counter() - self.wall_t0
        self.body = RigidBody(self.mass, c0, inertia, g["X"], g["N"])
        self.law = sh.law
        R, v = sh.rotation, sh.velocity
        self.v0 = sh.speed
        self.state = RigidState(R @ c0, matrix_to_quat(R), v.copy(), R @ inertia @ R.T @ sh.angular_velocity)
        self.crater = sh.crater(self.mass)
        self.dt = sh.rigid_step or budget.default_step(self.mass, self.v0, sh.nominal_diameter, self.law)
        if sh.end_time is None:  # a shot that never stops (a body slower than its first ring's reach) ends
            self.end = min(self.end, (budget.MAX_RIGID_STEPS - 0.5) * self.dt)  # in the step budget, "ended"
        if sh.tunnel and sh.rigid_step is None:  # the wall's spring (a tunnel: a target of one material)
            self.dt = min(self.dt, budget.wall_step(self.mass, self.shape.diameter, self.shape.length, self.law))
        self.tip_ref = np.zeros(3)
        self.tail_ref = np.array([0.0, self.shape.length, 0.0])
        self.tip_arm = self.tip_ref - self.body.centre0  # the tip about the centre, body frame
        self.w_ext = 0.0
        self.angular_impulse = np.zeros(3)  # the target's about O since the run began (N m s)
        self._row = None  # (the state's bytes, the target's load there) of the last history row
        self.ke0 = self.body.kinetic_energy(self.state)
        self.loaded = 0
        self.area = 0.0
        self.wear = None
        if sh.wear is not None:
            if sh.wear.distribution == "nose":
                self.pts = g = {k: np.array(v, copy=True) for k, v in g.items()}  # the nose moves its points
                self.body = RigidBody(self.mass, c0, inertia, g["X"], g["N"])
                y_c, r_c = revolution.nose_zone(self.shape, g["X"], g["radius"])
                self.wear = Wear(sh.wear, g, y_c, r_c)
            else:
                self.wear = Wear(sh.wear)
        self.tunnel = None
        xi_sh, a0 = tunnel_zones.shoulder_of(g["X"], g["radius"])
        self.zone = tunnel_zones.zones(g["X"][:, 1], xi_sh, self.shape.length, 2.0 * a0)
        if sh.tunnel:
            self.tunnel = Tunnel.of_points(g["X"], g["radius"])
            self.shoulder_arm = np.array([0.0, self.tunnel.xi_sh, 0.0]) - self.body.centre0
        self.t, self.step_count = 0.0, 0
        self.prev = self.state
        self.F = self.body.derivative(self.state, self.force_fn)[1]  # the force at the state (no target: zero)
        if sh.probes and history and self.out is not None:
            self.probes = run_probes.RigidProbes(sh.probes)
        #: the compiled step (rigid_batch.c's rigid_step, the batch's own), or None: the numpy step
        #: (RigidBody.rk4_step, the oracle), with FEPEN_KERNEL=numpy/python, without C kernels, or a layered target
        self.compiled = CompiledStep(self) if covers(self) else None

    # ------------------------------------------------------------------------------------------------
    def _load(self, s: RigidState, R, x, v, n):
        """The target's PointLoad on the load points at state s (rotation R)."""
        g = self.pts
        tip = s.c + R @ self.tip_arm
        xi = None
        if self.tunnel is not None:  # where the shoulder is now (the tunnel's open end)
            self.tunnel.at(s.c + R @ self.shoulder_arm, -R[:, 1])
            xi = np.ascontiguousarray(g["X"][:, 1])
        return tg.load_on_points(self.law, x, v, n, g["area0"], g["radius"], g["R_meridian"], g["sin_phi0"],
                                 -R[:, 1], self.crater, -tip[1], tunnel=self.tunnel, body_xi=xi)

    def _row_load(self, s: RigidState, R, x, v, n):
        """The target's load at the history row's state s, evaluated once for the row's columns (the split and
        the moment; nothing recorded)."""
        key = s.as_array().tobytes()
        if self._row is None or self._row[0] != key:
            self._row = (key, self._load(s, R, x, v, n))
        return self._row[1]

    def load_split(self) -> list[float]:
        """LOAD_COLUMNS at the present state (the target's forces evaluated there; nothing recorded)."""
        s = self.state
        x, v, n, _ = self.body.points(s)
        split = tunnel_zones.split(self._row_load(s, self.body.at(s)[1], x, v, n).force, self.zone)
        return [*np.linalg.norm(split[:, :3], axis=1).tolist(), *split[:, 3].tolist()]

    def force_fn(self, s: RigidState, x, v, n):
        """Target forces on the load points (zero outside the target)."""
        load = self._load(s, self.body.frame[0], x, v, n)  # s's rotation (RigidBody.derivative)
        self.loaded, self.area = load.loaded, load.area
        if self.wear is not None:
            self.wear.stage(load.force, n, v)
        return load.force

    def axis(self, s: RigidState) -> np.ndarray:
        """World unit vector of the projectile axis, tail to nose."""
        return self.body.at(s)[1] @ np.array([0.0, -1.0, 0.0])

    def step(self) -> None:
        """One RK4 step, then the wear (a history row evaluates the target's load at its own state)."""
        self.prev = s = self.state
        if self.compiled is not None:
            s = self._compiled_step(s)
        else:
            if self.tunnel is not None:
                self.tunnel.commit = True  # the first stage records the tunnel at the step's start
            s, self.F, _, work = self.body.rk4_step(s, self.dt, self.force_fn)
            self.w_ext += work
        self.angular_impulse = self.angular_impulse + self.body.angular_impulse_step
        if self.wear is not None:
            s = self.wear.step(self.body, s, self.dt)
            self.tip_ref[1] = self.wear.shortening
            self.tip_arm = self.tip_ref - self.body.centre0  # the worn nose's tip (force_fn's crater depth)
            if self.compiled is not None:
                self.compiled.refresh()  # the worn body's mass, inertia, points and tip
        self.state = s
        self.t += self.dt
        self.step_count += 1
        if self.check_finite:  # what the history rows would have caught
            results.finite_row(s.as_array().tolist(), self.step_count, self.t)

    def _compiled_step(self, s: RigidState) -> RigidState:
        """RigidBody.rk4_step with force_fn, compiled (rigid_batch.c's rigid_step): the state after the step,
        with the force at its start, its work, its angular impulse (the body's, as rk4_step leaves it), the last
        stage's load and the wear's four stages, as the numpy step gives them."""
        y = s.as_array()
        out = self.compiled(y)
        at = STEP
        self.F = out[at["force"]:at["force"] + 3].copy()
        self.w_ext += float(out[at["work"]])
        self.body.angular_impulse_step = out[at["angular"]:at["angular"] + 3].copy()
        self.loaded, self.area = int(out[at["loaded"]]), float(out[at["area"]])
        if self.wear is not None:
            for f, v, n in self.compiled.stages:
                self.wear.stage(f, n, v)
        return RigidState.from_array(y)

    def extent(self):
        s = self.state
        y = self.body.points(s)[0][:, 1]
        return float(y.min()), float(y.max()), s.V, self.axis(s), self.mass, self.ke0

    def stop_rules(self) -> str | None:
        """The rules of Run; a stop on V·a ≤ 0 is interpolated to where the speed along the axis vanishes."""
        outcome = super().stop_rules()
        if outcome != "embedded":
            return outcome
        lam = self.compiled.stop_back(self) if self.compiled is not None else self.stop_back()
        if lam is not None:
            self.t -= (1.0 - lam) * self.dt
            self.angular_impulse = self.angular_impulse - (1.0 - lam) * self.body.angular_impulse_step
        return outcome

    def stop_back(self) -> float | None:
        """An embedded stop's interpolation in numpy (the oracle of rigid_batch.c's rigid_stop_back, which the
        compiled step takes): when V·a ≤ 0, the state taken back along the step to where V·a vanishes.

        Returns:
            The fraction of the step kept, or None when the state stays."""
        s, prev = self.state, self.prev
        if not float(s.V @ self.axis(s)) <= 0.0:
            return None
        a0, a1 = float(prev.V @ self.axis(prev)), float(s.V @ self.axis(s))
        lam = a0 / (a0 - a1) if a0 - a1 > 0.0 else 1.0
        s = RigidState.from_array(prev.as_array() + lam * (s.as_array() - prev.as_array()))
        s.q /= np.linalg.norm(s.q)
        self.state = s
        return lam

    def finish_loop(self) -> None:
        """The final state's row, with the force at that state; a run whose energy balance has run away (the
        target law only takes energy) stops with a SimulationError instead of reporting its numbers."""
        self.F = self.body.derivative(self.state, self.force_fn)[1]
        self.record()
        removed = self.wear.kinetic_removed if self.wear is not None else 0.0
        err = energy.balance_error(self.body.kinetic_energy(self.state), self.ke0, self.w_ext, removed_kinetic=removed)
        if not err <= UNSTABLE_ENERGY_ERROR:
            tip = self.body.to_world(self.state, self.tip_ref[None])[0]
            raise SimulationError(f"the rigid body's motion ran away: energy balance error {err:.3g} (over "
                                  f"{UNSTABLE_ENERGY_ERROR:g}) at t = {self.t * 1e6:.1f} us, step {self.step_count}, "
                                  f"nose at ({tip[0] * 1e3:.4g}, {tip[1] * 1e3:.4g}) mm: the step is too long for "
                                  "this shot (run.rigid_step)")

    def snapshot(self) -> Snapshot:
        s, body = self.state, self.body
        tip = body.to_world(s, self.tip_ref[None])[0]
        tail = body.to_world(s, self.tail_ref[None])[0]
        ke = body.kinetic_energy(s)
        removed = self.wear.kinetic_removed if self.wear is not None else 0.0
        total = ke + removed - self.w_ext  # glstat's total: the target's work counted as energy it took
        en = dict(kinetic=ke, internal_work=0.0, external_work=self.w_ext, elastic=0.0, plastic=0.0, heat=0.0,
                  energy_error=energy.balance_error(ke, self.ke0, self.w_ext, removed_kinetic=removed),
                  total_energy=total, energy_ratio=total / self.ke0)
        rear = -float(body.points(s)[0][:, 1].max())
        R, w = body.at(s)[1:3]
        x, v, n, arm = body.points(s)  # the target's force and moment about the centre at the row's state
        load = self._row_load(s, R, x, v, n)
        F, M = body.force_moment(arm, load.force)
        loaded, area = load.loaded, load.area
        return Snapshot(tip, tail, s.V, F, body.mass, en, loaded, self.dt, 0.0, area, rear,
                        omega=w.copy(), moment=M, momentum=s.L.copy(), impulse=self.angular_impulse,
                        centre=s.c.copy())

    def removal(self) -> Removal:
        w = self.wear
        length = (self.shape.length - (w.shortening if w is not None else 0.0)) * 1e3
        if w is None:
            return Removal(remaining_kg=self.body.mass, length_mm=length)
        return Removal(w.mass_lost, w.heat, 0, w.kinetic_removed, remaining_kg=self.body.mass, length_mm=length)

    def interrupt(self, name: str) -> None:
        raise Interrupted(f"{name} at step {self.step_count}, t = {self.t * 1e6:.3f} us: a rigid run keeps no "
                          "checkpoint (it takes seconds); `fepen run --resume DIR` runs it again")

    def summary_extra(self, loop_s: float) -> dict:
        return {"dt_s": self.dt, "time_split_s": {"mesh": self.setup_s, "time_loop": loop_s},
                "mass_kg": self.mass, "cells": self.cells, "load_points": len(self.pts["area0"])}


class Wear:
    """The nose wear of the rigid fidelity (docs/theory.md §14): the interface heat μ σ_n |v_t| summed over
    the load points with the RK4 weights of the step's four stages, and the mass η Q/h it melts, taken off
    the body after each step (fepen.laws.wear). With ``distribution = "nose"`` the load points of the nose
    zone (ahead of ``zone_end``) follow the nose's contraction along its axis (fepen.laws.wear.contract_points),
    so the worn nose's shape feeds back into the load and the tip recedes.

    Args:
        p: the wear parameters (fepen.runs.shot.WearParameters).
        points: the run's load points (its own copies: the nose writes into them), or None (mass only).
        zone_end: y_c, the end of the nose zone (m). radius_end: the body's radius there (m).
    """

    def __init__(self, p, points: dict | None = None, zone_end: float = 0.0, radius_end: float = 0.0):
        self.mu, self.efficiency, self.enthalpy, self.density = p.friction, p.efficiency, p.enthalpy, p.density
        self.stages: list[float] = []
        self.heat = self.mass_lost = self.kinetic_removed = 0.0
        self.contraction = 1.0
        self.points = points
        if points is not None:
            self.original = {k: points[k].copy() for k in ("X", "N", "area0", "R_meridian")}
            self.zone_end = zone_end
            self.zone0 = wear.zone_volume(points["X"], points["N"], points["area0"], zone_end, radius_end)
            if not self.zone0 > 0.0:  # a flat nose: nothing to shorten, the mass alone leaves
                self.points = None

    @property
    def shortening(self) -> float:
        """How much shorter the nose is (m)."""
        return (1.0 - self.contraction) * self.zone_end if self.points is not None else 0.0

    def stage(self, force, n, v) -> None:
        """Record one RK4 stage's heat rate (W)."""
        self.stages.append(wear.heat_rate(force, n, v, self.mu))

    def step(self, body, s, dt: float):
        """Add the step's heat (its four RK4 stages, the last recorded), take its melted mass off the body and
        contract the nose by its volume; the state after."""
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
        if self.points is not None:
            self._contract(body, wear.contraction_after(self.contraction, dm / self.density, self.zone0))
        return s

    def _contract(self, body, contraction: float) -> None:
        """Move the nose zone's load points to the contraction λ (in place: the body's arms and normals, the
        law's areas, angles and curvatures)."""
        if contraction == self.contraction:
            return
        self.contraction = contraction
        o, g = self.original, self.points
        X, N, A, sphi, Rm = wear.contract_points(o["X"], o["N"], o["area0"], o["R_meridian"], self.zone_end,
                                                 contraction)
        body.r0[:] = X - body.centre0
        body.N0[:] = N
        body._last = None  # the cached load points of the last state are the uncontracted nose's
        g["X"][:], g["N"][:], g["area0"][:], g["sin_phi0"][:], g["R_meridian"][:] = X, N, A, sphi, Rm


# ------------------------------------------------------------------------------------------------------------
# The compiled step: rigid_batch.c's rk4, the one RK4 step of the rigid run, single (RigidRun.step, through
# rigid_step) or batched (fepen.runs.batch, through rigid_batch)

#: the per-shot numbers the kernel reads, in its order: rigid_batch.h's S_ members and the numbers each holds
#: (checked against the header, member by member, when the kernel is loaded: fepen.native.shares)
_SHOT_LAYOUT = (
    ("S_MASS", ("mass",)), ("S_DT", ("dt",)), ("S_HARD_END", ("hard_end",)), ("S_THICKNESS", ("thickness",)),
    ("S_UNTIL_STOPPED", ("until_stopped",)), ("S_HISTORY", ("history_interval",)), ("S_CRATER", ("crater",)),
    ("S_CRATER_KD", ("crater_kd",)), ("S_CRATER_C", ("crater_c",)), ("S_KE0", ("ke0",)),
    ("S_STOP_ENERGY", ("stop_energy",)), ("S_TIP", ("tip_x", "tip_y", "tip_z")),
    ("S_TAIL", ("tail_x", "tail_y", "tail_z")), ("S_IINV", tuple(f"I_inv_{i}{j}" for i in range(3) for j in range(3))),
    ("S_TUNNEL", ("tunnel",)), ("S_SPACING", ("tunnel_spacing",)), ("S_XI_SH", ("shoulder_xi",)),
    ("S_A0", ("shoulder_radius",)), ("S_RESERVED", ("reserved",)),
    ("S_SHOULDER", ("shoulder_x", "shoulder_y", "shoulder_z")))
SHOT_NUMBERS = tuple(name for _, names in _SHOT_LAYOUT for name in names)
native.shares("rigid_batch", "S_", [(member, len(names)) for member, names in _SHOT_LAYOUT])
#: a shot's state as fepen.laws.rigid_body.RigidState.as_array lays it out (centre, quaternion, velocity, angular
#: momentum): rigid_batch.h's Y_ enum
native.shares("rigid_batch", "Y_", [("Y_CENTRE", 3), ("Y_QUAT", 4), ("Y_VELOCITY", 3), ("Y_MOMENTUM", 3)])
#: one RK4 step's numbers (rigid_step's out): rigid_batch.h's STEP_ enum
_STEP_LAYOUT = (("STEP_FORCE", 3), ("STEP_WORK", 1), ("STEP_ANGULAR", 3), ("STEP_LOADED", 1), ("STEP_AREA", 1))
#: where each of them starts in the step's numbers, by name
STEP = {m[5:].lower(): sum(w for _, w in _STEP_LAYOUT[:i]) for i, (m, _) in enumerate(_STEP_LAYOUT)}
STEP_COUNT = sum(w for _, w in _STEP_LAYOUT)
native.shares("rigid_batch", "STEP_", _STEP_LAYOUT)
_KERNEL: dict = {}


def kernel():
    """(the rigid_batch library, the addresses of rigid_kernel.c's rigid_points and force_moment, the Gauss rule
    of the law) when the C kernels build and FEPEN_KERNEL is not python (fepen.native), else None."""
    if "fn" not in _KERNEL:
        _KERNEL["fn"] = None
        body, lib = native.kernel("rigid_body"), native.kernel("rigid_batch")
        if body is None or lib is None:
            return None
        native.check_layouts("events")  # the outcome codes the batch returns
        vp = ctypes.c_void_p
        _KERNEL["fn"] = (lib, [ctypes.cast(f, vp).value for f in (body.rigid_points, body.force_moment)],
                         tg.crater_gauss())
    return _KERNEL["fn"]


def covers(run) -> bool:
    """Whether the compiled step (CompiledStep) can advance a RigidRun: the C kernels are built (FEPEN_KERNEL is not
    python or numpy), the shot has a target law and its target kind is one the batch takes (not layered)."""
    return kernel() is not None and run.shot.target.not_batched() is None


def point_arrays(run) -> list:
    """A run's per-point arrays as rigid_batch.c reads them: r0, N0, area, ell = sqrt(area), radius, Rm, sphi0."""
    g, body = run.pts, run.body
    return [np.ascontiguousarray(a, dtype=float) for a in (body.r0, body.N0, g["area0"], np.sqrt(g["area0"]),
                                                           g["radius"], g["R_meridian"], g["sin_phi0"])]


class CompiledStep:
    """One RigidRun's compiled RK4 step: rigid_batch.c's rigid_step, the batch's own step (RigidBody.rk4_step
    with RigidRun.force_fn, operation by operation: tests/unit/runs/test_rigid_step.py holds them together).

    Args:
        run: the RigidRun (covers(run)); its tunnel's buffer is advanced in place. With wear, each step also
            gives its four stages' point forces, velocities and normals (``stages``, (4, 3, k, 3)) for
            Wear.stage, and ``refresh()`` takes the body's new numbers after the wear.
    """

    def __init__(self, run):
        self.run = run
        self.lib, (self.points, self.moment), self.gauss = kernel()
        self.law = np.ascontiguousarray(tg._law_numbers(run.law), dtype=float)
        self.out = np.zeros(STEP_COUNT)
        k = len(run.body.r0)
        self.stages = np.zeros((4, 3, k, 3)) if run.wear is not None else None
        self.refresh()

    def refresh(self) -> None:
        """Read the run's body again: its points, mass, inertia, tip (after the wear changed them)."""
        run = self.run
        self.const = point_arrays(run)
        self.sp = np.ascontiguousarray(shot_numbers(run), dtype=float)
        self.xi = np.ascontiguousarray(run.pts["X"][:, 1], dtype=float)

    def __call__(self, y: np.ndarray) -> np.ndarray:
        """Advance the state y (Y_ layout, float64, contiguous) by one step in place.

        Returns:
            The step's numbers (STEP: the force at its start, the work, the angular impulse about O, the last
            stage's loaded points and area), a buffer the next call overwrites.
        """
        run = self.run
        t = run.tunnel
        check = self.lib.rigid_step(len(self.const[2]), *[a.ctypes.data for a in self.const], self.gauss.ctypes.data,
                                    len(self.gauss) // 2, self.points, self.moment, self.sp.ctypes.data,
                                    self.law.ctypes.data, y.ctypes.data, self.xi.ctypes.data,
                                    None if t is None else t.buf.ctypes.data, self.out.ctypes.data,
                                    None if self.stages is None else self.stages.ctypes.data)
        if check < 0:
            raise MemoryError("rigid_step: no memory for its scratch arrays")
        assert check == len(SHOT_NUMBERS) * 100 + len(self.out), "rigid_batch.c and fepen.runs.rigid disagree"
        return self.out

    def stop_back(self, run) -> float | None:
        """RigidRun.stop_back by rigid_batch.c's rigid_stop_back, the batch's: the run's state taken back along
        its last step to where V·a vanishes, when V·a ≤ 0.

        Returns:
            The fraction of the step kept, or None when the state stays."""
        prev, y, lam = run.prev.as_array(), run.state.as_array(), np.zeros(1)
        if not self.lib.rigid_stop_back(prev.ctypes.data, y.ctypes.data, lam.ctypes.data):
            return None
        run.state = RigidState.from_array(y)
        return float(lam[0])


def shot_numbers(run) -> list[float]:
    """A shot's numbers in the kernel's order (_SHOT_LAYOUT: rigid_batch.h's S_ enum), by member."""
    body, crater, law, t = run.body, run.crater, run.law, run.tunnel
    at = {"S_MASS": body.mass, "S_DT": run.dt, "S_HARD_END": run.end,
          "S_THICKNESS": -1.0 if law.thickness is None else law.thickness,
          "S_UNTIL_STOPPED": float(run.rules.until_stopped), "S_HISTORY": run.history.clock.interval,
          "S_CRATER": float(crater is not None), "S_CRATER_KD": crater.kd if crater is not None else 0.0,
          "S_CRATER_C": crater.c if crater is not None else 0.0, "S_KE0": run.ke0,
          "S_STOP_ENERGY": events.stop_fraction(body.mass, run.ke0), "S_TIP": run.tip_arm,
          "S_TAIL": run.tail_ref - body.centre0, "S_IINV": body.I_body_inv.ravel(),
          "S_TUNNEL": 0.0 if t is None else 1.0,
          "S_SPACING": 0.0 if t is None else t.buf[tunnel_zones.T_SPACING],
          "S_XI_SH": 0.0 if t is None else t.buf[tunnel_zones.T_XI_SH],
          "S_A0": 0.0 if t is None else t.buf[tunnel_zones.T_A0],
          "S_RESERVED": 0.0, "S_SHOULDER": run.shoulder_arm if t is not None else np.zeros(3)}
    out: list = []
    for member, names in _SHOT_LAYOUT:
        part = list(at[member]) if len(names) > 1 else [at[member]]
        assert len(part) == len(names), f"{member}: {len(part)} numbers, not {len(names)}"
        out.extend(part)
    return out
