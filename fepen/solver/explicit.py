"""Explicit central-difference dynamics of the meshed projectile on a dolfinx mesh: lumped mass, the
internal-force form, energies, failure checks (docs/theory.md §3, §6, §11)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from time import perf_counter
from typing import Protocol

import numpy as np
from mpi4py import MPI

from fepen import dolfinx_api as dx
from fepen.errors import SimulationError
from fepen.laws import materials as M
from fepen.solver import assembly, ckernel, failures, kernels, reference, time_step, traffic
from fepen.solver import state as st

dx.quiet()  # quiet dolfinx wherever the solver is used


@dataclass
class StepTimes:
    """Wall seconds accumulated per part of the step (for benchmarks)."""

    kinematics: float = 0.0
    material: float = 0.0
    assembly: float = 0.0
    boundary: float = 0.0  #: the external load (the target's collectives included) and the interface
    update: float = 0.0
    target_comm: float = 0.0  #: of boundary: the target load's broadcasts, reductions and ghost sum

    def add(self, t0: float, t1: float, t2: float, t3: float, t4: float) -> None:
        """Add a force evaluation's parts: kinematics t0–t1, material t1–t2, assembly t2–t3, boundary t3–t4."""
        self.kinematics += t1 - t0
        self.material += t2 - t1
        self.assembly += t3 - t2
        self.boundary += t4 - t3


#: steps between two evaluations of the stable step
STEP_EVERY = 4


class Load(Protocol):
    """An external load hooked into the solver (``solver.external``): the target or the rigid wall."""

    force: np.ndarray  #: total force on the body (N, world), all ranks
    contact_nodes: int  #: loaded points (nodes on a rigid wall), all ranks
    area: float  #: loaded area (m^2), all ranks

    def __call__(self, solver: ExplicitSolver, dt: float) -> None:
        """Add the external nodal forces of the current positions into ``solver.fext`` (owned nodes); ``dt``:
        the step they act over (``solver.dt``; what a load accumulates in time, the wear heat, takes it)."""


class Interface(Protocol):
    """A constraint between two bodies hooked into the solver (``solver.interface``)."""

    def __call__(self, solver: ExplicitSolver) -> None:
        """Add the constraint forces of the coming step to ``solver.acc``; report their work
        (into ``solver.sums``: interface_normal, interface_tangential)."""

    def summary(self) -> dict:
        """Largest gap, interpenetration and slip (mm), fractions of pairs open and sliding."""

    def nodal_gap_and_slip(self) -> dict:
        """Nodal fields for output: interface_gap_m, interface_slip_m."""


#: the solver's state between two steps (checkpoints): nodal and cell arrays, and scalars; the work sums
#: are each rank's own partial sums
STATE_ARRAYS = {"U": "U", "Vel": "Vel", "acc": "acc", "fint": "node.fint", "fext": "fext", "s": "s",
                "eps_p": "eps_p", "temp": "temp", "sy0": "cell.sy0", "X": "X", "mat": "mat",
                "_removed": "sums.removed", "_work": "sums.work"}
STATE_SCALARS = {"t": "t", "step_count": "step_count", "dt": "dt", "dt_prev": "dt_prev", "dt0": "clock.dt0",
                 "dt_min": "clock.dt_min", "_plastic": "sums.plastic", "_heat": "sums.heat", "ke0": "sums.ke0",
                 "_w_if_n": "sums.interface_normal", "_w_if_t": "sums.interface_tangential",
                 "dt_stable": "clock.dt_stable", "_land_at": "clock.land_at"}


