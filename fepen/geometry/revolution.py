"""The projectile as a solid of revolution without a volume mesh: exact mass properties, and load points
on its outer surface that are symmetric about the axis (the rigid fidelity; docs/theory.md §9).

Body frame of fepen.geometry.shape: nose tip at the origin, axis along +y, x and z radial.
"""

from __future__ import annotations

import math

import numpy as np

from fepen.geometry.shape import Shape

#: Gauss-Legendre points per axial segment of the mass integrals (the ogive's r(z)^4 is smooth: exact
#: to round-off with far fewer)
GAUSS = 64


def _segments(shape: Shape) -> list[tuple[float, float]]:
    """Axial intervals on which the outer radius is smooth: the nose, the shank."""
    ln, L = shape.nose_length, shape.length
    return [(0.0, ln), (ln, L)] if ln > 0.0 else [(0.0, L)]


def _slices(shape: Shape, r_of_z, segments) -> np.ndarray:
    """∫ over z of (area, area z, area z², r⁴) of the discs of radius r(z): the four section integrals
    of a solid of revolution (π r², π r² y, π r² y², π r⁴)."""
    x, w = np.polynomial.legendre.leggauss(GAUSS)
    out = np.zeros(4)
    for z0, z1 in segments:
        if z1 <= z0:
            continue
        z = z0 + 0.5 * (z1 - z0) * (x + 1.0)
        r2 = np.asarray(r_of_z(z), dtype=float) ** 2
        h = 0.5 * (z1 - z0) * w
        out += math.pi * np.array([h @ r2, h @ (r2 * z), h @ (r2 * z * z), h @ (r2 * r2)])
    return out


def mass_properties(shape: Shape, shell_density: float, charge_density: float | None = None):
    """Mass, centre and inertia about the centre of the projectile (the charge filling the cavity when
    charge_density is given), exact to round-off.

    For a solid of revolution about y of density ρ: m = ρ ∫ π r² dy, m y_c = ρ ∫ π r² y dy,
    I_yy = ρ ∫ π r⁴/2 dy, I_xx = I_zz = ρ ∫ (π r⁴/4 + π r² y²) dy about the origin; the cavity's
    cylinders count with the charge's density minus the shell's.

    Returns:
        (mass (kg), centre (3,) (m), inertia (3, 3) about the centre (kg m²)).
    """
    outer = _slices(shape, shape.outer_radius, _segments(shape))
    sums = shell_density * outer
    fill = (charge_density or 0.0) - shell_density
    for z0, z1, r in shape.cavity_sections():
        sums += fill * _slices(shape, lambda z, r=r: np.full_like(z, r), [(z0, z1)])
    m, first, second, quartic = sums
    yc = first / m
    i_axial = 0.5 * quartic
    i_transverse = 0.25 * quartic + second - m * yc * yc
    return m, np.array([0.0, yc, 0.0]), np.diag([i_transverse, i_axial, i_transverse])


def load_points(shape: Shape, size: float, n_theta: int | None = None, n_gauss: int = 2) -> dict:
    """Load points on the outer surface, in rings symmetric about the axis.

    The meridian (nose arc, shank, rear face) is cut into panels of arc length about ``size``; each panel is
    integrated with ``n_gauss`` Gauss-Legendre rings (exact area, exact normal and curvature at the ring),
    and each ring swept into ``n_theta`` equal sectors (default: a sector about ``size`` wide at the shank,
    a multiple of 4, so that the points are symmetric in x and z). The nose force of a tangent ogive
    moving along its axis is then within 1e-5 of its closed form at the default size, and the sideways
    force at normal incidence vanishes to round-off.

    Returns:
        dict of arrays X (k, 3), area0 (k,), N (k, 3), radius, R_meridian, sin_phi0 (k,), as the target law
        takes them (fepen.laws.target.SurfaceState).
    """
    a, ln, L = shape.radius, shape.nose_length, shape.length
    if n_theta is None:
        n_theta = max(8, 4 * math.ceil(2.0 * math.pi * a / size / 4.0))
    xg, wg = np.polynomial.legendre.leggauss(n_gauss)
    rings = []  # arrays per part: y, r, n_r, n_y, ring area, R_meridian, sin_phi0

    def panels(lo: float, hi: float, length: float):
        """Gauss points t and weights (summing to hi - lo) of panels of arc length about ``size``."""
        n = max(1, math.ceil(length / size))
        e = np.linspace(lo, hi, n + 1)
        h = 0.5 * (e[1:] - e[:-1])
        t = (0.5 * (e[1:] + e[:-1]))[:, None] + h[:, None] * xg[None, :]
        return t.ravel(), (h[:, None] * wg[None, :]).ravel()

    if ln > 0.0:
        # the nose arc about (a - s, ln): r = (a - s) + s cos β, y = ln − s sin β, β from the tip to 0
        s = shape.ogive_radius
        beta_tip = math.asin(ln / s)
        b, w = panels(0.0, beta_tip, s * beta_tip)
        r = (a - s) + s * np.cos(b)
        one = np.ones_like(b)
        rings.append((ln - s * np.sin(b), r, np.cos(b), -np.sin(b), 2.0 * math.pi * r * s * w, s * one, np.sin(b)))
    else:
        r, w = panels(0.0, a, a)
        one = np.ones_like(r)
        rings.append((0.0 * r, r, 0.0 * r, -one, 2.0 * math.pi * r * w, math.inf * one, one))
    y, w = panels(ln, L, L - ln)
    one = np.ones_like(y)
    rings.append((y, a * one, one, 0.0 * y, 2.0 * math.pi * a * w, math.inf * one, 0.0 * y))
    r, w = panels(0.0, a, a)
    one = np.ones_like(r)
    rings.append((L * one, r, 0.0 * r, one, 2.0 * math.pi * r * w, math.inf * one, one))
    y, r, nr, ny, area, Rm, sphi = (np.repeat(np.concatenate([g[k] for g in rings]), n_theta) for k in range(7))
    theta = 2.0 * math.pi * (np.arange(n_theta) + 0.5) / n_theta
    cc, ss = np.tile(np.cos(theta), len(y) // n_theta), np.tile(np.sin(theta), len(y) // n_theta)
    X = np.stack([r * cc, y, r * ss], axis=1)
    N = np.stack([nr * cc, ny, nr * ss], axis=1)
    return dict(X=X, area0=area / n_theta, N=N, radius=r, R_meridian=Rm, sin_phi0=sphi)
