"""Tetrahedron geometry on plain arrays, against closed forms."""

import numpy as np

from fepen.geometry import tetra

REGULAR = np.array([[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0]])


def test_regular_tetrahedron():
    edge = np.linalg.norm(REGULAR[0] - REGULAR[1])
    p = REGULAR[None]
    assert np.isclose(abs(tetra.signed_volumes(p)[0]), edge**3 / (6 * np.sqrt(2)), rtol=1e-14)
    assert np.isclose(tetra.shortest_altitudes(p)[0], np.sqrt(2.0 / 3.0) * edge, rtol=1e-14)
    assert np.isclose(tetra.mean_ratio(p)[0], 1.0, rtol=1e-12)


def test_orientation_scale_and_degeneracy():
    p = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]], dtype=float)
    assert np.isclose(tetra.signed_volumes(p)[0], 1 / 6)
    assert np.isclose(tetra.signed_volumes(p[:, [1, 0, 2, 3]])[0], -1 / 6)
    # altitude of the unit corner tet: distance from origin to plane x + y + z = 1
    assert np.isclose(tetra.shortest_altitudes(p)[0], 1 / np.sqrt(3))
    assert np.isclose(tetra.shortest_altitudes(3.0 * p)[0], 3 / np.sqrt(3))
    assert np.isclose(tetra.mean_ratio(7.0 * p)[0], tetra.mean_ratio(p)[0])
    flat = p.copy()
    flat[0, 3] = [0.3, 0.3, 0.0]
    assert tetra.shortest_altitudes(flat)[0] == 0.0 and tetra.mean_ratio(flat)[0] == 0.0


def test_dilatational_speed_of_steel():
    # steel, E = 210 GPa, nu = 0.3, rho = 7850: c_d = 5.9 km/s; nu = 0 gives the bar speed
    assert np.isclose(tetra.dilatational_speed(210e9, 0.3, 7850.0), 6001.0, rtol=1e-3)
    assert np.isclose(tetra.dilatational_speed(210e9, 0.0, 7850.0), np.sqrt(210e9 / 7850.0))
