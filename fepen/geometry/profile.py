"""Meridian profiles of solids of revolution: paths of straight and conic (circle or ellipse) segments in the
(r, z) half plane, z along the axis from the nose, r from it (docs/theory.md §1.2).

A projectile's outer surface is the revolution of one path from the nose (on the axis, or at the rim of a
flat meplat) to the centre of the rear face; its cavity the revolution of another. Everything fepen needs
of an exact surface comes from the segments: points, outward normals, meridional curvature, closest points,
arc lengths, and the integrals of volume, area and inertia (Green's theorem along the path, Gauss-Legendre
in each segment's own parameter, so that an arc is integrated as exactly as a line).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

#: Gauss-Legendre points per segment of the profile integrals (smooth integrands: exact to round-off)
GAUSS = 64


@dataclass(frozen=True)
class Segment:
    """One piece of a meridian: a line from p0 to p1, or a conic arc r = cr + ar cos θ, z = cz + az sin θ for
    θ from t0 to t1 (a circle when ar = az).

    Attributes:
        kind: "line" or "conic".
        p0, p1: end points (r, z) (m).
        centre: (cr, cz) of a conic (m). ar, az: its radial and axial semi-axes (m). t0, t1: its angles (rad).
    """

    kind: str
    p0: tuple[float, float]
    p1: tuple[float, float]
    centre: tuple[float, float] = (0.0, 0.0)
    ar: float = 0.0
    az: float = 0.0
    t0: float = 0.0
    t1: float = 0.0

    # ---- construction ---------------------------------------------------------------------------
    @staticmethod
    def line(p0, p1) -> Segment:
        return Segment("line", (float(p0[0]), float(p0[1])), (float(p1[0]), float(p1[1])))

    @staticmethod
    def arc(p0, p1, centre) -> Segment:
        """The circle arc about ``centre`` from p0 to p1, the short way (less than half a turn)."""
        cr, cz = centre
        R = math.hypot(p0[0] - cr, p0[1] - cz)
        t0 = math.atan2(p0[1] - cz, p0[0] - cr)
        t1 = math.atan2(p1[1] - cz, p1[0] - cr)
        if t1 - t0 > math.pi:
            t1 -= 2 * math.pi
        elif t0 - t1 > math.pi:
            t1 += 2 * math.pi
        return Segment("conic", (float(p0[0]), float(p0[1])), (float(p1[0]), float(p1[1])),
                       (float(cr), float(cz)), R, R, t0, t1)

    @property
    def is_circle(self) -> bool:
        return self.kind == "conic" and self.ar == self.az

    # ---- geometry in the parameter u in [0, 1] ----------------------------------------------------
    def point(self, u):
        """(r, z) at parameters u (arrays)."""
        u = np.asarray(u, dtype=float)
        if self.kind == "line":
            return (self.p0[0] + u * (self.p1[0] - self.p0[0]), self.p0[1] + u * (self.p1[1] - self.p0[1]))
        t = self.t0 + u * (self.t1 - self.t0)
        return self.centre[0] + self.ar * np.cos(t), self.centre[1] + self.az * np.sin(t)

    def derivative(self, u):
        """(dr/du, dz/du) at u."""
        u = np.asarray(u, dtype=float)
        if self.kind == "line":
            one = np.ones_like(u)
            return (self.p1[0] - self.p0[0]) * one, (self.p1[1] - self.p0[1]) * one
        t = self.t0 + u * (self.t1 - self.t0)
        dt = self.t1 - self.t0
        return -self.ar * np.sin(t) * dt, self.az * np.cos(t) * dt

    def normal(self, u, outward_right: bool = True):
        """Unit normal (n_r, n_z) at u: the tangent turned clockwise, (dz, −dr)/|.| (outward for a path that
        runs from the nose to the rear with the material on its left in (r, z))."""
        dr, dz = self.derivative(u)
        s = np.hypot(dr, dz)
        return (dz / s, -dr / s) if outward_right else (-dz / s, dr / s)

    def length(self) -> float:
        """Arc length (m)."""
        if self.kind == "line":
            return math.hypot(self.p1[0] - self.p0[0], self.p1[1] - self.p0[1])
        if self.is_circle:
            return self.ar * abs(self.t1 - self.t0)
        x, w = gauss(GAUSS)
        u = 0.5 * (x + 1.0)
        dr, dz = self.derivative(u)
        return float(0.5 * w @ np.hypot(dr, dz))

    def meridian_radius(self, u):
        """Meridional radius of curvature at u (m): inf on a line or a concave (hollow) arc."""
        u = np.asarray(u, dtype=float)
        if self.kind == "line":
            return np.full_like(u, np.inf)
        t = self.t0 + u * (self.t1 - self.t0)
        if self.is_circle:
            R = np.full_like(u, self.ar)
        else:
            s, c = np.sin(t), np.cos(t)
            R = (self.ar**2 * s * s + self.az**2 * c * c) ** 1.5 / (self.ar * self.az)
        return R if self.convex else np.full_like(u, np.inf)

    @property
    def convex(self) -> bool:
        """True when the arc bulges outward: the centre lies on the material's side, to the left of a path
        with the material on its left, which then runs counter-clockwise about it (t increasing)."""
        return self.kind == "conic" and self.t1 > self.t0

    def z_range(self) -> tuple[float, float]:
        zs = [self.p0[1], self.p1[1]]
        if self.kind == "conic":
            for t in (-0.5 * math.pi, 0.5 * math.pi, 1.5 * math.pi, -1.5 * math.pi):
                if min(self.t0, self.t1) < t < max(self.t0, self.t1):
                    zs.append(self.centre[1] + self.az * math.sin(t))
        return min(zs), max(zs)

    def r_range(self) -> tuple[float, float]:
        rs = [self.p0[0], self.p1[0]]
        if self.kind == "conic":
            for t in (0.0, math.pi, -math.pi, 2 * math.pi, -2 * math.pi):
                if min(self.t0, self.t1) < t < max(self.t0, self.t1):
                    rs.append(self.centre[0] + self.ar * math.cos(t))
        return min(rs), max(rs)

    def closest(self, r, z):
        """Parameters u in [0, 1] and points (r, z) of this segment closest to the points (r, z).

        Exact on lines and circles (the radial projection from the centre); a few Newton steps on an
        ellipse."""
        r, z = np.asarray(r, dtype=float), np.asarray(z, dtype=float)
        if self.kind == "line":
            dr, dz = self.p1[0] - self.p0[0], self.p1[1] - self.p0[1]
            L2 = dr * dr + dz * dz
            u = np.clip(((r - self.p0[0]) * dr + (z - self.p0[1]) * dz) / L2, 0.0, 1.0)
            return u, self.point(u)
        cr, cz = self.centre
        t = np.arctan2((z - cz) / self.az, (r - cr) / self.ar)
        if not self.is_circle:
            for _ in range(8):  # Newton on d/dt |p(t) - q|^2 / 2
                s, c = np.sin(t), np.cos(t)
                er, ez = cr + self.ar * c - r, cz + self.az * s - z
                g = -er * self.ar * s + ez * self.az * c
                h = (self.ar * s) ** 2 + (self.az * c) ** 2 - er * self.ar * c - ez * self.az * s
                t = t - g / np.where(np.abs(h) > 1e-300, h, 1e-300)
        lo, hi = min(self.t0, self.t1), max(self.t0, self.t1)
        # angles are compared on the segment's branch
        t = np.where(t < lo - math.pi, t + 2 * math.pi, np.where(t > hi + math.pi, t - 2 * math.pi, t))
        u = np.clip((t - self.t0) / (self.t1 - self.t0), 0.0, 1.0)
        return u, self.point(u)

    def r_at_z(self, z):
        """r at axial positions z (the segment must be monotone in z); nan outside its z range."""
        z = np.asarray(z, dtype=float)
        z0, z1 = self.p0[1], self.p1[1]
        out = np.full(z.shape, np.nan)
        if z1 == z0:
            return out
        lo, hi = min(z0, z1), max(z0, z1)
        inside = (z >= lo) & (z <= hi)
        if self.kind == "line":
            out[inside] = self.p0[0] + (z[inside] - z0) / (z1 - z0) * (self.p1[0] - self.p0[0])
            return out
        zi = z[inside]
        lo_t, hi_t = min(self.t0, self.t1), max(self.t0, self.t1)
        base = np.arcsin(np.clip((zi - self.centre[1]) / self.az, -1.0, 1.0))
        t = np.full(zi.shape, np.nan)
        for cand in (base, math.pi - base, base - 2 * math.pi, base + 2 * math.pi, -math.pi - base,
                     3 * math.pi - base):
            ok = np.isnan(t) & (cand >= lo_t - 1e-12) & (cand <= hi_t + 1e-12)
            t[ok] = cand[ok]
        out[inside] = self.centre[0] + self.ar * np.cos(t)
        return out

    def monotone_in_z(self) -> bool:
        zlo, zhi = self.z_range()
        return math.isclose(zlo, min(self.p0[1], self.p1[1]), abs_tol=1e-15) and math.isclose(
            zhi, max(self.p0[1], self.p1[1]), abs_tol=1e-15)


@functools.lru_cache(maxsize=16)
def gauss(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre points and weights on [-1, 1] (numpy's leggauss), computed once per n and read-only:
    leggauss solves an eigenproblem each call, a millisecond that the mass rule paid hundreds of times per
    projectile (the values are the same ones, so nothing moves by round-off)."""
    x, w = np.polynomial.legendre.leggauss(n)
    x.setflags(write=False)
    w.setflags(write=False)
    return x, w