class ExplicitSolver:
    """Lumped-mass central differences on a dolfinx mesh of linear tetrahedra.

    Args:
        mesh: dolfinx mesh (reference configuration; it is never moved).
        cell_materials: Material per local cell (list of Materials and an int array of indices into it,
            over owned cells).
        safety: stable-step safety factor f in Δt = f min(h/c).
        nodal_pressure: averaged nodal pressure (True) or the plain tetrahedron (False).
        external: a Load (adds external nodal forces into ``solver.fext``), or None.
        kernel: the step's kernels: "C" (the C passes, fepen/solver/cell_kernel.c: kinematics, one fused
            stress-return-force pass, node update), "numba" (the numba kernels, the reference), or None: C
            where it can be built (always numba for the plain element). The C passes do not write
            ``P_packed`` (the form's coefficient; only the numba path and assemble_internal_force use it).

    ``interface``: an Interface set after construction (fepen.solver.shell_charge), called once a^n is
    known and Δt_{n+1/2} chosen, to add constraint forces of the coming step to ``acc``.
    """

    def __init__(self, mesh, materials: list[M.Material], cell_material: np.ndarray, safety: float = 0.8,
                 nodal_pressure: bool = True, external: Load | None = None, kernel: str | None = None):
        self.mesh = mesh
        self.comm = mesh.comm
        self.clock, self.sums = st.Clock(safety), st.WorkSums()
        self.node, self.cell, self.internal, self.passes = st.NodeData(), st.CellData(), st.Internal(), st.Passes(
            nodal_pressure)
        self.external = external
        _reference_body(self, mesh)
        _material_tables(self, materials, cell_material)
        nm = len(materials)
        imap = self.V.dofmap.index_map
        _nodal_arrays(self, self.V, imap, nm)
        self.lumped_mass(imap, nm)
        self.initial_mass = self.total_mass
        _cell_state(self)
        _internal_force_form(self, self.V, self.internal.Q)
        _stress_kernel(self, kernel)
        _clock(self)

    def lumped_mass(self, imap, nm: int, orphans_allowed: bool = False) -> None:
        """Lumped mass: ρ_e V0_e / 4 to each node, per material (the bodies' masses, for their mass-averaged
        accelerations) and in all; eroded cells give none. ``_mass_div`` is the mass the accelerations are
        divided by: the mass itself, or after an erosion a copy with 1 on the nodes left without a cell
        (their force is zero, their velocity held at zero)."""
        materials = self.materials
        rho = np.array([m.density for m in materials])[self.mat]
        mvec = dx.new_vector(imap, bs=nm)
        arr = mvec.array.reshape(-1, nm)
        _per_material_to_nodes(self, 0.25 * rho * self.vol0, mvec)
        self.node.mass_by_material = arr[: self.n_nodes].copy()
        self.mass = self.node.mass_by_material.sum(axis=1)
        self.node.body_mass = assembly.exact_sum(self.node.mass_by_material[: self.n_owned], self.comm)
        self.node.orphans = self.mass <= 0.0
        if not orphans_allowed and np.any(self.node.orphans[: self.n_owned]):
            raise SimulationError("a node has no mass (an orphan node in the mesh)")
        self.node.mass_div = self.mass
        if np.any(self.node.orphans):
            self.node.mass_div = np.where(self.node.orphans, 1.0, self.mass)
        self.total_mass = assembly.exact_sum(self.mass[: self.n_owned], self.comm)

    # ------------------------------------------------------------------------------------------------
    def volumes_to_nodes(self, cvol: np.ndarray, vec) -> None:
        """Nodal volumes per material (the vector vec), Σ V_e / 4 over live cells, the terms on the volume
        grid (exact sums: the same on any partition), ghosts summed and refreshed."""
        arr = vec.array.reshape(-1, len(self.materials))
        if self.passes.nodes is not None:
            self.passes.nodes.scatter_volumes(self.passes.cells.dofs32, self.mat, cvol, self.internal.volume_quantum,
                                              arr)
        else:
            kernels.grid_scatter(self.dofs, self.mat, cvol.reshape(-1, 1, 1), False, self.internal.volume_quantum, arr)
        _ghost_sum(self, vec)

    def _cells_to_nodes(self, Fc: np.ndarray, out: np.ndarray) -> None:
        """The cells' nodal forces Fc (n_cells, 4, 3) summed into out (n_nodes, 3), the terms on the force
        grid (exact sums: the same on any partition), ghost terms summed to their owners (ghost rows stale)."""
        if self.passes.nodes is not None:
            self.passes.nodes.scatter_forces(self.passes.cells.dofs32, Fc, self.internal.force_quantum, out)
        else:
            kernels.grid_scatter(self.dofs, self.mat, Fc, True, self.internal.force_quantum, out)
        _forces_to_owners(self)

    def positions(self) -> np.ndarray:
        """Current node positions (n_nodes, 3), ghosts included."""
        return self.X + self.U

    def stable_step(self) -> float:
        """Safety x min over cells of (shortest altitude / dilatational speed), current mesh, all ranks
        (fepen.solver.time_step.stable)."""
        return time_step.stable(self)

    def calibrate_step(self, iterations: int = 400, rtol: float = 1e-5) -> tuple[float, float]:
        """The critical step of the undeformed body by power iteration; sets ``step_gain``
        (fepen.solver.time_step.calibrate: the method's documentation).

        Returns:
            (critical step of the undeformed body (s), step_gain).
        """
        return time_step.calibrate(self, iterations, rtol)

    def set_initial(self, displacement=None, velocity=None) -> None:
        """Initial displacement (a rigid placement of the stress-free body) and velocity, as callables of
        the reference positions (n, 3) -> (n, 3), or arrays; then the initial acceleration."""
        if displacement is not None:
            self.U[:] = displacement(self.X) if callable(displacement) else displacement
        if velocity is not None:
            self.Vel[:] = velocity(self.X) if callable(velocity) else velocity
        if self.node.fixed is not None:
            self.Vel[self.node.fixed] = 0.0
        self._forces(0.0)
        n = self.n_owned
        self.acc[:n] = (self.fext[:n] - self.node.fint[:n]) / self.node.mass_div[:n, None]
        if self.node.fixed is not None:
            self.acc[self.node.fixed] = 0.0
        self.node.a_fn.x.scatter_forward()
        self.sums.ke0 = self.kinetic_energy(self.Vel)
        self.clock.dt_stable = self.clock.dt0 = self.clock.dt_min = self.stable_step()
        time_step.choose(self)
        if self.interface is not None:
            self.interface(self)

    def kinetic_energy(self, vel: np.ndarray) -> float:
        """Σ ½ m v² over owned nodes, all ranks (an exact sum: the same on any partition)."""
        n = self.n_owned
        return assembly.exact_sum(0.5 * self.mass[:n] * np.sum(vel[:n] ** 2, axis=1), self.comm)

    def velocity_at_step(self) -> np.ndarray:
        """v^n ≈ v^{n-1/2} + Δt/2 a^n (the velocity at the integer step, for energies and output)."""
        return self.Vel + 0.5 * self.dt_prev * self.acc

    # ------------------------------------------------------------------------------------------------
    def _forces(self, dt: float, x_ready: bool = False) -> float:
        """Internal and external forces at the current positions; returns the new stable-step estimate
        (h/c over the current mesh, before the safety factor) on this rank. x_ready: ``self.node.x`` already
        holds X + U (the C update pass wrote it)."""
        if self.passes.cells is not None:
            return self._forces_c(dt, x_ready)
        t0 = perf_counter()
        x = np.add(self.X, self.U, out=self.node.x)
        with_step = self.step_count % STEP_EVERY == 0
        jmin, worst, h_c, self.cell.step_cell = kernels.volumes_and_step(
            x, self.dofs, self.orient, self.vol0, self.mat, self.cell.speed, self.cell.vol, with_step, self.cell.dt)
        if self._any_inverted(jmin):
            if self.on_inverted is None or not self.on_inverted(x):
                failures.inverted(self, x, jmin, worst)
            jmin, worst, h_c, self.cell.step_cell = kernels.volumes_and_step(  # the inverted cells eroded
                x, self.dofs, self.orient, self.vol0, self.mat, self.cell.speed, self.cell.vol, with_step, self.cell.dt)
            if self._any_inverted(jmin):
                failures.inverted(self, x, jmin, worst)
        self.volumes_to_nodes(self.cell.vol, self.node.nvol)
        t1 = perf_counter()
        if self.passes.nodal:
            kernels.nodal_pressures(self.node.vol, self.node.vol0, self.cell.bulk, self.nodal_p)
        self._stress_update(x, dt)
        t2 = perf_counter()
        self.assemble_internal_force()
        t3 = perf_counter()
        self._external_forces()
        self.clock.times.add(t0, t1, t2, t3, perf_counter())
        return h_c

    def _forces_c(self, dt: float, x_ready: bool) -> float:
        """_forces through the C passes (fepen/solver/cell_kernel.c): the kinematics pass (cvol, J, h/c and
        the nodal volumes), the nodal pressures, the fused stress-and-force pass (the nodal forces summed in it
        block by block), the ghosts' sums."""
        t0 = perf_counter()
        x = self.node.x if x_ready else np.add(self.X, self.U, out=self.node.x)
        with_step = self.step_count % STEP_EVERY == 0
        cells = self.passes.cells
        q_vol, q_force = self.internal.volume_quantum, self.internal.force_quantum
        jmin, worst, h_c, self.cell.step_cell = cells.kinematics(with_step, q_vol)  # and the nodal volumes
        if self._any_inverted(jmin):
            if self.on_inverted is None or not self.on_inverted(x):
                failures.inverted(self, x, jmin, worst)
            jmin, worst, h_c, self.cell.step_cell = cells.kinematics(with_step, q_vol)  # the inverted cells eroded
            if self._any_inverted(jmin):
                failures.inverted(self, x, jmin, worst)
        _ghost_sum(self, self.node.nvol)
        t1 = perf_counter()
        self.passes.nodes.nodal_pressure(self.node.vol, self.node.vol0, self.cell.bulk, self.nodal_p)
        cells.cells(dt, q_force)  # and the cells' forces summed at the nodes
        self.sums.plastic += self.sums.totals[0]
        self.sums.heat += self.sums.totals[1]
        t2 = perf_counter()
        _forces_to_owners(self)  # ghost terms to their owners (ghost rows stale)
        t3 = perf_counter()
        self._external_forces()
        self.clock.times.add(t0, t1, t2, t3, perf_counter())
        return h_c

    def _external_forces(self) -> None:
        """fext from the external load (zero without one)."""
        self.fext[:] = 0.0
        if self.external is not None:
            self.external(self, self.dt)

    def _stress_update(self, x: np.ndarray, dt: float) -> None:
        """Every cell's stress over the step and P into the packed coefficient; plastic work and heat (the
        numba reference)."""
        kernels.stress_update(x, self.Vel, dt, self.dofs, self.cell.grad0, self.vol0, self.mat, self.cell.params,
                              self.nodal_p, self.passes.nodal, self.s, self.eps_p, self.temp, self.cell.sy0,
                              self.internal.P_packed, self.sums.totals)
        self.sums.plastic += self.sums.totals[0]
        self.sums.heat += self.sums.totals[1]

    def assemble_internal_force(self) -> None:
        """f_int = ∫ P : ∇_X w dX from the packed P on the owned nodes: each cell's four nodal forces with
        its reference gradients (kernels.internal_force_cells: the compiled form's vector to round-off, at a
        fraction of dolfinx's cost, which rebuilds each cell's geometry), summed at the nodes in the
        partition-independent order (contributions of other ranks' cells included; ghost rows are stale)."""
        kernels.internal_force_cells(self.internal.P_packed, self.dofs, self.cell.grad0, self.vol0, self.cell.Fc)
        self._cells_to_nodes(self.cell.Fc, self.node.fint)

    def _any_inverted(self, jmin: float) -> bool:
        """Whether a live cell on any rank is inverted (or NaN); every rank gets the same answer."""
        bad = not (jmin > 0.0)
        if self.comm.size > 1:  # every rank must stop together (and rank 0 must be able to say why)
            self.passes.flag[0] = 1.0 if bad else 0.0
            t0 = perf_counter()
            self.comm.Allreduce(MPI.IN_PLACE, self.passes.flag, op=MPI.MAX)
            traffic.count("inverted", 1, traffic.WORD, traffic.rounds(self.comm.size), t0)
            bad = self.passes.flag[0] > 0.0
        return bad

    def step(self) -> None:
        """Advance one central-difference step."""
        dt = self.dt
        n = self.n_owned
        t0 = perf_counter()
        h = 0.5 * (self.dt_prev + dt)
        if self.passes.nodes is not None:  # the C node passes: x = X + U written too
            self.passes.nodes.update_begin(h, dt, n, self.acc, self.Vel, self.U, self.X, self.node.x, self.node.du,
                                           self.node.fint, self.fext, self.sums.work)
        else:
            self.Vel += h * self.acc
            du = np.multiply(dt, self.Vel, out=self.node.du)
            self.U += du
            kernels.work_halves(du, self.node.fint, self.fext, n, self.sums.work)
        self.clock.times.update += perf_counter() - t0
        h_c = self._forces(dt, x_ready=self.passes.nodes is not None)
        t0 = perf_counter()
        du = self.node.du
        if self.passes.nodes is not None:
            nd = self.node
            self.passes.nodes.update_end(n, nd.fint, self.fext, nd.mass_div, nd.fixed, du, self.acc, self.sums.work)
        else:
            self.acc[:n] = (self.fext[:n] - self.node.fint[:n]) / self.node.mass_div[:n, None]
            if self.node.fixed is not None:
                self.acc[self.node.fixed] = 0.0
            kernels.work_halves(du, self.node.fint, self.fext, n, self.sums.work)
        t1 = perf_counter()
        self.node.a_fn.x.scatter_forward()
        traffic.count("accelerations", 1, 3 * traffic.WORD * self.ghosts.forward, self.ghosts.forward_ranks, t1)
        traffic.step_done()
        self.t = self.clock.land_at if self.clock.land_at >= 0.0 else self.t + dt
        self.step_count += 1
        self.dt_prev = dt
        self.clock.times.update += perf_counter() - t0
        if self.step_count % STEP_EVERY == 1:
            self._new_step(h_c)
        time_step.choose(self)
        if self.interface is not None:
            t0 = perf_counter()
            self.interface(self)
            self.clock.times.boundary += perf_counter() - t0

    def _new_step(self, h_c: float) -> None:
        """The next stable Δt from this rank's h/c (fepen.solver.time_step.new_stable)."""
        time_step.new_stable(self, h_c)

    def state(self) -> dict[str, np.ndarray]:
        """This rank's state between two steps: STATE_ARRAYS, the reference positions ``X`` and the
        STATE_SCALARS packed in ``scalars`` (for checkpoints; the arrays are views, copy to keep)."""
        out = {k: _get(self, where) for k, where in STATE_ARRAYS.items()}
        out["X0"] = self.X0
        out["scalars"] = np.array([float(_get(self, where)) for where in STATE_SCALARS.values()])
        return out

    def restore(self, state) -> None:
        """Put back what state() returned (any mapping of the same names), in place: the compiled kernels
        hold these arrays' addresses. The mesh must be the same, node for node (ValueError if not)."""
        X0 = state["X0"] if "X0" in state else state["X"]
        if not (X0.shape == self.X0.shape and np.array_equal(X0, self.X0)):
            raise ValueError("the state was taken on another mesh or partition")
        for k, where in STATE_ARRAYS.items():
            if k in state:
                np.copyto(_get(self, where), state[k])
        for (k, where), v in zip(STATE_SCALARS.items(), state["scalars"]):
            _set(self, where, int(v) if k == "step_count" else float(v))
        changed = bool(np.any(self.mat < 0)) or not np.array_equal(self.X, self.X0)  # eroded or receded
        if self.comm.allreduce(changed, op=MPI.LOR):  # rebuild (collective)
            removed = self.sums.removed.copy()
            reference.rebuild(self, np.arange(self.n_cells))
            self.internal.P_packed[: self.n_cells][self.mat < 0] = 0.0
            self.sums.removed[:] = removed


