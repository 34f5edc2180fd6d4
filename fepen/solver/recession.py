"""Nose abrasion on the deforming mesh (docs/theory.md §14.2–§14.3): the interface heat of the load points
(fepen.laws.wear) melts mass off the nose.

By default (``zone_end`` given: the "nose" distribution, §14.3) the melted volume η Q/(h ρ) of each
application shortens the nose zone (reference y < y_c) along its axis: every node of the zone moves toward
y_c by the factor κ = 1 − ΔV/V_zone (y' = y_c − κ (y_c − y)), so the tip recedes the most and the cells
keep their shape up to the axial factor (no surface cell is flattened). Otherwise (the "surface"
distribution, §14.2) each point's own heat makes it recede along its normal:

Each step the target load hands its point forces, normals and velocities to :meth:`Recession.add`, which
shares each point's heat rate × Δt to its facet's three nodes. Every ``every`` (50) steps :meth:`apply`
(collective) turns each surface node's heat into a recession depth d_a = η Q_a / (h ρ A_a) (A_a a third of
its facets' exact reference areas), moves the node's reference position inward by d_a along its area-weighted
reference normal, and spreads the move over the ``layers`` node layers behind the surface by Jacobi
sweeps of the graph Laplacian (the move fixed on the surface, zero beyond the band and on every other
boundary, such as a cavity wall), so cells shrink gradually rather than the surface cells alone.
fepen.solver.reference.change_reference then takes the melted mass off the nodes (mass and carried kinetic
energy accounted), and the load points follow the new reference facets: the worn nose's own normals and
areas feed back into σ_n.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from mpi4py import MPI

from fepen import dolfinx_api as dx
from fepen.laws import wear
from fepen.solver import assembly, reference

__all__ = ["Recession"]

#: Jacobi sweeps of the band relaxation per application
SWEEPS = 12


class Recession:
    """Surface recession of an ExplicitSolver's loaded Surface.

    Args:
        solver: the ExplicitSolver. surface: its loaded Surface.
        mu: friction coefficient of the heat μ σ_n |v_t|. efficiency: η. enthalpy: h (J/kg).
        density: the surface material's density (kg/m³).
        every: steps between two applications. layers: node layers of the relaxed band.
    """

    def __init__(self, solver, surface, mu: float, efficiency: float, enthalpy: float, density: float,
                 every: int = 50, layers: int = 3, zone_end: float | None = None):
        self.solver, self.surface = solver, surface
        self.zone_end = zone_end
        self.contraction = 1.0  # the nose zone's length factor λ (the "nose" distribution)
        self.mu, self.efficiency, self.enthalpy, self.density = mu, efficiency, enthalpy, density
        self.every, self.layers = every, layers
        #: () -> the body's turn from its reference axis (3 × 3), the recession's frame (the model sets it from
        #: the load's tip-tail axis; by default none: the reference frame)
        self.rotation = lambda: None
        imap = solver.V.dofmap.index_map
        self._vec3 = dx.new_vector(imap, bs=3)
        self._vec1 = dx.new_vector(imap, bs=1)
        self.heat_nodes = np.zeros(solver.n_nodes)  # heat since the last application (J), this rank's facets
        self.heat_total = 0.0  # this rank's heat so far (J)
        # the heat since the last application, summed exactly (the contraction's: the same on any partition)
        self._heat_exact = assembly.ExactAccumulator(1)
        self.depth = np.zeros(solver.n_nodes)  # total recession of each node (m), ghosts consistent
        n = solver.n_nodes
        d = solver.dofs
        rows = np.concatenate([d[:, i] for i in range(4) for j in range(4) if i != j])
        cols = np.concatenate([d[:, j] for i in range(4) for j in range(4) if i != j])
        self._adjacency_all = (rows, cols, n)
        self.boundary = self._boundary_nodes()
        self._adj = None
        if zone_end is not None:
            self.zone0 = self._zone_volume()
            if not self.zone0 > 0.0:  # a flat nose: the surface recedes where heated
                self.zone_end = None

    # --------------------------------------------------------------------------------------------------
    def state(self) -> dict[str, np.ndarray]:
        """The heat and recession so far (for checkpoints)."""
        return {"heat_nodes": self.heat_nodes, "depth": self.depth, "heat_total": np.array([self.heat_total]),
                "contraction": np.array([self.contraction]), "heat_limbs": self._heat_exact.limbs}

    def restore(self, state: dict) -> None:
        """Put back what state() returned."""
        self.heat_nodes[:] = state["heat_nodes"]
        self.depth[:] = state["depth"]
        self.heat_total = float(state["heat_total"][0])
        if "contraction" in state:
            self.contraction = float(state["contraction"][0])
        if "heat_limbs" in state:
            self._heat_exact.limbs[:] = state["heat_limbs"]

    def _zone_volume(self) -> float:
        """Reference volume of the nose zone (y < zone_end) (m³, all ranks): each live owned cell's volume
        times the share of its nodes in the zone (cells across y_c count by halves, about)."""
        s = self.solver
        inside = (s.X[:, 1] < self.zone_end)[s.dofs].mean(axis=1)
        own = s.mat[: s.n_cells] >= 0
        return assembly.exact_sum(s.vol0[own] * inside[own], s.comm)

    def _zone_eroding(self) -> bool:
        """Whether a cell of the nose zone has eroded (collective): the nose no longer keeps its kind (it
        mushrooms or breaks up), so from then on each point recedes by its own heat (§14.3's limit)."""
        s = self.solver
        ahead = (s.X[s.dofs].mean(axis=1)[:, 1] < self.zone_end) & (s.mat < 0)
        return s.comm.allreduce(bool(ahead.any()), op=MPI.LOR)

    @property
    def shortening(self) -> float:
        """How much the nose zone has shortened (m)."""
        return (1.0 - self.contraction) * self.zone_end if self.zone_end is not None else 0.0
    def add(self, force: np.ndarray, n: np.ndarray, v: np.ndarray, dt: float) -> None:
        """Record one step's heat at the surface's points (their target forces, normals, velocities): the
        heat of fepen.laws.wear.heat_rates × Δt, a third to each of the point's facet nodes."""
        q = wear.heat_rates(force, n, v, self.mu) * dt
        self.heat_nodes += np.bincount(self.surface.tri.ravel(), weights=np.repeat(q / 3.0, 3),
                                       minlength=len(self.heat_nodes))
        self.heat_total += float(q.sum())
        if self.zone_end is not None:
            self._heat_exact.add(q[q > 0.0])

    def _ghost_sum(self, vec, values: np.ndarray) -> np.ndarray:
        """The sum over ranks of a nodal array (n_nodes, k), ghosts consistent."""
        arr = vec.array.reshape(len(values), -1)
        arr[:] = values.reshape(len(values), -1)
        dx.scatter_reverse_add(vec)
        vec.scatter_forward()
        return arr.reshape(values.shape).copy()

    def _boundary_nodes(self) -> np.ndarray:
        """Nodes on the mesh's boundary (ghosts included): the relaxation holds them, so that no other
        surface (a cavity wall, the charge's face) moves."""
        s = self.solver
        mesh = s.mesh
        tdim = mesh.topology.dim
        mesh.topology.create_connectivity(tdim - 1, tdim)
        mesh.topology.create_connectivity(tdim - 1, 0)
        mesh.topology.create_connectivity(tdim, 0)
        facets = dx.exterior_facets(mesh)
        f2v = mesh.topology.connectivity(tdim - 1, 0)
        c2v = mesh.topology.connectivity(tdim, 0).array.reshape(-1, 4)
        v2d = np.full(c2v.max() + 1, -1, dtype=np.int64)
        v2d[c2v.ravel()] = dx.cell_dofs(s.V).ravel()
        flag = np.zeros(s.n_nodes)
        for f in facets:
            flag[v2d[f2v.links(f)]] = 1.0
        return self._ghost_sum(self._vec1, flag) > 0.0

    def _adjacency(self) -> sp.csr_matrix:
        """Node-node adjacency through live cells (each cell sharing an edge counts once), this rank's cells."""
        s = self.solver
        dead = int(np.count_nonzero(s.mat < 0))
        if self._adj is None or self._adj[0] != dead:  # built once, again only after an erosion
            rows, cols, n = self._adjacency_all
            live = np.tile(s.mat >= 0, 12)
            self._adj = (dead, sp.csr_matrix((np.ones(int(live.sum())), (rows[live], cols[live])), shape=(n, n)))
        return self._adj[1]

    def apply(self) -> float:
        """Recede the surface by the heat gathered since the last call (collective). Returns the largest
        recession of this application (m), all ranks."""
        s, surf = self.solver, self.surface
        if self.zone_end is not None and not self._zone_eroding():
            return self._contract()
        heat = self._ghost_sum(self._vec1, self.heat_nodes)
        self.heat_nodes[:] = 0.0
        self._heat_exact.clear()
        nrm = np.zeros((s.n_nodes, 3))
        area = np.zeros(s.n_nodes)
        av = 0.5 * np.cross(s.X[surf.tri[:, 1]] - s.X[surf.tri[:, 0]], s.X[surf.tri[:, 2]] - s.X[surf.tri[:, 0]])
        a = surf.area0  # the load's own (exact-surface) reference areas: heat and area on the same patch
        idx = surf.tri.ravel()
        for k in range(3):
            nrm[:, k] = np.bincount(idx, weights=np.repeat(av[:, k], 3), minlength=s.n_nodes)
        area = np.bincount(idx, weights=np.repeat(a / 3.0, 3), minlength=s.n_nodes).astype(float)
        packed = self._ghost_sum(self._vec3, nrm)
        area = self._ghost_sum(self._vec1, area)
        norm = np.linalg.norm(packed, axis=1)
        on_surface = area > 0.0
        unit = np.zeros_like(packed)
        unit[on_surface] = packed[on_surface] / norm[on_surface, None]
        d = wear.recession_depth(heat, area, self.efficiency, self.enthalpy, self.density)
        largest = s.comm.allreduce(float(d.max(initial=0.0)), op=MPI.MAX)
        if largest <= 0.0:
            return 0.0
        dX = -d[:, None] * unit
        dX = self._relax(dX, on_surface)
        X_old = s.X.copy()
        reference.change_reference(s, dX, self.rotation())
        surf.follow_reference(X_old, s.X)
        self.depth += d
        return largest

    def _contract(self) -> float:
        """The "nose" distribution: shorten the nose zone by the volume melted since the last call
        (collective). Returns the tip's recession of this application (m)."""
        s, surf = self.solver, self.surface
        heat = float(self._heat_exact.total(s.comm)[0])
        self._heat_exact.clear()
        self.heat_nodes[:] = 0.0
        volume = wear.melted_mass(heat, self.efficiency, self.enthalpy) / self.density
        if volume <= 0.0:
            return 0.0
        old = self.contraction
        new = wear.contraction_after(old, volume, self.zone0)
        kappa = new / old
        self.contraction = new
        y = s.X[:, 1]
        zone = y < self.zone_end
        dX = np.zeros_like(s.X)
        dX[zone, 1] = (1.0 - kappa) * (self.zone_end - y[zone])
        X_old = s.X.copy()
        reference.change_reference(s, dX, self.rotation())
        surf.follow_reference(X_old, s.X)
        self.depth += dX[:, 1]
        return (1.0 - kappa) * old * self.zone_end

    def _relax(self, dX: np.ndarray, on_surface: np.ndarray) -> np.ndarray:
        """Spread the surface move over the band of ``layers`` node layers behind it (Jacobi sweeps of the
        graph Laplacian; the move held on the surface, zero beyond the band)."""
        A = self._adjacency()
        band = on_surface.astype(float)
        for _ in range(self.layers):
            band = np.maximum(band, (self._ghost_sum(self._vec1, A @ band) > 0.0).astype(float))
        inner = (band > 0.0) & ~on_surface & ~self.boundary
        if not self.solver.comm.allreduce(bool(inner.any()), op=MPI.LOR):
            return dX
        deg = self._ghost_sum(self._vec1, np.asarray(A.sum(axis=1)).ravel())
        deg[deg == 0.0] = 1.0
        out = dX.copy()
        for _ in range(SWEEPS):
            avg = self._ghost_sum(self._vec3, A @ out) / deg[:, None]
            out[inner] = avg[inner]
        return out


