"""The projectile as an exact solid of revolution, without any mesh: a tangent ogive (or flat) nose, a
cylinder, a closed two-section cavity sized to a mass. Body frame: nose tip at the origin, axis along +y
(docs/theory.md §1).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

import numpy as np

from fepen.errors import InputError
from fepen.geometry import profile as P

#: thinnest wall fepen accepts anywhere around the cavity, as a fraction of the diameter
MIN_WALL_FRACTION = 0.05


#: nose families (projectile.nose); "profile" is a drawn outer profile (outer_points)
NOSES = ("ogive", "secant", "cone", "hemisphere", "ellipsoid", "flat", "profile")


@dataclass(frozen=True)
class Shape:
    """Exact geometry of the projectile (SI units), a solid of revolution about the y axis.

    Attributes:
        diameter, length: outer calibre and overall length (m), from the nose (meplat) to the rear face.
        nose: one of NOSES: tangent ("ogive") or secant ogive, cone, hemisphere, ellipsoid, flat, or a drawn
            "profile".
        crh: ogive radius over diameter (tangent and secant ogives).
        cavity_diameter, cavity_length: rear cavity section's diameter and the total cavity length (m);
            0: solid.
        step_diameter, step_length: the narrower forward cavity section (m) (the paper's wall step).
        base_thickness: rear wall behind the cavity (m).
        nose_length_given: axial length of a secant ogive, cone or ellipsoid nose before any meplat (m)
            (projectile.nose_length).
        meplat_diameter: diameter of the flat blunt tip (m); 0: pointed.
        boattail_length, boattail_diameter: the tapered rear (m); 0: none.
        cavity_table: forward cavity sections ((length, diameter), ...) front to rear, before the rear
            section (replaces the step when given).
        outer_points, inner_points: drawn profiles ((z, r, arc_radius), ...) of the outside (nose "profile")
            and of the cavity (fepen.geometry.profile.read_points).
    """

    diameter: float
    length: float
    nose: str = "ogive"
    crh: float = 3.0
    cavity_diameter: float = 0.0
    cavity_length: float = 0.0
    step_diameter: float = 0.0
    step_length: float = 0.0
    base_thickness: float = 0.0
    nose_length_given: float = 0.0
    meplat_diameter: float = 0.0
    boattail_length: float = 0.0
    boattail_diameter: float = 0.0
    cavity_table: tuple = ()
    outer_points: tuple = ()
    inner_points: tuple = ()
    cad_file: str = ""
    cad_scale: float = 1.0
    cad_digest: str = ""
    tip_point: tuple = ()
    tail_point: tuple = ()

    def __post_init__(self):
        for name in ("cavity_table", "outer_points", "inner_points"):  # lists from JSON back to tuples
            object.__setattr__(self, name, tuple(tuple(float(v) for v in row) for row in getattr(self, name)))
        for name in ("tip_point", "tail_point"):
            object.__setattr__(self, name, tuple(float(v) for v in getattr(self, name)))

    @property
    def is_cad(self) -> bool:
        """A body read from a CAD file (fepen.geometry.cad): no exact surface, mass from the mesh."""
        return self.nose == "cad"

    @property
    def tip(self) -> tuple:
        """The tracked nose-tip point of the reference body (a mesh node)."""
        return self.tip_point or (0.0, 0.0, 0.0)

    @property
    def tail(self) -> tuple:
        """The tracked tail-centre point of the reference body (a mesh node)."""
        return self.tail_point or (0.0, self.length, 0.0)

    @property
    def radius(self) -> float:
        return 0.5 * self.diameter

    # ---- the meridian ----------------------------------------------------------------------------
    def _nose_path(self) -> tuple[list, float]:
        """Segments of the nose from the axis (or the meplat's centre) to the shoulder, and the nose's
        axial length."""
        a, rm = self.radius, 0.5 * self.meplat_diameter
        tip = [P.Segment.line((0.0, 0.0), (rm, 0.0))] if rm > 0.0 else []
        nose = self.nose
        if nose == "flat":
            return [P.Segment.line((0.0, 0.0), (a, 0.0))], 0.0
        if nose in ("ogive", "secant", "hemisphere"):
            if nose == "hemisphere":
                s, l0, cr = a, a, 0.0
                cz = a
            else:
                s = self.crh * self.diameter
                if nose == "ogive":
                    l0 = a * math.sqrt(4.0 * self.crh - 1.0)
                    cr, cz = a - s, l0
                else:  # centre on the chord's bisector, away from the bulge
                    l0 = self.nose_length_given
                    c = math.hypot(a, l0)
                    h = math.sqrt(max(s * s - 0.25 * c * c, 0.0))
                    cr, cz = 0.5 * a - h * l0 / c, 0.5 * l0 + h * a / c
            zm = cz - math.sqrt(max(s * s - (rm - cr) ** 2, 0.0)) if rm > 0.0 else 0.0
            ln = l0 - zm
            return tip + [P.Segment.arc((rm, 0.0), (a, ln), (cr, cz - zm))], ln
        if nose == "cone":
            ln = self.nose_length_given * (1.0 - rm / a)
            return tip + [P.Segment.line((rm, 0.0), (a, ln))], ln
        if nose == "ellipsoid":
            l0 = self.nose_length_given
            tm = -math.acos(min(rm / a, 1.0))
            zm = l0 * (1.0 + math.sin(tm))
            ln = l0 - zm
            seg = P.Segment("conic", (rm, 0.0), (a, ln), (0.0, l0 - zm), a, l0, tm, 0.0)
            return tip + [seg], ln
        raise ValueError(nose)

    @functools.cached_property
    def outer_path(self) -> list:
        """The outer meridian (fepen.geometry.profile.Segment list) from the nose on the axis to the centre
        of the rear face."""
        if self.is_cad:
            return []
        if self.nose == "profile":
            pts = list(self.outer_points)
            z0 = pts[0][0]
            pts = [(z - z0, r, arc) for z, r, arc in pts]
            segs = P.drawn_path(pts, "projectile.profile")
            if pts[0][1] > 0.0:
                segs.insert(0, P.Segment.line((0.0, 0.0), (pts[0][1], 0.0)))
            if pts[-1][1] > 0.0:
                segs.append(P.Segment.line((pts[-1][1], pts[-1][0]), (0.0, pts[-1][0])))
            return segs
        segs, ln = self._nose_path()
        a, L = self.radius, self.length
        rear_r, z_tail = a, L
        if self.boattail_length > 0.0:
            z_tail, rear_r = L - self.boattail_length, 0.5 * self.boattail_diameter
        if z_tail > ln:
            segs.append(P.Segment.line((a, ln), (a, z_tail)))
        if self.boattail_length > 0.0:
            segs.append(P.Segment.line((a, z_tail), (rear_r, L)))
        segs.append(P.Segment.line((rear_r, L), (0.0, L)))
        return segs

    @property
    def nose_length(self) -> float:
        """Axial length of the nose: from the tip (or meplat) to where the outer radius first reaches the
        calibre (0 for a flat nose)."""
        if self.is_cad:
            return 0.0
        if self.nose == "profile":
            for seg in self.outer_path:
                for r, z in (seg.p0, seg.p1):
                    if r >= self.radius * (1.0 - 1e-12):
                        return z
            return self.length
        return self._nose_path()[1]

    @property
    def ogive_radius(self) -> float:
        return self.crh * self.diameter

    def outer_radius(self, z):
        """Outer radius at axial distance z from the tip (array-aware)."""
        z = np.asarray(z, dtype=float)
        if self.is_cad:  # no exact surface: the calibre
            return np.full(z.shape, self.radius)
        return P.radius_at(self.outer_path, np.clip(z, 0.0, self.length))

    @functools.cached_property
    def inner_path(self) -> list:
        """The cavity's meridian from its front on the axis to its rear on the axis (empty: solid)."""
        if self.inner_points:
            pts = list(self.inner_points)
            segs = P.drawn_path(pts, "projectile.inner_profile")
            if pts[0][1] > 0.0:
                segs.insert(0, P.Segment.line((0.0, pts[0][0]), (pts[0][1], pts[0][0])))
            if pts[-1][1] > 0.0:
                segs.append(P.Segment.line((pts[-1][1], pts[-1][0]), (0.0, pts[-1][0])))
            return segs
        sec = self.cavity_sections()
        if not sec:
            return []
        segs, r_prev, z_prev = [], 0.0, sec[0][0]
        for z0, z1, r in sec:
            segs.append(P.Segment.line((r_prev, z0), (r, z0)))
            segs.append(P.Segment.line((r, z0), (r, z1)))
            r_prev, z_prev = r, z1
        segs.append(P.Segment.line((r_prev, z_prev), (0.0, z_prev)))
        return segs

    @property
    def has_cavity(self) -> bool:
        return bool(self.inner_points) or (self.cavity_diameter > 0.0 and self.cavity_length > 0.0)

    def _fore(self) -> list[tuple[float, float]]:
        """The forward cavity sections (length, diameter) before the rear one."""
        if self.cavity_table:
            return [(float(l), float(d)) for l, d in self.cavity_table]
        if self.step_length > 0.0 and self.step_diameter > 0.0:
            return [(self.step_length, self.step_diameter)]
        return []

    def fore_length(self) -> float:
        return sum(l for l, _ in self._fore())

    def cavity_sections(self) -> list[tuple[float, float, float]]:
        """Cavity as (z_front, z_rear, radius) cylinders, forward first; empty for a solid body (or a drawn
        cavity)."""
        if self.inner_points or not (self.cavity_diameter > 0.0 and self.cavity_length > 0.0):
            return []
        z_rear = self.length - self.base_thickness
        z_front = z_rear - self.cavity_length
        out = []
        for l, d in self._fore():
            step = min(l, z_rear - z_front)
            if step > 0.0:
                out.append((z_front, z_front + step, 0.5 * d))
                z_front += step
        if z_rear > z_front:
            out.append((z_front, z_rear, 0.5 * self.cavity_diameter))
        return out

    def outer_volume(self) -> float:
        """Exact volume inside the outer surface (m^3) (Green's theorem along the meridian); nan for a CAD
        body."""
        if self.is_cad:
            return math.nan
        if self.nose == "ogive" and not self.meplat_diameter and not self.boattail_length:
            # the paper's family, summed exactly as fepen always did (shank, then Gauss-Legendre along z on the
            # nose), so that the cavity sized to the mass, the mesh and Table 1 do not move by round-off
            ln, a, s = self.nose_length, self.radius, self.ogive_radius
            vol = math.pi * a**2 * (self.length - ln)
            x, w = np.polynomial.legendre.leggauss(64)
            z = 0.5 * ln * (x + 1.0)
            r = np.sqrt(np.maximum(s * s - (ln - np.minimum(z, ln)) ** 2, 0.0)) - (s - a)
            return vol + 0.5 * ln * float(np.sum(w * math.pi * r**2))
        return float(P.path_integrals(self.outer_path)[0])

    def outer_area(self) -> float:
        """Exact area of the outer surface (m^2)."""
        return P.path_area(self.outer_path)

    def cavity_area(self) -> float:
        """Exact area of the cavity wall (m^2)."""
        return P.path_area(self.inner_path) if self.has_cavity else 0.0

    def cavity_volume(self) -> float:
        """Exact cavity volume (m^3)."""
        if self.inner_points:
            return float(P.path_integrals(self.inner_path)[0])
        return sum(math.pi * r * r * (z1 - z0) for z0, z1, r in self.cavity_sections())

    def shell_volume(self) -> float:
        """Exact volume of steel (m^3)."""
        return self.outer_volume() - self.cavity_volume()

    def mass(self, shell_density: float, charge_density: float | None = None) -> float:
        """Total mass (kg): the shell, plus the charge filling the cavity when charge_density is given."""
        m = shell_density * self.shell_volume()
        if charge_density is not None:
            m += charge_density * self.cavity_volume()
        return m

    def nose_factor(self) -> float:
        """N* of the nose: (1/(π a²)) ∫ (−n_y)³ dA over the surface facing forward, so that a rigid nose moving
        along its axis at V against σ_n = σ_s + ρ (v·n)² feels π a² (σ_s + N* ρ V²) (frictionless):
        (8ψ − 1)/(24ψ²) for a tangent ogive, 1/2 for a hemisphere, 1 flat."""
        x, w = np.polynomial.legendre.leggauss(P.GAUSS)
        u = 0.5 * (x + 1.0)
        total = 0.0
        for seg in self.outer_path:
            r, _ = seg.point(u)
            nr, nz = seg.normal(u)
            dr, dz = seg.derivative(u)
            c = np.maximum(-nz, 0.0)
            total += 2.0 * math.pi * float(0.5 * w @ (r * c**3 * np.hypot(dr, dz)))
        return total / (math.pi * self.radius**2)

    # ---- outer surface, for the target law -------------------------------------------------------
    def classify(self, P3: np.ndarray, n_flat: np.ndarray) -> np.ndarray:
        """The meridian segment each flat surface triangle lies on: all three corners on it (to 1e-6 L), and
        of several, the one whose exact normal at the centroid agrees best with the triangle's.

        Args:
            P3: triangle corners (f, 3, 3), body frame. n_flat: their flat unit normals (f, 3).

        Returns:
            (f,) segment indices into outer_path.
        """
        f = len(P3)
        tol = 1e-6 * self.length
        r = np.hypot(P3[..., 0], P3[..., 2]).ravel()
        y = P3[..., 1].ravel()
        c = P3.mean(axis=1)
        rc = np.hypot(c[:, 0], c[:, 2])
        radial = np.stack([c[:, 0], np.zeros(f), c[:, 2]], axis=1) / np.maximum(rc, 1e-300)[:, None]
        best, score = np.full(f, -1), np.full(f, -np.inf)
        near, dist = np.zeros(f, dtype=np.int64), np.full(f, np.inf)
        for i, seg in enumerate(self.outer_path):
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

    def segment_of_points(self, X: np.ndarray) -> np.ndarray:
        """The meridian segment nearest each point (k, 3) (a point on an edge: the first one)."""
        r, y = np.hypot(X[:, 0], X[:, 2]), X[:, 1]
        best, dist = np.zeros(len(X), dtype=np.int64), np.full(len(X), np.inf)
        for i, seg in enumerate(self.outer_path):
            _, (pr, pz) = seg.closest(r, y)
            d = np.hypot(pr - r, pz - y)
            closer = d < dist - 1e-12 * self.length
            best[closer], dist[closer] = i, d[closer]
        return best

    def surface_info(self, X: np.ndarray, seg: np.ndarray | None = None):
        """Exact outward normals and curvature data of outer-surface points given in the body frame.

        Args:
            X: points on the outer surface (k, 3), body frame (tip at the origin, axis +y).
            seg: the meridian segment of each point (classify); default: the nearest.

        Returns:
            (normal (k, 3); radius (k,): distance from the axis; R_meridian (k,): meridional radius of
             curvature (inf on straight or hollow meridians); sin_phi0 (k,): sine of the angle between the
             surface and the axis, |n_y|).
        """
        X = np.asarray(X, dtype=float)
        seg = self.segment_of_points(X) if seg is None else np.asarray(seg)
        x, y, z = X[:, 0], X[:, 1], X[:, 2]
        r = np.hypot(x, z)
        safe = np.maximum(r, 1e-300)
        radial = np.stack([x / safe, np.zeros_like(r), z / safe], axis=1)
        normal = np.zeros_like(X)
        Rm = np.full(len(X), np.inf)
        ey = np.array([0.0, 1.0, 0.0])
        for i, sg in enumerate(self.outer_path):
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

    def project(self, X: np.ndarray, seg: np.ndarray) -> np.ndarray:
        """Closest points on the exact outer surface of points near it, given their meridian segment.

        Args:
            X: points (k, 3), body frame. seg: per point its segment of outer_path (classify).

        Returns:
            (k, 3) points on the exact surface.
        """
        X = np.array(X, dtype=float)
        out = X.copy()
        r = np.hypot(X[:, 0], X[:, 2])
        safe = np.maximum(r, 1e-300)
        for i, sg in enumerate(self.outer_path):
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
                if top[0] == self.radius:  # on the shoulder's plane or past it: onto the shank, as it does
                    past = X[on, 1] >= top[1]
                    idx = np.flatnonzero(on)[past]
                    out[idx, 0] *= self.radius / safe[idx]
                    out[idx, 2] *= self.radius / safe[idx]
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

    # ---- limits of the cavity --------------------------------------------------------------------
    def _min_wall(self) -> float:
        return MIN_WALL_FRACTION * self.diameter

    def front_limit(self, radius: float) -> float:
        """Smallest z at which a cavity of this radius keeps the minimum wall to the outer surface."""
        need = radius + self._min_wall()
        if need >= self.radius:
            return math.inf
        if self.nose_length == 0.0:
            return self._min_wall()
        # outer_radius is monotone on the nose: bisection
        lo, hi = 0.0, self.nose_length
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            if self.outer_radius(mid) < need:
                lo = mid
            else:
                hi = mid
        return max(hi, self._min_wall())

    def _fits(self, cavity_length: float) -> bool:
        """The cavity of this total length keeps the minimum wall everywhere (sideways and ahead)."""
        wall = self._min_wall()
        for z0, z1, r in replace(self, cavity_length=cavity_length).cavity_sections():
            if z0 < wall * (1.0 - 1e-12) or P.min_radius(self.outer_path, z0, z1) < (r + wall) * (1.0 - 1e-12):
                return False
        return True

    def max_cavity_length(self) -> float:
        """Longest cavity that fits with the minimum wall everywhere (m): bisection on the total length (the
        sections move forward into the nose as it grows; the rear one must fit any boat-tail)."""
        return _max_cavity_length(self)

    def _max_cavity_length(self) -> float:
        z_rear = self.length - self.base_thickness
        lo = self.fore_length() + 1e-9 * self.length
        if not self._fits(lo):
            return 0.0
        hi = z_rear
        if self._fits(hi):
            return hi
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            if self._fits(mid):
                lo = mid
            else:
                hi = mid
        return lo

    def check(self) -> None:
        """Raise InputError (naming the scene key) if this shape cannot be built."""
        D, a = self.diameter, self.radius
        rm = 0.5 * self.meplat_diameter
        if self.is_cad:
            return
        if self.nose != "profile":
            if rm >= a and self.nose != "flat":
                raise InputError("projectile.meplat_diameter",
                                 f"{self.meplat_diameter:g} m: must be less than projectile.diameter = {D:g} m")
            if self.nose in ("secant", "cone", "ellipsoid") and self.nose_length_given <= 0.0:
                raise InputError("projectile.nose_length", f"a {self.nose} nose needs its length: give "
                                                           f"projectile.nose_length > 0 (m)")
            if self.nose == "secant":
                tangent = a * math.sqrt(4.0 * self.crh - 1.0)
                if self.nose_length_given > tangent * (1.0 + 1e-12):
                    raise InputError("projectile.nose_length",
                                     f"{self.nose_length_given:g} m: a secant ogive of crh {self.crh:g} must be at "
                                     f"most the tangent ogive's {tangent:.6g} m long (longer bulges past the "
                                     f"calibre); use a larger projectile.crh")
            if self.nose_length >= self.length - self.boattail_length:
                raise InputError("projectile.length",
                                 f"{self.length:g} m is too short for the {self.nose} nose ({self.nose_length:g} m)"
                                 + (f" and the boat-tail ({self.boattail_length:g} m)" if self.boattail_length else "")
                                 + "; use a longer body or a shorter nose")
            if self.boattail_length > 0.0 and not 0.0 < self.boattail_diameter < D:
                raise InputError("projectile.boattail_diameter",
                                 f"{self.boattail_diameter:g} m: must be in (0, {D:g}) m (projectile.diameter) "
                                 f"with a boat-tail")
        if self.inner_points:
            self._check_drawn_cavity()
            return
        if self.cavity_diameter <= 0.0:
            return
        wall = self._min_wall()
        if self.cavity_diameter > D - 2 * wall:
            raise InputError("projectile.cavity_diameter",
                             f"{self.cavity_diameter:g} m leaves no wall: must be at most diameter - 2 x "
                             f"{wall:g} m = {D - 2 * wall:g} m")
        if self.step_diameter > self.cavity_diameter:
            raise InputError("projectile.cavity_step_diameter",
                             f"{self.step_diameter:g} m: must be at most projectile.cavity_diameter = "
                             f"{self.cavity_diameter:g} m")
        for l, d in self._fore() if self.cavity_table else []:
            if not (0.0 < d <= D - 2 * wall and l > 0.0):
                raise InputError("projectile.cavity_sections",
                                 f"section [{l:g}, {d:g}]: lengths must be > 0 and diameters in (0, "
                                 f"{D - 2 * wall:g}] m (the minimum wall {wall:g} m)")
        if self.base_thickness >= self.length - self.nose_length:
            raise InputError("projectile.base_thickness",
                             f"{self.base_thickness:g} m: must be less than the body behind the nose, "
                             f"{self.length - self.nose_length:g} m")
        if self.cavity_length > 0.0:
            top = self.max_cavity_length()
            if self.cavity_length > top * (1.0 + 1e-12):
                raise InputError("projectile.cavity_length",
                                 f"{self.cavity_length:g} m does not fit: must be in (0, {top:.6g}] m with "
                                 f"this nose, diameter, boat-tail and base thickness")
            if self.fore_length() >= self.cavity_length:
                key = "projectile.cavity_sections" if self.cavity_table else "projectile.cavity_step_length"
                raise InputError(key, f"{self.fore_length():g} m: the forward sections must be shorter than "
                                      f"the cavity, {self.cavity_length:g} m")
        del a

    def _check_drawn_cavity(self) -> None:
        """A drawn cavity lies inside the body with the minimum wall."""
        wall = self._min_wall()
        for seg in self.inner_path:
            z0, z1 = seg.z_range()
            r = seg.r_range()[1]
            if z0 < wall * (1 - 1e-9) or z1 > self.length - wall * (1 - 1e-9) or (
                    r > 0 and P.min_radius(self.outer_path, z0, z1) < r + wall * (1 - 1e-9)):
                raise InputError("projectile.inner_profile",
                                 f"the segment from (z {seg.p0[1]:g}, r {seg.p0[0]:g}) to (z {seg.p1[1]:g}, r "
                                 f"{seg.p1[0]:g}) m leaves less than the minimum wall {wall:g} m to the outside")

    def with_mass(self, mass: float, shell_density: float, charge_density: float | None = None) -> Shape:
        """The same shape with the cavity length that gives this total mass.

        Args:
            mass: wanted total mass (kg).
            shell_density: steel density (kg/m^3).
            charge_density: charge density (kg/m^3) when the cavity is filled, else None.

        Returns:
            A new Shape. Raises InputError (key projectile.mass) when the mass cannot be reached.
        """
        rho_fill = charge_density or 0.0
        top, fore = self.max_cavity_length(), self.fore_length()
        if top <= fore:  # not even the forward sections fit: no mass range to speak of
            rear = replace(self, step_length=0.0, step_diameter=0.0, cavity_table=())
            key = ("projectile.cavity_diameter" if not fore or not rear._fits(1e-9 * self.length) else
                   "projectile.cavity_sections" if self.cavity_table else "projectile.cavity_step_length")
            raise InputError(key, f"the cavity ({1e3 * self.cavity_diameter:g} mm rear section"
                                  + (f" behind {1e3 * fore:g} mm of forward sections" if fore else "")
                                  + f") does not fit this nose, diameter, boat-tail and base thickness with the "
                                    f"minimum wall {self._min_wall():g} m" + (f": at most {top:.4g} m of cavity fits"
                                                                              if top > 0 else ""))
        longest = replace(self, cavity_length=top)
        shortest = replace(self, cavity_length=self.fore_length() + 1e-9 * self.length)
        m_hi = shortest.mass(shell_density, charge_density)
        m_lo = longest.mass(shell_density, charge_density)
        if not (m_lo <= mass <= m_hi):
            raise InputError("projectile.mass",
                             f"{mass:g} kg is unreachable with this shape and cavity diameters: must be in "
                             f"[{m_lo:.4g}, {m_hi:.4g}] kg")
        # mass is linear in the main section's length
        r = 0.5 * self.cavity_diameter
        slope = (shell_density - rho_fill) * math.pi * r * r
        extra = (m_hi - mass) / slope
        out = replace(self, cavity_length=shortest.cavity_length + extra)
        out.check()
        return out


@functools.lru_cache(maxsize=64)
def _max_cavity_length(shape: Shape) -> float:
    return shape._max_cavity_length()


#: shortest cavity worth keeping, in its own diameters: below this a sized cavity is reduced instead
MIN_CAVITY_ASPECT = 1.0
#: narrowest cavity worth keeping, as a fraction of the outer diameter: below this the body is made solid
MIN_CAVITY_FRACTION = 0.05
#: largest change of the steel density the mass rule makes when no cavity reaches the mass
MAX_DENSITY_CHANGE = 0.25


@dataclass(frozen=True)
class Built:
    """A projectile built to a mass (reach_mass).

    Attributes:
        shape: the exact geometry. shell_density: the steel's density used (kg/m^3), the scene's unless the
        body had to be made solid with an adjusted density. note: one line saying what was changed, "" if
        the given cavity was only sized.
    """

    shape: Shape
    shell_density: float
    note: str = ""


def reach_mass(shape: Shape, mass: float, shell_density: float, charge_density: float | None = None,
               adapt: bool = True) -> Built:
    """The projectile of this outside with this total mass (docs/theory.md §1.1, the mass-reaching rule).

    In order, the first that reaches the mass:
      1. the given cavity (both sections), its length sized (the paper's rule), if the cavity is at least
         MIN_CAVITY_ASPECT diameters long;
      2. one cylindrical cavity (the step dropped), as long as fits, its diameter sized, between
         MIN_CAVITY_FRACTION of the calibre and the widest that keeps the minimum wall;
      3. lighter than the widest cavity: that cavity with the steel density lowered; heavier than
         solid: a solid body with the steel density adjusted to the mass (said in the note), by at most
         MAX_DENSITY_CHANGE; beyond, InputError.

    Args:
        shape: the checked outside and the wanted cavity (its length a first guess).
        mass: total mass (kg). shell_density, charge_density: kg/m^3 (charge None: an empty cavity).
        adapt: False keeps rule 1 only (the user fixed the cavity; InputError if unreachable).

    Returns:
        Built. Raises InputError (key projectile.mass) when rule 1 fails and adapt is False, or when a
        filled cavity cannot be kept.
    """
    first = None
    if shape.cavity_diameter > 0.0:
        try:
            out = shape.with_mass(mass, shell_density, charge_density)
            if out.cavity_length >= MIN_CAVITY_ASPECT * out.cavity_diameter or not adapt:
                return Built(out, shell_density)
        except InputError as err:
            first = err
    if not adapt and first is not None:
        raise first
    solid = replace(shape, cavity_diameter=0.0, cavity_length=0.0, step_diameter=0.0, step_length=0.0,
                    cavity_table=())
    widest, length = _widest_cavity(shape)
    built = _one_cylinder(shape, solid, widest, length, mass, shell_density, charge_density)
    if built is not None:
        return built
    m_solid = solid.mass(shell_density)
    if charge_density is not None:
        raise first or InputError("projectile.mass", f"{mass:g} kg cannot be reached with a charge-filled "
                                                     f"cavity in this outside (solid: {m_solid:.4g} kg)")
    rho = mass / solid.outer_volume()
    if abs(rho / shell_density - 1.0) > MAX_DENSITY_CHANGE:
        lightest = (1.0 - MAX_DENSITY_CHANGE) * (
            replace(solid, cavity_diameter=widest, cavity_length=length).mass(shell_density) if length > 0.0
            else m_solid)
        raise InputError("projectile.mass", f"{mass:g} kg cannot be reached in this outside: must be in "
                                            f"[{lightest:.4g}, {m_solid * (1.0 + MAX_DENSITY_CHANGE):.4g}] kg "
                                            f"(a cavity, or the steel density changed by at most "
                                            f"{MAX_DENSITY_CHANGE:.0%})")
    return Built(solid, rho, f"projectile.mass {mass:g} kg: solid body, steel density adjusted to "
                             f"{rho:.1f} kg/m^3 ({rho / shell_density - 1:+.1%}; no cavity reaches it)")


def _widest_cavity(shape: Shape) -> tuple[float, float]:
    """Diameter of the widest cavity that keeps the minimum wall, and the longest length it fits (0 if none):
    narrower cavities fit that length too."""
    widest = (shape.diameter - 2.0 * shape._min_wall()) * (1.0 - 1e-9)
    if widest <= MIN_CAVITY_FRACTION * shape.diameter or shape.base_thickness >= shape.length - shape.nose_length:
        return widest, 0.0
    return widest, max(0.0, shape.length - shape.base_thickness - shape.front_limit(0.5 * widest))


def _one_cylinder(shape, solid, widest, length, mass, shell_density, charge_density) -> Built | None:
    """Rules 2 and 3 (light side) of reach_mass: one cylinder of the longest length, its diameter sized (mass
    is linear in r²); lighter than the widest, that one with the steel lightened. None if neither applies."""
    if length <= 0.0:
        return None
    need = (solid.mass(shell_density) - mass) / ((shell_density - (charge_density or 0.0)) * math.pi * length)
    if need <= 0.0:
        return None
    d = 2.0 * math.sqrt(need)
    given = (f"the given {1e3 * shape.cavity_diameter:g} mm cavity"
             f"{' with its step' if shape.step_length > 0 else ''} cannot reach it")
    if MIN_CAVITY_FRACTION * shape.diameter <= d <= widest:
        out = replace(solid, cavity_diameter=d, cavity_length=length)
        out.check()
        return Built(out, shell_density, f"projectile.mass {mass:g} kg: cavity {1e3 * d:.2f} mm x "
                                         f"{1e3 * length:.1f} mm (one section; {given})")
    if d > widest and charge_density is None:
        out = replace(solid, cavity_diameter=widest, cavity_length=length)
        rho = mass / out.shell_volume()
        if rho >= shell_density * (1.0 - MAX_DENSITY_CHANGE):
            out.check()
            return Built(out, rho, f"projectile.mass {mass:g} kg: widest cavity {1e3 * widest:.2f} mm x "
                                   f"{1e3 * length:.1f} mm and steel density adjusted to {rho:.1f} kg/m^3 "
                                   f"({rho / shell_density - 1:+.1%}; lighter than any cavity makes it)")
    return None
