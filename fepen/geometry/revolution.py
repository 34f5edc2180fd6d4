"""The projectile as a solid of revolution without a volume mesh: exact mass properties, and load points
on its outer surface that are symmetric about the axis (the rigid fidelity; docs/theory.md §9).

Body frame of fepen.geometry.shape: nose tip at the origin, axis along +y, x and z radial.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from fepen.geometry import profile
from fepen.geometry.cad import CadBody
from fepen.geometry.shape import Shape


def mass_properties(shape: Shape, shell_density: float, charge_density: float | None = None):
    """Mass, centre and inertia about the centre of the projectile (the charge filling the cavity when
    charge_density is given), exact to round-off.

    For a solid of revolution about y of density ρ: m = ρ ∫ π r² dy, m y_c = ρ ∫ π r² y dy,
    I_yy = ρ ∫ π r⁴/2 dy, I_xx = I_zz = ρ ∫ (π r⁴/4 + π r² y²) dy about the origin, each integral taken along
    the meridian (fepen.geometry.profile.path_integrals); the cavity counts with the charge's density minus
    the shell's.

    Returns:
        (mass (kg), centre (3,) (m), inertia (3, 3) about the centre (kg m²)).
    """
    sums = shell_density * profile.path_integrals(shape.outer_path)
    if shape.has_cavity:
        sums += ((charge_density or 0.0) - shell_density) * profile.path_integrals(shape.inner_path)
    m, first, second, quartic = sums
    yc = first / m
    i_axial = 0.5 * quartic
    i_transverse = 0.25 * quartic + second - m * yc * yc
    return m, np.array([0.0, yc, 0.0]), np.diag([i_transverse, i_axial, i_transverse])


def load_points(shape: Shape, size: float, n_theta: int | None = None, n_gauss: int = 2) -> dict:
    """Load points on the outer surface, in rings symmetric about the axis.

    Each meridian segment (nose arcs and lines, meplat, shank, boat-tail, rear face) is cut into panels of
    arc length about ``size`` (equal steps of its own parameter); each panel is integrated with ``n_gauss``
    Gauss-Legendre rings (exact area, exact normal and curvature at the ring), and each ring swept into
    ``n_theta`` equal sectors (default: a sector about ``size`` wide at the calibre, a multiple of 4, so that
    the points are symmetric in x and z). The nose force of a nose moving along its axis is then within
    1e-5 of its closed form at the default size, and the sideways force at normal incidence vanishes to
    round-off.

    Returns:
        dict of arrays X (k, 3), area0 (k,), N (k, 3), radius, R_meridian, sin_phi0 (k,), as the target law
        takes them (fepen.laws.target.SurfaceState).
    """
    a = shape.radius
    if n_theta is None:
        n_theta = max(8, 4 * math.ceil(2.0 * math.pi * a / size / 4.0))
    xg, wg = profile.gauss(n_gauss)
    rings = []  # arrays per segment: y, r, n_r, n_y, ring area, R_meridian, sin_phi0
    for seg in shape.outer_path:
        n = max(1, math.ceil(seg.length() / size))
        e = np.linspace(0.0, 1.0, n + 1)
        h = 0.5 * (e[1:] - e[:-1])
        u = ((0.5 * (e[1:] + e[:-1]))[:, None] + h[:, None] * xg[None, :]).ravel()
        w = (h[:, None] * wg[None, :]).ravel()
        r, y = seg.point(u)
        dr, dy = seg.derivative(u)
        nr, ny = seg.normal(u)
        keep = r > 0.0  # a ring on the axis has no area
        area = 2.0 * math.pi * r * np.hypot(dr, dy) * w
        rings.append(tuple(v[keep] for v in (y, r, nr, ny, area, seg.meridian_radius(u), np.abs(ny))))
    y, r, nr, ny, area, Rm, sphi = (np.repeat(np.concatenate([g[k] for g in rings]), n_theta) for k in range(7))
    theta = 2.0 * math.pi * (np.arange(n_theta) + 0.5) / n_theta
    cc, ss = np.tile(np.cos(theta), len(y) // n_theta), np.tile(np.sin(theta), len(y) // n_theta)
    X = np.stack([r * cc, y, r * ss], axis=1)
    N = np.stack([nr * cc, ny, nr * ss], axis=1)
    return dict(X=X, area0=area / n_theta, N=N, radius=r, R_meridian=Rm, sin_phi0=sphi)


@functools.singledispatch
def nose_zone(shape, X: np.ndarray, radius: np.ndarray, comm=None) -> tuple[float, float]:
    """The nose zone that wear shortens (docs/theory.md §14.3), by the body's kind: from the tip to where the
    outer radius first reaches the calibre, or to the front of a cavity if that comes first; and the outer
    radius there.

    Args:
        shape: the Shape (its zone from its meridian), or a CadBody (no meridian: its zone from the surface
            points, the body taken as solid).
        X: points on the outer surface (k, 3) (m), axis +y from the tip. radius: their distances from the
            axis (k,) (m). comm: the MPI communicator sharing the points (None: all here).

    Returns:
        (y_c, r_c) (m), the same on every rank of comm.
    """
    raise TypeError(f"no nose zone for a {type(shape).__name__}")


@nose_zone.register(Shape)
def _exact_nose_zone(shape, X, radius, comm=None) -> tuple[float, float]:
    """The exact solid's, from its meridian (the points are not read)."""
    y_c = shape.nose_length
    inner = shape.inner_path
    if inner:
        y_c = min(y_c, min(min(seg.p0[1], seg.p1[1]) for seg in inner))
    return y_c, float(shape.outer_radius(y_c))


@nose_zone.register(CadBody)
def _cad_nose_zone(shape, X, radius, comm=None) -> tuple[float, float]:
    """A CAD body's, from the surface points: to the foremost point within 1e-3 of the largest radius."""
    if comm is None:
        r_max = float(radius.max())
        return float(X[radius >= (1.0 - 1e-3) * r_max, 1].min()), r_max
    from mpi4py import MPI

    r_max = comm.allreduce(float(radius.max(initial=0.0)), op=MPI.MAX)
    y = X[radius >= (1.0 - 1e-3) * r_max, 1]
    return comm.allreduce(float(y.min(initial=np.inf)), op=MPI.MIN), r_max
