"""Element erosion on the explicit solver (docs/theory.md §15): cells past the criteria of
fepen.laws.erosion are removed (fepen.solver.explicit.ExplicitSolver.remove_cells: their mass and kinetic
energy accounted), and the faces they expose become loaded surface with their own flat normals and areas.

Faces are matched across ranks by the global numbers of their three nodes, so an erosion on one rank
exposes its neighbour's face on another.
"""

from __future__ import annotations

import numpy as np
from mpi4py import MPI

from fepen.laws import erosion as law

__all__ = ["Erosion"]

#: the three nodes of the face opposite each of a tetrahedron's four nodes
_FACES = np.array([[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]])


class Erosion:
    """Element erosion of an ExplicitSolver and its loaded Surface.

    Args:
        solver: the ExplicitSolver.
        surface: its loaded Surface (fepen.solver.surface), or None (no target).
        strain: erosion strain (equivalent plastic strain), or None.
        step_ratio: erode a cell whose own stable step falls below this times the initial step.
    """

    def __init__(self, solver, surface, strain: float | None, step_ratio: float):
        self.solver, self.surface = solver, surface
        self.strain, self.step_ratio = strain, step_ratio
        self.count = 0  # cells eroded, all ranks
        self._codes = None  # every local cell's face codes, built at the first erosion
        imap = solver.V.dofmap.index_map
        self._global = np.asarray(imap.local_to_global(np.arange(solver.n_nodes, dtype=np.int32)), dtype=np.int64)
        self._n_global = imap.size_global

    def _face_codes(self, cells: np.ndarray) -> np.ndarray:
        """One int64 code per face (4 per cell, in _FACES order) from its nodes' sorted global numbers."""
        if self._n_global > 2_000_000:
            raise NotImplementedError("erosion's face matching supports meshes of up to 2 million nodes")
        g = np.sort(self._global[self.solver.dofs[cells][:, _FACES]], axis=2)  # (k, 4, 3)
        N = self._n_global
        return ((g[..., 0] * N + g[..., 1]) * N + g[..., 2]).reshape(-1)

    def check(self) -> int:
        """Erode the live cells past the criteria (collective). Returns how many, all ranks."""
        s = self.solver
        step = s.cell_dt * (s.safety * s.step_gain)
        cells = np.flatnonzero(law.failed(s.eps_p, step, s.dt0, self.strain, self.step_ratio) & (s.mat >= 0))
        n = s.comm.allreduce(len(cells), op=MPI.SUM)
        if n == 0:
            return 0
        dead = np.concatenate(s.comm.allgather(self._face_codes(cells)))
        s.remove_cells(cells)
        if self.surface is not None:
            self._expose(cells, dead)
        self.count += n
        return n

    def _expose(self, cells: np.ndarray, dead_codes: np.ndarray) -> None:
        """Drop the facets of the eroded cells; load the faces of live cells they shared."""
        s, surf = self.solver, self.surface
        surf.keep(s.mat[surf.cell] >= 0)
        if self._codes is None:
            self._codes = self._face_codes(np.arange(s.n_cells))
        hit = np.flatnonzero(np.isin(self._codes, dead_codes))
        cell, k = hit // 4, hit % 4
        live = s.mat[cell] >= 0
        cell, k = cell[live], k[live]
        if not len(cell):
            return
        tri = s.dofs[cell[:, None], _FACES[k]]
        opp = s.dofs[cell, k]
        X = s.X
        p = X[tri]
        out = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p.mean(axis=1) - X[opp])
        flip = out < 0.0
        tri[flip] = tri[flip][:, [0, 2, 1]]
        surf.append_flat(X, tri, cell)