def path_integrals(path: list[Segment]) -> np.ndarray:
    """∫ π r² z^k dz (k = 0, 1, 2) and ∫ π r⁴ dz along a path (Green's theorem: the volume, first and second
    axial moments and the quartic integral of the solid between the path and the axis, signed by the
    direction of z along the path).

    Returns:
        array [V, ∫ π r² z dz, ∫ π r² z² dz, ∫ π r⁴ dz].
    """
    x, w = gauss(GAUSS)
    u = 0.5 * (x + 1.0)
    out = np.zeros(4)
    for seg in path:
        if seg.kind == "line" and seg.p0[1] == seg.p1[1]:
            continue
        r, z = seg.point(u)
        dz = seg.derivative(u)[1] * 0.5 * w
        r2 = r * r
        out += math.pi * np.array([dz @ r2, dz @ (r2 * z), dz @ (r2 * z * z), dz @ (r2 * r2)])
    return out


def path_area(path: list[Segment]) -> float:
    """Area of the surface of revolution of a path, ∫ 2π r ds (m²)."""
    x, w = gauss(GAUSS)
    u = 0.5 * (x + 1.0)
    total = 0.0
    for seg in path:
        r, _ = seg.point(u)
        dr, dz = seg.derivative(u)
        total += 2.0 * math.pi * float(0.5 * w @ (r * np.hypot(dr, dz)))
    return total