def _ghost_sum(s: ExplicitSolver, vec) -> None:
    """The nodal volumes' ghost terms added to their owners, the sums sent back to the ghosts (counted:
    fepen.solver.traffic's ``volumes``)."""
    t0 = perf_counter()
    dx.scatter_reverse_add(vec)
    vec.scatter_forward()
    g = s.ghosts
    traffic.count("volumes", 2, traffic.WORD * len(s.materials) * (g.reverse + g.forward),
                  g.reverse_ranks + g.forward_ranks, t0)


def _forces_to_owners(s: ExplicitSolver) -> None:
    """The internal forces' ghost terms added to their owners (ghost rows stale; counted: ``forces``)."""
    t0 = perf_counter()
    dx.scatter_reverse_add(s.node.fint_fn.x)
    traffic.count("forces", 1, 3 * traffic.WORD * s.ghosts.reverse, s.ghosts.reverse_ranks, t0)


def _get(s: ExplicitSolver, where: str):
    """The solver's value at a dotted path ("clock.dt0")."""
    out = s
    for part in where.split("."):
        out = getattr(out, part)
    return out


def _set(s: ExplicitSolver, where: str, value) -> None:
    """Set the solver's value at a dotted path."""
    *path, last = where.split(".")
    setattr(_get(s, ".".join(path)) if path else s, last, value)


