"""The exact outer surface of a Shape seen from a surface mesh: which meridian segment a facet or a point lies
on, the exact normal and curvature there, and the closest point on the surface (body frame of
fepen.geometry.shape: nose tip at the origin, axis +y). The deformable and mesh-based rigid load points
(fepen.solver.surface) stand on it.
"""

from __future__ import annotations

import math

import numpy as np

from fepen.geometry.shape import Shape


def classify(shape: Shape, P3: np.ndarray, n_flat: np.ndarray) -> np.ndarray:
    """The meridian segment each flat surface triangle lies on: all three corners on it (to 1e-6 L), and
    of several, the one whose exact normal at the centroid agrees best with the triangle's.

    Args:
        shape: the exact geometry. P3: triangle corners (f, 3, 3), body frame. n_flat: their flat unit
            normals (f, 3).

    Returns:
        (f,) segment indices into shape.outer_path.
    """
    f = len(P3)
    tol = 1e-6 * shape.length
    r = np.hypot(P3[..., 0], P3[..., 2]).ravel()
    y = P3[..., 1].ravel()
    c = P3.mean(axis=1)
    rc = np.hypot(c[:, 0], c[:, 2])
    radial = np.stack([c[:, 0], np.zeros(f), c[:, 2]], axis=1) / np.maximum(rc, 1e-300)[:, None]
    best, score = np.full(f, -1), np.full(f, -np.inf)
    near, dist = np.zeros(f, dtype=np.int64), np.full(f, np.inf)
    for i, seg in enumerate(shape.outer_path):
        _, (pr, pz) = seg.closest(r, y)
        d = np.hypot(pr - r, pz - y).reshape(f, 3).max(axis=1)
        uc, _ = seg.closest(rc, c[:, 1])
        nr, nz = seg.normal(uc)
        agree = np.einsum("ij,ij->i", nr[:, None] * radial + nz[:, None] * np.array([0.0, 1.0, 0.0]), n_flat)
        take = (d < tol) & (agree > score)
        best[take], score[take] = i, agree[take]
        closer = d < dist
        near[closer], dist[closer] = i, d[closer]
    return np.where(best >= 0, best, near)


def segment_of_points(shape: Shape, X: np.ndarray) -> np.ndarray:
    """The meridian segment nearest each point (a point on an edge: the first one).

    Args:
        shape: the exact geometry. X: points (k, 3), body frame.

    Returns:
        (k,) segment indices into shape.outer_path.
    """
    r, y = np.hypot(X[:, 0], X[:, 2]), X[:, 1]
    best, dist = np.zeros(len(X), dtype=np.int64), np.full(len(X), np.inf)
    for i, seg in enumerate(shape.outer_path):
        _, (pr, pz) = seg.closest(r, y)
        d = np.hypot(pr - r, pz - y)
        closer = d < dist - 1e-12 * shape.length
        best[closer], dist[closer] = i, d[closer]
    return best


def surface_info(shape: Shape, X: np.ndarray, seg: np.ndarray | None = None):
    """Exact outward normals and curvature data of outer-surface points given in the body frame.

    Args:
        shape: the exact geometry.
        X: points on the outer surface (k, 3), body frame (tip at the origin, axis +y).
        seg: the meridian segment of each point (classify); default: the nearest.

    Returns:
        (normal (k, 3); radius (k,): distance from the axis; R_meridian (k,): meridional radius of
         curvature (inf on straight or hollow meridians); sin_phi0 (k,): sine of the angle between the
         surface and the axis, |n_y|).
    """
    X = np.asarray(X, dtype=float)
    seg = segment_of_points(shape, X) if seg is None else np.asarray(seg)
    x, y, z = X[:, 0], X[:, 1], X[:, 2]
    r = np.hypot(x, z)
    safe = np.maximum(r, 1e-300)
    radial = np.stack([x / safe, np.zeros_like(r), z / safe], axis=1)
    normal = np.zeros_like(X)
    Rm = np.full(len(X), np.inf)
    ey = np.array([0.0, 1.0, 0.0])
    for i, sg in enumerate(shape.outer_path):
        on = seg == i
        if not np.any(on):
            continue
        if sg.is_circle:  # as the ogive always was: from the arc's centre
            rc, yc = r[on] - sg.centre[0], y[on] - sg.centre[1]
            sign = 1.0 if sg.convex else -1.0
            normal[on] = sign * (rc[:, None] * radial[on] + yc[:, None] * ey) / sg.ar
            Rm[on] = sg.ar if sg.convex else np.inf
        else:
            u, _ = sg.closest(r[on], y[on])
            nr, nz = sg.normal(u)
            normal[on] = nr[:, None] * radial[on] + nz[:, None] * ey
            Rm[on] = sg.meridian_radius(u)
    return normal, r, Rm, np.abs(normal[:, 1])


def project(shape: Shape, X: np.ndarray, seg: np.ndarray) -> np.ndarray:
    """Closest points on the exact outer surface of points near it, given their meridian segment.

    Args:
        shape: the exact geometry.
        X: points (k, 3), body frame. seg: per point its segment of shape.outer_path (classify).

    Returns:
        (k, 3) points on the exact surface.
    """
    X = np.array(X, dtype=float)
    out = X.copy()
    r = np.hypot(X[:, 0], X[:, 2])
    safe = np.maximum(r, 1e-300)
    for i, sg in enumerate(shape.outer_path):
        on = seg == i
        if not np.any(on):
            continue
        if sg.kind == "line" and sg.p0[1] == sg.p1[1]:  # a flat face: y only, as it always was
            out[on, 1] = sg.p0[1]
            continue
        if sg.kind == "line" and sg.p0[0] == sg.p1[0]:  # a cylinder: r only
            out[on, 0] *= sg.p0[0] / safe[on]
            out[on, 2] *= sg.p0[0] / safe[on]
            continue
        if sg.is_circle:
            cr, cz = sg.centre
            rc, yc = r[on] - cr, X[on, 1] - cz
            d = np.hypot(rc, yc)
            rn = cr + sg.ar * rc / d
            yn = cz + sg.ar * yc / d
            t = np.arctan2(yc, rc)
            lo, hi = min(sg.t0, sg.t1), max(sg.t0, sg.t1)
            t = np.where(t < lo - math.pi, t + 2 * math.pi, np.where(t > hi + math.pi, t - 2 * math.pi, t))
            outside = (t < lo - 1e-9) | (t > hi + 1e-9)  # beyond the arc's ends: its nearest end
            _, (pr, pz) = sg.closest(r[on], X[on, 1])
            rn, yn = np.where(outside, pr, rn), np.where(outside, pz, yn)
            top = max(sg.p0, sg.p1, key=lambda p: p[1])
            if top[0] == shape.radius:  # on the shoulder's plane or past it: onto the shank, as it does
                past = X[on, 1] >= top[1]
                idx = np.flatnonzero(on)[past]
                out[idx, 0] *= shape.radius / safe[idx]
                out[idx, 2] *= shape.radius / safe[idx]
                keep = ~past
                idx = np.flatnonzero(on)[keep]
                out[idx, 1] = yn[keep]
                out[idx, 0] = X[idx, 0] * rn[keep] / safe[idx]
                out[idx, 2] = X[idx, 2] * rn[keep] / safe[idx]
                continue
            out[on, 1] = yn
        else:
            _, (rn, yn) = sg.closest(r[on], X[on, 1])
            out[on, 1] = yn
        out[on, 0] = X[on, 0] * rn / safe[on]
        out[on, 2] = X[on, 2] * rn / safe[on]
    return out
