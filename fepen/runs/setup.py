"""The one door from a scene to the physics: every law, shape and mesh a run needs, built from a resolved
Scene (the deformable model on top of them: fepen.runs.model). No module below fepen.runs reads a scene
(docs/theory.md §1-§10 give the defaults' reasons). Imports no dolfinx: the rigid fidelity needs none.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from mpi4py import MPI

from fepen.errors import InputError
from fepen.geometry import gmsh_model, profile, tags, tetra
from fepen.geometry import mesh as fmesh
from fepen.geometry.cad import CadBody
from fepen.geometry.checks import check
from fepen.geometry.mass_rule import Built, reach_mass
from fepen.geometry.shape import Shape
from fepen.runs import targets
from fepen.runs.targets import check_friction, material_law, strength_field, target_law  # noqa: F401 - their names here
from fepen.scene import SCHEMA


# ---------------------------------------------------------------------------------------------------------
# laws and shape from the scene
# ---------------------------------------------------------------------------------------------------------
def projectile_material(scene, built: Built | None = None):
    """The projectile material (fepen.laws.materials.Material): elastic or Johnson-Cook by effects.fidelity.

    Args:
        built: the projectile, when already built (its shell density); default: projectile(scene).
    """
    from fepen.laws import materials as M  # numba: only a deformable run pays for importing it

    m = scene.projectile.material
    rho = (built or projectile(scene)).shell_density
    if scene.effects.fidelity == "elastic":
        return M.elastic(m.youngs_modulus, m.poisson_ratio, rho)
    return M.johnson_cook(m.youngs_modulus, m.poisson_ratio, rho, m.A, m.B, m.n, m.C, m.m,
                          m.melt_temperature, m.room_temperature, m.reference_strain_rate, m.specific_heat,
                          m.taylor_quinney, scene.effects.strain_rate, scene.effects.thermal)


def materials(scene, built: Built) -> list:
    """The deformable fidelities' materials: the shell's, then the charge's when effects.charge."""
    return [projectile_material(scene, built)] + ([charge_material(scene)] if scene.effects.charge else [])


def charge_material(scene):
    """The explosive charge material (bilinear, docs/charge.md)."""
    from fepen.laws import materials as M

    c = scene.charge.material
    return M.bilinear(c.youngs_modulus, c.poisson_ratio, c.density, c.yield_stress, c.tangent_modulus)


#: cavity keys that, when the user gives any of them, fix the cavity (its length is still sized to the mass)
CAVITY_KEYS = ("projectile.cavity_diameter", "projectile.cavity_length", "projectile.cavity_step_diameter",
               "projectile.cavity_step_length", "projectile.cavity_sections")


#: the projectiles built so far in this process, by _built_key: a sweep's, a depth study's or a calibration's
#: shots of one projectile build it once (the mass rule's bisections are most of a rigid shot's set-up)
_BUILT: dict = {}
#: keys that name files the projectile is read from: such a projectile is built anew every time
FILE_KEYS = ("projectile.cad", "projectile.profile", "projectile.inner_profile")


def projectile(scene) -> Built:
    """See _projectile (built once per projectile in a process: a Built is frozen, share it); a cavity given
    as projectile.cavity_sections is named so in errors."""
    key = _built_key(scene)
    hit = _BUILT.get(key) if key is not None else None
    if hit is not None:
        return hit
    try:
        built = _projectile(scene)
    except InputError as err:
        if scene.get("projectile.cavity_sections") and err.key in CAVITY_KEYS:
            raise InputError("projectile.cavity_sections", err.message) from None
        raise
    if key is not None:
        if len(_BUILT) >= 64:
            _BUILT.clear()
        _BUILT[key] = built
    return built


def _built_key(scene) -> tuple | None:
    """What _projectile reads of a scene: its body_key and which projectile keys were given (a given cavity is
    only sized); None for a projectile read from files (they may change between two runs)."""
    if any(scene.get(k) for k in FILE_KEYS):
        return None
    return body_key(scene), tuple(sorted(k for k in scene.explicit if k.startswith("projectile.")))