#: the grids' ranges: a nodal sum is exact while its partial sums stay below 2^53 quanta, here FORCE_RANGE x
#: the largest reference face area x the stiffest bulk modulus (forces of a stress of 4 K: far beyond what the
#: solver survives; the force quantum is then ~1e-13 of a typical nodal force) and VOLUME_RANGE x the largest
#: reference cell volume; past them the sums are still accurate, only no longer exact
FORCE_RANGE = 4.0
VOLUME_RANGE = 64.0


def _grids(s: ExplicitSolver) -> tuple[float, float]:
    """The quanta (powers of two) that the cells' nodal forces and volumes are rounded to before they are
    summed at the nodes (docs/theory.md §3.4): the same on every rank (a maximum over all of them) and over
    the run, from the reference body."""
    area = 3.0 * s.vol0[:, None] * np.linalg.norm(s.cell.grad0, axis=2) if s.n_cells else np.zeros((0, 4))
    local = np.array([float(area.max(initial=0.0)) * float(s.cell.bulk.max()), float(s.vol0.max(initial=0.0))])
    top = local.copy()
    s.comm.Allreduce(local, top, op=MPI.MAX)
    return tuple(2.0 ** (math.ceil(math.log2(r * v)) - 52) for r, v in zip((FORCE_RANGE, VOLUME_RANGE), top))


