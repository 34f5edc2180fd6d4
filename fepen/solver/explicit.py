"""Explicit central-difference dynamics of the meshed projectile on a dolfinx mesh: lumped mass, the
internal-force form, energies, failure checks (docs/theory.md §3, §6, §11)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from time import perf_counter
from typing import Protocol

import numpy as np
import ufl
from dolfinx import cpp as _cpp
from dolfinx import fem, la
from dolfinx import log as _log
from mpi4py import MPI

from fepen.errors import SimulationError
from fepen.laws import materials as M
from fepen.solver import ckernel, kernels

_log.set_log_level(_log.LogLevel.WARNING)  # quiet dolfinx wherever the solver is used


@dataclass
class Energies:
    """Global energies (J) at the current step."""

    kinetic: float
    internal_work: float
    external_work: float
    elastic: float
    plastic: float
    heat: float
    initial_kinetic: float
    interface_normal_work: float = 0.0
    friction: float = 0.0
    removed_kinetic: float = 0.0
    removed_internal: float = 0.0

    @property
    def balance_error(self) -> float:
        """Relative energy-balance error: KE + KE_removed + W_int − KE_0 − W_ext − W_interface, with
        W_interface the work of the shell–charge contact forces (normal work − friction dissipation;
        fepen.solver.shell_charge) and KE_removed the kinetic energy the removed material carried away when
        it was removed (erosion, surface recession; W_int keeps the work done on it)."""
        scale = max(self.initial_kinetic, abs(self.external_work), self.kinetic, 1e-300)
        w_if = self.interface_normal_work - self.friction
        return abs(self.kinetic + self.removed_kinetic + self.internal_work - self.initial_kinetic
                   - self.external_work - w_if) / scale


@dataclass
class StepTimes:
    """Wall seconds accumulated per part of the step (for benchmarks)."""

    kinematics: float = 0.0
    material: float = 0.0
    assembly: float = 0.0
    boundary: float = 0.0  #: the external load (the target's collectives included) and the interface
    update: float = 0.0
    target_comm: float = 0.0  #: of boundary: the target load's broadcasts, reductions and ghost sum


#: steps between two evaluations of the stable step
STEP_EVERY = 4
#: the eigenvalue step's gain over the altitude estimate is rounded down to a multiple of this (calibrate_step)
GAIN_QUANTUM = 0.005


class Load(Protocol):
    """An external load hooked into the solver (``solver.external``): the target or the rigid wall."""

    force: np.ndarray  #: total force on the body (N, world), all ranks
    contact_nodes: int  #: loaded points (nodes on a rigid wall), all ranks
    area: float  #: loaded area (m^2), all ranks

    def __call__(self, solver: ExplicitSolver) -> None:
        """Add the external nodal forces of the current positions into ``solver.fext`` (owned nodes)."""


class Interface(Protocol):
    """A constraint between two bodies hooked into the solver (``solver.interface``)."""

    def __call__(self, solver: ExplicitSolver) -> None:
        """Add the constraint forces of the coming step to ``solver.acc``; report their work
        (``solver.add_interface_work``)."""

    def summary(self) -> dict:
        """Largest gap, interpenetration and slip (mm), fractions of pairs open and sliding."""

    def nodal_gap_and_slip(self) -> dict:
        """Nodal fields for output: interface_gap_m, interface_slip_m."""


#: the solver's state between two steps (checkpoints): nodal and cell arrays, and scalars; the work sums
#: are each rank's own partial sums
STATE_ARRAYS = ("U", "Vel", "acc", "fint", "fext", "s", "eps_p", "temp", "sy0", "X", "mat", "_removed")
STATE_SCALARS = ("t", "step_count", "dt", "dt_prev", "dt0", "dt_min", "_w_int", "_w_ext", "_plastic", "_heat",
                 "ke0", "_w_if_n", "_w_if_t")


class ExplicitSolver:
    """Lumped-mass central differences on a dolfinx mesh of linear tetrahedra.

    Args:
        mesh: dolfinx mesh (reference configuration; it is never moved).
        cell_materials: Material per local cell (list of Materials and an int array of indices into it,
            over owned cells).
        safety: stable-step safety factor f in Δt = f min(h/c).
        nodal_pressure: averaged nodal pressure (True) or the plain tetrahedron (False).
        external: a Load (adds external nodal forces into ``solver.fext``), or None.
        kernel: the stress update: "C" (the C trial pass and the numba return), "numba" (the numba kernel
            alone, the reference), or None: C where it can be built (always numba for the plain element).

    ``interface``: an Interface set after construction (fepen.solver.shell_charge), called once a^n is
    known and Δt_{n+1/2} chosen, to add constraint forces of the coming step to ``acc``.
    """

    def __init__(self, mesh, materials: list[M.Material], cell_material: np.ndarray, safety: float = 0.8,
                 nodal_pressure: bool = True, external: Load | None = None, kernel: str | None = None):
        self.mesh = mesh
        self.comm = mesh.comm
        self.safety = safety
        self.nodal = nodal_pressure
        self.external = external
        V = fem.VectorFunctionSpace(mesh, ("CG", 1))
        Q = fem.TensorFunctionSpace(mesh, ("DG", 0))
        self.V, self.Q = V, Q
        imap = V.dofmap.index_map
        self.n_owned = imap.size_local
        self.n_nodes = imap.size_local + imap.num_ghosts
        n_cells = mesh.topology.index_map(mesh.topology.dim).size_local
        self.n_cells = n_cells
        self.dofs = np.ascontiguousarray(V.dofmap.list.array.reshape(-1, 4)[:n_cells]).astype(np.int64)
        self.X = V.tabulate_dof_coordinates()[: self.n_nodes].copy()
        self.X0 = self.X.copy()  # X moves only where a surface recedes (fepen.solver.recession)
        # the mesh geometry's node of each dof, so that a moved reference reaches the assembled form
        gdofs = mesh.geometry.dofmap.array.reshape(-1, 4)
        self._geometry_node = np.zeros(self.n_nodes, dtype=np.int64)
        self._geometry_node[V.dofmap.list.array.reshape(-1, 4).ravel()] = gdofs.ravel()
        self.geometry_x = mesh.geometry.x
        assert np.allclose(self.geometry_x[self._geometry_node, :3], self.X)
        self.X[:] = self.geometry_x[self._geometry_node, :3]  # the mesh's own numbers (tabulated ones may
        self.X0[:] = self.X  # differ in the last bit), so that writing X back into the geometry changes nothing
        self.grad0, self.vol0, self.orient = kernels.reference_gradients(self.X, self.dofs)
        self.materials = materials
        self.params = np.stack([m.params for m in materials])
        self.mat = np.ascontiguousarray(cell_material, dtype=np.int64)  # −1: an eroded cell
        assert len(self.mat) == n_cells
        self.cell_dt = np.full(n_cells, np.inf)  # each cell's altitude / wave speed, every STEP_EVERY steps
        #: this rank's removed mass (owned nodes), kinetic energy carried away, stored elastic energy of
        #: the removed cells (J); see remove_cells and change_reference
        self._removed = np.zeros(3)
        self.speed = np.array([float(np.sqrt((m.bulk_modulus + 4.0 * m.shear_modulus / 3.0) / m.density))
                               for m in materials])
        self.bulk = np.array([m.bulk_modulus for m in materials])
        nm = len(materials)

        self._nodal_arrays(V, imap, nm)
        self._lumped_mass(imap, nm)
        self.initial_mass = self.total_mass

        # cell state
        self._sT = np.zeros((6, n_cells))  # component-major for the C trial pass
        self.s = self._sT.T  # (n_cells, 6) view: xx, yy, zz, xy, yz, xz
        self.eps_p = np.zeros(n_cells)
        self.temp = np.array([m.params[M.TROOM] for m in materials])[self.mat].astype(float)
        self._totals = np.zeros(4)
        self.sy0 = np.empty(n_cells)
        kernels.static_flow_stress(self.mat, self.params, self.eps_p, self.temp, self.sy0)

        self._internal_force_form(V, Q)

        self._stress_kernel(kernel)

        # time and energy
        self.step_gain = 1.0  # stable step = safety * step_gain * min(h/c); see calibrate_step
        self.t = 0.0
        self.step_count = 0
        self.dt_prev = 0.0
        self.dt = self.stable_step()
        self.dt0 = self.dt
        self.dt_min = self.dt
        self._w_int = 0.0
        self._w_ext = 0.0
        self._plastic = 0.0
        self._heat = 0.0
        self._w_if_n = 0.0  # work of the interface's normal and tangential forces (fepen.solver.shell_charge)
        self._w_if_t = 0.0
        self.interface = None
        # called with the current positions when a live cell inverts (collective): True if it eroded the
        # inverted cells (fepen.solver.erosion), False or None to stop the run
        self.on_inverted = None
        self.ke0 = None
        self.times = StepTimes()

    def _nodal_arrays(self, V, imap, nm: int) -> None:
        """Nodal vectors (ghosted, block size 3) and nodal scalars per material; the reference nodal volumes."""
        self.u = fem.Function(V, name="displacement")
        self.v = fem.Function(V, name="velocity")
        self.fint_fn = fem.Function(V)
        self.U, self.Vel = self.u.x.array.reshape(-1, 3), self.v.x.array.reshape(-1, 3)
        self.a_fn = fem.Function(V, name="acceleration")
        self.acc = self.a_fn.x.array.reshape(-1, 3)
        self.fint = self.fint_fn.x.array.reshape(-1, 3)
        self.fint_old = np.zeros_like(self.fint)
        self.fixed = None  # (n_nodes, 3) bool: velocity components held at zero (symmetry planes)
        self.fext = np.zeros((self.n_nodes, 3))
        self.fext_old = np.zeros_like(self.fext)
        self._nvol = la.vector(imap, bs=nm)
        self._nvol0 = la.vector(imap, bs=nm)
        self.nodal_vol = self._nvol.array.reshape(-1, nm)
        self.nodal_vol0 = self._nvol0.array.reshape(-1, nm)
        self.nodal_p = np.zeros_like(self.nodal_vol0)
        kernels.volumes_and_step(self.X, self.dofs, self.orient, self.vol0, self.mat, self.speed, self.nodal_vol0)
        self._ghost_sum(self._nvol0)

    def _lumped_mass(self, imap, nm: int, orphans_allowed: bool = False) -> None:
        """Lumped mass: ρ_e V0_e / 4 to each node, per material (the bodies' masses, for their mass-averaged
        accelerations) and in all; eroded cells give none. ``_mass_div`` is the mass the accelerations are
        divided by: the mass itself, or after an erosion a copy with 1 on the nodes left without a cell
        (their force is zero, their velocity held at zero)."""
        materials = self.materials
        rho = np.array([m.density for m in materials])[self.mat]
        mvec = la.vector(imap, bs=nm)
        arr = mvec.array.reshape(-1, nm)
        for k in range(nm):
            sel = self.mat == k
            arr[:, k] += np.bincount(self.dofs[sel].ravel(), weights=np.repeat(0.25 * rho[sel] * self.vol0[sel], 4),
                                     minlength=len(arr))
        self._ghost_sum(mvec)
        self.mass_by_material = arr[: self.n_nodes].copy()
        self.mass = self.mass_by_material.sum(axis=1)
        self.body_mass = self.comm.allreduce(self.mass_by_material[: self.n_owned].sum(axis=0), op=MPI.SUM)
        self.orphans = self.mass <= 0.0
        if not orphans_allowed and np.any(self.orphans[: self.n_owned]):
            raise SimulationError("a node has no mass (an orphan node in the mesh)")
        self._mass_div = self.mass
        if np.any(self.orphans):
            self._mass_div = np.where(self.orphans, 1.0, self.mass)
        self.total_mass = self.comm.allreduce(float(self.mass[: self.n_owned].sum()), op=MPI.SUM)

    def _internal_force_form(self, V, Q) -> None:
        """The internal-force form, with P packed once and rewritten in place each step."""
        n_cells = self.n_cells
        self.P = fem.Function(Q, name="P")
        w = ufl.TestFunction(V)
        self.form = fem.form(ufl.inner(self.P, ufl.grad(w)) * ufl.dx)
        self._consts = _cpp.fem.pack_constants(self.form)
        self._coeffs = _cpp.fem.pack_coefficients(self.form)
        key = next(iter(self._coeffs))
        self.P_packed = self._coeffs[key]
        assert self.P_packed.shape[1] == 9 and self.P_packed.shape[0] >= n_cells

    def _stress_kernel(self, kernel: str | None) -> None:
        """The stress update: the C trial pass + numba radial return, or the numba kernel alone (the
        reference; also the plain element's)."""
        materials = self.materials
        self.x = np.empty((self.n_nodes, 3))  # current positions X + U of the last force evaluation
        self._flag = np.zeros(1)
        self._trial = None
        if kernel not in (None, "C", "numba"):
            raise ValueError(f"kernel must be 'C', 'numba' or None, not {kernel!r}")
        if kernel == "C" and (not self.nodal or ckernel.library() is None):
            raise RuntimeError(f"the C kernel is not available: {ckernel.why_not() or 'plain element'}")
        if self.nodal and kernel != "numba" and ckernel.library() is not None:
            self.G_m = np.array([m.shear_modulus for m in materials])
            self._trial = ckernel.TrialPass(self.x, self.Vel, self.X, self.dofs, self.mat,
                                            6.0 * self.vol0 * self.orient, self.G_m, self.nodal_p, self._sT,
                                            self.sy0, self.P_packed)
        self.kernel = "C" if self._trial is not None else "numba"

    # ------------------------------------------------------------------------------------------------
    def _ghost_sum(self, vec) -> None:
        vec.scatter_reverse(la.ScatterMode.add)
        vec.scatter_forward()

    def positions(self) -> np.ndarray:
        """Current node positions (n_nodes, 3), ghosts included."""
        return self.X + self.U

    def stable_step(self) -> float:
        """Safety x min over cells of (shortest altitude / dilatational speed), current mesh, all ranks."""
        # a scratch array: nodal_vol must keep the ghost-summed volumes of the last step (energies use them)
        _, _, h_c, _ = kernels.volumes_and_step(self.positions(), self.dofs, self.orient, self.vol0,
                                                       self.mat, self.speed, np.empty_like(self.nodal_vol))
        return self.safety * self.step_gain * self.comm.allreduce(h_c, op=MPI.MIN)

    def calibrate_step(self, iterations: int = 400, rtol: float = 1e-5) -> tuple[float, float]:
        """The critical step 2/ω_max of the undeformed, unstressed body, by power iteration on M⁻¹K.

        K d is the internal force of a tiny displacement ε d from the reference state (the solver's own
        element, nodal pressure included), so ω_max is that of the discrete system actually integrated.
        Sets ``step_gain`` = (2/ω_max) / min(h/c) (rounded down to a multiple of GAIN_QUANTUM), by which the
        altitude estimate is multiplied from then
        on (it keeps tracking the deformed mesh). Call before set_initial: the state is zeroed after.
        The start vector is a smooth-free oscillating field of the reference positions, the same on any
        partition. The Rayleigh quotient approaches ω_max² from below, so the safety factor keeps a margin.

        Returns:
            (critical step of the undeformed body (s), step_gain).
        """
        n = self.n_owned
        X = self.X
        L = float(np.ptp(X, axis=0).max())
        d = np.stack([np.sin(X @ np.array(w) / L * 977.0 + k) for k, w in
                      enumerate(([1.0, 0.31, 0.57], [0.23, 1.0, 0.71], [0.61, 0.43, 1.0]))], axis=1)
        external, self.external = self.external, None
        eps = 1e-9 * L
        lam = lam_prev = 0.0
        for it in range(iterations):
            if self.fixed is not None:
                d[self.fixed] = 0.0
            norm = np.sqrt(self.comm.allreduce(float(np.sum(self.mass[:n, None] * d[:n] ** 2)), op=MPI.SUM))
            d /= norm
            self.U[:] = eps * d
            self.Vel[:] = eps * d
            self.s[:] = 0.0
            self._forces(1.0)  # increment v dt = eps d from the reference: f_int = K eps d
            Kd = self.fint[:n] / eps
            lam = self.comm.allreduce(float(np.sum(d[:n] * Kd)), op=MPI.SUM)
            self.Vel[:n] = Kd / self.mass[:n, None]
            self.v.x.scatter_forward()
            d = self.Vel.copy()
            if it > 30 and abs(lam - lam_prev) < rtol * lam:
                break
            lam_prev = lam
        self.external = external
        for a in (self.U, self.Vel, self.s, self.fint, self.fext, self.acc):
            a[:] = 0.0
        self.eps_p[:] = 0.0
        _, _, h_c, _ = kernels.volumes_and_step(self.positions(), self.dofs, self.orient, self.vol0, self.mat,
                                                   self.speed, np.empty_like(self.nodal_vol))
        h_c = self.comm.allreduce(h_c, op=MPI.MIN)
        dt_crit = 2.0 / np.sqrt(lam)
        # rounded down to a multiple of GAIN_QUANTUM: the Rayleigh quotient of a 1e-9 L displacement carries
        # round-off of ~1e-6 that depends on the partition; rounded, the step is the same on any number of
        # ranks (unless the gain falls within ~1e-6 of a multiple), and at most GAIN_QUANTUM / 2 smaller
        self.step_gain = max(math.floor(dt_crit / h_c / GAIN_QUANTUM) * GAIN_QUANTUM, GAIN_QUANTUM)
        self.dt = self.dt0 = self.dt_min = self.stable_step()
        return dt_crit, self.step_gain

    def set_initial(self, displacement=None, velocity=None) -> None:
        """Initial displacement (a rigid placement of the stress-free body) and velocity, as callables of
        the reference positions (n, 3) -> (n, 3), or arrays; then the initial acceleration."""
        if displacement is not None:
            self.U[:] = displacement(self.X) if callable(displacement) else displacement
        if velocity is not None:
            self.Vel[:] = velocity(self.X) if callable(velocity) else velocity
        if self.fixed is not None:
            self.Vel[self.fixed] = 0.0
        self._forces(0.0)
        n = self.n_owned
        self.acc[:n] = (self.fext[:n] - self.fint[:n]) / self._mass_div[:n, None]
        if self.fixed is not None:
            self.acc[self.fixed] = 0.0
        self.a_fn.x.scatter_forward()
        self.ke0 = self.kinetic_energy(self.Vel)
        self.dt = self.stable_step()
        self.dt0 = self.dt_min = self.dt
        if self.interface is not None:
            self.interface(self)

    def kinetic_energy(self, vel: np.ndarray) -> float:
        """Σ ½ m v² over owned nodes, all ranks."""
        local = 0.5 * float(np.sum(self.mass[: self.n_owned, None] * vel[: self.n_owned] ** 2))
        return self.comm.allreduce(local, op=MPI.SUM)

    def velocity_at_step(self) -> np.ndarray:
        """v^n ≈ v^{n-1/2} + Δt/2 a^n (the velocity at the integer step, for energies and output)."""
        return self.Vel + 0.5 * self.dt_prev * self.acc

    # ------------------------------------------------------------------------------------------------
    def _forces(self, dt: float) -> float:
        """Internal and external forces at the current positions; returns the new stable-step estimate
        (h/c over the current mesh, before the safety factor) on this rank."""
        t0 = perf_counter()
        x = np.add(self.X, self.U, out=self.x)
        with_step = self.step_count % STEP_EVERY == 0
        jmin, worst, h_c, self._step_cell = kernels.volumes_and_step(
            x, self.dofs, self.orient, self.vol0, self.mat, self.speed, self.nodal_vol, with_step, self.cell_dt)
        if self._any_inverted(jmin):
            if self.on_inverted is None or not self.on_inverted(x):
                self._raise_inverted(x, jmin, worst)
            jmin, worst, h_c, self._step_cell = kernels.volumes_and_step(  # the inverted cells eroded
                x, self.dofs, self.orient, self.vol0, self.mat, self.speed, self.nodal_vol, with_step, self.cell_dt)
            if self._any_inverted(jmin):
                self._raise_inverted(x, jmin, worst)
        if self.nodal:
            self._ghost_sum(self._nvol)
        t1 = perf_counter()
        if self.nodal:
            kernels.nodal_pressures(self.nodal_vol, self.nodal_vol0, self.bulk, self.nodal_p)
        self._stress_update(x, dt)
        t2 = perf_counter()
        self.assemble_internal_force()
        t3 = perf_counter()
        self.fext[:] = 0.0
        if self.external is not None:
            self.external(self)
        t4 = perf_counter()
        tm = self.times
        tm.kinematics += t1 - t0
        tm.material += t2 - t1
        tm.assembly += t3 - t2
        tm.boundary += t4 - t3
        return h_c

    def _stress_update(self, x: np.ndarray, dt: float) -> None:
        """Every cell's stress over the step and P into the packed coefficient; plastic work and heat."""
        if self._trial is not None:
            yielding = self._trial(dt)
            kernels.plastic_pass(x, dt, self.dofs, self.grad0, self.vol0, self.mat, self.params, self.s,
                                 self.eps_p, self.temp, self.sy0, self.P_packed, yielding, self._totals)
        else:
            kernels.stress_update(x, self.Vel, dt, self.dofs, self.grad0, self.vol0, self.mat, self.params,
                                  self.nodal_p, self.nodal, self.s, self.eps_p, self.temp, self.sy0,
                                  self.P_packed, self._totals)
        self._plastic += self._totals[0]
        self._heat += self._totals[1]

    def assemble_internal_force(self) -> None:
        """f_int = ∫ P : ∇_X w dX from the packed P (ghost contributions summed to their owners), in one pass
        over the owned cells with their reference gradients (kernels.internal_force: the compiled form's
        vector to round-off, at a fraction of dolfinx's cost, which rebuilds each cell's geometry)."""
        self.fint[:] = 0.0
        kernels.internal_force(self.P_packed, self.dofs, self.grad0, self.vol0, self.fint)
        self.fint_fn.x.scatter_reverse(la.ScatterMode.add)

    def assemble_form(self, out: np.ndarray) -> None:
        """The same internal force through dolfinx: the compiled form assembled into ``out`` (the flat array
        of a V function, zeroed by the caller), no ghost sum (the reference, and the benchmarks' floor)."""
        _cpp.fem.assemble_vector(out, self.form, self._consts, self._coeffs)

    def _any_inverted(self, jmin: float) -> bool:
        """Whether a live cell on any rank is inverted (or NaN); every rank gets the same answer."""
        bad = not (jmin > 0.0)
        if self.comm.size > 1:  # every rank must stop together (and rank 0 must be able to say why)
            self._flag[0] = 1.0 if bad else 0.0
            self.comm.Allreduce(MPI.IN_PLACE, self._flag, op=MPI.MAX)
            bad = self._flag[0] > 0.0
        return bad

    def _raise_inverted(self, x: np.ndarray, jmin: float, worst: int) -> None:
        """SimulationError naming the inverted element, where and when (collective)."""
        local = (0 if not (jmin > 0.0) else 1, self.comm.rank)
        _, owner = self.comm.allreduce(local, op=MPI.MIN)
        info = None
        if self.comm.rank == owner:
            c = x[self.dofs[worst]].mean(axis=0)
            c0 = self.X[self.dofs[worst]].mean(axis=0)
            info = (self.mesh.topology.index_map(3).local_range[0] + worst, jmin, c, c0)
        gidx, jw, c, c0 = self.comm.bcast(info, root=owner)
        raise SimulationError(
            f"element {gidx} inverted (J = {jw:.3g}) at step {self.step_count}, t = {self.t * 1e6:.3f} us, "
            f"centre ({c[0] * 1e3:.2f}, {c[1] * 1e3:.2f}, {c[2] * 1e3:.2f}) mm; in the undeformed projectile "
            f"{c0[1] * 1e3:.1f} mm behind the nose tip, radius {np.hypot(c0[0], c0[2]) * 1e3:.1f} mm")

    def step(self) -> None:
        """Advance one central-difference step."""
        dt = self.dt
        t0 = perf_counter()
        self.Vel += (0.5 * (self.dt_prev + dt)) * self.acc
        du = dt * self.Vel
        self.U += du
        self.fint_old[:] = self.fint
        self.fext_old[:] = self.fext
        self.times.update += perf_counter() - t0
        h_c = self._forces(dt)
        t0 = perf_counter()
        n = self.n_owned
        f = self.fext[:n] - self.fint[:n]
        self.acc[:n] = f / self._mass_div[:n, None]
        if self.fixed is not None:
            self.acc[self.fixed] = 0.0
        self.a_fn.x.scatter_forward()
        self._w_int += 0.5 * float(np.sum(du[:n] * (self.fint_old[:n] + self.fint[:n])))
        self._w_ext += 0.5 * float(np.sum(du[:n] * (self.fext_old[:n] + self.fext[:n])))
        self.t += dt
        self.step_count += 1
        self.dt_prev = dt
        self.times.update += perf_counter() - t0
        if self.step_count % STEP_EVERY == 1:
            self._new_step(h_c)
        if self.interface is not None:
            t0 = perf_counter()
            self.interface(self)
            self.times.boundary += perf_counter() - t0

    def _new_step(self, h_c: float) -> None:
        """The next Δt from this rank's h/c (all ranks agree), or SimulationError if it collapsed."""
        new = self.safety * self.step_gain * self.comm.allreduce(h_c, op=MPI.MIN)
        if not (new > 1e-3 * self.dt0):
            _, owner = self.comm.allreduce((h_c, self.comm.rank), op=MPI.MIN)
            c = self.X[self.dofs[self._step_cell]].mean(axis=0) if self.comm.rank == owner else None
            c = self.comm.bcast(c, root=owner)
            raise SimulationError(
                f"stable step collapsed to {new:.3g} s (initial {self.dt0:.3g} s) at step {self.step_count}, "
                f"t = {self.t * 1e6:.3f} us: an element is nearly flat, {c[1] * 1e3:.1f} mm behind the nose "
                f"tip (radius {np.hypot(c[0], c[2]) * 1e3:.1f} mm) in the undeformed projectile")
        self.dt = new
        self.dt_min = min(self.dt_min, new)

    # ------------------------------------------------------------------------------------------------
    def remove_cells(self, cells: np.ndarray) -> None:
        """Erode owned cells (collective; ``cells`` may be empty on some ranks): their stress and force go,
        their mass leaves their nodes, and a node left without a live cell stops (docs/theory.md §15).

        The removed mass, the kinetic energy it carried (½ Δm_a |v_a|² at the integer step) and the elastic
        energy stored in the removed cells are added to this rank's ``_removed`` sums.
        """
        cells = np.asarray(cells, dtype=np.int64)
        if len(cells):
            J = np.empty(self.n_cells)
            kernels.cell_jacobians(self.positions(), self.dofs, self.orient, self.vol0, self.mat, J)
            G = np.array([m.shear_modulus for m in self.materials])[self.mat[cells]]
            self._removed[2] += kernels.deviatoric_energy(self.s[cells], J[cells], self.vol0[cells], G)
            self.mat[cells] = -1
            self.s[cells] = 0.0
            self.P_packed[cells] = 0.0
            self.sy0[cells] = np.inf
            self.cell_dt[cells] = np.inf
        self._new_reference(np.zeros(0, dtype=np.int64))

    def change_reference(self, dX: np.ndarray) -> None:
        """Move the reference positions of nodes by dX (n_nodes, 3), ghosts included and equal on every rank
        that holds a node: material removed from a receding surface (fepen.solver.recession). The
        displacement is kept, so the current positions move with the reference ones; the cells touched get
        their new reference gradients and volumes, the nodes their new masses (collective)."""
        moved = np.any(dX != 0.0, axis=1)
        cells = np.flatnonzero(moved[self.dofs].any(axis=1))
        self.X += dX
        self._new_reference(cells)

    def _new_reference(self, cells: np.ndarray) -> None:
        """Recompute the reference data of ``cells`` and every nodal mass and volume (collective)."""
        if len(cells):
            g, v, o = kernels.reference_gradients(self.X, self.dofs[cells])
            self.grad0[cells], self.vol0[cells], self.orient[cells] = g, v, o
            if self.geometry_x is not None:
                self.geometry_x[self._geometry_node, :3] = self.X
        if self._trial is not None:
            self._trial.refresh(self.mat, 6.0 * self.vol0 * self.orient)
        old = self.mass.copy()
        v = self.velocity_at_step()
        kernels.volumes_and_step(self.X, self.dofs, self.orient, self.vol0, self.mat, self.speed,
                                 self.nodal_vol0, False)
        self._ghost_sum(self._nvol0)
        nm = len(self.materials)
        self._lumped_mass(self.V.dofmap.index_map, nm, orphans_allowed=True)
        n = self.n_owned
        dm = old[:n] - self.mass[:n]
        self._removed[0] += float(dm.sum())
        self._removed[1] += 0.5 * float(np.sum(dm[:, None] * v[:n] ** 2))
        if np.any(self.orphans):
            for a in (self.Vel, self.acc):
                a[self.orphans] = 0.0

    @property
    def removed_mass(self) -> float:
        """Mass removed so far (kg), all ranks."""
        return self.comm.allreduce(float(self._removed[0]), op=MPI.SUM)

    def state(self) -> dict[str, np.ndarray]:
        """This rank's state between two steps: STATE_ARRAYS, the reference positions ``X`` and the
        STATE_SCALARS packed in ``scalars`` (for checkpoints; the arrays are views, copy to keep)."""
        out = {k: getattr(self, k) for k in STATE_ARRAYS}
        out["X0"] = self.X0
        out["scalars"] = np.array([float(getattr(self, k)) for k in STATE_SCALARS])
        return out

    def restore(self, state) -> None:
        """Put back what state() returned (any mapping of the same names), in place: the compiled kernels
        hold these arrays' addresses. The mesh must be the same, node for node (ValueError if not)."""
        X0 = state["X0"] if "X0" in state else state["X"]
        if not (X0.shape == self.X0.shape and np.array_equal(X0, self.X0)):
            raise ValueError("the state was taken on another mesh or partition")
        for k in STATE_ARRAYS:
            if k in state:
                np.copyto(getattr(self, k), state[k])
        for k, v in zip(STATE_SCALARS, state["scalars"]):
            setattr(self, k, int(v) if k == "step_count" else float(v))
        changed = bool(np.any(self.mat < 0)) or not np.array_equal(self.X, self.X0)  # eroded or receded
        if self.comm.allreduce(changed, op=MPI.LOR):  # rebuild (collective)
            removed = self._removed.copy()
            self._new_reference(np.arange(self.n_cells))
            self.P_packed[: self.n_cells][self.mat < 0] = 0.0
            self._removed[:] = removed

    def add_interface_work(self, normal: float, tangential: float) -> None:
        """Add this rank's share of the interface forces' work over the step (J)."""
        self._w_if_n += normal
        self._w_if_t += tangential

    def momentum_velocity(self) -> np.ndarray:
        """Velocity of the centre of mass (m/s), all ranks."""
        n = self.n_owned
        p = np.sum(self.mass[:n, None] * self.velocity_at_step()[:n], axis=0)
        return self.comm.allreduce(p, op=MPI.SUM) / self.total_mass

    def body_accelerations(self, axis: np.ndarray) -> np.ndarray:
        """Mass-averaged acceleration of each material's body along the axis (m/s^2), all ranks:
        Σ_a m_a^(body) a_a · axis / m_body, with m_a^(body) the lumped mass node a takes from that body's
        cells (interface nodes share theirs)."""
        n = self.n_owned
        along = self.acc[:n] @ axis
        local = np.array([float(self.mass_by_material[:n, k] @ along) for k in range(len(self.materials))])
        return self.comm.allreduce(local, op=MPI.SUM) / self.body_mass

    def max_peeq(self) -> float:
        """The largest equivalent plastic strain, all ranks."""
        return self.comm.allreduce(float(self.live_peeq().max()) if self.n_cells else 0.0, op=MPI.MAX)

    def live_peeq(self) -> np.ndarray:
        """The owned cells' equivalent plastic strain, 0 on eroded cells."""
        return self.eps_p if self.mat.min(initial=0) >= 0 else np.where(self.mat >= 0, self.eps_p, 0.0)

    def max_peeq_where(self) -> tuple[float, np.ndarray]:
        """The largest equivalent plastic strain and its cell's centre in the reference body, all ranks."""
        ep = self.live_peeq()
        local = (float(ep.max()), self.comm.rank, int(np.argmax(ep))) if self.n_cells else (-1.0, 0, -1)
        peeq, owner, cell = self.comm.allreduce(local, op=MPI.MAX)
        where = self.X[self.dofs[cell]].mean(axis=0) if self.comm.rank == owner else None
        return peeq, self.comm.bcast(where, root=owner)

    def von_mises(self) -> np.ndarray:
        """Equivalent (von Mises) stress of the owned cells (Pa)."""
        sd = self.s
        return np.sqrt(1.5 * (sd[:, 0] ** 2 + sd[:, 1] ** 2 + sd[:, 2] ** 2
                              + 2 * (sd[:, 3] ** 2 + sd[:, 4] ** 2 + sd[:, 5] ** 2)))

    def axial_stress(self, axis: np.ndarray) -> np.ndarray:
        """Normal Cauchy stress along the axis of the owned cells (Pa): a·s·a plus the cells' mean stress."""
        sd = self.s
        pm = self.nodal_p[self.dofs, np.maximum(self.mat, 0)[:, None]].mean(axis=1) * (self.mat >= 0) \
            if self.nodal else 0.0
        ax, ay, az = axis
        return (sd[:, 0] * ax * ax + sd[:, 1] * ay * ay + sd[:, 2] * az * az
                + 2 * (sd[:, 3] * ax * ay + sd[:, 4] * ay * az + sd[:, 5] * ax * az)) + pm

    # ------------------------------------------------------------------------------------------------
    def energies(self) -> Energies:
        """Global energies at the current step."""
        c = self.comm
        ke = self.kinetic_energy(self.velocity_at_step())
        vol = kernels.volumetric_energy(self.nodal_vol, self.nodal_vol0, self.bulk, self.n_owned)
        if not self.nodal:
            vol = self._element_volumetric_energy()
        dev = self._deviatoric_energy()
        sums = c.allreduce(np.array([self._w_int, self._w_ext, vol + dev, self._plastic, self._heat,
                                     self._w_if_n, self._w_if_t, self._removed[1], self._removed[2]]), op=MPI.SUM)
        return Energies(ke, sums[0], sums[1], sums[2], sums[3], sums[4], self.ke0 or 0.0, sums[5], -sums[6],
                        sums[7], sums[8])

    def _cell_J(self) -> np.ndarray:
        J = np.empty(self.n_cells)
        kernels.cell_jacobians(self.positions(), self.dofs, self.orient, self.vol0, self.mat, J)
        return J

    def _deviatoric_energy(self) -> float:
        G = np.array([m.shear_modulus for m in self.materials])[self.mat]
        return kernels.deviatoric_energy(self.s, self._cell_J(), self.vol0, G)

    def _element_volumetric_energy(self) -> float:
        lj = np.log(self._cell_J())
        return float(np.sum(self.vol0 * 0.5 * self.bulk[self.mat] * lj * lj))

    # ------------------------------------------------------------------------------------------------
    def node_at(self, point) -> tuple[int, int]:
        """(owner rank, local index) of the owned node at a point of the initial reference body (exact match),
        or (-1, -1)."""
        d = np.linalg.norm(self.X0[: self.n_owned] - np.asarray(point), axis=1)
        local = int(np.argmin(d)) if len(d) else -1
        mine = local >= 0 and d[local] < 1e-12
        ranks = self.comm.allgather(self.comm.rank if mine else -1)
        owner = max(ranks)
        return owner, (local if self.comm.rank == owner else -1)

    def node_values(self, handles, array: np.ndarray) -> np.ndarray:
        """The (3,) values of a nodal array at several nodes located with node_at, as (k, 3) on every rank, in
        one reduction (each owner's value against −inf elsewhere: bit for bit the owner's)."""
        buf = np.full((len(handles), 3), -np.inf)
        for k, (owner, local) in enumerate(handles):
            if self.comm.rank == owner:
                buf[k] = array[local]
        if self.comm.size > 1:
            self.comm.Allreduce(MPI.IN_PLACE, buf, op=MPI.MAX)
        return buf

    def node_value(self, owner_local: tuple[int, int], array: np.ndarray) -> np.ndarray:
        """The (3,) value of a nodal array at a node located with node_at, on every rank."""
        owner, local = owner_local
        val = array[local].copy() if self.comm.rank == owner else None
        return self.comm.bcast(val, root=owner)
