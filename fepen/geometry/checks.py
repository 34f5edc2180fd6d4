"""Whether a Shape can be built: the minimum wall around the cavity, the room the outside leaves for a cavity
(front_limit, max_cavity_length), and check, which names the scene key of the first thing that does not fit
(docs/theory.md §1). The mass rule (fepen.geometry.mass_rule) sizes cavities within these limits.
"""

from __future__ import annotations

import functools
import math
from dataclasses import replace

from fepen.errors import InputError
from fepen.geometry import profile as P
from fepen.geometry.shape import Shape

#: thinnest wall fepen accepts anywhere around the cavity, as a fraction of the diameter
MIN_WALL_FRACTION = 0.05


def min_wall(shape: Shape) -> float:
    """The thinnest wall allowed around the cavity of this shape (m).

    Args:
        shape: the exact geometry.

    Returns:
        MIN_WALL_FRACTION times the diameter.
    """
    return MIN_WALL_FRACTION * shape.diameter


def front_limit(shape: Shape, radius: float) -> float:
    """Smallest z at which a cavity of this radius keeps the minimum wall to the outer surface.

    Args:
        shape: the exact geometry. radius: the cavity's radius (m).

    Returns:
        The axial distance from the tip (m); inf when no such cavity fits the calibre.
    """
    need = radius + min_wall(shape)
    if need >= shape.radius:
        return math.inf
    if shape.nose_length == 0.0:
        return min_wall(shape)
    # outer_radius is monotone on the nose: bisection
    lo, hi = 0.0, shape.nose_length
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if shape.outer_radius(mid) < need:
            if mid == lo:  # nothing moved: every further step is this one (the same bisection, sooner)
                break
            lo = mid
        else:
            if mid == hi:
                break
            hi = mid
    return max(hi, min_wall(shape))


def fits(shape: Shape, cavity_length: float) -> bool:
    """Whether the cavity of this total length keeps the minimum wall everywhere (sideways and ahead).

    Args:
        shape: the exact geometry (its cavity sections). cavity_length: the total cavity length to try (m).

    Returns:
        True when every section keeps the minimum wall.
    """
    wall = min_wall(shape)
    for z0, z1, r in replace(shape, cavity_length=cavity_length).cavity_sections():
        if z0 < wall * (1.0 - 1e-12) or P.min_radius(shape.outer_path, z0, z1) < (r + wall) * (1.0 - 1e-12):
            return False
    return True


def max_cavity_length(shape: Shape) -> float:
    """Longest cavity that fits with the minimum wall everywhere: bisection on the total length (the sections
    move forward into the nose as it grows; the rear one must fit any boat-tail). Cached per shape but for
    its cavity length, which it ignores (the mass rule asks of a shape, then checks it with the length found).

    Args:
        shape: the exact geometry (its cavity sections; its cavity length is ignored).

    Returns:
        The longest total cavity length (m); 0 when not even the forward sections fit.
    """
    return _max_cavity_length(replace(shape, cavity_length=0.0) if shape.cavity_length else shape)


@functools.lru_cache(maxsize=64)
def _max_cavity_length(shape: Shape) -> float:
    z_rear = shape.length - shape.base_thickness
    lo = shape.fore_length() + 1e-9 * shape.length
    if not fits(shape, lo):
        return 0.0
    hi = z_rear
    if fits(shape, hi):
        return hi
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if fits(shape, mid):
            if mid == lo:  # nothing moved: every further step is this one (the same bisection, sooner)
                break
            lo = mid
        else:
            if mid == hi:
                break
            hi = mid
    return lo


def check(shape: Shape) -> None:
    """Raise InputError (naming the scene key) if this shape cannot be built.

    Args:
        shape: the exact geometry.

    Returns:
        None; raises InputError on the first part that does not fit.
    """
    if shape.nose != "profile":
        _check_outside(shape)
    if shape.inner_points:
        _check_drawn_cavity(shape)
        return
    if shape.cavity_diameter <= 0.0:
        return
    _check_cavity(shape)