def radius_at(path: list[Segment], z):
    """Largest r of the path at axial positions z (nan where the path has none).

    A segment whose z range holds none of the z (or that has no z extent) gives only nan, which leaves the
    result as it is: it is skipped (the mass rule's bisections ask one z, or a span, among many segments)."""
    z = np.asarray(z, dtype=float)
    out = np.full(z.shape, np.nan)
    zmin, zmax = (float(z.min()), float(z.max())) if z.size else (math.inf, -math.inf)
    for seg in path:
        z0, z1 = seg.p0[1], seg.p1[1]
        if z0 == z1 or (zmin > max(z0, z1) or zmax < min(z0, z1)):  # false with a nan z: no skipping
            continue
        r = seg.r_at_z(z)
        out = np.where(np.isnan(out), r, np.where(np.isnan(r), out, np.maximum(out, r)))
    return out


def min_radius(path: list[Segment], z0: float, z1: float) -> float:
    """Smallest r of the path over z0 <= z <= z1 (from samples at the ends, every vertex inside and 64 points
    per segment: exact for the monotone segments fepen builds)."""
    zs = [z0, z1]
    for seg in path:
        for p in (seg.p0, seg.p1):
            if z0 < p[1] < z1:
                zs.append(p[1])
    zs = np.array(sorted(zs))
    dense = np.unique(np.concatenate([np.linspace(a, b, 65) for a, b in zip(zs[:-1], zs[1:])] or [zs]))
    r = radius_at(path, dense)
    return float(np.nanmin(r)) if np.any(np.isfinite(r)) else 0.0


# ---------------------------------------------------------------------------------------------------------
# drawn profiles: CSV of (z, r[, arc radius]) points
# ---------------------------------------------------------------------------------------------------------
#: the largest drawn profile read (bytes): a few thousand rows are a few hundred kB
PROFILE_MAX = 16 << 20
#: the most points a drawn profile holds: each segment between two is a panel of the rigid fidelity's load rings
#: and a curve of the meshed body's outline (a rigid shot of the default body drawn with 200 points, 5,472 load
#: points: 1.5 s; 2,000 points, 48,672 load points: 3.4 s; 20,000 points: 27 s; 200,000: 9 minutes and 3.9 GB);
#: an arc row draws a curve exactly with one segment
PROFILE_POINTS_MAX = 2000


