"""The shell-charge interface on a split cavity wall: node pairs, their normals, the contact hooked into
the explicit solver, gap and slip (docs/theory.md §13; the pair law: fepen.laws.contact)."""

from __future__ import annotations

import numpy as np
from mpi4py import MPI

from fepen.geometry import tags
from fepen.laws.contact import pair_forces, pair_work, wall_facet_normals
from fepen.laws.explosive import pair_friction
from fepen.solver import assembly


class ShellChargeContact:
    """The contact of a split cavity wall, hooked into an ExplicitSolver (``solver.interface``).

    Args:
        solver: fepen.explicit.ExplicitSolver; material 0 the shell, 1 the charge.
        facet_tags: the mesh's facet tags (CHARGE_FACE: the charge's side of the wall).
        friction: Coulomb coefficient μ ≥ 0.

    Attributes:
        pa, pb: local shell and charge node of each pair held on this rank.
        force, fn, pair_state: the last contact forces (on a), normal forces and states (0 open, 1 stuck, 2 sliding).
        count: pairs this rank counts in sums (its shell node is owned).
        area: each pair's wall area (m², its charge node's share of the wall facets, current configuration).
        friction_heat: the friction heat dissipated at each pair so far (J; their sum over the counted pairs is
            the interface's friction dissipation).
        friction_work: the same per unit area (J/m²), each step's heat over the pair's area then.
        friction_power: its rate at the last step (W/m²): mu p v on a sliding pair, 0 on a stuck or open one.
        friction_power_peak: the largest friction_power of each pair so far (W/m²).
    """

    def __init__(self, solver, facet_tags, friction: float):
        from fepen import dolfinx_api as dx
        from fepen.errors import SimulationError
        from fepen.solver.surface import oriented_facets

        self.solver, self.mu = solver, float(friction)
        s = solver
        self.tri = oriented_facets(s.V, facet_tags, tags.CHARGE_FACE)
        self._nvec = dx.new_vector(s.V.dofmap.index_map, bs=3)
        self.nodal_n = self._nvec.array.reshape(-1, 3)
        self._facet_n = np.zeros((len(self.tri), 3))
        self._wall_sum = assembly.NodalSum(s.comm, s.V.dofmap.index_map, self.tri,
                                           assembly.input_keys(self.tri, s.node.input_index))
        # wall nodes: those of the owned wall facets, marked and ghost-summed
        mark = dx.new_vector(s.V.dofmap.index_map, bs=1)
        mark.array[np.unique(self.tri)] = 1.0
        dx.scatter_reverse_add(mark)
        mark.scatter_forward()
        charge_wall = np.flatnonzero(mark.array[: s.n_nodes] > 0.0)
        # their twins: the local shell node at the same reference place (to round-off: the dof
        # coordinates are interpolated)
        from scipy.spatial import cKDTree

        shell_nodes = np.flatnonzero(s.node.mass_by_material[:, 0] > 0.0)
        tol = 1e-9 * max(float(np.ptp(s.X, axis=0).max()), 1e-300)
        dist, near = cKDTree(s.X[shell_nodes]).query(s.X[charge_wall], distance_upper_bound=tol)
        found = np.isfinite(dist)
        self.pa = shell_nodes[near[found]].astype(np.int64)
        self.pb = charge_wall[found].astype(np.int64)
        n = s.n_owned
        owned_b = charge_wall[charge_wall < n]
        missing = len(owned_b) - int(np.sum(self.pb < n))
        if s.comm.allreduce(missing, op=MPI.SUM):
            raise SimulationError("the partition separated a charge wall node from its twin in the shell")
        keep = (self.pa < n) | (self.pb < n)
        self.pa, self.pb = self.pa[keep], self.pb[keep]
        self.count = self.pa < n
        self.n_pairs = s.comm.allreduce(int(self.count.sum()), op=MPI.SUM)
        k = len(self.pa)
        self.force = np.zeros((k, 3))
        self.fn = np.zeros(k)
        self.pair_state = np.zeros(k, dtype=np.int8)
        self.normal = np.zeros((k, 3))
        self._work = np.zeros(2)
        self.area = np.zeros(k)
        self.friction_heat = np.zeros(k)
        self.friction_work = np.zeros(k)
        self.friction_power = np.zeros(k)
        self.friction_power_peak = np.zeros(k)
        self.X_pairs = s.X[self.pb]
        # constant over the run: which pair ends this rank owns (it applies their forces), their masses
        self._a_own, self._b_own = np.flatnonzero(self.pa < n), np.flatnonzero(self.pb < n)
        self._inv_ma = 1.0 / s.mass[self.pa[self._a_own], None]
        self._inv_mb = 1.0 / s.mass[self.pb[self._b_own], None]

    def normals(self, x=None) -> np.ndarray:
        """Unit normals out of the charge at the pairs, current configuration (x: the current positions,
        if at hand)."""
        s = self.solver
        wall_facet_normals(s.positions() if x is None else x, self.tri, self._facet_n)
        self._wall_sum(self._facet_n, self.nodal_n)  # in the facets' canonical order: any partition alike
        self._nvec.scatter_forward()
        nn = self.nodal_n[self.pb]
        self.area = np.linalg.norm(nn, axis=1)
        return nn / self.area[:, None]

    def __call__(self, solver) -> None:
        """Add the contact forces of the coming step to solver.acc (owned nodes), then refresh the ghosts."""
        s = solver
        dt, dt_avg = s.dt, 0.5 * (s.dt_prev + s.dt)
        x = s.positions()  # X + U: the positions of the solver's last force evaluation
        self.normal = self.normals(x)
        pair_forces(x, s.Vel, s.acc, s.mass, self.pa, self.pb, self.normal, dt, dt_avg, self.mu,
                    self.force, self.fn, self.pair_state)
        self._work[:] = 0.0
        pair_work(s.Vel, s.acc, s.mass, self.pa, self.pb, self.normal, self.force, self.fn, s.dt_prev, dt,
                  dt_avg, self.count, self._work)
        s.sums.interface_normal += self._work[0]
        s.sums.interface_tangential += self._work[1]
        pair_friction(s.Vel, s.acc, s.mass, self.pa, self.pb, self.normal, self.force, self.fn, s.dt_prev, dt, dt_avg,
                      self.area, self.friction_heat, self.friction_work, self.friction_power,
                      self.friction_power_peak)
        ia, ib = self._a_own, self._b_own
        s.acc[self.pa[ia]] += self.force[ia] * self._inv_ma
        s.acc[self.pb[ib]] -= self.force[ib] * self._inv_mb
        s.node.a_fn.x.scatter_forward()

    def state(self) -> dict:
        """The friction heat per pair so far and its largest rate (a checkpoint's arrays)."""
        return {"friction_heat": self.friction_heat, "friction_work": self.friction_work,
                "friction_power_peak": self.friction_power_peak}

    def restore(self, state: dict) -> None:
        """Put back what state() returned."""
        self.friction_heat[:] = state["friction_heat"]
        self.friction_work[:] = state["friction_work"]
        self.friction_power_peak[:] = state["friction_power_peak"]

    def resultant(self) -> np.ndarray:
        """The resultant of the last step's contact forces on the charge (N, world), all ranks: what the shell
        exerts on the charge across the interface (LS-DYNA's rcforc), −Σ force over the pairs whose charge
        node this rank owns (those it applied), an exact sum (the same bits on any partition)."""
        return -assembly.exact_sum(self.force[self._b_own], self.solver.comm)

    # ------------------------------------------------------------------------------------------------
    def gap_and_slip(self) -> tuple[np.ndarray, np.ndarray]:
        """Per local pair: the gap (m, > 0 open) and the slip, the tangential relative displacement (m)."""
        s = self.solver
        x = s.positions()
        n = self.normal if np.any(self.normal) else self.normals()
        d = x[self.pa] - x[self.pb]
        g = np.einsum("ij,ij->i", d, n)
        t = d - g[:, None] * n
        return g, np.linalg.norm(t, axis=1)

    def nodal_gap_and_slip(self) -> dict:
        """Gap and slip (m) as nodal scalars, at both nodes of each pair, zero off the wall (field output)."""
        g, slip = self.gap_and_slip()
        out = {}
        for name, v in (("interface_gap_m", g), ("interface_slip_m", slip)):
            a = np.zeros(self.solver.n_nodes)
            a[self.pa] = v
            a[self.pb] = v
            out[name] = a
        return out

    def summary(self) -> dict:
        """Global figures of the interface now: largest gap, interpenetration and slip (mm), the fractions
        of pairs carrying no force and sliding."""
        c = self.solver.comm
        g, slip = self.gap_and_slip()
        m = self.count
        mx = np.array([g[m].max(initial=0.0), (-g[m]).max(initial=0.0), slip[m].max(initial=0.0)])
        c.Allreduce(MPI.IN_PLACE, mx, op=MPI.MAX)
        counts = c.allreduce(np.array([np.sum(self.pair_state[m] == k) for k in (0, 2)], dtype=float), op=MPI.SUM)
        return {"gap_max_mm": mx[0] * 1e3, "penetration_max_mm": mx[1] * 1e3, "slip_max_mm": mx[2] * 1e3,
                "free_fraction": counts[0] / max(self.n_pairs, 1), "sliding_fraction": counts[1] / max(self.n_pairs, 1)}
