"""What a run reads off an ExplicitSolver between steps: the energies and their balance, the body's
momentum and accelerations, each body's energies and momentum and the force across the tied shell–charge
interface, plastic strain, the stress fields written out, and the internal force through dolfinx (the
reference of the solver's own assembly, for tests and benchmarks). Nothing here changes the solver's state."""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from mpi4py import MPI

from fepen import dolfinx_api as dx
from fepen.laws import energy
from fepen.laws import materials as M
from fepen.solver import assembly, kernels


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
    #: per material (0 the shell, 1 the charge): stored elastic energy and plastic work (J)
    elastic_by_body: tuple = ()
    plastic_by_body: tuple = ()

    @property
    def total(self) -> float:
        """The total energy (J), glstat's: KE + W_int + E_interface + KE_removed + E_target, with E_interface
        = friction dissipation − normal work of the shell–charge contact and E_target = −W_ext the energy the
        target (or rigid wall) took; the terms of balance_error, so that a perfect balance keeps it at KE_0."""
        return (self.kinetic + self.internal_work + self.friction - self.interface_normal_work
                + self.removed_kinetic - self.external_work)

    @property
    def ratio(self) -> float:
        """glstat's energy ratio: total / (KE_0 + external work), the target's work being counted in the total
        (as LS-DYNA counts a stonewall's or a contact's energy), so total / KE_0; 1 for a perfect balance."""
        return self.total / max(self.initial_kinetic, 1e-300)

    @property
    def balance_error(self) -> float:
        """Relative energy-balance error: KE + KE_removed + W_int − KE_0 − W_ext − W_interface, with
        W_interface the work of the shell–charge contact forces (normal work − friction dissipation;
        fepen.solver.shell_charge) and KE_removed the kinetic energy the removed material carried away when
        it was removed (erosion, surface recession; W_int keeps the work done on it): fepen.laws.energy, the
        one formula of both fidelities."""
        return energy.balance_error(self.kinetic, self.initial_kinetic, self.external_work, self.internal_work,
                                    self.removed_kinetic, self.interface_normal_work - self.friction)


def energies(solver) -> Energies:
    """Global energies at the current step."""
    s = solver
    c = s.comm
    ke = s.kinetic_energy(s.velocity_at_step())
    nm = len(s.materials)
    w_int, w_ext = work_sums(s)
    w = s.sums
    sums = c.allreduce(np.concatenate([_elastic_by_material(s), _bilinear_plastic(s),
                                       [w.plastic, w.heat, w.interface_normal, w.interface_tangential, w.removed[1],
                                        w.removed[2]]]), op=MPI.SUM)
    elastic, bilinear = sums[:nm], sums[nm: 2 * nm]
    plastic, heat, w_n, w_t, removed_ke, removed_ie = sums[2 * nm:]
    return Energies(ke, w_int, w_ext, float(np.sum(elastic)), plastic, heat, w.ke0 or 0.0, w_n, -w_t, removed_ke,
                    removed_ie, tuple(elastic), tuple(_plastic_by_material(s.materials, plastic, heat, bilinear)))


def work_sums(solver) -> tuple[float, float]:
    """(internal, external) work done since the start (J), all ranks: exact sums of each owned node's
    running sum (the same on any partition)."""
    return tuple(assembly.exact_sum(solver.sums.work[: solver.n_owned], solver.comm))


def _cell_J(solver) -> np.ndarray:
    s = solver
    J = np.empty(s.n_cells)
    kernels.cell_jacobians(s.positions(), s.dofs, s.orient, s.vol0, s.mat, J)
    return J


