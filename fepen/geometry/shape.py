"""The projectile as an exact solid of revolution, without any mesh: a tangent ogive (or flat) nose, a
cylinder, a closed two-section cavity sized to a mass. Body frame: nose tip at the origin, axis along +y
(docs/theory.md §1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from fepen.errors import InputError

#: thinnest wall fepen accepts anywhere around the cavity, as a fraction of the diameter
MIN_WALL_FRACTION = 0.05


@dataclass(frozen=True)
class Shape:
    """Exact geometry of the projectile (SI units).

    Attributes:
        diameter, length: outer calibre and overall length (m).
        nose: "ogive" or "flat".
        crh: ogive radius over diameter (tangent ogive).
        cavity_diameter, cavity_length: main cavity diameter and total cavity length (m); 0: solid.
        step_diameter, step_length: the narrower forward cavity section (m).
        base_thickness: rear wall behind the cavity (m).
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

    @property
    def radius(self) -> float:
        return 0.5 * self.diameter

    @property
    def nose_length(self) -> float:
        """Axial length of the tangent ogive, a sqrt(4 crh - 1); 0 for a flat nose."""
        if self.nose == "flat":
            return 0.0
        return self.radius * math.sqrt(4.0 * self.crh - 1.0)

    @property
    def ogive_radius(self) -> float:
        return self.crh * self.diameter

    def outer_radius(self, z):
        """Outer radius at axial distance z from the tip (array-aware)."""
        z = np.asarray(z, dtype=float)
        a, ln = self.radius, self.nose_length
        if ln == 0.0:
            return np.full_like(z, a)
        s = self.ogive_radius
        nose = np.sqrt(np.maximum(s * s - (ln - np.minimum(z, ln)) ** 2, 0.0)) - (s - a)
        return np.where(z < ln, np.maximum(nose, 0.0), a)

    @property
    def has_cavity(self) -> bool:
        return self.cavity_diameter > 0.0 and self.cavity_length > 0.0

    def cavity_sections(self) -> list[tuple[float, float, float]]:
        """Cavity as (z_front, z_rear, radius) cylinders, forward first; empty for a solid body."""
        if not self.has_cavity:
            return []
        z_rear = self.length - self.base_thickness
        z_front = z_rear - self.cavity_length
        step = min(self.step_length, self.cavity_length)
        out = []
        if step > 0.0 and self.step_diameter > 0.0:
            out.append((z_front, z_front + step, 0.5 * self.step_diameter))
            z_front += step
        if z_rear > z_front:
            out.append((z_front, z_rear, 0.5 * self.cavity_diameter))
        return out

    def outer_volume(self) -> float:
        """Exact volume inside the outer surface (m^3): Gauss-Legendre on the nose, exact on the rest."""
        ln = self.nose_length
        vol = math.pi * self.radius**2 * (self.length - ln)
        if ln > 0.0:
            x, w = np.polynomial.legendre.leggauss(64)
            z = 0.5 * ln * (x + 1.0)
            vol += 0.5 * ln * float(np.sum(w * math.pi * self.outer_radius(z) ** 2))
        return vol

    def outer_area(self) -> float:
        """Exact area of the outer surface (m^2): ogive 2 pi s (l - c asin(l/s)), shank, rear face."""
        a, ln = self.radius, self.nose_length
        area = 2 * math.pi * a * (self.length - ln) + math.pi * a * a
        if ln > 0.0:
            s = self.ogive_radius
            area += 2 * math.pi * s * (ln - (s - a) * math.asin(ln / s))
        else:
            area += math.pi * a * a
        return area

    def cavity_area(self) -> float:
        """Exact area of the cavity wall (m^2): two end discs, the step ring, the lateral surfaces."""
        sec = self.cavity_sections()
        if not sec:
            return 0.0
        area = sum(2 * math.pi * r * (z1 - z0) for z0, z1, r in sec)
        radii = [0.0] + [r for _, _, r in sec] + [0.0]
        return area + sum(math.pi * abs(r1 * r1 - r0 * r0) for r0, r1 in zip(radii[:-1], radii[1:]))

    def cavity_volume(self) -> float:
        """Exact cavity volume (m^3)."""
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

    # ---- outer surface, for the target law -------------------------------------------------------
    def surface_info(self, X: np.ndarray, tol: float | None = None):
        """Exact outward normals and curvature data of outer-surface points given in the body frame.

        Args:
            X: points on the outer surface (k, 3), body frame (tip at the origin, axis +y).
            tol: distance tolerance (default 1e-7 L).

        Returns:
            (normal (k, 3), nan rows on edges and the ogive apex where no single normal exists;
             radius (k,): distance from the axis;
             R_meridian (k,): meridional radius of curvature (s on the ogive, inf elsewhere);
             sin_phi0 (k,): sine of the angle between the surface and the axis (1 on flat faces)).
        """
        tol = 1e-7 * self.length if tol is None else tol
        X = np.asarray(X, dtype=float)
        x, y, z = X[:, 0], X[:, 1], X[:, 2]
        r = np.hypot(x, z)
        safe = np.maximum(r, 1e-300)
        radial = np.stack([x / safe, np.zeros_like(r), z / safe], axis=1)
        normal = np.full_like(X, np.nan)
        Rm = np.full(len(X), np.inf)
        sphi = np.zeros(len(X))
        a, L, ln = self.radius, self.length, self.nose_length
        on_rim = np.abs(r - a) < tol
        rear = np.abs(y - L) < tol
        normal[rear & ~on_rim] = [0.0, 1.0, 0.0]
        sphi[rear] = 1.0
        if ln == 0.0:
            front = np.abs(y) < tol
            normal[front & ~on_rim] = [0.0, -1.0, 0.0]
            sphi[front] = 1.0
            side = on_rim & ~front & ~rear
        else:
            s = self.ogive_radius
            nose = (y < ln - tol) & (r > tol)
            rc = r[nose] - (a - s)  # meridional offset from the arc centre (a - s, ln)
            yc = y[nose] - ln
            normal[nose] = (rc[:, None] * radial[nose] + yc[:, None] * np.array([0.0, 1.0, 0.0])) / s
            Rm[nose] = s
            sphi[nose] = np.abs(yc) / s
            side = on_rim & (y >= ln - tol) & ~rear
        normal[side] = radial[side]
        return normal, r, Rm, sphi

    def project(self, X: np.ndarray, patch: np.ndarray) -> np.ndarray:
        """Closest points on the exact outer surface of points near it, given their patch.

        Args:
            X: points (k, 3), body frame. patch: per point 0 = lateral (ogive or shank, by y), 1 = rear face,
               2 = flat front face.

        Returns:
            (k, 3) points on the exact surface.
        """
        X = np.array(X, dtype=float)
        out = X.copy()
        r = np.hypot(X[:, 0], X[:, 2])
        safe = np.maximum(r, 1e-300)
        a, ln = self.radius, self.nose_length
        rear, front, lat = patch == 1, patch == 2, patch == 0
        out[rear, 1] = self.length
        out[front, 1] = 0.0
        shank = lat & (X[:, 1] >= ln)
        out[shank, 0] *= a / safe[shank]
        out[shank, 2] *= a / safe[shank]
        nose = lat & (X[:, 1] < ln)
        if np.any(nose):
            s = self.ogive_radius
            rc, yc = r[nose] - (a - s), X[nose, 1] - ln  # from the arc centre (a - s, ln)
            d = np.hypot(rc, yc)
            rn = (a - s) + s * rc / d
            out[nose, 1] = ln + s * yc / d
            out[nose, 0] = X[nose, 0] * rn / safe[nose]
            out[nose, 2] = X[nose, 2] * rn / safe[nose]
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

    def max_cavity_length(self) -> float:
        """Longest cavity that fits with the minimum wall everywhere (m)."""
        z_rear = self.length - self.base_thickness
        lead_r = 0.5 * (self.step_diameter if self.step_length > 0.0 and self.step_diameter > 0 else
                        self.cavity_diameter)
        z_step = self.front_limit(lead_r)
        # the main section must also fit where the step ends
        z_main = self.front_limit(0.5 * self.cavity_diameter) - (self.step_length if lead_r > 0 else 0.0)
        return max(0.0, z_rear - max(z_step, z_main))

    def check(self) -> None:
        """Raise InputError (naming the scene key) if this shape cannot be built."""
        D, a = self.diameter, self.radius
        if self.nose == "ogive" and self.nose_length >= self.length:
            raise InputError("projectile.length",
                             f"{self.length:g} m is shorter than the ogive nose ({self.nose_length:g} m at "
                             f"crh {self.crh:g}); use a longer body or a smaller projectile.crh")
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
        if self.base_thickness >= self.length - self.nose_length:
            raise InputError("projectile.base_thickness",
                             f"{self.base_thickness:g} m: must be less than the body behind the nose, "
                             f"{self.length - self.nose_length:g} m")
        if self.cavity_length > 0.0:
            top = self.max_cavity_length()
            if self.cavity_length > top:
                raise InputError("projectile.cavity_length",
                                 f"{self.cavity_length:g} m does not fit: must be in (0, {top:.6g}] m with "
                                 f"this nose, diameter and base thickness")
            if self.step_length >= self.cavity_length:
                raise InputError("projectile.cavity_step_length",
                                 f"{self.step_length:g} m: must be less than the cavity length "
                                 f"{self.cavity_length:g} m")
        del a

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
        longest = replace(self, cavity_length=self.max_cavity_length())
        shortest = replace(self, cavity_length=self.step_length + 1e-9 * self.length)
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
    solid = replace(shape, cavity_diameter=0.0, cavity_length=0.0, step_diameter=0.0, step_length=0.0)
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
