"""The mass-reaching rule (docs/theory.md §1.1): the projectile of a given outside with a given total mass, its
cavity sized, reduced or dropped (reach_mass), the cavity length that gives a mass (with_mass), and on the
mesh, the cavity length corrected until gmsh's mesh has the mass (mesh_to_mass).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from fepen.errors import InputError
from fepen.geometry import gmsh_model, tags
from fepen.geometry.cad import CadBody
from fepen.geometry.checks import check, fits, front_limit, max_cavity_length, min_wall
from fepen.geometry.shape import Shape

#: shortest cavity worth keeping, in its own diameters: below this a sized cavity is reduced instead
MIN_CAVITY_ASPECT = 1.0
#: narrowest cavity worth keeping, as a fraction of the outer diameter: below this the body is made solid
MIN_CAVITY_FRACTION = 0.05
#: largest change of the steel density the mass rule makes when no cavity reaches the mass
MAX_DENSITY_CHANGE = 0.25


@dataclass(frozen=True)
class Built:
    """A projectile built to a mass (reach_mass), or a CAD body as read (fepen.runs.setup).

    Attributes:
        shape: the exact geometry, or the CadBody. shell_density: the steel's density used (kg/m^3), the
        scene's unless the body had to be made solid with an adjusted density. note: one line saying what
        was changed, "" if the given cavity was only sized.
    """

    shape: Shape | CadBody
    shell_density: float
    note: str = ""


def with_mass(shape: Shape, mass: float, shell_density: float, charge_density: float | None = None) -> Shape:
    """The same shape with the cavity length that gives this total mass.

    Args:
        shape: the checked geometry with its cavity sections (its cavity length a first guess).
        mass: wanted total mass (kg).
        shell_density: steel density (kg/m^3).
        charge_density: charge density (kg/m^3) when the cavity is filled, else None.

    Returns:
        A new Shape. Raises InputError (key projectile.mass) when the mass cannot be reached.
    """
    rho_fill = charge_density or 0.0
    top, fore = max_cavity_length(shape), shape.fore_length()
    if top <= fore:  # not even the forward sections fit: no mass range to speak of
        rear = replace(shape, step_length=0.0, step_diameter=0.0, cavity_table=())
        key = ("projectile.cavity_diameter" if not fore or not fits(rear, 1e-9 * shape.length) else
               "projectile.cavity_sections" if shape.cavity_table else "projectile.cavity_step_length")
        raise InputError(key, f"the cavity ({1e3 * shape.cavity_diameter:g} mm rear section"
                              + (f" behind {1e3 * fore:g} mm of forward sections" if fore else "")
                              + f") does not fit this nose, diameter, boat-tail and base thickness with the "
                                f"minimum wall {min_wall(shape):g} m" + (f": at most {top:.4g} m of cavity fits"
                                                                          if top > 0 else ""))
    longest = replace(shape, cavity_length=top)
    shortest = replace(shape, cavity_length=shape.fore_length() + 1e-9 * shape.length)
    m_hi = shortest.mass(shell_density, charge_density)
    m_lo = longest.mass(shell_density, charge_density)
    if not (m_lo <= mass <= m_hi):
        raise InputError("projectile.mass",
                         f"{mass:g} kg is unreachable with this shape and cavity diameters: must be in "
                         f"[{m_lo:.4g}, {m_hi:.4g}] kg")
    # mass is linear in the main section's length
    r = 0.5 * shape.cavity_diameter
    slope = (shell_density - rho_fill) * math.pi * r * r
    extra = (m_hi - mass) / slope
    out = replace(shape, cavity_length=shortest.cavity_length + extra)
    check(out)
    return out


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
            out = with_mass(shape, mass, shell_density, charge_density)
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
    """The widest cavity that keeps the minimum wall and the longest length it fits: narrower cavities fit
    that length too.

    Args:
        shape: the checked outside.

    Returns:
        (diameter, length) (m); length 0 when none fits.
    """
    widest = (shape.diameter - 2.0 * min_wall(shape)) * (1.0 - 1e-9)
    if widest <= MIN_CAVITY_FRACTION * shape.diameter or shape.base_thickness >= shape.length - shape.nose_length:
        return widest, 0.0
    return widest, max(0.0, shape.length - shape.base_thickness - front_limit(shape, 0.5 * widest))


def _one_cylinder(shape, solid, widest, length, mass, shell_density, charge_density) -> Built | None:
    """Rules 2 and 3 (light side) of reach_mass: one cylinder of the longest length, its diameter sized (mass
    is linear in r²); lighter than the widest, that one with the steel lightened.

    Args:
        shape: the given shape (for the note). solid: its outside without a cavity. widest, length: of
            _widest_cavity. mass, shell_density, charge_density: as reach_mass.

    Returns:
        Built, or None if neither rule applies.
    """
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
        check(out)
        return Built(out, shell_density, f"projectile.mass {mass:g} kg: cavity {1e3 * d:.2f} mm x "
                                         f"{1e3 * length:.1f} mm (one section; {given})")
    if d > widest and charge_density is None:
        out = replace(solid, cavity_diameter=widest, cavity_length=length)
        rho = mass / out.shell_volume()
        if rho >= shell_density * (1.0 - MAX_DENSITY_CHANGE):
            check(out)
            return Built(out, rho, f"projectile.mass {mass:g} kg: widest cavity {1e3 * widest:.2f} mm x "
                                   f"{1e3 * length:.1f} mm and steel density adjusted to {rho:.1f} kg/m^3 "
                                   f"({rho / shell_density - 1:+.1%}; lighter than any cavity makes it)")
    return None


# ---------------------------------------------------------------------------------------------------------
# the cavity sized to the mass on the mesh
# ---------------------------------------------------------------------------------------------------------
#: mesh-mass tolerance of the cavity sizing (kg)
MASS_TOLERANCE = 2.5e-4


def mesh_mass(rho_s: float, rho_c: float | None) -> float:
    """Rank 0: the mass of the mesh in gmsh (kg): its shell at rho_s, its charge at rho_c unless None."""
    m = rho_s * gmsh_model.tet_volumes(tags.SHELL).sum()
    if rho_c is not None:
        m += rho_c * gmsh_model.tet_volumes(tags.CHARGE).sum()
    return m


def mesh_to_mass(shape: Shape | CadBody, opts: gmsh_model.MeshOptions, charge: bool, mass: float | None,
                 rho_s: float, rho_c: float | None) -> Shape | CadBody:
    """Rank 0: the body meshed in gmsh, its cavity length corrected until the mesh's mass is within
    MASS_TOLERANCE of ``mass`` (five tries on seed 1's meshes), then the seeds tried for the best altitude (the
    surface mesh, hence the mass, kept).

    Args:
        shape: the checked body (its cavity length a first guess). opts: gmsh's sizes and optimiser.
        charge: mesh the charge. mass: the mass to reach (kg), or None. rho_s, rho_c: the shell's and the
            charge's densities (kg/m^3; rho_c None: no charge).

    Returns:
        The body as meshed: its cavity length as corrected, a CAD body's tracked ends the mesh's nodes.
    """
    import gmsh

    current = shape
    for attempt in range(5):  # the cavity sized to the mass on seed 1's meshes; then the seeds for the altitude
        gmsh.clear()
        gmsh_model.build(current, opts, charge, 1)
        if mass is None or not current.has_cavity:
            break
        error = mesh_mass(rho_s, rho_c) - mass
        if abs(error) <= MASS_TOLERANCE or attempt == 4:
            break
        r = 0.5 * current.cavity_diameter
        step = error / ((rho_s - (rho_c or 0.0)) * math.pi * r * r)
        current = replace(current, cavity_length=current.cavity_length + step)
        check(current)
    gmsh_model.best_seed(opts)  # the volumes again with other seeds: the surface mesh, hence the mass, kept
    return current.after_meshing()  # a CAD body's tracked ends: mesh nodes