def _elastic_by_material(solver) -> np.ndarray:
    """This rank's stored elastic energy per material (J): the volumetric part on the owned nodes' columns
    (Σ V0_a K/2 (ln J_a)^2; per cell without nodal pressure) and the deviatoric Σ V s:s / (4G) per live cell."""
    s = solver
    nm, n = len(s.materials), s.n_owned
    mat = s.mat
    live = mat >= 0
    J = _cell_J(s)
    G = np.array([m.shear_modulus for m in s.materials])
    if s.passes.nodal:
        v0, v = s.node.vol0[:n], s.node.vol[:n]
        has = v0 > 0.0
        lj = np.log(np.where(has, v, 1.0) / np.where(has, v0, 1.0))
        out = 0.5 * s.cell.bulk * np.sum(v0 * lj * lj, axis=0)
        return out + _deviatoric_by_material(J, s.vol0, np.ascontiguousarray(s.s.T), mat, G, nm)
    sd = s.s  # column-major: whole columns are cheap, rows are not
    ss = sd[:, 0] ** 2 + sd[:, 1] ** 2 + sd[:, 2] ** 2 + 2.0 * (sd[:, 3] ** 2 + sd[:, 4] ** 2 + sd[:, 5] ** 2)
    per_cell = J * s.vol0 * ss / (4.0 * G[mat])  # eroded cells (−1): weighed 0 below
    lj = np.log(np.where(live, J, 1.0))
    per_cell += s.vol0 * 0.5 * s.cell.bulk[mat] * lj * lj
    return np.bincount(np.where(live, mat, 0), weights=np.where(live, per_cell, 0.0), minlength=nm)


@numba.njit(cache=True)
def _deviatoric_by_material(J, vol0, sT, mat, G, nm):
    """Σ V s:s / (4G) over the live cells of each material (J), in cell order: V = J V0, s:s = s_xx² + s_yy² +
    s_zz² + 2 (s_xy² + s_yz² + s_xz²) from the component-major stress sT (6, n)."""
    out = np.zeros(nm)
    for e in range(len(mat)):
        k = mat[e]
        if k < 0:
            continue
        out[k] += J[e] * vol0[e] * deviator_square(sT, e) / (4.0 * G[k])
    return out


@numba.njit(cache=True)
def deviator_square(sT, e):
    """s:s of cell e from the component-major deviatoric stress sT (6, n): s_xx² + s_yy² + s_zz² + 2 (s_xy² +
    s_yz² + s_xz²), added in von_mises's order (the compiled loops and numpy give the same bits)."""
    return sT[0, e] ** 2 + sT[1, e] ** 2 + sT[2, e] ** 2 + 2.0 * (sT[3, e] ** 2 + sT[4, e] ** 2 + sT[5, e] ** 2)


def _bilinear_plastic(solver) -> np.ndarray:
    """This rank's plastic work per material in closed form for the bilinear materials (J): Σ V0 (σ_0 ε_p +
    H ε_p² / 2) over their cells, the work of σ_y = σ_0 + H ε_p along ε_p per reference volume (the solver's
    own sum Σ σ_y Δε_p V is over the current volume: this differs from it by the volume change, under 1 %
    for the charge); 0 for the other materials."""
    s = solver
    nm = len(s.materials)
    out = np.zeros(nm)
    for k, m in enumerate(s.materials):
        if m.kind == M.BILINEAR:
            e = s.eps_p[: s.n_cells][s.mat == k]
            out[k] = float(np.sum(s.vol0[s.mat == k] * (m.params[M.A_] * e + 0.5 * m.params[M.H_] * e * e)))
    return out


def _heats(m) -> bool:
    """Whether material m turns a fraction β > 0 of its plastic work into heat (Johnson–Cook, thermal on)."""
    p = m.params
    return m.kind == M.JOHNSON_COOK and p[M.THERMAL_ON] > 0.0 and p[M.BETA] > 0.0


