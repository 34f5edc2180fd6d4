"""What a run reads off an ExplicitSolver between steps: the energies and their balance, the body's
momentum and accelerations, plastic strain, the stress fields written out, and the internal force through
dolfinx (the reference of the solver's own assembly, for tests and benchmarks). Nothing here changes the
solver's state."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from dolfinx import cpp as _cpp
from mpi4py import MPI

from fepen.laws import energy
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
    vol = kernels.volumetric_energy(s.nodal_vol, s.nodal_vol0, s.bulk, s.n_owned)
    if not s.nodal:
        vol = _element_volumetric_energy(s)
    dev = _deviatoric_energy(s)
    w_int, w_ext = work_sums(s)
    sums = c.allreduce(np.array([vol + dev, s._plastic, s._heat, s._w_if_n, s._w_if_t, s._removed[1],
                                 s._removed[2]]), op=MPI.SUM)
    return Energies(ke, w_int, w_ext, sums[0], sums[1], sums[2], s.ke0 or 0.0, sums[3], -sums[4], sums[5], sums[6])


def work_sums(solver) -> tuple[float, float]:
    """(internal, external) work done since the start (J), all ranks: exact sums of each owned node's
    running sum (the same on any partition)."""
    return tuple(assembly.exact_sum(solver._work[: solver.n_owned], solver.comm))


def _cell_J(solver) -> np.ndarray:
    s = solver
    J = np.empty(s.n_cells)
    kernels.cell_jacobians(s.positions(), s.dofs, s.orient, s.vol0, s.mat, J)
    return J


def _deviatoric_energy(solver) -> float:
    G = np.array([m.shear_modulus for m in solver.materials])[solver.mat]
    return kernels.deviatoric_energy(solver.s, _cell_J(solver), solver.vol0, G)


def _element_volumetric_energy(solver) -> float:
    lj = np.log(_cell_J(solver))
    return float(np.sum(solver.vol0 * 0.5 * solver.bulk[solver.mat] * lj * lj))


def momentum_velocity(solver) -> np.ndarray:
    """Velocity of the centre of mass (m/s), all ranks."""
    n = solver.n_owned
    return assembly.exact_sum(solver.mass[:n, None] * solver.velocity_at_step()[:n], solver.comm) / solver.total_mass


def body_accelerations(solver, axis: np.ndarray) -> np.ndarray:
    """Mass-averaged acceleration of each material's body along the axis (m/s^2), all ranks:
    Σ_a m_a^(body) a_a · axis / m_body, with m_a^(body) the lumped mass node a takes from that body's
    cells (interface nodes share theirs)."""
    n = solver.n_owned
    along = solver.acc[:n] @ axis
    return assembly.exact_sum(solver.mass_by_material[:n] * along[:, None], solver.comm) / solver.body_mass


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


def axial_stress(solver, axis: np.ndarray) -> np.ndarray:
    """Normal Cauchy stress along the axis of the owned cells (Pa): a·s·a plus the cells' mean stress."""
    sd = solver.s
    pm = solver.nodal_p[solver.dofs, np.maximum(solver.mat, 0)[:, None]].mean(axis=1) * (solver.mat >= 0) \
        if solver.nodal else 0.0
    ax, ay, az = axis
    return (sd[:, 0] * ax * ax + sd[:, 1] * ay * ay + sd[:, 2] * az * az
            + 2 * (sd[:, 3] * ax * ay + sd[:, 4] * ay * az + sd[:, 5] * ax * az)) + pm


def assemble_form(solver, out: np.ndarray) -> None:
    """The solver's internal force through dolfinx: the compiled form assembled into ``out`` (the flat array
    of a V function, zeroed by the caller), no ghost sum (the reference, and the benchmarks' floor)."""
    _cpp.fem.assemble_vector(out, solver.form, solver._consts, solver._coeffs)