def _per_material_to_nodes(s: ExplicitSolver, cell_values: np.ndarray, vec) -> None:
    """Each live cell's value (n_cells,) to each of its four nodes, in its material's column of the vector
    ``vec`` (bs = number of materials), summed in the partition-independent order (assembly.NodalSum),
    ghosts refreshed."""
    nm = len(s.materials)
    if nm == 1:
        np.multiply(cell_values, s.mat >= 0, out=s.cell.vol4[:, 0])  # eroded cells give nothing
        vals = s.cell.vol4
    else:
        live = s.mat >= 0
        vals = np.zeros((s.n_cells, nm))
        vals[np.flatnonzero(live), s.mat[live]] = cell_values[live]
    s.node.cell_sum(vals, vec.array.reshape(-1, nm))
    vec.scatter_forward()


# ------------------------------------------------------------------------------------------------
# the solver's set-up, in the order ExplicitSolver.__init__ calls them

def _reference_body(s: ExplicitSolver, mesh) -> None:
    """The function spaces, the node and cell numbering, the reference positions and gradients."""
    V = dx.vector_space(mesh)
    Q = dx.tensor_dg0_space(mesh)
    s.V, s.internal.Q = V, Q
    imap = V.dofmap.index_map
    s.n_owned = imap.size_local
    s.n_nodes = imap.size_local + imap.num_ghosts
    s.ghosts = traffic.GhostPlan.of(imap, s.comm)  # what the nodal scatters move (fepen.solver.traffic)
    n_cells = mesh.topology.index_map(mesh.topology.dim).size_local
    s.n_cells = n_cells
    s.dofs = np.ascontiguousarray(dx.cell_dofs(V)[:n_cells]).astype(np.int64)
    s.X = V.tabulate_dof_coordinates()[: s.n_nodes].copy()
    s.X0 = s.X.copy()  # X moves only where a surface recedes (fepen.solver.recession)
    # the mesh geometry's node of each dof, so that a moved reference reaches the assembled form
    gdofs = dx.geometry_dofs(mesh)
    s.node.geometry_node = np.zeros(s.n_nodes, dtype=np.int64)
    s.node.geometry_node[dx.cell_dofs(V).ravel()] = gdofs.ravel()
    s.node.geometry_x = mesh.geometry.x
    assert np.allclose(s.node.geometry_x[s.node.geometry_node, :3], s.X)
    s.X[:] = s.node.geometry_x[s.node.geometry_node, :3]  # the mesh's own numbers (tabulated ones may differ in
    s.X0[:] = s.X  # the last bit), so that writing X back into the geometry changes nothing
    s.cell.grad0, s.vol0, s.orient = kernels.reference_gradients(s.X, s.dofs)
    # each node's input-mesh number (the same on any partition) and the cells' nodal sums in their order
    s.node.input_index = np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)[s.node.geometry_node]
    s.node.cell_sum = assembly.NodalSum(s.comm, imap, s.dofs, assembly.input_keys(s.dofs, s.node.input_index))
    s.cell.vol = np.zeros(n_cells)  # each cell's current volume
    s.cell.vol4 = np.zeros((n_cells, 1))
    s.passes.cells = s.passes.nodes = None  # the C passes (_stress_kernel)
    s.cell.Fc = np.zeros((n_cells, 4, 3))  # each cell's internal forces on its nodes