def _plastic_by_material(materials, plastic: float, heat: float, bilinear) -> list[float]:
    """The plastic work (J) split per material, from the solver's two running sums (the plastic work and the
    heat, over all cells). Exact (to round-off) when at most one material is left unknown after these:
    an elastic material does none; when exactly one material heats, its share is heat / β (the solver adds
    β σ_y Δε_p V to the heat and σ_y Δε_p V to the plastic work, the same terms); the one material left takes
    the rest. The charged projectile (a Johnson–Cook shell with effects.thermal, a bilinear charge) is so.
    Otherwise (effects.thermal = false) a bilinear material's share is its closed form (_bilinear_plastic) and
    the last material takes the rest.

    Args:
        materials: the solver's materials. plastic, heat: the global sums (J). bilinear: the global closed
            forms per material (_bilinear_plastic).
    """
    nm = len(materials)
    known: dict[int, float] = {k: 0.0 for k, m in enumerate(materials) if m.kind == M.ELASTIC}
    heating = [k for k, m in enumerate(materials) if _heats(m)]
    if len(heating) == 1:
        known[heating[0]] = heat / materials[heating[0]].params[M.BETA]
    unknown = [k for k in range(nm) if k not in known]
    if unknown:
        other = [k for k in unknown if materials[k].kind != M.BILINEAR]
        rest = other[-1] if other else unknown[-1]  # the one that takes the rest
        for k in unknown:
            if k != rest:  # the bilinear ones by their closed form (no other rule: the rest takes all)
                known[k] = float(bilinear[k]) if materials[k].kind == M.BILINEAR else 0.0
        known[rest] = plastic - sum(known.values())
    return [known[k] for k in range(nm)]


def momentum_velocity(solver) -> np.ndarray:
    """Velocity of the centre of mass (m/s), all ranks."""
    n = solver.n_owned
    return assembly.exact_sum(solver.mass[:n, None] * solver.velocity_at_step()[:n], solver.comm) / solver.total_mass


def rotation(solver, x: np.ndarray, f_target: np.ndarray | None):
    """The body's centre of mass x_c (m) and its rotation about it, all ranks (exact sums over the owned nodes:
    the same on any partition): the angular velocity ω = I⁻¹ H (rad/s), the target's moment Σ r × f (N m)
    and the angular momentum H = Σ m r × (v − v_c) (N m s), r = x − x_c, world frame; I = Σ m (|r|² 1 − r rᵀ);
    and the centre's velocity v_c (m/s: momentum_velocity's, from the same sum).

    Args:
        solver: the ExplicitSolver. x: its node positions now (m). f_target: the target's nodal forces of the
            last step (N; None: no target, zero moment).
    """
    n = solver.n_owned
    m = solver.mass[:n]
    v = solver.velocity_at_step()[:n]
    terms = np.empty((n, 15))
    _first_moments(m, x, v, terms)
    first = assembly.exact_sum(terms[:, :6], solver.comm)
    xc, vc = first[:3] / solver.total_mass, first[3:] / solver.total_mass
    f = np.zeros((n, 3)) if f_target is None else f_target
    _rotation_terms(m, x, v, f, xc, vc, terms)
    sums = assembly.exact_sum(terms, solver.comm)
    H, M, inertia = sums[:3], sums[3:6], sums[6:].reshape(3, 3)
    return xc, np.linalg.solve(inertia, H), M, H, vc


@numba.njit(cache=True)
def _first_moments(m, x, v, out):
    """out[:, :6] = m x, m v over the rows of m."""
    for i in range(len(m)):
        for j in range(3):
            out[i, j] = m[i] * x[i, j]
            out[i, 3 + j] = m[i] * v[i, j]


@numba.njit(cache=True)
def _rotation_terms(m, x, v, f, xc, vc, out):
    """Each node's terms of rotation's sums into out (n, 15): m r × u, r × f, m (|r|² 1 − r rᵀ) (row-major),
    r = x − x_c, u = v − v_c (the products in numpy.cross's order)."""
    for i in range(len(m)):
        r0, r1, r2 = x[i, 0] - xc[0], x[i, 1] - xc[1], x[i, 2] - xc[2]
        u0, u1, u2 = v[i, 0] - vc[0], v[i, 1] - vc[1], v[i, 2] - vc[2]
        mi = m[i]
        out[i, 0] = mi * (r1 * u2 - r2 * u1)
        out[i, 1] = mi * (r2 * u0 - r0 * u2)
        out[i, 2] = mi * (r0 * u1 - r1 * u0)
        out[i, 3] = r1 * f[i, 2] - r2 * f[i, 1]
        out[i, 4] = r2 * f[i, 0] - r0 * f[i, 2]
        out[i, 5] = r0 * f[i, 1] - r1 * f[i, 0]
        rr = (r0 * r0 + r2 * r2) + r1 * r1  # |r|² as numpy 1.24's einsum added it (the rows' bits kept)
        r = (r0, r1, r2)
        for a in range(3):
            for b in range(3):
                out[i, 6 + 3 * a + b] = mi * ((rr if a == b else 0.0) - r[a] * r[b])


