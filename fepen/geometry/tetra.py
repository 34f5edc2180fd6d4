"""Geometry of linear tetrahedra on plain arrays: volumes, altitudes, shape quality, wave speeds.

Everything takes node coordinates ``p`` of shape (n_cells, 4, 3) and works without a mesh library.
"""

from __future__ import annotations

import numpy as np


def signed_volumes(p: np.ndarray) -> np.ndarray:
    """Signed volumes (m^3); positive for a right-handed ordering of the four nodes."""
    return np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0]) / 6.0


def face_areas(p: np.ndarray) -> np.ndarray:
    """Areas of the four faces, shape (n, 4); face i is opposite node i."""
    areas = np.empty((p.shape[0], 4))
    for i in range(4):
        a, b, c = (p[:, j] for j in range(4) if j != i)
        areas[:, i] = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    return areas


def shortest_altitudes(p: np.ndarray) -> np.ndarray:
    """Shortest altitude of each tetrahedron, 3 V / (largest face area) (m).

    This is the length that sets the stable explicit step of a linear tetrahedron (the distance a
    dilatational wave crosses the element in its thinnest direction)."""
    return 3.0 * np.abs(signed_volumes(p)) / face_areas(p).max(axis=1)


def mean_ratio(p: np.ndarray) -> np.ndarray:
    """Mean-ratio shape quality 12 (3V)^(2/3) / sum(edge^2): 1 for the regular tetrahedron, 0 if flat."""
    edges = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    s = sum(np.sum((p[:, i] - p[:, j]) ** 2, axis=1) for i, j in edges)
    return 12.0 * (3.0 * np.abs(signed_volumes(p))) ** (2.0 / 3.0) / s


def dilatational_speed(E, nu, rho):
    """Dilatational (P) wave speed sqrt(E (1 - nu) / (rho (1 + nu)(1 - 2 nu))) (m/s)."""
    return np.sqrt(E * (1.0 - nu) / (rho * (1.0 + nu) * (1.0 - 2.0 * nu)))
