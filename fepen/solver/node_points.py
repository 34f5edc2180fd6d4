"""The target's load at the surface nodes (``target.load_points = "nodes"``, the paper's discretisation;
docs/theory.md §8.5): each owned node of the outer surface is one load point, with the node's own position and
velocity, the area a third of its facets' stretched exact areas, and the normal the area-weighted mean of their
exact normals, turned with the facets. The force of a point is its node's, whole.

The facets' sums at a node are taken in one canonical order whatever rank holds the facets
(fepen.solver.assembly.NodalSum), so the points are the same on any partition.
"""

from __future__ import annotations

import numpy as np

from fepen.solver import assembly
from fepen.solver.surface import Surface


class NodePoints:
    """The owned outer-surface nodes of a Surface as load points.

    Args:
        solver: the ExplicitSolver (its V's index map and input indices, its reference positions X).
        surf: the Surface of the owned outer facets.

    Attributes:
        node: the owned nodes' local indices (p,). X: their reference positions (p, 3).
        radius, R_meridian, sin_phi0: the shape data of the law at each node (area-weighted over its facets;
            R_meridian harmonically, so that a flat facet's infinite radius counts as zero curvature).
    """

    def __init__(self, solver, surf: Surface):
        self.surf = surf
        tri = surf.tri
        self._sum = assembly.NodalSum(solver.comm, solver.V.dofmap.index_map, tri,
                                      assembly.input_keys(tri, solver.node.input_index))
        self._out = np.zeros((solver.n_nodes, 5))
        a = surf.area0 / 3.0
        ref = self._nodal(np.column_stack([a, a * surf.radius, a / surf.R_meridian, a * surf.sin_phi0,
                                           np.zeros_like(a)]))
        area = ref[:, 0]
        self.node = np.flatnonzero(area > 0.0)
        area = area[self.node]
        self.X = np.ascontiguousarray(solver.X[self.node])
        self.radius = ref[self.node, 1] / area
        curvature = ref[self.node, 2] / area
        with np.errstate(divide="ignore"):
            self.R_meridian = np.where(curvature > 0.0, 1.0 / np.maximum(curvature, 1e-300), np.inf)
        self.sin_phi0 = ref[self.node, 3] / area

    def _nodal(self, values: np.ndarray) -> np.ndarray:
        """The owned nodes' sums of the facets' values (f, 5) (collective)."""
        self._out[:] = 0.0
        self._sum(np.ascontiguousarray(values), self._out)
        return self._out

    def kinematics(self, x_all: np.ndarray, v_all: np.ndarray):
        """The points' positions, velocities, areas and unit normals (collective).

        Args:
            x_all, v_all: current positions and velocities of all local nodes (ghosts included).

        Returns:
            (x (p, 3), v (p, 3), area (p,), n (p, 3)).
        """
        _, _, area_f, n_f = self.surf.kinematics(x_all, v_all)
        a = area_f / 3.0
        out = self._nodal(np.column_stack([a, a[:, None] * n_f, np.zeros_like(a)]))[self.node]
        area = out[:, 0]
        n = out[:, 1:4] / np.maximum(np.linalg.norm(out[:, 1:4], axis=1), 1e-300)[:, None]
        return (np.ascontiguousarray(x_all[self.node]), np.ascontiguousarray(v_all[self.node]),
                np.ascontiguousarray(area), np.ascontiguousarray(n))

    def to_nodes(self, f: np.ndarray, out: np.ndarray) -> None:
        """The points' forces (p, 3) to their own nodes, whole, into out (n_nodes, 3)."""
        out[:] = 0.0
        out[self.node] = f