def body_accelerations(solver, axis: np.ndarray) -> np.ndarray:
    """Mass-averaged acceleration of each material's body along the axis (m/s^2), all ranks:
    Σ_a m_a^(body) a_a · axis / m_body, with m_a^(body) the lumped mass node a takes from that body's
    cells (interface nodes share theirs)."""
    n = solver.n_owned
    along = solver.acc[:n] @ axis
    return assembly.exact_sum(solver.node.mass_by_material[:n] * along[:, None], solver.comm) / solver.node.body_mass


@dataclass
class Bodies:
    """Each body's (material's: 0 the shell, 1 the charge) energies and momentum, LS-DYNA's matsum. A node on
    a tied interface counts in each body with the lumped mass it takes from that body's cells (as
    body_accelerations), so the bodies' sums are the whole projectile's.

    Attributes:
        kinetic: Σ ½ m_a^(body) |v_a|² (J), v at the step. internal: elastic + plastic (J; Energies'
        elastic_by_body and plastic_by_body). momentum: Σ m_a^(body) v_a, world x and y (N s).
    """

    kinetic: np.ndarray
    internal: np.ndarray
    momentum: np.ndarray


def bodies(solver, e: Energies) -> Bodies:
    """Each body's kinetic energy and world x, y momentum, and its internal energy from the step's energies
    ``e`` (collective). Exact sums over the owned nodes (the same bits on any partition): the whole body's
    momentum, the last body's (the charge's) over its own nodes; the first (the shell) is the whole less the
    others (the whole kinetic energy is e.kinetic, an exact sum too)."""
    s = solver
    n, nm = s.n_owned, len(s.materials)
    v = s.velocity_at_step()[:n]
    mb = s.node.mass_by_material[:n]
    whole = assembly.exact_sum(s.mass[:n, None] * v[:, :2], s.comm)
    kinetic, momentum = np.zeros(nm), np.zeros((nm, 2))
    for k in range(1, nm):
        on = np.flatnonzero(mb[:, k] > 0.0)
        w, vk = mb[on, k], v[on]
        sums = assembly.exact_sum(np.column_stack([0.5 * w * np.sum(vk * vk, axis=1), w * vk[:, 0], w * vk[:, 1]]),
                                  s.comm)
        kinetic[k], momentum[k] = sums[0], sums[1:]
    kinetic[0] = e.kinetic - np.sum(kinetic[1:])
    momentum[0] = whole - np.sum(momentum[1:], axis=0)
    internal = np.array(e.elastic_by_body) + np.array(e.plastic_by_body)
    return Bodies(kinetic, internal, momentum)


def tied_interface_force(solver, body: int = 1) -> np.ndarray:
    """The resultant force the other bodies exert on ``body`` (the charge) across a tied interface (N, world),
    all ranks: the rate of change of its momentum minus the external load on it,
    Σ_a m_a^(body) a_a − Σ_a (m_a^(body) / m_a) f_ext,a over the owned nodes (exact sums). A node of the
    shared wall counts in the body with its share m_a^(body) of its mass, so this is the force that changes
    the body's momentum as Bodies defines it; the sum of the body's own internal forces vanishes (each
    cell's nodal forces sum to zero), so it is what the other body's cells give across the wall. With the
    charge enclosed in the shell, the external term is zero."""
    s = solver
    n = s.n_owned
    mb = s.node.mass_by_material[:n, body]
    share = np.where(mb > 0.0, mb / s.node.mass_div[:n], 0.0)
    return assembly.exact_sum(mb[:, None] * s.acc[:n] - share[:, None] * s.fext[:n], s.comm)