def _cad_projectile(scene) -> Built:
    """A body read from projectile.cad: calibre and length from the file, mass from its mesh."""
    import os

    from fepen.geometry import cad

    path = os.path.abspath(scene.projectile.cad)
    scale = scene.projectile.cad_scale
    D, L = cad.probe(path, scale)
    if not (0.0 < D <= 1.0 and 0.0 < L <= 10.0):
        raise InputError("projectile.cad_scale", f"the body is {D:g} m wide and {L:g} m long after scaling by "
                                                 f"{scale:g}: give the scale that makes its lengths metres")
    body = CadBody(D, L, path, scale, cad.digest(path))
    return Built(body, scene.projectile.material.density)


def _projectile(scene) -> Built:
    if scene.get("projectile.cad"):
        return _cad_projectile(scene)
    """The checked exact projectile built to projectile.mass by the mass-reaching rule
    (fepen.geometry.mass_rule.reach_mass): the given cavity sized, else reduced or dropped, with one line in
    Built.note saying what was chosen. A cavity the user gave explicitly is only sized (InputError if the
    mass is out of its reach). InputError on impossible geometry, in well under a second."""
    p = scene.projectile
    solid = p.cavity_diameter == 0.0
    explicit = any(k in scene.explicit for k in CAVITY_KEYS)
    mass = scene.get("projectile.mass")
    sections = scene.get("projectile.cavity_sections")
    inner = scene.get("projectile.inner_profile")
    outer = scene.get("projectile.profile")
    table, cav_d, step_d, step_l = (), p.cavity_diameter, p.cavity_step_diameter, p.cavity_step_length
    cav_l = scene.get("projectile.cavity_length") or 0.0
    if sections:  # front ones fixed, the rear one sized (or the sum when no mass is asked for)
        table = tuple((l, d) for l, d in sections[:-1])
        cav_d, step_d, step_l, solid, explicit = sections[-1][1], 0.0, 0.0, False, True
        cav_l = sum(l for l, _ in sections) if mass is None else 0.0
    geometry = dict(nose=p.nose, crh=p.crh, base_thickness=p.base_thickness,
                    nose_length_given=scene.get("projectile.nose_length") or 0.0,
                    meplat_diameter=p.meplat_diameter, boattail_length=p.boattail_length,
                    boattail_diameter=scene.get("projectile.boattail_diameter") or 0.0)
    D, L = p.diameter, p.length
    if outer:
        pts = tuple(profile.read_points(outer, "projectile.profile"))
        geometry["outer_points"] = pts
        D, L = 2.0 * max(r for _, r, _ in pts), max(z for z, _, _ in pts) - min(z for z, _, _ in pts)
    if inner:
        geometry["inner_points"] = tuple(profile.read_points(inner, "projectile.inner_profile"))
        solid, cav_d = False, 0.0
    shape = Shape(
        diameter=D, length=L,
        cavity_diameter=0.0 if solid else cav_d,
        cavity_length=0.0 if solid else cav_l,
        step_diameter=0.0 if solid else step_d,
        step_length=0.0 if solid else step_l,
        cavity_table=() if solid else table, **geometry,
    )
    if mass is None or explicit or inner:
        check(shape)
    else:  # the outside only: a default cavity that does not fit is left to the mass rule
        check(replace(shape, cavity_diameter=0.0, cavity_table=()))
        _check_base(scene, shape)
    if mass is None or (solid and explicit) or inner:
        return Built(shape, p.material.density)
    rho_c = scene.charge.material.density if scene.effects.charge else None
    return reach_mass(shape, mass, p.material.density, rho_c, adapt=not explicit and not scene.effects.charge)


def _check_base(scene, shape: Shape) -> None:
    """A base thickness the user gave leaves room for a cavity behind the nose (the mass rule would otherwise
    drop the cavity and say so only in a note)."""
    room = shape.length - shape.nose_length
    if "projectile.base_thickness" in scene.explicit and shape.base_thickness >= room:
        raise InputError("projectile.base_thickness", f"{shape.base_thickness:g} m: must be less than the body "
                                                      f"behind the nose, {room:g} m")


def thin_target_note(scene, built: Built) -> str | None:
    """A line when the target, or one of its layers, is thinner than the nose is long: the nose is through
    before its shoulder enters, and the cavity-expansion law is a law of thick targets (docs/theory.md §16)."""
    nose = built.shape.nose_length  # a CAD body's is unknown: 0
    if not nose:
        return None
    for key, t in targets.of(scene).plates(scene):  # a rigid wall's: none
        if t is not None and t < nose:
            return (f"{key} {1e3 * t:g} mm is less than the nose length {1e3 * nose:.3g} mm: the nose is through "
                    "before its shoulder enters; the cavity-expansion law is a thick-target law, and a thin "
                    "plate's plugging, petalling or scabbing is beyond the method (docs/theory.md §16)")
    return None


