"""From what the user gave to a resolved :class:`Scene`: what was given (read by fepen.scene.reading: TOML files
and text, dicts and ``--set``) checked against SCHEMA; the named shot, steel and target material filled in; the
checks across keys run (fepen.scene.checks, each with its own description); the read-only Scene.
"""

from __future__ import annotations

import copy
import os
import tomllib
from pathlib import Path
from typing import Any

from fepen.data import CONSTANTS, STEELS, TARGETS
from fepen.errors import InputError
from fepen.inputs import NotRegularFile, open_input, read_capped, unreadable
from fepen.laws.target import cylinder_strength
from fepen.scene.checks import (
    CAD_EXCLUDES,
    CHECKS_AFTER_RESOLUTION,
    CROSS_CHECKS,
    check_across,
    check_target,
    cross_check,
    layer_family,
    layer_lock,
    layers_alone,
    metal_constants_known,
    registered_checks,
    shot_agrees,
    shot_values,
    written_scene_fits,
)
from fepen.scene.keys import ABSENT, check_nesting
from fepen.scene.reading import (
    SCENE_MAX,
    check_sets,
    flatten,
    given_twice,
    parse_set,
    read_toml,
    set_item,
    toml_error,
    unknown_key,
)
from fepen.scene.schema import SCHEMA

__all__ = ["Section", "Scene", "load", "resolve", "read_toml", "parse_set", "flatten", "unknown_key",
           "cross_check", "registered_checks", "CROSS_CHECKS", "CHECKS_AFTER_RESOLUTION", "CAD_EXCLUDES",
           "read_capped", "open_input", "unreadable", "NotRegularFile", "toml_error", "SCENE_MAX", "given_twice",
           "set_item", "given_from"]




# ---------------------------------------------------------------------------------------------------------
# resolution: the named shot, steel and target material
# ---------------------------------------------------------------------------------------------------------
def _resolve_shot(flat: dict, given: dict) -> None:
    """impact.shot's velocity and angles (after shot_agrees: the given ones equal them)."""
    shot_agrees(flat, given)
    if flat.get("impact.shot") is not None:
        flat.update(shot_values(flat["impact.shot"]))


def _resolve_steel(flat: dict, given: dict) -> None:
    """The named steel's constants for every projectile.material key the user did not give."""
    for key, value in STEELS[flat["projectile.material.name"]].items():
        name = f"projectile.material.{key}"
        if name in SCHEMA and name not in given:
            flat[name] = SCHEMA[name].check(name, value)


def _tensile_default(fc_cylinder: float) -> float:
    """target.tensile_strength when neither the scene nor the material gives it: f_c / 10, of the cylinder
    strength."""
    return 0.1 * fc_cylinder


def _fc_cylinder(c: dict) -> float | None:
    """A target's compressive strength on the cylinder basis the law takes (Pa): the user's or the material's
    strength on its strength_basis, a cube strength converted (fepen.laws.target.cylinder_strength). The one
    conversion: the scene keeps the value (Scene.derived) and every law, check and default reads it."""
    fc = c.get("compressive_strength")
    return None if fc is None else cylinder_strength(fc, c.get("strength_basis") or "cylinder")


def _material_constants(name: str, given: dict, crater_given: str | None) -> dict:
    """Every target constant of a named material, the given ones winning, with the derived defaults
    (tensile strength f_c/10) and its crater (the scene's explicit effects.crater, else the material's)."""
    out = {k: v for k, v in TARGETS[name].items() if k in CONSTANTS}
    if "compressive_strength" in given and "strength_basis" in out:  # a material's basis goes with its strength
        out["strength_basis"] = "cylinder"
    out.update(given)
    out["fc_cylinder"] = _fc_cylinder(out)
    if "tensile_strength" not in out and out["fc_cylinder"] is not None:
        out["tensile_strength"] = _tensile_default(out["fc_cylinder"])
    out["crater"] = crater_given or TARGETS[name].get("crater", "energy")
    out["family"] = TARGETS[name]["family"]
    metal_constants_known(name, out)
    return out


