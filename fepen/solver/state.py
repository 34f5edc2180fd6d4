"""The explicit solver's state as small named records (fenics-constitutive's state arrays, JAX MD's state
tuples): the solver holds its body's numbering and kinematics itself, and hands these records to the sibling
modules that read or change them (diagnostics, reference, failures, erosion, the loads), so that nothing
outside the solver reaches a private member of it.

    Clock      the step: the stable step and its bounds, the calibrated gain, the safety factor, the landing
    WorkSums   the energy bookkeeping: the nodes' work halves, plastic work, heat, the interface's work, the
               removed mass and energies, the striking kinetic energy
    NodeData   nodal arrays beyond the kinematics: the dolfinx functions, masses, nodal volumes, numbering
    CellData   per-cell arrays: material parameters, wave speeds, bulk moduli, reference gradients, volumes,
               flow stress, the stable-step estimates, the nodal forces of each cell
    Internal   the internal-force form: its spaces and packed coefficients, the exact-sum grids
    Passes     the compiled passes (fepen.solver.ckernel) or None, and the element (nodal pressure or not)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["Clock", "WorkSums", "NodeData", "CellData", "Internal", "Passes"]


@dataclass
class Clock:
    """The step. dt_stable: the stable step now (s); dt0, dt_min: the first and the smallest (s); step_gain:
    the calibrated factor on min(h/c) (ExplicitSolver.calibrate_step); safety: the safety factor; land_at:
    the time the coming step ends on when it lands on an output time (else −1); times: where the wall time
    goes (StepTimes)."""

    safety: float
    dt_stable: float = 0.0
    dt0: float = 0.0
    dt_min: float = 0.0
    step_gain: float = 1.0
    land_at: float = -1.0
    times: Any = None


@dataclass
class WorkSums:
    """The energy bookkeeping of this rank. work: each node's internal and external work (n_nodes, 2);
    plastic, heat: plastic work and heat (J); interface_normal, interface_tangential: the interface's work
    (J); removed: removed mass (kg), its kinetic energy and the stored elastic energy of removed cells (J);
    totals: the last pass's plastic work and heat; ke0: the striking kinetic energy (J, all ranks)."""

    work: np.ndarray | None = None
    plastic: float = 0.0
    heat: float = 0.0
    interface_normal: float = 0.0
    interface_tangential: float = 0.0
    removed: np.ndarray = field(default_factory=lambda: np.zeros(3))
    totals: np.ndarray = field(default_factory=lambda: np.zeros(4))
    ke0: float | None = None


@dataclass
class NodeData:
    """Nodal arrays. u, v, a_fn, fint_fn: the dolfinx functions of displacement, velocity, acceleration and
    internal force; fint: the internal forces (n_nodes, 3); du: the step's displacement increment; x: the
    positions of the last force evaluation; fixed: velocity components held at zero (or None);
    mass_by_material (n_nodes, materials), body_mass (each material's, all ranks), mass_div (what the
    accelerations are divided by), orphans (nodes left without a cell); nvol, nvol0 (vectors) and vol, vol0
    (their arrays): nodal volumes per material now and in the reference; input_index: each node's input-mesh
    number; geometry_node, geometry_x: each node's row in the mesh geometry and that geometry; cell_sum: the
    cells' nodal sums in the partition-independent order (assembly.NodalSum)."""

    input_index: np.ndarray | None = None
    geometry_node: np.ndarray | None = None
    geometry_x: np.ndarray | None = None
    cell_sum: Any = None
    u: Any = None
    v: Any = None
    a_fn: Any = None
    fint_fn: Any = None
    fint: np.ndarray | None = None
    du: np.ndarray | None = None
    x: np.ndarray | None = None
    fixed: np.ndarray | None = None
    mass_by_material: np.ndarray | None = None
    body_mass: np.ndarray | None = None
    mass_div: np.ndarray | None = None
    orphans: np.ndarray | None = None
    nvol: Any = None
    nvol0: Any = None
    vol: np.ndarray | None = None
    vol0: np.ndarray | None = None


@dataclass
class CellData:
    """Per-cell arrays. grad0: reference shape-function gradients; vol, vol4: current volumes; Fc: each cell's
    internal forces on its nodes (n_cells, 4, 3); params, G_m, speed, bulk: the materials' parameters, shear
    moduli, wave speeds, bulk moduli; sT: the stress, component-major (the solver's ``s`` is its transposed
    view); sy0: static flow stress; dt: altitude over wave speed; step_cell: the cell that set the step."""

    grad0: np.ndarray | None = None
    vol: np.ndarray | None = None
    vol4: np.ndarray | None = None
    Fc: np.ndarray | None = None
    params: np.ndarray | None = None
    G_m: np.ndarray | None = None
    speed: np.ndarray | None = None
    bulk: np.ndarray | None = None
    sT: np.ndarray | None = None
    sy0: np.ndarray | None = None
    dt: np.ndarray | None = None
    step_cell: int = -1


@dataclass
class Internal:
    """The internal-force form. Q: its tensor space; P: the first Piola stress function; P_packed: P's packed
    coefficient (rewritten in place); form, consts, coeffs: the form and its packed constants and
    coefficients; force_quantum, volume_quantum: the grids nodal forces and volumes are summed on."""

    Q: Any = None
    force_quantum: float = 0.0
    volume_quantum: float = 0.0
    P: Any = None
    P_packed: np.ndarray | None = None
    form: Any = None
    consts: Any = None
    coeffs: Any = None


@dataclass
class Passes:
    """The compiled passes: cells, nodes (fepen.solver.ckernel.CellPasses, NodePasses) or None (the numba
    kernels); nodal: the nodal-pressure element (False: the plain tetrahedron); flag: a one-number buffer for
    the collective inversion check."""

    nodal: bool
    cells: Any = None
    nodes: Any = None
    flag: np.ndarray = field(default_factory=lambda: np.zeros(1))
