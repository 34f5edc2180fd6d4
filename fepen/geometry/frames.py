"""The projectile's frame in the world: its axis from the tracked nose tip and tail centre, the rotation that
turns the reference body's axis onto it, and the striking attitude and rates in three dimensions."""

from __future__ import annotations

import math

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


def rotation_about(axis: np.ndarray, angle: float) -> np.ndarray:
    """The rotation (3 × 3) by ``angle`` (rad, right-handed) about the unit vector ``axis`` (Rodrigues)."""
    k = np.asarray(axis, dtype=float)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * K @ K


#: the plane of fire's normal (the scene's z): the velocity and the target's normal span the plane of fire
PLANE_NORMAL = np.array([0.0, 0.0, 1.0])


def striking_rotation(obliquity: float, attack: float, plane: float) -> np.ndarray:
    """The body's turn at impact (3 × 3) from its reference attitude (axis along −y, tail to nose), about its
    nose tip (docs/theory.md §7): first along the velocity, at the obliquity α about z; then by the attack ϑ
    about k = cos φ z + sin φ (d × z), d the velocity's direction, so that φ = 0 turns the nose in the plane of
    fire toward +x (the axis at α + ϑ from the normal) and φ = 90° out of it toward +z.

    Args:
        obliquity, attack, plane: α, ϑ and φ (rad).

    Returns:
        R, a proper rotation.
    """
    if plane == 0.0:  # in the plane of fire: one turn about z by α + ϑ
        th = obliquity + attack
        return np.array([[math.cos(th), -math.sin(th), 0.0], [math.sin(th), math.cos(th), 0.0], [0.0, 0.0, 1.0]])
    R0 = rotation_about(PLANE_NORMAL, obliquity)
    d = R0 @ np.array([0.0, -1.0, 0.0])
    k = math.cos(plane) * PLANE_NORMAL + math.sin(plane) * np.cross(d, PLANE_NORMAL)
    return rotation_about(k / np.linalg.norm(k), attack) @ R0


def striking_rate(R: np.ndarray, pitch: float, yaw: float) -> np.ndarray:
    """The body's angular velocity at impact (rad/s, world): ``pitch`` about z, turning the nose in the plane
    of fire toward +x; ``yaw`` about a × z / |a × z|, a the nose's direction R (0, −1, 0), turning the nose out
    of the plane toward +z."""
    a = R @ np.array([0.0, -1.0, 0.0])
    u = np.cross(a, PLANE_NORMAL)
    return pitch * PLANE_NORMAL + yaw * u / np.linalg.norm(u)
