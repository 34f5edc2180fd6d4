"""The projectile's frame in the world: its axis from the tracked nose tip and tail centre, and the rotation that
turns the reference body's axis onto it."""

from __future__ import annotations

import numpy as np


def unit_axis(tip: np.ndarray, tail: np.ndarray) -> np.ndarray:
    """Unit vector of the projectile axis, tail to nose."""
    return (tip - tail) / np.linalg.norm(tip - tail)


#: the reference body's axis, tail to nose: the tip at the origin, the body along +y behind it
REFERENCE_AXIS = np.array([0.0, -1.0, 0.0])


def rotation_onto(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The rotation (3 × 3) that turns the unit vector ``a`` onto the unit vector ``b`` about their common normal
    (Rodrigues; the identity when they agree, a half turn about an axis normal to ``a`` when they oppose): the
    body's turn when it does not spin about its own axis, as a projectile without rifling does not.

    Args:
        a, b: unit vectors (3).

    Returns:
        R with R a = b, R R^T = I, det R = 1.
    """
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    v, c = np.cross(a, b), float(np.dot(a, b))
    if c < -1.0 + 1e-12:  # opposed: a half turn about any axis normal to a
        n = np.cross(a, [1.0, 0.0, 0.0] if abs(a[0]) < 0.9 else [0.0, 1.0, 0.0])
        n /= np.linalg.norm(n)
        return 2.0 * np.outer(n, n) - np.eye(3)
    K = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + K + K @ K / (1.0 + c)