def _material_tables(s: ExplicitSolver, materials: list[M.Material], cell_material: np.ndarray) -> None:
    """Each cell's material (−1: eroded) and the materials' parameters, wave speeds and bulk moduli."""
    s.materials = materials
    s.cell.params = np.stack([m.params for m in materials])
    s.mat = np.ascontiguousarray(cell_material, dtype=np.int64)  # −1: an eroded cell
    assert len(s.mat) == s.n_cells
    s.cell.dt = np.full(s.n_cells, np.inf)  # each cell's altitude / wave speed, every STEP_EVERY steps
    #: this rank's removed mass (owned nodes), kinetic energy carried away, stored elastic energy of
    #: the removed cells (J); see fepen.solver.reference
    s.sums.removed = np.zeros(3)
    s.cell.speed = np.array([float(np.sqrt((m.bulk_modulus + 4.0 * m.shear_modulus / 3.0) / m.density))
                        for m in materials])
    s.cell.bulk = np.array([m.bulk_modulus for m in materials])
    s.internal.force_quantum, s.internal.volume_quantum = _grids(s)


def _cell_state(s: ExplicitSolver) -> None:
    """Stress, plastic strain, temperature and static flow stress of each cell, at rest."""
    n_cells = s.n_cells
    s.cell.sT = np.zeros((6, n_cells))  # component-major for the C trial pass
    s.s = s.cell.sT.T  # (n_cells, 6) view: xx, yy, zz, xy, yz, xz
    s.eps_p = np.zeros(n_cells)
    s.temp = np.array([m.params[M.TROOM] for m in s.materials])[s.mat].astype(float)
    s.sums.totals = np.zeros(4)
    s.cell.sy0 = np.empty(n_cells)
    kernels.static_flow_stress(s.mat, s.cell.params, s.eps_p, s.temp, s.cell.sy0)


