"""The concrete target acting on the deformable projectile: the nodal external force of each step
(docs/theory.md §10).

Each step: the load points of the deformed surface (fepen.solver.surface) → the target law on them
(fepen.laws.target.load_on_points) → forces shared to the facets' nodes, summed in the facets' canonical
order whatever rank holds them, added to the owned nodes' external force.
"""

from __future__ import annotations

from time import perf_counter

import numba
import numpy as np
from mpi4py import MPI

from fepen.geometry.frames import REFERENCE_AXIS, rotation_onto, unit_axis
from fepen.laws import target as tg
from fepen.solver import assembly, probes, traffic
from fepen.solver.surface import Surface


class _Settled:
    """An attribute of TargetLoad's last totals: read, it settles a pending reduction first (TargetLoad._settle);
    set, it replaces the value and drops the pending one."""

    def __set_name__(self, owner, name):
        self.key = "_" + name

    def __get__(self, obj, objtype=None):
        if obj is None:
            return self
        obj._settle()
        return getattr(obj, self.key)

    def __set__(self, obj, value):
        setattr(obj, self.key, value)
        obj._pending = None


class TargetLoad:
    """External force of the concrete target on an ExplicitSolver (an explicit.Load).

    The same numbers on any partition: the points' forces reach their nodes in the facets' canonical order
    (fepen.solver.assembly.NodalSum), and the total force that scales the crater is an exact sum.

    Args:
        solver: the ExplicitSolver.
        surf: its Surface (owned outer facets).
        law: the TargetLaw.
        tip, tail: (owner, local) node handles of the nose tip and tail centre (probes.node_at).
        crater: a ForrestalCrater for the linear crater, else None.
        tunnel: keep the tunnel the projectile opens (fepen.laws.tunnel). Its shoulder is found on the
            reference surface of all ranks; each step records a station and pushes the wall out where the points
            press it, the wall's radii taken as their largest over the ranks, so the tunnel is the same on any
            partition.
        points: "facets", one load point per outer facet, its force shared by the facet's three nodes; or
            "nodes", one per owned surface node (fepen.solver.node_points), its force the node's.
    """

    def __init__(self, solver, surf: Surface, law: tg.TargetLaw, tip, tail, crater=None, tunnel: bool = False,
                 points: str = "facets"):
        self.surf, self.law, self.tip, self.tail, self.crater = surf, law, tip, tail, crater
        self.nodal = None
        if points == "nodes":
            from fepen.solver.node_points import NodePoints

            self.nodal = NodePoints(solver, surf)
        self.tunnel = None
        comm = solver.comm
        a0 = comm.allreduce(float(np.max(surf.radius, initial=0.0)), op=MPI.MAX)
        wide = surf.radius >= (1.0 - 1e-3) * a0
        xi_sh = comm.allreduce(float(np.min(surf.X[wide, 1], initial=np.inf)), op=MPI.MIN)
        length = comm.allreduce(float(np.max(surf.X[:, 1], initial=-np.inf)), op=MPI.MAX)
        self.xi_sh, self.length, self.calibre = xi_sh, length, 2.0 * a0
        self.last_force = np.zeros((0, 3))  # the points' forces of the last step (this rank's)
        self.axis = None  # the body's unit axis, tail to nose, at the last call (every rank's the same)
        #: the target's angular impulse about O (N m s): up to the last history row (the same on every rank),
        #: and this rank's part since then; the moment about O of this rank's points at the last step
        self.angular_impulse = np.zeros(3)
        self.angular_since, self.moment_o = np.zeros(3), np.zeros(3)
        self.last_X = np.zeros((0, 3))  # and those points' reference positions
        self.last_area, self.last_n = np.zeros(0), np.zeros((0, 3))  # and their areas and normals
        if tunnel:
            from fepen.laws.tunnel import Tunnel

            self.tunnel = Tunnel(xi_sh, a0)
        self._pending = None  # the last step's totals left to their readers (_settle)
        self._x_all = None  # the node positions of the last call
        self._xi = self._xi_of = None  # the points' body-axial distances, and the positions they were taken from
        self.force = np.zeros(3)
        self.contact_nodes = 0
        self.area = 0.0
        self.wear = None  # a fepen.solver.recession.Recession fed each step's point loads, or None
        self._nodes = np.zeros((solver.n_nodes, 3))
        self._sum = None  # the facets' NodalSum, rebuilt when the facets change (erosion; collective)
        self._sum_version = -1

    def body_rotation(self) -> np.ndarray | None:
        """The body's turn from its reference axis onto its tip-tail axis at the last call (3 × 3; None before the
        first): the frame the nose's wear recedes in (fepen.solver.reference.change_reference)."""
        if self.axis is None:
            return None
        return rotation_onto(REFERENCE_AXIS, self.axis)

    def _facet_sum(self, solver) -> assembly.NodalSum:
        if self._sum is None or self._sum_version != self.surf.version:
            tri = self.surf.tri
            self._sum = assembly.NodalSum(solver.comm, solver.V.dofmap.index_map, tri,
                                          assembly.input_keys(tri, solver.node.input_index))
            self._sum_version = self.surf.version
        return self._sum

    def __call__(self, solver, dt: float) -> None:
        # from X and U (a load may be evaluated on a state set by hand: wear playback), into a kept buffer
        if self._x_all is None or self._x_all.shape != solver.X.shape:
            self._x_all = np.empty_like(solver.X)
        x_all = np.add(solver.X, solver.U, out=self._x_all)
        t0 = perf_counter()
        tip, tail = probes.node_values(solver, (self.tip, self.tail), x_all)  # one reduction for both
        comm_s = perf_counter() - t0
        if solver.comm.size > 1:
            traffic.count("nose_axis", 1, 6 * traffic.WORD, traffic.rounds(solver.comm.size), t0)
        axis = unit_axis(tip, tail)
        self.axis = axis
        comm = solver.comm

        hit = None  # the loaded points (whose force is not zero)
        # without a linear crater nothing in the step needs the totals over the ranks: the history rows and
        # checkpoints take them when they read them (force, contact_nodes, area), from the same terms
        deferred = self.crater is None

        def reduce(f, sums):
            """All ranks' totals in one reduction: the force exactly, the loaded count and area (deferred: this
            rank's, the reduction left to _settle)."""
            nonlocal comm_s, hit
            hit = _loaded_rows(f)
            if deferred:
                return sums
            t1 = perf_counter()
            out = _totals(f, hit, sums[tg.SUM_LOADED:tg.SUM_AREA + 1], comm)
            comm_s += perf_counter() - t1
            return out

        s = self.surf if self.nodal is None else self.nodal
        x, v, area, n = s.kinematics(x_all, solver.Vel)
        xi = None
        if self.tunnel is not None:  # the shoulder on the deformed axis, tip to tail
            self.tunnel.at(tip - self.tunnel.xi_sh * axis, axis)
            self.tunnel.commit = True
            if self._xi_of is not s.X:  # the points' distances behind the tip (a rebuilt surface: new arrays)
                self._xi, self._xi_of = np.ascontiguousarray(s.X[:, 1]), s.X
            xi = self._xi
        load = tg.load_on_points(self.law, x, v, n, area, s.radius, s.R_meridian, s.sin_phi0, axis, self.crater,
                                 -tip[1], reduce, tunnel=self.tunnel, body_xi=xi)
        # the target's moment about O on this rank's points (Σ x × f: a facet's thirds at its corners have its
        # centroid's moment), integrated by the trapezoid rule, whose weights are the central difference's
        m_o = _moment(x, load.force, hit)  # hit: reduce's, which load_on_points always calls
        self.angular_since += 0.5 * dt * (self.moment_o + m_o)
        self.moment_o = m_o
        if self.tunnel is not None and comm.size > 1:  # every rank's pushes of the wall
            t1 = perf_counter()
            radii = self.tunnel.recorded()
            comm.Allreduce(MPI.IN_PLACE, radii, op=MPI.MAX)
            comm_s += perf_counter() - t1
            traffic.count("tunnel", 1, radii.nbytes, traffic.rounds(comm.size), t1)
        if self.wear is not None:
            self.wear.add(load.force, n, v, dt)
        t1 = perf_counter()
        if self.nodal is None:
            facets = self._facet_sum(solver)
            facets(load.force / 3.0, self._nodes)  # a third to each corner
            traffic.count("load_points", 1, 3 * traffic.WORD * facets.sent, facets.sent_ranks, t1)
        else:
            self.nodal.to_nodes(load.force, self._nodes)  # each point's force is its node's
        comm_s += perf_counter() - t1
        n_own = solver.n_owned
        solver.fext[:n_own] += self._nodes[:n_own]
        if deferred:
            self._pending = (hit, np.array([load.loaded, load.area], dtype=float), comm)
        else:
            self.force, self.contact_nodes, self.area = load.total, load.loaded, load.area
        self.last_force, self.last_area, self.last_n = load.force, area, n
        # the points it acted on: an erosion may rebuild the surface before the history row splits it
        self.last_X = (self.surf if self.nodal is None else self.nodal).X
        solver.clock.times.target_comm += comm_s

    def _settle(self) -> None:
        """The last step's totals over the ranks, if the step left them to its readers (collective then: the
        history rows and checkpoints read them on every rank)."""
        if self._pending is not None:
            hit, local, comm = self._pending
            self._pending = None
            out = _totals(self.last_force, hit, local, comm)
            self._force, self._contact_nodes, self._area = (out[tg.SUM_FORCE:tg.SUM_FORCE + 3], int(out[tg.SUM_LOADED]),
                                                            float(out[tg.SUM_AREA]))

    # the last step's totals over the ranks (collective to read while pending: the history rows and
    # checkpoints read them on every rank): force (N, world frame), contact_nodes (loaded points), area (m²)
    force = _Settled()
    contact_nodes = _Settled()
    area = _Settled()

    def surface_fields(self, solver) -> dict[str, np.ndarray]:
        """The load the last step applied, as nodal fields (fields.xdmf; collective): ``target_force_N`` the
        target's force on each owned node (N; their sum over the nodes is the history's target force), and
        the traction it makes on the surface around the node, ``target_normal_stress_Pa`` (pressing in:
        positive) and ``target_friction_traction_Pa`` (the tangential part's size): with facet points, each
        facet's σ_n = −f·n/A and |f − (f·n) n|/A averaged over the node's facets weighted by their areas;
        with node points, the node's own."""
        f, a, n = self.last_force, self.last_area, self.last_n
        safe = np.maximum(a, 1e-300)
        fn = np.einsum("ij,ij->i", f, n) if len(f) else np.zeros(0)
        sigma = -fn / safe
        tau = np.linalg.norm(f - fn[:, None] * n, axis=1) / safe if len(f) else np.zeros(0)
        sig_node, tau_node = np.zeros(solver.n_nodes), np.zeros(solver.n_nodes)
        if self.nodal is None:
            out = np.zeros((solver.n_nodes, 3))
            third = a / 3.0
            self._facet_sum(solver)(np.ascontiguousarray(np.column_stack([third * sigma, third * tau, third])), out)
            hit = out[:, 2] > 0.0
            sig_node[hit], tau_node[hit] = out[hit, 0] / out[hit, 2], out[hit, 1] / out[hit, 2]
        else:
            sig_node[self.nodal.node], tau_node[self.nodal.node] = sigma, tau
        return {"target_force_N": self._nodes.copy(), "target_normal_stress_Pa": sig_node,
                "target_friction_traction_Pa": tau_node}

    #: the fields it writes into fields.xdmf (nodal vectors, nodal scalars; surface_fields gives them)
    field_names: tuple = (("target_force_N",), ("target_normal_stress_Pa", "target_friction_traction_Pa"))

    def stop_rule(self, run) -> str | None:
        """The run's rules in a target (fepen.runs.deformable.DeformableRun.target_rules)."""
        return run.target_rules()

    def angular_impulse_now(self, comm) -> np.ndarray:
        """The target's angular impulse about O since the run began (N m s; collective, exact: the same on any
        partition), folded into angular_impulse."""
        self.angular_impulse = self.angular_impulse + assembly.exact_sum(self.angular_since[None, :], comm)
        self.angular_since = np.zeros(3)
        return self.angular_impulse

    @property
    def sent_terms(self) -> int:
        """The point forces a step sends to other ranks' nodes (fepen.solver.traffic; facet points: their nodal
        sum's terms, 0 on one rank; node points: none)."""
        return self._sum.sent if self.nodal is None and self._sum is not None else 0

    @property
    def nodal_force(self) -> np.ndarray:
        """The target's force on each node at the last step (N, this rank's nodes, world frame)."""
        return self._nodes

    def split(self, comm) -> list[float]:
        """The last step's load by zone (fepen.laws.tunnel.zones: nose, shank, tail): the size of each zone's
        resultant (N), then its loaded points, summed exactly over the ranks (collective; the same on any
        partition)."""
        from fepen.laws import tunnel

        f = self.last_force
        zone = tunnel.zones(self.last_X[:, 1], self.xi_sh, self.length, self.calibre)
        hit = np.flatnonzero(np.any(f != 0.0, axis=1)) if len(f) == len(zone) else np.zeros(0, dtype=np.int64)
        terms = np.zeros((len(hit), 12))
        for j in range(3):
            terms[np.arange(len(hit)), 4 * zone[hit] + j] = f[hit, j]
        terms[np.arange(len(hit)), 4 * zone[hit] + 3] = 1.0
        sums = assembly.exact_sum(terms, comm).reshape(3, 4)
        return [*np.linalg.norm(sums[:, :3], axis=1).tolist(), *sums[:, 3].tolist()]

    def state(self) -> dict[str, np.ndarray]:
        """The load's last totals and the angular impulse's sums (for checkpoints; this rank's)."""
        out = {"force": np.asarray(self.force, dtype=float), "totals": np.array([self.contact_nodes, self.area]),
               # the angular impulse as of the last history row, this rank's since, and its last moment about O
               "angular": np.concatenate([self.angular_impulse, self.angular_since, self.moment_o])}
        if self.tunnel is not None:
            out["tunnel"] = self.tunnel.state()
        return out

    def restore(self, state: dict) -> None:
        """Put back what state() returned."""
        self.force = np.array(state["force"][:3])
        self.contact_nodes, self.area = int(state["totals"][0]), float(state["totals"][1])
        if "angular" in state:
            a = np.asarray(state["angular"], dtype=float)
            self.angular_impulse, self.angular_since, self.moment_o = a[:3].copy(), a[3:6].copy(), a[6:9].copy()
        if self.tunnel is not None and "tunnel" in state:
            self.tunnel.restore(np.asarray(state["tunnel"]))