def announce(scene, comm, built: Built | None = None) -> Built:
    """projectile(scene) (or ``built``), with its note (if any) and the friction note logged once, on rank 0:
    the front door of a run or a mesh."""
    built = built or projectile(scene)
    if comm.rank == 0:
        import logging

        for note in (built.note, thin_target_note(scene, built), *envelope_note(scene, built).split("\n")):
            if note:
                logging.getLogger("fepen").warning(note)
    return built


def projectile_shape(scene) -> Shape | CadBody:
    """The exact geometry of projectile(scene) (a CadBody for projectile.cad)."""
    return projectile(scene).shape


def placement(scene) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rotation (3x3) of the body about the nose tip, its velocity (3,) and its angular velocity (3, rad/s) at
    impact (docs/theory.md §7): the velocity v0 (sin α, −cos α, 0); the axis turned from it by ϑ in the plane
    at φ to the plane of fire (φ = 0: θ = α + ϑ about +z; fepen.geometry.frames.striking_rotation); the pitch
    rate about z and the yaw rate out of the plane (frames.striking_rate)."""
    from fepen.geometry import frames

    i = scene.impact
    a = math.radians(i.obliquity_deg)
    R = frames.striking_rotation(a, math.radians(i.attack_deg), math.radians(scene.get("impact.attack_plane_deg")))
    v = i.velocity * np.array([math.sin(a), -math.cos(a), 0.0])
    w = frames.striking_rate(R, scene.get("impact.pitch_rate_rad_s"), scene.get("impact.yaw_rate_rad_s"))
    return R, v, w


def check_supported(scene, built: Built | None = None, meshes: bool = True) -> Built:
    """Raise InputError for settings this version cannot simulate, before anything is meshed.

    Args:
        built: the projectile, when already built; default: projectile(scene) (InputError on its geometry).
        meshes: whether the caller goes on to mesh and run the scene; False (``fepen envelope``, which judges a
            scene and runs nothing) skips the dolfinx release and the mesh's cost, which only a mesh needs.

    Returns:
        The built projectile.
    """
    built = built or projectile(scene)
    mesh = meshes and (scene.effects.fidelity != "rigid" or scene.get("mesh.rigid_panel") is not None)
    if mesh:
        from fepen import dolfinx_api

        dolfinx_api.check_version()  # a mesh is made: only on the dolfinx releases fepen supports
    if meshes and built.shape.needs_volume_mesh(scene.effects.fidelity):
        check_mesh_cost(scene, MPI.COMM_WORLD, built)
    targets.of(scene).check(scene)  # the friction's strength; a rigid wall refuses the rigid fidelity
    return built


def check_mesh_cost(scene, comm, built: Built | None = None) -> dict:
    """The mesh's expected cells and memory, refused before gmsh starts when too coarse for the body or past
    mesh.max_cells or the machine's memory (fepen.runs.budget.check_mesh)."""
    from fepen.runs import budget

    built = built or projectile(scene)
    return budget.check_mesh(built.shape, scene.mesh.size, scene.get("mesh.nose_size"), bool(scene.effects.charge),
                             scene.mesh.max_cells, comm.size)


def body_key(scene) -> tuple:
    """What identifies a scene's projectile body: its projectile.* and charge.* keys, effects.charge and
    mesh.rigid_panel (a sweep's shots with equal keys share one body)."""
    return tuple((k, repr(scene.get(k))) for k in SCHEMA
                 if k.startswith(("projectile.", "charge.")) or k in ("effects.charge", "mesh.rigid_panel"))


# ---------------------------------------------------------------------------------------------------------
# the mesh
# ---------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class MeshRequest:
    """The volume mesh of a projectile, as fepen.geometry.mesh.create takes it.

    Attributes:
        options: gmsh's sizes and optimiser. charge: mesh the charge. split: give the charge its own wall
        nodes (a deformable charge in frictional contact). mass: projectile.mass or None.
        charge_density: kg/m^3. rigid_panel: mesh.rigid_panel (the rigid body's load-point panels) or None.
    """

    options: gmsh_model.MeshOptions
    charge: bool
    split: bool
    mass: float | None
    charge_density: float
    rigid_panel: float | None