def _resolve_layers(flat: dict, given: dict, crater: str | None) -> list:
    """Each [[target.layers]] table with its material's constants, checked as a target material; returns each
    layer's cylinder strength (Pa, None for a metal)."""
    layers_alone(flat, given)
    out, fc = [], []
    for i, layer in enumerate(flat["target.layers"]):
        where = f"target.layers[{i}]"
        layer_family(where, layer)
        here = {**{k: v for k, v in layer.items() if k in ("material", "thickness", "gap")},
                **_material_constants(layer["material"], {k: v for k, v in layer.items() if k in CONSTANTS},
                                      crater or layer.get("crater"))}
        check_target(where, here, here["family"], set(layer))
        layer_lock(where, here)
        fc.append(here.pop("fc_cylinder"))
        out.append(here)
    flat["target.layers"] = out
    flat.pop("target.material", None)  # each layer names its own
    return fc


def _resolve_target(flat: dict, given: dict) -> dict:
    """The named target material's constants for every target key the user did not give; each layer's.
    Returns what they imply, computed here once: {"target.fc_cylinder": the cylinder strength (Pa), or a list of
    each layer's}."""
    crater = flat["effects.crater"] if "effects.crater" in given else None
    if "target.layers" in flat:
        return {"target.fc_cylinder": _resolve_layers(flat, given, crater)}
    else:
        mine = {k: flat[f"target.{k}"] for k in CONSTANTS if f"target.{k}" in given}
        constants = _material_constants(flat["target.material"], mine, crater)
        for k in CONSTANTS:
            if k in constants:
                flat[f"target.{k}"] = SCHEMA[f"target.{k}"].check(f"target.{k}", constants[k])
        flat["effects.crater"] = constants["crater"]
    fc = _fc_cylinder({k: flat.get(f"target.{k}") for k in ("compressive_strength", "strength_basis")})
    if "target.tensile_strength" not in flat:
        flat["target.tensile_strength"] = _tensile_default(fc)
    return {"target.fc_cylinder": fc}


#: the keys that name a file the projectile is read from
FILE_KEYS = ("projectile.cad", "projectile.profile", "projectile.inner_profile")


def resolve(given: dict[str, Any]) -> Scene:
    """Validate user-given keys and fill in every default.

    Args:
        given: flat {dotted key: value} from the file and --set options, later entries winning.

    Returns:
        The resolved, read-only Scene.
    """
    for name, value in given.items():
        if not isinstance(name, str) or name not in SCHEMA:
            raise unknown_key(str(name))
        check_nesting(value, name, "the value")
    flat: dict[str, Any] = {}
    for name, key in SCHEMA.items():
        if name in given:
            flat[name] = key.check(name, given[name])
        elif key.default is not ABSENT:
            flat[name] = key.default

    for name in FILE_KEYS:  # a file is named by its absolute path: a run's scene.toml reads the same file from
        if flat.get(name):  # any working directory (fepen run --resume)
            flat[name] = os.path.abspath(flat[name])
    _resolve_shot(flat, given)
    _resolve_steel(flat, given)
    derived = _resolve_target(flat, given)
    check_across(flat, given, derived)

    tree: dict[str, Any] = {}
    for name, value in flat.items():
        node = tree
        parts = name.split(".")
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = value
    scene = Scene._resolved(tree, set(given), derived)
    written_scene_fits(scene)
    return scene


def given_from(source) -> dict[str, Any]:
    """The flat {dotted key: value} a user gave, from any Scene source."""
    if source is None:
        return {}
    if isinstance(source, Scene):
        return {k: source.get(k) for k in source.explicit}
    if isinstance(source, dict):
        return flatten(source)
    if isinstance(source, Path) or (isinstance(source, str) and "\n" not in source and "=" not in source):
        return read_toml(source)
    if isinstance(source, str):
        try:
            tree = tomllib.loads(source)
        except (ValueError, RecursionError) as err:
            raise toml_error(err, "SCENE", "the scene text") from None
        return flatten(tree)
    raise InputError("SCENE", f"expected a TOML file, TOML text, a dict or a Scene, got {type(source).__name__}")