def _totals(f: np.ndarray, hit: np.ndarray, local, comm) -> np.ndarray:
    """(force (3), loaded points, loaded area) over the ranks: the loaded points' forces f[hit] summed exactly
    with each rank's count and area (local (2,)), in one reduction (the same on any partition)."""
    terms = np.zeros((len(hit) + 1, tg.SUM_COUNT))  # target_kernel.h's sums
    terms[:-1, tg.SUM_FORCE:tg.SUM_FORCE + 3] = f[hit]
    terms[-1, tg.SUM_LOADED:tg.SUM_AREA + 1] = local
    return assembly.exact_sum(terms, comm)


@numba.njit(cache=True)
def _loaded_rows(f):
    """The rows of f (k, 3) with a component that is not zero."""
    out = np.empty(len(f), dtype=np.int64)
    n = 0
    for i in range(len(f)):
        if f[i, 0] != 0.0 or f[i, 1] != 0.0 or f[i, 2] != 0.0:
            out[n] = i
            n += 1
    return out[:n]


@numba.njit(cache=True)
def _moment(x, f, rows):
    """Σ x × f over the given rows (the loaded points: the others add nothing), in row order."""
    m = np.zeros(3)
    for i in rows:
        m[0] += x[i, 1] * f[i, 2] - x[i, 2] * f[i, 1]
        m[1] += x[i, 2] * f[i, 0] - x[i, 0] * f[i, 2]
        m[2] += x[i, 0] * f[i, 1] - x[i, 1] * f[i, 0]
    return m