def max_peeq(solver) -> float:
    """The largest equivalent plastic strain, all ranks."""
    return solver.comm.allreduce(float(live_peeq(solver).max()) if solver.n_cells else 0.0, op=MPI.MAX)


def live_peeq(solver) -> np.ndarray:
    """The owned cells' equivalent plastic strain, 0 on eroded cells."""
    return solver.eps_p if solver.mat.min(initial=0) >= 0 else np.where(solver.mat >= 0, solver.eps_p, 0.0)


def max_peeq_where(solver) -> tuple[float, np.ndarray]:
    """The largest equivalent plastic strain and its cell's centre in the reference body, all ranks."""
    ep = live_peeq(solver)
    local = (float(ep.max()), solver.comm.rank, int(np.argmax(ep))) if solver.n_cells else (-1.0, 0, -1)
    peeq, owner, cell = solver.comm.allreduce(local, op=MPI.MAX)
    where = solver.X[solver.dofs[cell]].mean(axis=0) if solver.comm.rank == owner else None
    return peeq, solver.comm.bcast(where, root=owner)


def von_mises(solver) -> np.ndarray:
    """Equivalent (von Mises) stress of the owned cells (Pa)."""
    sd = solver.s
    return np.sqrt(1.5 * (sd[:, 0] ** 2 + sd[:, 1] ** 2 + sd[:, 2] ** 2
                          + 2 * (sd[:, 3] ** 2 + sd[:, 4] ** 2 + sd[:, 5] ** 2)))


def mean_stress(solver) -> np.ndarray:
    """Mean (Cauchy) stress of the owned cells (Pa, positive in tension): the average of the cell's nodes'
    pressures with the averaged-nodal-pressure element, else the trace of its stress over 3 (as
    fepen.solver.probes.mean_stress, one cell)."""
    if solver.passes.nodal:
        return solver.nodal_p[solver.dofs, np.maximum(solver.mat, 0)[:, None]].mean(axis=1) * (solver.mat >= 0)
    return solver.s[:, :3].sum(axis=1) / 3.0


def stress_fields(solver) -> dict[str, np.ndarray]:
    """The owned cells' Cauchy stress tensor ``stress_Pa`` (n, 6) in the solver's column order xx, yy, zz, xy,
    yz, xz (target's frame, tension positive), ``pressure_Pa`` (positive in compression) and ``triaxiality``
    (the mean stress over von Mises, -; 0 where von Mises vanishes)."""
    pm = mean_stress(solver)
    stress = solver.s.copy()
    if solver.passes.nodal:  # the deviator with the nodal pressure's mean stress (else s carries the trace)
        stress[:, :3] += pm[:, None]
    vm = von_mises(solver)
    return {"stress_Pa": stress, "pressure_Pa": -pm,
            "triaxiality": np.divide(pm, vm, out=np.zeros_like(vm), where=vm > 0.0)}


def axial_stress(solver, axis: np.ndarray) -> np.ndarray:
    """Normal Cauchy stress along the axis of the owned cells (Pa): a·s·a plus the cells' mean stress."""
    sd = solver.s
    pm = mean_stress(solver) if solver.passes.nodal else 0.0
    ax, ay, az = axis
    return (sd[:, 0] * ax * ax + sd[:, 1] * ay * ay + sd[:, 2] * az * az
            + 2 * (sd[:, 3] * ax * ay + sd[:, 4] * ay * az + sd[:, 5] * ax * az)) + pm


def assemble_form(solver, out: np.ndarray) -> None:
    """The solver's internal force through dolfinx: the compiled form assembled into ``out`` (the flat array
    of a V function, zeroed by the caller), no ghost sum (the reference, and the benchmarks' floor)."""
    dx.assemble_into(out, solver.internal.form, solver.internal.consts, solver.internal.coeffs)