def _clock(s: ExplicitSolver) -> None:
    """Time, the first stable step, the work sums, no hooks yet."""
    s.clock.step_gain = 1.0  # stable step = safety * step_gain * min(h/c); see calibrate_step
    s.t = s.dt_prev = 0.0
    s.step_count = 0
    s.dt = s.clock.dt_stable = s.clock.dt0 = s.clock.dt_min = s.stable_step()
    # the next time a step must end on, from the time now (fepen.runs.outputs.Landing), or None: every step
    # the stable step; _land_at: the time the coming step ends on when it lands (else -1)
    s.landing = None
    s.clock.land_at = -1.0
    # the work sums: each node's internal and external work (_work, summed exactly when asked: work_sums),
    # this rank's plastic work, heat, and the interface's normal and tangential work
    s.sums.work = np.zeros((s.n_nodes, 2))
    s.sums.plastic = s.sums.heat = s.sums.interface_normal = s.sums.interface_tangential = 0.0
    s.interface = None
    # called with the current positions when a live cell inverts (collective): True if it eroded the
    # inverted cells (fepen.solver.erosion), False or None to stop the run
    s.on_inverted = None
    s.sums.ke0 = None
    s.clock.times = StepTimes()


def _nodal_arrays(s: ExplicitSolver, V, imap, nm: int) -> None:
    """Nodal vectors (ghosted, block size 3) and nodal scalars per material; the reference nodal volumes."""
    s.node.u = dx.function(V, "displacement")
    s.node.v = dx.function(V, "velocity")
    s.node.fint_fn = dx.function(V)
    s.U, s.Vel = s.node.u.x.array.reshape(-1, 3), s.node.v.x.array.reshape(-1, 3)
    s.node.a_fn = dx.function(V, "acceleration")
    s.acc = s.node.a_fn.x.array.reshape(-1, 3)
    s.node.fint = s.node.fint_fn.x.array.reshape(-1, 3)
    s.node.du = np.zeros_like(s.node.fint)  # the displacement increment of the step (for the work of the forces)
    s.node.fixed = None  # (n_nodes, 3) bool: velocity components held at zero (symmetry planes)
    s.fext = np.zeros((s.n_nodes, 3))
    s.node.nvol = dx.new_vector(imap, bs=nm)
    s.node.nvol0 = dx.new_vector(imap, bs=nm)
    s.node.vol = s.node.nvol.array.reshape(-1, nm)
    s.node.vol0 = s.node.nvol0.array.reshape(-1, nm)
    s.nodal_p = np.zeros_like(s.node.vol0)
    kernels.volumes_and_step(s.X, s.dofs, s.orient, s.vol0, s.mat, s.cell.speed, s.cell.vol)
    s.volumes_to_nodes(s.cell.vol, s.node.nvol0)