def mesh_request(scene) -> MeshRequest:
    """The MeshRequest of a scene."""
    charge = bool(scene.effects.charge)
    split = charge and scene.charge.contact == "frictional" and scene.effects.fidelity != "rigid"
    opts = gmsh_model.MeshOptions(scene.mesh.size, scene.get("mesh.nose_size"), scene.mesh.optimize)
    return MeshRequest(opts, charge, split, scene.get("projectile.mass"), scene.charge.material.density,
                       scene.get("mesh.rigid_panel"))


def build_mesh(built: Built, request: MeshRequest, comm: MPI.Comm = MPI.COMM_WORLD, use_cache: bool = True,
               split: bool | None = None) -> fmesh.ProjectileMesh:
    """The distributed mesh of a built projectile.

    Args:
        split: override request.split (give the charge its own wall nodes).
    """
    return fmesh.create(built.shape, request.options, comm, charge=request.charge, mass=request.mass,
                        shell_density=built.shell_density, charge_density=request.charge_density,
                        split=request.split if split is None else split, use_cache=use_cache)


def mesh(scene, comm: MPI.Comm = MPI.COMM_WORLD, use_cache: bool = True,
         split: bool | None = None) -> fmesh.ProjectileMesh:
    """The distributed projectile mesh of a scene.

    Args:
        split: give the charge its own wall nodes; default: a deformable charge in frictional contact.
    """
    return build_mesh(projectile(scene), mesh_request(scene), comm, use_cache, split)


def densities(scene) -> dict[int, float]:
    """Density (kg/m^3) per volume tag."""
    return {tags.SHELL: projectile(scene).shell_density, tags.CHARGE: scene.charge.material.density}


def mesh_metrics(pm: fmesh.ProjectileMesh, scene) -> dict:
    """The figures of mesh.json for a scene's mesh (fepen.geometry.mesh.metrics)."""
    p, c = scene.projectile.material, scene.charge.material
    speed = {tags.SHELL: tetra.dilatational_speed(p.youngs_modulus, p.poisson_ratio, projectile(scene).shell_density),
             tags.CHARGE: tetra.dilatational_speed(c.youngs_modulus, c.poisson_ratio, c.density)}
    return fmesh.metrics(pm, densities(scene), speed, scene.run.safety_factor, scene.mesh.size)


def envelope_note(scene, built: Built | None = None) -> str:
    """One line when the shot lies outside the validated envelope (fepen.stats.envelope), else ""."""
    from fepen.stats import envelope

    v = envelope.verdict(envelope_facts(scene, built))
    return "" if v["inside"] else "\n".join([*envelope.unit_slips(v), envelope.line(v)])


def envelope_facts(scene, built: Built | None = None) -> dict:
    """What the validated envelope looks at (fepen.stats.envelope.verdict), from the scene and its built
    projectile (the calibre and length of a drawn or CAD body)."""
    p, i, t = scene.projectile, scene.impact, scene.target
    D = built.shape.diameter if built is not None else p.diameter
    L = built.shape.length if built is not None else p.length
    target = targets.of(scene).envelope_name(scene)  # "layered", "a rigid wall" or target.material
    mass = scene.get("projectile.mass")  # absent for a fixed cavity or a CAD body: from the body
    fc = scene.derived["target.fc_cylinder"]  # a layered target's are its layers' (its verdict: not validated)
    if mass is None and built is not None:  # the body's, when known before any mesh (a CAD body's: None)
        fill = scene.charge.material.density if scene.effects.charge else None
        mass = built.shape.exact_mass(built.shell_density, fill)
    values = {"D_m": D, "L_over_D": L / D, "crh": scene.get("projectile.crh"), "mass_kg": mass, "V_m_s": i.velocity,
              "fc_cylinder_Pa": None if isinstance(fc, list) else fc,
              "rho_kg_m3": t.density, "obliquity_deg": i.obliquity_deg, "attack_deg": i.attack_deg}
    return {"law": t.strength_model, "target": target, "nose": "CAD body" if p.get("cad") else p.nose,
            "thickness_m": scene.get("target.thickness"), "fidelity": scene.effects.fidelity,
            "steel_A_Pa": p.material.A, "reference_A_Pa": SCHEMA["projectile.material.A"].default,
            "values": values}

