"""Element erosion on the explicit solver (docs/theory.md §15): cells past the criteria of
fepen.laws.erosion are removed (fepen.solver.reference.remove_cells: their mass and kinetic
energy accounted), and the faces they expose become loaded surface with their own flat normals and areas.

Faces are matched across ranks by the global numbers of their three nodes, so an erosion on one rank
exposes its neighbour's face on another.
"""

from __future__ import annotations

import numpy as np
from mpi4py import MPI

from fepen.laws import erosion as law
from fepen.solver import kernels, reference

__all__ = ["Erosion"]

#: the three nodes of the face opposite each of a tetrahedron's four nodes
_FACES = np.array([[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]])

#: the largest fraction of the cells that may invert within one step and be eroded; more stops the run
MAX_INVERTED = 0.01


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
        self._n_cells_global = solver.comm.allreduce(solver.n_cells, op=MPI.SUM)
        self.inverted = 0  # of which inverted within a step, all ranks
        self.pending = False  # cells eroded inside a step since the run last looked (take_pending)
        solver.on_inverted = self._erode_inverted

    def state(self) -> dict:
        """The count of eroded cells (for checkpoints; the mesh's state is the solver's)."""
        return {"count": self.count}

    def restore(self, state: dict) -> None:
        """Put back what state() returned."""
        self.count = int(state["count"])

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
        step = s.cell.dt * (s.clock.safety * s.clock.step_gain)
        cells = np.flatnonzero(law.failed(s.eps_p, step, s.clock.dt0, self.strain, self.step_ratio) & (s.mat >= 0))
        return self._remove(cells)

    def _erode_inverted(self, x: np.ndarray) -> bool:
        """The solver's hook for cells that inverted within a step (collective): a cell that collapses
        between two checks has passed the step criterion's limit (its stable step reaches zero), so it is
        eroded like one that failed. More than MAX_INVERTED of the cells at once is not a collapse but an
        instability: False, and the run stops."""
        s = self.solver
        J = np.empty(s.n_cells)
        kernels.cell_jacobians(x, s.dofs, s.orient, s.vol0, s.mat, J)
        cells = np.flatnonzero(~(J > 0.0) & (s.mat >= 0))
        n = s.comm.allreduce(len(cells), op=MPI.SUM)
        if n == 0 or n > MAX_INVERTED * self._n_cells_global:
            return False
        self._remove(cells)
        self.inverted += n
        self.pending = True
        return True

    def take_pending(self) -> bool:
        """Whether cells were eroded inside a step since the last call (then the run re-elects its tip
        and tail)."""
        pending, self.pending = self.pending, False
        return pending

    def _remove(self, cells: np.ndarray) -> int:
        """Erode ``cells`` (this rank's; collective). Returns how many, all ranks."""
        s = self.solver
        n = s.comm.allreduce(len(cells), op=MPI.SUM)
        if n == 0:
            return 0
        dead = np.concatenate(s.comm.allgather(self._face_codes(cells)))
        reference.remove_cells(s, cells)
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