def _internal_force_form(s: ExplicitSolver, V, Q) -> None:
    """The internal-force form, with P packed once and rewritten in place each step."""
    n_cells = s.n_cells
    s.internal.P = dx.function(Q, "P")
    s.internal.form = dx.internal_force_form(s.internal.P, V)
    s.internal.consts, s.internal.coeffs = dx.pack(s.internal.form)
    key = next(iter(s.internal.coeffs))
    s.internal.P_packed = s.internal.coeffs[key]
    assert s.internal.P_packed.shape[1] == 9 and s.internal.P_packed.shape[0] >= n_cells


def _stress_kernel(s: ExplicitSolver, kernel: str | None) -> None:
    """The step's kernels: the C passes (fepen.solver.ckernel: kinematics, fused stress and force, node
    update), or the numba kernels alone (the reference; also the plain element's)."""
    materials = s.materials
    s.node.x = np.empty((s.n_nodes, 3))  # current positions X + U of the last force evaluation (the kernels')
    s.passes.flag = np.zeros(1)
    s.passes.cells = s.passes.nodes = None
    if kernel not in (None, "C", "numba"):
        raise ValueError(f"kernel must be 'C', 'numba' or None, not {kernel!r}")
    if kernel == "C" and (not s.passes.nodal or ckernel.library() is None):
        raise RuntimeError(f"the C kernel is not available: {ckernel.why_not() or 'plain element'}")
    if s.passes.nodal and kernel != "numba" and ckernel.library() is not None:
        s.cell.G_m = np.array([m.shear_modulus for m in materials])
        c = s.cell
        s.passes.cells = ckernel.CellPasses(s.node.x, s.Vel, s.dofs, s.mat, s.orient, s.vol0, c.speed, c.params, c.G_m,
                                            s.nodal_p, c.sT, s.eps_p, s.temp, c.sy0, c.vol, c.dt, None, s.sums.totals,
                                            nvol=s.node.vol, fint=s.node.fint)
        s.passes.nodes = ckernel.NodePasses()
    s.kernel = "C" if s.passes.cells is not None else "numba"