def read_points(path: str, key: str) -> list[tuple[float, float, float]]:
    """A drawn profile: rows ``z_m, r_m[, arc_radius_m]`` (a header line allowed, # comments), at most
    PROFILE_POINTS_MAX of them. The segment into each point is straight, or a circle arc of that radius when
    arc_radius_m is not 0: positive bulging away from the axis (convex, an ogive), negative toward it.

    Args:
        path: the CSV file: a regular file (not a pipe or a device, checked without blocking) of at most
            PROFILE_MAX bytes. key: the scene key that names it (for the error message).

    Returns:
        [(z, r, arc)] in file order. Raises InputError naming ``key`` when unreadable.
    """
    from fepen.errors import InputError
    from fepen.inputs import read_capped

    data = read_capped(path, PROFILE_MAX, key, "the profile",
                       missing=f"cannot read the profile {path!r}: No such file or directory")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise InputError(key, f"cannot read the profile {path!r}: {err}") from None
    rows = []
    for n, line in enumerate(text.splitlines(), 1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        cells = [c.strip() for c in line.replace(";", ",").split(",")]
        try:
            nums = [float(c) if c else 0.0 for c in cells]
        except ValueError:
            if not rows:
                continue  # a header line before the first point
            raise InputError(key, f"{path}:{n}: expected numbers z_m, r_m[, arc_radius_m], got {line!r}") from None
        if len(nums) not in (2, 3) or not all(math.isfinite(v) for v in nums):
            raise InputError(key, f"{path}:{n}: expected 2 or 3 finite numbers (z_m, r_m[, arc_radius_m]), "
                                  f"got {line!r}")
        if len(rows) == PROFILE_POINTS_MAX:
            raise InputError(key, f"{path}:{n}: more than {PROFILE_POINTS_MAX} points; a drawn profile holds at most "
                                  f"{PROFILE_POINTS_MAX} (each segment is a ring of load points and a curve of the "
                                  "mesh): thin them, or draw curves as arcs (a third column, the arc radius)")
        rows.append((nums[0], nums[1], nums[2] if len(nums) == 3 else 0.0))
    if len(rows) < 2:
        raise InputError(key, f"{path}: a profile needs at least 2 points, got {len(rows)}")
    return rows


def drawn_path(points, key: str) -> list[Segment]:
    """Segments through drawn points (z, r, arc) in order (see read_points). Raises InputError (``key``) on
    an arc shorter than its chord, a negative radius, or a segment that turns back in z."""
    from fepen.errors import InputError

    segs = []
    for (z0, r0, _), (z1, r1, R) in zip(points[:-1], points[1:]):
        if r0 < 0 or r1 < 0:
            raise InputError(key, f"radius {min(r0, r1):g} m < 0: points are (z_m, r_m) with r >= 0")
        if math.hypot(z1 - z0, r1 - r0) == 0.0:
            raise InputError(key, f"repeated point ({z1:g}, {r1:g})")
        if R == 0.0:
            segs.append(Segment.line((r0, z0), (r1, z1)))
            continue
        c = math.hypot(z1 - z0, r1 - r0)
        if abs(R) < 0.5 * c * (1 - 1e-12):
            raise InputError(key, f"arc radius {R:g} m into ({z1:g}, {r1:g}) is shorter than half its chord "
                                  f"({0.5 * c:g} m)")
        # centre on the chord's perpendicular bisector, on the side away from the bulge
        mr, mz = 0.5 * (r0 + r1), 0.5 * (z0 + z1)
        tr, tz = (r1 - r0) / c, (z1 - z0) / c
        nr, nz = tz, -tr  # the right-hand normal (outward for a nose-to-rear path)
        h = math.sqrt(max(R * R - 0.25 * c * c, 0.0))
        sgn = 1.0 if R > 0 else -1.0
        centre = (mr - sgn * h * nr, mz - sgn * h * nz)
        segs.append(Segment.arc((r0, z0), (r1, z1), centre))
    for s in segs:
        if not s.monotone_in_z():
            raise InputError(key, f"the segment from (z {s.p0[1]:g}, r {s.p0[0]:g}) to (z {s.p1[1]:g}, r "
                                  f"{s.p1[0]:g}) turns back along the axis: split it at its extreme")
    return segs
