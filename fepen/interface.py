"""The shell–charge interface: node-to-node contact with Coulomb friction (physics.md §7).

The charge has nodes of its own on the cavity wall (fepen.mesh.split_wall): each wall node a of the shell
is paired, once and for all, with the charge node b that starts at the same place (small sliding: the
pairing is fixed, which holds while the slip stays well below the element size; the run reports the
largest slip). n is the charge's outward unit normal at b in the current configuration (area-weighted
over its wall facets) and g = (x_a − x_b)·n the gap, positive when open.

Contact is enforced kinematically, as ABAQUS/Explicit's default contact does, within the central
difference step: with a^n the accelerations from the bodies' own forces,

    predicted velocities  ṽ = v^{n−1/2} + Δt_avg a^n,    Δt_avg = (Δt_{n−1/2} + Δt_{n+1/2}) / 2
    predicted gap         g̃ = g^n + Δt_{n+1/2} (ṽ_a − ṽ_b)·n
    normal force          F_N = −g̃ / (Δt_{n+1/2} Δt_avg (1/m_a + 1/m_b))   if g̃ < 0, else 0
    sticking force        F_s = −(ṽ_a − ṽ_b)_t / (Δt_avg (1/m_a + 1/m_b))
    friction (Coulomb)    F_t = F_s if |F_s| ≤ μ F_N, else μ F_N F_s / |F_s|

and the pair force F = F_N n + F_t acts on a, −F on b. A closing pair ends the step with exactly zero gap
(interpenetration only from the change of the normal within a step), an opening pair is free, a pair
pressed together sticks unless the tangential force it needs exceeds μ F_N, and then slides with the
Coulomb force opposing its tangential velocity. Each pair's impulse conserves momentum exactly.

Energy: the work of the pair forces, trapezoidal like the solver's, F^n·(Δu_rel^{n−1/2} + Δu_rel^{n+1/2})/2,
split into its normal part (≈ 0 in persistent contact; the loss of a closing impact) and its tangential
part, minus which is the friction dissipation; both enter the energy balance (fepen.explicit.Energies).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from mpi4py import MPI

from fepen import geometry


@numba.njit(cache=True, error_model="numpy")
def pair_forces(x, vel, acc, mass, pa, pb, normal, dt, dt_avg, mu, force, fn, state):
    """The kinematic contact forces of node pairs (module docstring).

    Args:
        x, vel, acc: current positions, v^{n−1/2}, a^n without contact (n_nodes, 3).
        mass: lumped nodal masses (n_nodes,). pa, pb: shell and charge node of each pair (k,).
        normal: unit normal of each pair, out of the charge (k, 3).
        dt: Δt_{n+1/2}; dt_avg: (Δt_{n−1/2} + Δt_{n+1/2}) / 2; mu: Coulomb friction coefficient (≥ 0).
        force: (k, 3) output, the force on a (−force on b). fn: (k,) output, F_N.
        state: (k,) output, 0 open, 1 stuck, 2 sliding.
    """
    for i in range(len(pa)):
        a, b = pa[i], pb[i]
        inv = 1.0 / mass[a] + 1.0 / mass[b]
        nx, ny, nz = normal[i, 0], normal[i, 1], normal[i, 2]
        rx = vel[a, 0] + dt_avg * acc[a, 0] - vel[b, 0] - dt_avg * acc[b, 0]
        ry = vel[a, 1] + dt_avg * acc[a, 1] - vel[b, 1] - dt_avg * acc[b, 1]
        rz = vel[a, 2] + dt_avg * acc[a, 2] - vel[b, 2] - dt_avg * acc[b, 2]
        rn = rx * nx + ry * ny + rz * nz
        g = (x[a, 0] - x[b, 0]) * nx + (x[a, 1] - x[b, 1]) * ny + (x[a, 2] - x[b, 2]) * nz
        gp = g + dt * rn
        if gp >= 0.0:
            force[i, 0] = force[i, 1] = force[i, 2] = 0.0
            fn[i] = 0.0
            state[i] = 0
            continue
        f_n = -gp / (dt * dt_avg * inv)
        tx, ty, tz = rx - rn * nx, ry - rn * ny, rz - rn * nz
        sx, sy, sz = -tx / (dt_avg * inv), -ty / (dt_avg * inv), -tz / (dt_avg * inv)
        s = math.sqrt(sx * sx + sy * sy + sz * sz)
        cap = mu * f_n
        if s <= cap:
            state[i] = 1
        else:
            k = cap / s
            sx, sy, sz = k * sx, k * sy, k * sz
            state[i] = 2
        force[i, 0] = f_n * nx + sx
        force[i, 1] = f_n * ny + sy
        force[i, 2] = f_n * nz + sz
        fn[i] = f_n


@numba.njit(cache=True, error_model="numpy")
def pair_work(vel, acc, mass, pa, pb, normal, force, fn, dt_prev, dt, dt_avg, count, out):
    """Add the pairs' normal and tangential work over the two half steps around this force to out[0:2]
    (pairs with count False skipped: another rank counts them).

    vel, acc: v^{n−1/2} and a^n before the contact forces were added."""
    for i in range(len(pa)):
        if not count[i] or (fn[i] == 0.0 and force[i, 0] == 0.0 and force[i, 1] == 0.0 and force[i, 2] == 0.0):
            continue
        a, b = pa[i], pb[i]
        inv = 1.0 / mass[a] + 1.0 / mass[b]
        wn = 0.0
        wt = 0.0
        for k in range(3):
            before = dt_prev * (vel[a, k] - vel[b, k])
            after = dt * (vel[a, k] + dt_avg * acc[a, k] - vel[b, k] - dt_avg * acc[b, k]
                          + dt_avg * inv * force[i, k])
            d = 0.5 * (before + after)
            fnk = fn[i] * normal[i, k]
            wn += fnk * d
            wt += (force[i, k] - fnk) * d
        out[0] += wn
        out[1] += wt


@numba.njit(cache=True, error_model="numpy")
def _wall_normals(x, tri, out):
    """Area vectors of the wall facets (oriented out of the charge), a third to each node, into out."""
    for i in range(tri.shape[0]):
        i0, i1, i2 = tri[i, 0], tri[i, 1], tri[i, 2]
        ax, ay, az = x[i1, 0] - x[i0, 0], x[i1, 1] - x[i0, 1], x[i1, 2] - x[i0, 2]
        bx, by, bz = x[i2, 0] - x[i0, 0], x[i2, 1] - x[i0, 1], x[i2, 2] - x[i0, 2]
        cx, cy, cz = (ay * bz - az * by) / 6.0, (az * bx - ax * bz) / 6.0, (ax * by - ay * bx) / 6.0
        for j in range(3):
            out[tri[i, j], 0] += cx
            out[tri[i, j], 1] += cy
            out[tri[i, j], 2] += cz


class ShellChargeContact:
    """The contact of a split cavity wall, hooked into an ExplicitSolver (``solver.interface``).

    Args:
        solver: fepen.explicit.ExplicitSolver; material 0 the shell, 1 the charge.
        facet_tags: the mesh's facet tags (CHARGE_FACE: the charge's side of the wall).
        friction: Coulomb coefficient μ ≥ 0.

    Attributes:
        pa, pb: local shell and charge node of each pair held on this rank.
        force, fn, state: the last contact forces (on a), normal forces and states (0 open, 1 stuck, 2 sliding).
        count: pairs this rank counts in sums (its shell node is owned).
    """

    def __init__(self, solver, facet_tags, friction: float):
        from dolfinx import la

        from fepen.errors import SimulationError
        from fepen.surface import oriented_facets

        self.solver, self.mu = solver, float(friction)
        s = solver
        self.tri = oriented_facets(s.V, facet_tags, geometry.CHARGE_FACE)
        self._nvec = la.vector(s.V.dofmap.index_map, bs=3)
        self.nodal_n = self._nvec.array.reshape(-1, 3)
        # wall nodes: those of the owned wall facets, marked and ghost-summed
        mark = la.vector(s.V.dofmap.index_map, bs=1)
        mark.array[np.unique(self.tri)] = 1.0
        mark.scatter_reverse(la.ScatterMode.add)
        mark.scatter_forward()
        charge_wall = np.flatnonzero(mark.array[: s.n_nodes] > 0.0)
        # their twins: the local shell node at the same reference place (to round-off: the dof
        # coordinates are interpolated)
        from scipy.spatial import cKDTree

        shell_nodes = np.flatnonzero(s.mass_by_material[:, 0] > 0.0)
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
        self.state = np.zeros(k, dtype=np.int8)
        self.normal = np.zeros((k, 3))
        self._work = np.zeros(2)
        self.X_pairs = s.X[self.pb]
        # constant over the run: which pair ends this rank owns (it applies their forces), their masses
        self._a_own, self._b_own = np.flatnonzero(self.pa < n), np.flatnonzero(self.pb < n)
        self._inv_ma = 1.0 / s.mass[self.pa[self._a_own], None]
        self._inv_mb = 1.0 / s.mass[self.pb[self._b_own], None]

    def normals(self, x=None) -> np.ndarray:
        """Unit normals out of the charge at the pairs, current configuration (x: the current positions,
        if at hand)."""
        from dolfinx import la

        s = self.solver
        self.nodal_n[:] = 0.0
        _wall_normals(s.positions() if x is None else x, self.tri, self.nodal_n)
        self._nvec.scatter_reverse(la.ScatterMode.add)
        self._nvec.scatter_forward()
        nn = self.nodal_n[self.pb]
        return nn / np.linalg.norm(nn, axis=1)[:, None]

    def __call__(self, solver) -> None:
        """Add the contact forces of the coming step to solver.acc (owned nodes), then refresh the ghosts."""
        s = solver
        dt, dt_avg = s.dt, 0.5 * (s.dt_prev + s.dt)
        x = s._x  # X + U, as the solver's last force evaluation left it
        self.normal = self.normals(x)
        pair_forces(x, s.Vel, s.acc, s.mass, self.pa, self.pb, self.normal, dt, dt_avg, self.mu,
                    self.force, self.fn, self.state)
        self._work[:] = 0.0
        pair_work(s.Vel, s.acc, s.mass, self.pa, self.pb, self.normal, self.force, self.fn, s.dt_prev, dt,
                  dt_avg, self.count, self._work)
        s._w_if_n += self._work[0]
        s._w_if_t += self._work[1]
        ia, ib = self._a_own, self._b_own
        s.acc[self.pa[ia]] += self.force[ia] * self._inv_ma
        s.acc[self.pb[ib]] -= self.force[ib] * self._inv_mb
        s.a_fn.x.scatter_forward()

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
        counts = c.allreduce(np.array([np.sum(self.state[m] == k) for k in (0, 2)], dtype=float), op=MPI.SUM)
        return {"gap_max_mm": mx[0] * 1e3, "penetration_max_mm": mx[1] * 1e3, "slip_max_mm": mx[2] * 1e3,
                "free_fraction": counts[0] / max(self.n_pairs, 1), "sliding_fraction": counts[1] / max(self.n_pairs, 1)}
