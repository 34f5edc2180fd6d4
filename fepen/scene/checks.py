"""The checks across scene keys, each registered with its one-line description (:func:`cross_check`):
``CROSS_CHECKS``, the list ``fepen keys`` prints under the key table and docs/scenes.md shows, is built from them;
``check_across`` runs them on a scene being resolved (fepen.scene.resolve), ``written_scene_fits`` on the
resolved one.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from fepen.data import CONSTANTS, TARGETS, shot
from fepen.errors import InputError
from fepen.laws.target import a_over_c_cubed, youngs_modulus_aci
from fepen.scene.reading import SCENE_MAX
from fepen.scene.schema import SCHEMA


# ---------------------------------------------------------------------------------------------------------
# the checks across keys, each with its description
# ---------------------------------------------------------------------------------------------------------
def shot_values(name: str) -> tuple[tuple[str, float], ...]:
    """The impact keys a Table 1 shot sets."""
    s = shot(name)
    return (("impact.velocity", s.v0), ("impact.obliquity_deg", s.obliquity_deg), ("impact.attack_deg", s.attack_deg))


_REGISTRY: list[tuple[str, Callable]] = []


def cross_check(description: str) -> Callable[[Callable], Callable]:
    """Register a check across keys with its one-line description; ``fepen keys`` and docs/scenes.md list the
    descriptions in the order the checks are defined in this module (the order they run in is resolve's:
    the first refusal is the one reported). A check raises InputError naming a key; it takes
    ``(flat, given)`` (the scene's resolved values and the keys the user gave), or for one target material
    or layer ``(where, constants, family, given)``, ``(where, layer)`` or ``(name, constants)``, or the
    resolved Scene itself.

    Args:
        description: what the check demands, in one line, naming the keys.

    Returns:
        The decorator (the function is returned unchanged).
    """
    def register(function: Callable) -> Callable:
        _REGISTRY.append((description, function))
        return function

    return register


def registered_checks() -> tuple[tuple[str, Callable], ...]:
    """Every check across keys as (description, function), in the order they are listed."""
    return tuple(_REGISTRY)


def _given_one(given, *names: str) -> str:
    """The first of these keys the user gave, else the first: the key an error across keys names."""
    return next((n for n in names if n in given), names[0])


@cross_check("projectile.material.melt_temperature > projectile.material.room_temperature (Johnson-Cook's T*)")
def _melt_above_room(flat: dict, given: dict) -> None:
    melt, room = flat["projectile.material.melt_temperature"], flat["projectile.material.room_temperature"]
    if melt <= room:
        key = _given_one(given, "projectile.material.melt_temperature", "projectile.material.room_temperature")
        raise InputError(key, f"melting temperature {melt:g} K must exceed room temperature {room:g} K "
                              "(projectile.material.*: Johnson-Cook's T* = (T - T_room)/(T_melt - T_room))")


@cross_check("charge.material.tangent_modulus < charge.material.youngs_modulus (bilinear hardening)")
def _charge_hardening(flat: dict, given: dict) -> None:
    E, Et = flat["charge.material.youngs_modulus"], flat["charge.material.tangent_modulus"]
    if Et >= E:
        raise InputError(_given_one(given, "charge.material.tangent_modulus", "charge.material.youngs_modulus"),
                         f"the charge's tangent modulus {Et:g} Pa must be below its Young's modulus {E:g} Pa "
                         "(charge.material.*: bilinear hardening H = E Et / (E - Et))")


@cross_check("the axis at impact (impact.obliquity_deg, impact.attack_deg in its plane impact.attack_plane_deg) "
             "< 90 deg from the normal: the axis points into the target")
def _axis_into_target(flat: dict, given: dict) -> None:
    from fepen.geometry import frames

    alpha, attack, plane = flat["impact.obliquity_deg"], flat["impact.attack_deg"], flat["impact.attack_plane_deg"]
    R = frames.striking_rotation(math.radians(alpha), math.radians(attack), math.radians(plane))
    theta = math.degrees(math.acos(max(-1.0, min(1.0, float(R[1, 1])))))  # the nose R (0, -1, 0) from -y
    if not theta < 90.0 - 1e-9:
        key = _given_one(given, "impact.attack_deg", "impact.obliquity_deg")
        raise InputError(key, f"obliquity {alpha:g} deg with attack {attack:g} deg in the plane at {plane:g} deg "
                              f"turns the projectile's axis {theta:.4g} deg from the normal, to or past the target "
                              "face (its tail would start inside the target): it must be < 90 deg")


@cross_check("run.rigid_step at most run.end_time, when both are given")
def _rigid_step_within_end(flat: dict, given: dict) -> None:
    end = flat.get("run.end_time")  # (a field output interval past the end is harmless: the first and last states)
    key = "run.rigid_step"
    if end is not None and key in given and "run.end_time" in given and flat[key] > end:
        raise InputError(key, f"{flat[key]:g} s: must be at most run.end_time = {end:g} s")


@cross_check("a concrete, rock or soil target (or layer): tensile_strength < compressive_strength, and a plastic "
             "zone wider than the cavity, (9 fc/(4 E)) sqrt(fc/(2 ft)) < 1; strength_model 'metal' for metals only")
def _concrete_law(where: str, c: dict, family: str, given: set) -> None:
    if c.get("strength_model") == "metal":
        raise InputError(f"{where}.strength_model", f"'metal' is the law of a metal target.material (6061-T6511, "
                                                    f"armour-steel), not of a {family} one")
    fc, T = c["fc_cylinder"], c["tensile_strength"]
    if T >= fc:
        key = _given_one(given, "tensile_strength", "compressive_strength")
        cube = "" if fc == c["compressive_strength"] else f" (of the {c['compressive_strength']:g} Pa cube)"
        raise InputError(f"{where}.{key}", f"tensile strength {T:g} Pa must be below compressive strength "
                                           f"{fc:g} Pa{cube}")
    E = c.get("youngs_modulus") or youngs_modulus_aci(fc)
    ratio = a_over_c_cubed(fc, E, T)
    if ratio >= 1.0:
        key = _given_one(given, "youngs_modulus", "tensile_strength", "compressive_strength")
        raise InputError(f"{where}.{key}", f"Young's modulus {E:g} Pa, compressive strength {fc:g} Pa and tensile "
                                           f"strength {T:g} Pa leave no plastic zone around the cavity: (9 fc/(4 "
                                           f"E)) sqrt(fc/(2 ft)) = {ratio:.3g} must be below 1")


@cross_check("a metal target (or layer): yield_stress < 2/3 youngs_modulus (Forrestal-Warren), and strength_model "
             "'metal' (or none)")
def _metal_law(where: str, c: dict, family: str, given: set) -> None:
    model = c.get("strength_model")
    if model not in (None, "metal"):
        raise InputError(f"{where}.strength_model", f"got {model!r}: a metal target's law is 'metal' (drop the key)")
    Y, E = c.get("yield_stress"), c.get("youngs_modulus")
    if Y is not None and E is not None and 1.5 * Y >= E:
        key = _given_one(given, "yield_stress", "youngs_modulus")
        raise InputError(f"{where}.{key}", f"a metal target's yield stress {Y:g} Pa must be below 2/3 of its "
                                           f"Young's modulus {E:g} Pa (Forrestal-Warren: 3Y/(2E) < 1)")


@cross_check("target.lock_density > target.density with the energy crater; target.friction_dynamic <= "
             "target.friction; mesh.nose_size <= mesh.size")
def _orders(flat: dict, given: dict) -> None:
    if flat["effects.crater"] == "energy" and flat["target.lock_density"] <= flat["target.density"]:
        raise InputError("target.lock_density", f"{flat['target.lock_density']:g} kg/m^3: must exceed "
                                                f"target.density = {flat['target.density']:g} kg/m^3")
    if flat.get("target.friction_dynamic", 0.0) > flat["target.friction"]:
        raise InputError("target.friction_dynamic", f"{flat['target.friction_dynamic']:g}: the sliding coefficient "
                                                    f"must be at most target.friction = {flat['target.friction']:g}")
    if "mesh.nose_size" in flat and flat["mesh.nose_size"] > flat["mesh.size"]:
        raise InputError("mesh.nose_size", f"must be at most mesh.size = {flat['mesh.size']:g} m")


@cross_check("effects.charge needs a cavity (not a solid or CAD body); projectile.mass and projectile.cavity_length "
             "not both; neither with a solid body (projectile.cavity_diameter = 0)")
def _mass_and_charge(flat: dict, given: dict) -> None:
    """(A solid body, or a given cavity length, drops the mass rule: projectile.mass leaves the scene.)"""
    if "projectile.cavity_length" in given:
        if "projectile.mass" in given:
            raise InputError("projectile.mass", "give projectile.mass or projectile.cavity_length, not both")
        flat.pop("projectile.mass", None)
    if flat["projectile.cavity_diameter"] == 0.0:
        if "projectile.mass" in given:
            raise InputError("projectile.mass",
                             "a solid body (projectile.cavity_diameter = 0) has its mass set by its shape; "
                             "drop projectile.mass")
        if "projectile.cavity_length" in given:
            raise InputError("projectile.cavity_length", "a solid body (projectile.cavity_diameter = 0) has no "
                                                         "cavity: drop projectile.cavity_length")
        flat.pop("projectile.mass", None)
        flat.pop("projectile.cavity_length", None)
    if flat["effects.charge"] and flat["projectile.cavity_diameter"] == 0.0:
        raise InputError("effects.charge", "needs a cavity to fill: projectile.cavity_diameter must be > 0")


@cross_check("impact.velocity, impact.obliquity_deg and impact.attack_deg, when given with impact.shot, equal to "
             "the shot's (Table 1)")
def shot_agrees(flat: dict, given: dict) -> None:
    name = flat.get("impact.shot")
    if name is None:
        return
    for key, value in shot_values(name):
        if key in given and flat[key] != value:
            raise InputError(key, f"conflicts with impact.shot = {name!r}, which sets it to {value:g}; "
                                  "give one of the two")


@cross_check("effects.erosion with effects.fidelity 'elastic' or 'plastic' (the rigid fidelity has the scalar "
             "wear)")
def _erosion_meshed(flat: dict, given: dict) -> None:
    if flat["effects.erosion"] and flat["effects.fidelity"] == "rigid":
        raise InputError("effects.erosion", "removes cells of the meshed projectile: use it with effects.fidelity "
                                            "= 'elastic' or 'plastic' (the rigid fidelity has the scalar wear)")


@cross_check("[[target.layers]]: target.material and target.thickness per layer, not beside the layers; "
             "effects.crater 'energy' or 'none' (not 'linear')")
def layers_alone(flat: dict, given: dict) -> None:
    for key in ("target.material", "target.thickness"):
        if key in given:
            raise InputError(key, "give it per layer in [[target.layers]] (material, thickness), not both")
    if "effects.crater" in given and flat["effects.crater"] == "linear":
        raise InputError("effects.crater", "'linear' is Forrestal's crater of one target; with target.layers "
                                           "use 'energy' or 'none'")


@cross_check("a layer's family, when given (as a resolved scene writes it back), is its material's")
def layer_family(where: str, layer: dict) -> None:
    family = TARGETS[layer["material"]]["family"]
    if layer.get("family", family) != family:
        raise InputError(f"{where}.family", f"{layer['family']!r}: {layer['material']!r} is a {family} (drop the "
                                            "key)")


@cross_check("a layer with the energy crater: its lock_density > its density")
def layer_lock(where: str, c: dict) -> None:
    if c["crater"] == "energy" and c.get("lock_density", SCHEMA["target.lock_density"].default) <= c["density"]:
        raise InputError(f"{where}.lock_density", "must exceed the layer's density with the energy crater")


@cross_check("a metal target (or layer): yield_stress, hardening_exponent and youngs_modulus known (from its "
             "target.material or given)")
def metal_constants_known(name: str, c: dict) -> None:
    if c["family"] == "metal":
        for k in ("yield_stress", "hardening_exponent", "youngs_modulus"):
            if k not in c:
                raise InputError(f"target.{k}", f"a metal target ({name}) needs it")


@cross_check("[[output.probes]] of kind 'cell' with effects.fidelity 'elastic' or 'plastic' (the rigid body has no "
             "stresses)")
def _cell_probes_meshed(flat: dict, given: dict) -> None:
    if flat["effects.fidelity"] != "rigid":
        return
    for i, probe in enumerate(flat.get("output.probes") or ()):
        if probe["kind"] == "cell":
            raise InputError(f"output.probes[{i}].kind", "'cell' reads a cell's stresses, PEEQ and temperature: "
                                                          "use it with effects.fidelity = 'elastic' or 'plastic' (the "
                                                          "rigid fidelity has 'node' probes only)")


@cross_check("charge.* keys only with effects.charge = true, or with effects.charge = false given (a sweep that "
             "varies the charge); left off by default, they would change nothing")
def _charge_keys_need_the_charge(flat: dict, given: dict) -> None:
    if flat["effects.charge"] or "effects.charge" in given:  # given false: the keys are kept for the charged shots
        return
    for key in given:
        if key.startswith("charge."):
            raise InputError(key, "a key of the charge, which is off: set effects.charge = true, or drop the key (it "
                                  "would change nothing; a sweep that varies the charge gives effects.charge = false "
                                  "in its base)")


#: the rows of the list keys (layers, probes, cavity sections) up to which the scene fepen writes is not measured:
#: each row writes at most about 2 kB, the rest of a scene about 10 kB, far below SCENE_MAX
ROWS_UNMEASURED = 64
#: the list keys whose rows make a written scene long, and what their rows are called
_ROW_KEYS = (("target.layers", "layers"), ("output.probes", "probes"), ("projectile.cavity_sections", "sections"))


@cross_check(f"the scene.toml fepen writes into the results (every key) within the {SCENE_MAX >> 20} MiB a scene file "
             "may be, so that it reads back (fepen run --resume, fepen.load): not too many target.layers, "
             "output.probes or projectile.cavity_sections")
def written_scene_fits(scene) -> None:
    """(Measured only past ROWS_UNMEASURED rows: fepen.scene.text.to_toml writes the scene.)"""
    rows = {key: len(scene.get(key) or ()) for key, _ in _ROW_KEYS}
    if sum(rows.values()) <= ROWS_UNMEASURED:
        return
    from fepen.scene.text import to_toml

    size = len(to_toml(scene).encode())
    if size > SCENE_MAX:
        key, word = max(_ROW_KEYS, key=lambda kw: rows[kw[0]])
        n = rows[key]
        raise InputError(key, f"{n} {word} would make the scene.toml fepen writes into the results {size >> 10} "
                              f"KiB, past the {SCENE_MAX >> 10} KiB a scene file may be: it could not be read back "
                              f"(fepen run --resume, fepen.load); give at most about {n * SCENE_MAX // size} of these")


#: the projectile keys of a drawn body, refused beside projectile.cad
CAD_EXCLUDES = ("projectile.nose", "projectile.diameter", "projectile.length", "projectile.crh", "projectile.mass",
                "projectile.nose_length", "projectile.meplat_diameter", "projectile.boattail_length",
                "projectile.boattail_diameter", "projectile.profile", "projectile.inner_profile",
                "projectile.cavity_sections", "projectile.cavity_diameter", "projectile.cavity_length",
                "projectile.cavity_step_diameter", "projectile.cavity_step_length", "projectile.base_thickness")


@cross_check("projectile.cad: none of the keys of a drawn body (nose, diameter, length, crh, mass, meplat, "
             "boat-tail, profiles, cavity, base), and no effects.charge")
def _cad_body(flat: dict, given: dict) -> None:
    """(A CAD body is solid: projectile.cavity_diameter = 0.)"""
    if "projectile.cad" not in flat:
        return
    for key in CAD_EXCLUDES:
        if key in given:
            raise InputError(key, "the body is read from projectile.cad (its shape, and its mass from its mesh "
                                  "and projectile.material.density): drop this key")
    if flat["effects.charge"]:
        raise InputError("effects.charge", "a CAD body has no charge: it is meshed as one steel solid")
    flat["projectile.cavity_diameter"] = 0.0


@cross_check("projectile.profile draws the whole outside: projectile.nose 'profile' (or not given), none of "
             "diameter, length, crh, nose_length, meplat, boat-tail; projectile.nose = 'profile' needs it")
def _drawn_outside(flat: dict, given: dict) -> None:
    """(A drawn body without a given mass or cavity is solid: the paper's cavity belongs to the paper's body.)"""
    nose = flat["projectile.nose"]
    if "projectile.profile" in flat:
        if "projectile.nose" in given and nose != "profile":
            raise InputError("projectile.profile", f"draws the whole outside: drop projectile.nose = {nose!r} (or "
                                                   "set it to 'profile')")
        flat["projectile.nose"] = "profile"
        for key in ("projectile.diameter", "projectile.length", "projectile.crh", "projectile.nose_length",
                    "projectile.meplat_diameter", "projectile.boattail_length", "projectile.boattail_diameter"):
            if key in given:
                raise InputError(key, "is set by projectile.profile: drop it")
        if "projectile.mass" not in given and not any(k in given for k in (
                "projectile.cavity_diameter", "projectile.cavity_length", "projectile.cavity_sections",
                "projectile.inner_profile")):
            flat["projectile.cavity_diameter"] = 0.0
    elif nose == "profile":
        raise InputError("projectile.nose", "'profile' needs projectile.profile, the CSV of the outside")


@cross_check("projectile.nose_length given with a secant, cone or ellipsoid nose, and only with one")
def _nose_length(flat: dict, given: dict) -> None:
    nose = flat["projectile.nose"]
    if nose in ("secant", "cone", "ellipsoid") and "projectile.nose_length" not in flat:
        raise InputError("projectile.nose_length", f"a {nose} nose needs its axial length (m)")
    if "projectile.nose_length" in given and nose not in ("secant", "cone", "ellipsoid"):
        raise InputError("projectile.nose_length", f"is for a secant, cone or ellipsoid nose, not {nose!r} (a "
                                                   "tangent ogive's length follows from projectile.crh)")


@cross_check("projectile.meplat_diameter > 0 not with a flat or drawn nose")
def _meplat(flat: dict, given: dict) -> None:
    nose = flat["projectile.nose"]
    if flat["projectile.meplat_diameter"] > 0.0 and nose in ("flat", "profile"):
        raise InputError("projectile.meplat_diameter", f"a {nose!r} nose has no tip to blunt: drop it")


@cross_check("projectile.boattail_length > 0 and projectile.boattail_diameter together")
def _boattail(flat: dict, given: dict) -> None:
    if flat["projectile.boattail_length"] > 0.0 and "projectile.boattail_diameter" not in flat:
        raise InputError("projectile.boattail_diameter", "a boat-tail (projectile.boattail_length > 0) needs its "
                                                         "rear diameter (m)")
    if "projectile.boattail_diameter" in given and flat["projectile.boattail_length"] == 0.0:
        raise InputError("projectile.boattail_length", "must be > 0 with projectile.boattail_diameter")


@cross_check("one form of cavity: projectile.cavity_sections, or projectile.inner_profile (which fixes the mass "
             "too: no projectile.mass), or the cavity_* keys")
def _cavity_forms(flat: dict, given: dict) -> None:
    """(A drawn cavity drops the mass rule: projectile.mass and projectile.cavity_length leave the scene.)"""
    if "projectile.cavity_sections" in flat:
        for key in ("projectile.cavity_diameter", "projectile.cavity_length", "projectile.cavity_step_diameter",
                    "projectile.cavity_step_length", "projectile.inner_profile"):
            if key in given:
                raise InputError(key, "give the cavity as projectile.cavity_sections or with this key, not both")
    if "projectile.inner_profile" in flat:
        for key in ("projectile.mass", "projectile.cavity_diameter", "projectile.cavity_length",
                    "projectile.cavity_step_diameter", "projectile.cavity_step_length"):
            if key in given:
                raise InputError(key, "a drawn cavity (projectile.inner_profile) fixes the mass and the cavity: "
                                      "drop it")
        flat.pop("projectile.mass", None)
        flat.pop("projectile.cavity_length", None)


#: checks across keys made after resolution, by the code that builds the run (listed after the scene's)
CHECKS_AFTER_RESOLUTION = (
    # fepen.geometry.shape.Shape.check, through fepen.runs.setup.projectile
    "the projectile, built from its exact outside before any mesh: the nose shorter than the body, the meplat "
    "and boat-tail narrower than it, the cavity inside it with a wall of 5 % of the calibre and the base "
    "behind it, projectile.mass within the reach of the cavity (docs/theory.md §1.1)",
    # fepen.runs.setup.check_supported
    "effects.fidelity 'rigid' with target.kind 'concrete' (a rigid projectile on a rigid wall has nothing to "
    "compute)",
    # fepen.runs.setup.thin_target_note
    "noted, not refused: a target (or a layer) thinner than the nose is long (the cavity-expansion law is a "
    "thick-target law)",
)

#: the checks across keys, as ``fepen keys`` lists them under the table (each refusal names the key)
CROSS_CHECKS = tuple(description for description, _ in _REGISTRY) + CHECKS_AFTER_RESOLUTION


def check_target(where: str, c: dict, family: str, given: set) -> None:
    """One target material's constants (c: target.* names without the prefix; given: those the user gave)
    make a law: a metal's law for a metal and only for it, its yield below 2E/3; a concrete's, rock's or soil's
    tensile strength below its compressive strength and a plastic zone wider than the cavity (docs/theory.md
    §8.1, §16)."""
    (_metal_law if family == "metal" else _concrete_law)(where, c, family, given)


def _check_projectile_keys(flat: dict, given: dict) -> None:
    """Which projectile keys go together (CAD, drawn profiles, nose families, cavity forms). The geometry
    itself is checked in full by fepen.geometry.shape.Shape.check, through fepen.runs.setup.projectile."""
    _cad_body(flat, given)
    if "projectile.cad" in flat:
        return
    for check in (_drawn_outside, _nose_length, _meplat, _boattail, _cavity_forms):
        check(flat, given)


def check_across(flat: dict, given: dict, derived: dict) -> None:
    """The checks across keys of the resolved values, in this order (the first refusal is the one reported);
    each layer's and the mass rule of a shot were checked as they resolved."""
    _check_projectile_keys(flat, given)
    for check in (_mass_and_charge, _erosion_meshed, _cell_probes_meshed, _orders, _melt_above_room, _axis_into_target,
                  _rigid_step_within_end, _charge_hardening, _charge_keys_need_the_charge):
        check(flat, given)
    if "target.layers" not in flat:
        check_target("target", {**{k: flat[f"target.{k}"] for k in CONSTANTS if f"target.{k}" in flat},
                                 "fc_cylinder": derived["target.fc_cylinder"]},
                      TARGETS[flat["target.material"]]["family"], {k[7:] for k in given if k.startswith("target.")})
