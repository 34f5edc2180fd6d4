"""Plane cuts of tetrahedra (fepen.slices.cut), mesh-free: the cut polygons of a meshed cube tile the
cube's cross-section exactly, whatever the plane, including planes through mesh nodes and faces."""

import numpy as np
import pytest

from fepen.post.slices import cut, polygon_area


def cube_tets(n: int = 3) -> np.ndarray:
    """The unit cube in n^3 sub-cubes of six tetrahedra each (Kuhn), as (6 n^3, 4, 3) vertex arrays."""
    kuhn = [(0, 1, 3, 7), (0, 1, 5, 7), (0, 2, 3, 7), (0, 2, 6, 7), (0, 4, 5, 7), (0, 4, 6, 7)]
    corner = np.array([[(k >> 0) & 1, (k >> 1) & 1, (k >> 2) & 1] for k in range(8)], dtype=float)
    tets = []
    for i in range(n):
        for j in range(n):
            for k in range(n):
                p = (corner + [i, j, k]) / n
                tets += [p[list(t)] for t in kuhn]
    return np.array(tets)


@pytest.mark.parametrize("offset", [0.37, 1.0 / 3.0, 0.5])
def test_axis_aligned_cuts_tile_the_section(offset):
    """y = const, between node layers or through one (1/3): area 1, each piece once."""
    polys, cells = cut(cube_tets(), [0.0, 1.0, 0.0], offset, np.array([[1.0, 0, 0], [0, 0, 1.0]]))
    assert sum(polygon_area(q) for q in polys) == pytest.approx(1.0, rel=1e-12)
    assert len(set(cells.tolist())) == len(cells)
    assert all(len(q) in (3, 4) for q in polys)


def test_oblique_cut_has_the_diagonal_area():
    """The plane x + y = 1 through the cube: a sqrt(2) x 1 rectangle."""
    nrm = np.array([1.0, 1.0, 0.0]) / np.sqrt(2.0)
    basis = np.array([[1.0, -1.0, 0.0] / np.sqrt(2.0), [0.0, 0.0, 1.0]])
    polys, _ = cut(cube_tets(), nrm, 1.0 / np.sqrt(2.0), basis)
    assert sum(polygon_area(q) for q in polys) == pytest.approx(np.sqrt(2.0), rel=1e-12)


def test_a_plane_missing_the_mesh_cuts_nothing():
    polys, cells = cut(cube_tets(), [0.0, 1.0, 0.0], 1.5, np.array([[1.0, 0, 0], [0, 0, 1.0]]))
    assert polys == [] and len(cells) == 0