def _check_outside(shape: Shape) -> None:
    """The nose family's own limits, the length behind the nose and the boat-tail (a parametric outside)."""
    D, a = shape.diameter, shape.radius
    rm = 0.5 * shape.meplat_diameter
    if rm >= a and shape.nose != "flat":
        raise InputError("projectile.meplat_diameter",
                         f"{shape.meplat_diameter:g} m: must be less than projectile.diameter = {D:g} m")
    if shape.nose in ("secant", "cone", "ellipsoid") and shape.nose_length_given <= 0.0:
        raise InputError("projectile.nose_length", f"a {shape.nose} nose needs its length: give "
                                                   f"projectile.nose_length > 0 (m)")
    if shape.nose == "secant":
        tangent = a * math.sqrt(4.0 * shape.crh - 1.0)
        if shape.nose_length_given > tangent * (1.0 + 1e-12):
            raise InputError("projectile.nose_length",
                             f"{shape.nose_length_given:g} m: a secant ogive of crh {shape.crh:g} must be at "
                             f"most the tangent ogive's {tangent:.6g} m long (longer bulges past the "
                             f"calibre); use a larger projectile.crh")
    if shape.nose_length >= shape.length - shape.boattail_length:
        raise InputError("projectile.length",
                         f"{shape.length:g} m is too short for the {shape.nose} nose ({shape.nose_length:g} m)"
                         + (f" and the boat-tail ({shape.boattail_length:g} m)" if shape.boattail_length else "")
                         + "; use a longer body or a shorter nose")
    if shape.boattail_length > 0.0 and not 0.0 < shape.boattail_diameter < D:
        raise InputError("projectile.boattail_diameter",
                         f"{shape.boattail_diameter:g} m: must be in (0, {D:g}) m (projectile.diameter) "
                         f"with a boat-tail")


def _check_cavity(shape: Shape) -> None:
    """A cavity of sections (rear diameter, step or table, length, base) inside the body with the minimum
    wall."""
    D = shape.diameter
    wall = min_wall(shape)
    if shape.cavity_diameter > D - 2 * wall:
        raise InputError("projectile.cavity_diameter",
                         f"{shape.cavity_diameter:g} m leaves no wall: must be at most diameter - 2 x "
                         f"{wall:g} m = {D - 2 * wall:g} m")
    if shape.step_diameter > shape.cavity_diameter:
        raise InputError("projectile.cavity_step_diameter",
                         f"{shape.step_diameter:g} m: must be at most projectile.cavity_diameter = "
                         f"{shape.cavity_diameter:g} m")
    for l, d in shape.fore_sections() if shape.cavity_table else []:
        if not (0.0 < d <= D - 2 * wall and l > 0.0):
            raise InputError("projectile.cavity_sections",
                             f"section [{l:g}, {d:g}]: lengths must be > 0 and diameters in (0, "
                             f"{D - 2 * wall:g}] m (the minimum wall {wall:g} m)")
    if shape.base_thickness >= shape.length - shape.nose_length:
        raise InputError("projectile.base_thickness",
                         f"{shape.base_thickness:g} m: must be less than the body behind the nose, "
                         f"{shape.length - shape.nose_length:g} m")
    if shape.cavity_length > 0.0:
        top = max_cavity_length(shape)
        if shape.cavity_length > top * (1.0 + 1e-12):
            raise InputError("projectile.cavity_length",
                             f"{shape.cavity_length:g} m does not fit: must be in (0, {top:.6g}] m with "
                             f"this nose, diameter, boat-tail and base thickness")
        if shape.fore_length() >= shape.cavity_length:
            key = "projectile.cavity_sections" if shape.cavity_table else "projectile.cavity_step_length"
            raise InputError(key, f"{shape.fore_length():g} m: the forward sections must be shorter than "
                                  f"the cavity, {shape.cavity_length:g} m")


def _check_drawn_cavity(shape: Shape) -> None:
    """A drawn cavity lies inside the body with the minimum wall."""
    wall = min_wall(shape)
    for seg in shape.inner_path:
        z0, z1 = seg.z_range()
        r = seg.r_range()[1]
        if z0 < wall * (1 - 1e-9) or z1 > shape.length - wall * (1 - 1e-9) or (
                r > 0 and P.min_radius(shape.outer_path, z0, z1) < r + wall * (1 - 1e-9)):
            raise InputError("projectile.inner_profile",
                             f"the segment from (z {seg.p0[1]:g}, r {seg.p0[0]:g}) to (z {seg.p1[1]:g}, r "
                             f"{seg.p1[0]:g}) m leaves less than the minimum wall {wall:g} m to the outside")
