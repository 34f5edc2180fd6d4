"""The projectile as an exact solid of revolution, without any mesh: its meridian (fepen.geometry.profile
segments) from a nose family (NOSES: tangent or secant ogive, cone, hemisphere, ellipsoid, flat, with a
meplat and a boat-tail) or a drawn outer profile, and a cavity of sections (a step, or a table) or a drawn
one; its exact volumes, areas, mass and nose factor. Body frame: nose tip at the origin, axis along +y
(docs/theory.md §1).

Elsewhere: whether it fits (fepen.geometry.checks), its cavity sized to a mass (fepen.geometry.mass_rule),
points of a mesh on its surface (fepen.geometry.projection); a body from a CAD file is a
fepen.geometry.cad.CadBody instead.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from fepen.geometry import profile as P

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

    def __post_init__(self):
        for name in ("cavity_table", "outer_points", "inner_points"):  # lists from JSON back to tuples
            object.__setattr__(self, name, tuple(tuple(float(v) for v in row) for row in getattr(self, name)))

    @property
    def tip(self) -> tuple:
        """The tracked nose-tip point of the reference body (a mesh node): the origin."""
        return (0.0, 0.0, 0.0)

    @property
    def tail(self) -> tuple:
        """The tracked tail-centre point of the reference body (a mesh node): on the axis at the length."""
        return (0.0, self.length, 0.0)

    @property
    def radius(self) -> float:
        """Half the calibre (m)."""
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
        if self.nose == "profile":
            for seg in self.outer_path:
                for r, z in (seg.p0, seg.p1):
                    if r >= self.radius * (1.0 - 1e-12):
                        return z
            return self.length
        return self._nose_path()[1]

    @property
    def ogive_radius(self) -> float:
        """Radius of the ogive's arc (m): crh times the diameter."""
        return self.crh * self.diameter

    def outer_radius(self, z):
        """Outer radius at axial distances from the tip.

        Args:
            z: axial distance(s) from the tip (m), clipped to [0, length].

        Returns:
            The radius (m), an array of z's shape.
        """
        z = np.asarray(z, dtype=float)
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

    def meshed_volume(self, charge: bool) -> float:
        """The volume gmsh fills (m^3): the outside with a meshed charge, the shell without."""
        return self.outer_volume() if charge else self.shell_volume()

    #: the exact volume its mesh approximates (m^3), the meshed volume (a CadBody's is not known: None)
    exact_volume = meshed_volume

    def needs_volume_mesh(self, fidelity: str) -> bool:
        """Whether a run of ``fidelity`` (effects.fidelity) meshes the body: the deformable ones only (a rigid
        body's load points and mass properties are the exact solid's, fepen.geometry.revolution).

        Returns:
            True when a volume mesh is made."""
        return fidelity != "rigid"

    def crater_nose_factor(self) -> float | None:
        """N* the linear crater takes: None (Forrestal's ogive formula) for a sharp ogive, else nose_factor."""
        return None if self.nose == "ogive" and not self.meplat_diameter else self.nose_factor()

    def after_meshing(self) -> Shape:
        """The body after gmsh meshed it: unchanged (its ends are exact points)."""
        return self

    @property
    def has_cavity(self) -> bool:
        """Whether the body is hollow (a cavity of sections or a drawn one)."""
        return bool(self.inner_points) or (self.cavity_diameter > 0.0 and self.cavity_length > 0.0)

    def fore_sections(self) -> list[tuple[float, float]]:
        """The forward cavity sections (length, diameter) before the rear one."""
        if self.cavity_table:
            return [(float(l), float(d)) for l, d in self.cavity_table]
        if self.step_length > 0.0 and self.step_diameter > 0.0:
            return [(self.step_length, self.step_diameter)]
        return []

    def fore_length(self) -> float:
        """Total length of the forward cavity sections (m)."""
        return sum(l for l, _ in self.fore_sections())

    def cavity_sections(self) -> list[tuple[float, float, float]]:
        """Cavity as (z_front, z_rear, radius) cylinders, forward first; empty for a solid body (or a drawn
        cavity)."""
        if self.inner_points or not (self.cavity_diameter > 0.0 and self.cavity_length > 0.0):
            return []
        z_rear = self.length - self.base_thickness
        z_front = z_rear - self.cavity_length
        out = []
        for l, d in self.fore_sections():
            step = min(l, z_rear - z_front)
            if step > 0.0:
                out.append((z_front, z_front + step, 0.5 * d))
                z_front += step
        if z_rear > z_front:
            out.append((z_front, z_rear, 0.5 * self.cavity_diameter))
        return out

    def outer_volume(self) -> float:
        """Exact volume inside the outer surface (m^3) (Green's theorem along the meridian)."""
        if self.nose == "ogive" and not self.meplat_diameter and not self.boattail_length:
            # the paper's family, summed exactly as fepen always did (shank, then Gauss-Legendre along z on the
            # nose), so that the cavity sized to the mass, the mesh and Table 1 do not move by round-off
            ln, a, s = self.nose_length, self.radius, self.ogive_radius
            vol = math.pi * a**2 * (self.length - ln)
            x, w = P.gauss(64)
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
        """Total mass: the shell, plus the charge filling the cavity when charge_density is given.

        Args:
            shell_density: steel density (kg/m^3). charge_density: the charge's (kg/m^3), or None (empty).

        Returns:
            The mass (kg).
        """
        m = shell_density * self.shell_volume()
        if charge_density is not None:
            m += charge_density * self.cavity_volume()
        return m

    #: the mass known before any mesh (kg): mass() (a CadBody's comes from its mesh: None)
    exact_mass = mass

    def nose_factor(self) -> float:
        """N* of the nose: (1/(π a²)) ∫ (−n_y)³ dA over the surface facing forward, so that a rigid nose moving
        along its axis at V against σ_n = σ_s + ρ (v·n)² feels π a² (σ_s + N* ρ V²) (frictionless):
        (8ψ − 1)/(24ψ²) for a tangent ogive, 1/2 for a hemisphere, 1 flat."""
        x, w = P.gauss(P.GAUSS)
        u = 0.5 * (x + 1.0)
        total = 0.0
        for seg in self.outer_path:
            r, _ = seg.point(u)
            nr, nz = seg.normal(u)
            dr, dz = seg.derivative(u)
            c = np.maximum(-nz, 0.0)
            total += 2.0 * math.pi * float(0.5 * w @ (r * c**3 * np.hypot(dr, dz)))
        return total / (math.pi * self.radius**2)