def load(path: str | Path | None = None, sets: list[str] | tuple[str, ...] = ()) -> Scene:
    """Read a scene file (or none: all defaults), apply ``--set`` overrides, validate.

    Args:
        path: TOML scene file, or None for the default scene.
        sets: ``KEY=VALUE`` strings, applied after the file in order.

    Returns:
        The resolved Scene.
    """
    return Scene(Path(path) if path is not None else None, sets)


# ---------------------------------------------------------------------------------------------------------
# the resolved scene
# ---------------------------------------------------------------------------------------------------------
class Section:
    """Read-only attribute access to a part of a resolved scene (``scene.projectile.material.A``).

    Args:
        values: the part as nested dicts.
    """

    def __init__(self, values: dict[str, Any]):
        object.__setattr__(self, "_values", values)

    def __getattr__(self, name: str) -> Any:
        values = object.__getattribute__(self, "_values")
        if name not in values:
            raise AttributeError(name)
        value = values[name]
        return Section(value) if isinstance(value, dict) else value

    def __setattr__(self, name, value):
        raise AttributeError("a resolved scene is read-only")

    def as_dict(self) -> dict[str, Any]:
        """A deep copy as plain dicts (absent optional keys are left out)."""
        return copy.deepcopy(object.__getattribute__(self, "_values"))

    def get(self, dotted: str) -> Any:
        """Value of a dotted key, None when an optional key is absent.

        Args:
            dotted: the key (``"target.thickness"``), or a table (``"projectile.material"``: a dict).

        Returns:
            The value, or None.
        """
        node = object.__getattribute__(self, "_values")
        for part in dotted.split("."):
            if not isinstance(node, dict) or part not in node:
                return None
            node = node[part]
        return node


class Scene(Section):
    """A resolved scene: every key validated, every default filled in, read-only.

    Args:
        source: None (the default scene), a TOML file (str or Path), TOML text (a str holding a newline or
            an ``=``), a nested dict ({"impact": {"velocity": 700.0}}) or a flat one of dotted keys, or
            another Scene.
        sets: overrides applied after the source, in order: ``KEY=VALUE`` strings as ``--set`` takes them
            (VALUE in TOML syntax, bare words are strings), or a dict of dotted keys.

    Raises:
        InputError: naming the key and what is allowed.

    ``scene.explicit`` is the set of dotted keys the user gave; ``scene.derived`` what the keys imply, computed
    once as the scene resolves: {"target.fc_cylinder": the target's compressive strength on the cylinder
    basis (Pa; a list, one per layer, for target.layers; None for a metal)}.
    """

    def __init__(self, source=None, sets=()):
        if not isinstance(sets, dict):
            check_sets(source, sets)
        given = given_from(source)
        items = sets.items() if isinstance(sets, dict) else (parse_set(item) for item in sets)
        for key, value in items:
            given[key] = value
        resolved = resolve(given)
        object.__setattr__(self, "_values", object.__getattribute__(resolved, "_values"))
        object.__setattr__(self, "explicit", resolved.explicit)
        object.__setattr__(self, "derived", resolved.derived)

    @classmethod
    def _resolved(cls, values: dict[str, Any], explicit: set[str], derived: dict) -> Scene:
        out = object.__new__(cls)
        Section.__init__(out, values)
        object.__setattr__(out, "explicit", frozenset(explicit))
        object.__setattr__(out, "derived", dict(derived))
        return out

    def with_sets(self, sets) -> Scene:
        """A new Scene: this one's given keys with more overrides.

        Args:
            sets: as the constructor's ``sets``.

        Returns:
            The new Scene.
        """
        return Scene(self, sets)

    def __repr__(self) -> str:
        given = {k: self.get(k) for k in sorted(self.explicit)}
        return f"fepen.Scene({given})"
