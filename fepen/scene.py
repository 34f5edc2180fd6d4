"""Scenes: one TOML file in, typed and validated settings with every default filled in.

The key names are the public interface of fepen (docs/scenes.md). Every key is declared once in
``SCHEMA`` below with its type, default, unit and allowed range; nothing else is accepted. Bad input raises
:class:`fepen.errors.InputError` naming the key and what is allowed, before any solver work starts.

Defaults are the paper's projectile (45 steel, D = 23.6 mm, L = 144 mm, 367 g), its concrete target
(Table 3) and the striking conditions of Table 1 shot C3. The choices the paper leaves open (nose CRH,
cavity, tensile strength, ...) are explained in docs/theory.md.
"""

from __future__ import annotations

import difflib
import math
import sys
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fepen.data import CONSTANTS, FAMILIES, SHOTS, STEELS, TARGETS, shot
from fepen.errors import InputError

_ABSENT = object()  # marks an optional key whose absence means something (e.g. semi-infinite target)


@dataclass(frozen=True)
class Key:
    """One scene key: its type, default, unit and allowed values."""

    kind: type
    default: Any
    unit: str = ""
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    choices: tuple = ()
    doc: str = ""
    form: str = ""  # what a list key holds

    def allowed(self) -> str:
        """Human-readable description of the allowed values."""
        if self.choices:
            return "one of " + ", ".join(repr(c) for c in self.choices)
        if self.kind is bool:
            return "true or false"
        if self.kind is str:
            return self.form or "a string"
        if self.kind is list:
            return self.form or "a list"
        lo = "-inf" if self.lo is None else f"{self.lo:g}"
        hi = "inf" if self.hi is None else f"{self.hi:g}"
        brackets = ("(" if self.lo_open or self.lo is None else "[") + lo + ", " + hi + (
            ")" if self.hi_open or self.hi is None else "]")
        what = "an integer" if self.kind is int else "a number"
        return f"{what} in {brackets}" + (f" {self.unit}" if self.unit else "")

    def check(self, name: str, value: Any) -> Any:
        """Return the value converted to the key's type, or raise InputError."""
        if self.kind is float:
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not _finite(value):
                raise InputError(name, f"got {_shown(value)}, expected {self.allowed()}")
            value = float(value)
        elif self.kind is int:
            if isinstance(value, bool) or not isinstance(value, int):
                raise InputError(name, f"got {_shown(value)}, expected {self.allowed()}")
        elif self.kind is bool:
            if not isinstance(value, bool):
                raise InputError(name, f"got {_shown(value)}, expected true or false")
        elif self.kind is str:
            if not isinstance(value, str):
                raise InputError(name, f"got {_shown(value)}, expected {self.allowed()}")
            if self.form and (not value.strip() or "\x00" in value):  # a path: open() fails on both
                raise InputError(name, f"got {_shown(value)}, expected {self.allowed()}")
        elif self.kind is list:
            return LIST_CHECKS[name](name, value)
        if self.choices and value not in self.choices:
            raise InputError(name, f"got {_shown(value)}, expected {self.allowed()}")
        if self.kind in (int, float):
            bad_lo = self.lo is not None and (value < self.lo or (self.lo_open and value == self.lo))
            bad_hi = self.hi is not None and (value > self.hi or (self.hi_open and value == self.hi))
            if bad_lo or bad_hi:
                raise InputError(name, f"got {_shown(value)}, expected {self.allowed()}")
        return value


def _finite(value: int | float) -> bool:
    """A finite number, as a float can hold it (TOML integers have no bound: 10**400 is not)."""
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


def _shown(value: Any, limit: int = 60) -> str:
    """A value as an error line shows it: floats as %g, others by repr, long ones cut, always one line."""
    if isinstance(value, float):
        return f"{value:g}"
    try:
        text = repr(value)
    except ValueError:  # an int past Python's 4300-digit limit of conversion to text
        text = f"an integer of more than {sys.get_int_max_str_digits()} digits"
    text = " ".join(text.split())
    return text if len(text) <= limit else text[:limit - 3] + "..."


def _name(name: str, limit: int = 80) -> str:
    """A key or a path as the user wrote it, shown on one line (TOML allows any character in a quoted key)."""
    return name if name.isprintable() and len(name) <= limit else _shown(name, limit)


def _num(default, unit, lo=None, hi=None, lo_open=False, hi_open=False, doc=""):
    return Key(float, default, unit, lo, hi, lo_open, hi_open, doc=doc)


def _pos(default, unit, hi=None, doc=""):
    """A strictly positive number."""
    return Key(float, default, unit, 0.0, hi, lo_open=True, doc=doc)


def _choice(default, *choices, doc=""):
    return Key(str, default, choices=choices, doc=doc)


def _flag(default, doc=""):
    return Key(bool, default, doc=doc)


C3 = shot("C3")

#: Every scene key, dotted name -> Key. Units are SI. ``_ABSENT`` defaults are optional keys whose absence
#: has a meaning given in their doc.
SCHEMA: dict[str, Key] = {
    # --- projectile geometry (docs/theory.md, "The projectile") ---
    "projectile.nose": _choice("ogive", "ogive", "secant", "cone", "hemisphere", "ellipsoid", "flat", "profile",
                               doc="tangent or secant ogive, cone, hemisphere, ellipsoid, flat (a plain cylinder), "
                                   "or a drawn profile (projectile.profile); docs/projectiles-and-targets.md"),
    "projectile.nose_length": _pos(_ABSENT, "m", 10.0, doc="axial length of a secant ogive, cone or ellipsoid nose "
                                                           "(before any meplat)"),
    "projectile.meplat_diameter": _num(0.0, "m", 0.0, 1.0, doc="flat blunt tip of an ogive, cone, hemisphere or "
                                                                "ellipsoid nose; 0: pointed"),
    "projectile.boattail_length": _num(0.0, "m", 0.0, 10.0, doc="tapered rear; 0: none"),
    "projectile.boattail_diameter": _pos(_ABSENT, "m", 1.0, doc="rear-face diameter of the boat-tail"),
    "projectile.profile": Key(str, _ABSENT, doc="CSV of the outer profile, rows z_m, r_m[, arc_radius_m] from the "
                                                "nose (projectile.nose = 'profile'; sets diameter and length)",
                              form="a file path (CSV)"),
    "projectile.inner_profile": Key(str, _ABSENT, doc="CSV of the cavity profile, rows z_m, r_m[, arc_radius_m] "
                                                      "(a fixed cavity: the mass follows from it)",
                                    form="a file path (CSV)"),
    "projectile.cavity_sections": Key(list, _ABSENT, doc="cavity as [[length_m, diameter_m], ...] front to rear; "
                                                         "the rear one's length is sized to projectile.mass",
                                      form="a list of [length, diameter] pairs in metres, each > 0"),
    "projectile.cad": Key(str, _ABSENT, doc="STEP or BREP file of the projectile body (axis +y, nose toward -y); "
                                            "meshed as is, mass from the mesh (docs/projectiles-and-targets.md)",
                          form="a file path (STEP or BREP)"),
    "projectile.cad_scale": _pos(1.0, "m per file unit", 1.0e3, doc="lengths of projectile.cad times this are "
                                                                     "metres (0.001 for a file in mm)"),
    "projectile.diameter": _num(0.0236, "m", 1.0e-3, 1.0, doc="calibre (fepen's laws are for 1 mm and more)"),
    "projectile.length": _num(0.144, "m", 1.0e-3, 10.0),
    "projectile.crh": _num(3.0, "", 0.5, 50.0, doc="ogive radius over diameter (0.5: hemisphere)"),
    "projectile.mass": _pos(0.367, "kg", 1.0e4,
                            doc="total mass; the cavity is sized, reduced or dropped to reach it (theory §1.1)"),
    "projectile.cavity_diameter": _num(0.012, "m", 0.0, 1.0, doc="main (rear) cavity diameter; 0: solid"),
    "projectile.cavity_length": _pos(_ABSENT, "m", 10.0,
                                     doc="total cavity length; absent: sized from projectile.mass"),
    "projectile.cavity_step_diameter": _num(0.008, "m", 0.0, 1.0,
                                            doc="diameter of the narrower forward cavity section (the step)"),
    "projectile.cavity_step_length": _num(0.020, "m", 0.0, 10.0,
                                          doc="length of the narrower forward cavity section; 0: no step"),
    "projectile.base_thickness": _pos(0.015, "m", 10.0, doc="solid rear wall behind the cavity"),
    # --- projectile material: 45 steel, Johnson-Cook (Table 2) ---
    "projectile.material.name": _choice("45-steel", *STEELS, doc="a named steel of fepen/data/steels.toml: sets "
                                        "every projectile.material key not given explicitly (sources: "
                                        "docs/theory.md §4)"),
    "projectile.material.density": _num(7850.0, "kg/m^3", 100.0, 30000.0),
    "projectile.material.youngs_modulus": _num(210.0e9, "Pa", 1.0e6, 1.0e13),
    "projectile.material.poisson_ratio": _num(0.3, "", 0.0, 0.5, hi_open=True),
    "projectile.material.A": _num(950.0e6, "Pa", 0.0, 1.0e11, lo_open=True),
    "projectile.material.B": _num(725.0e6, "Pa", 0.0, 1.0e11),
    "projectile.material.n": _num(0.375, "", 0.0, 2.0, lo_open=True),
    "projectile.material.C": _num(0.015, "", 0.0, 1.0),
    "projectile.material.m": _num(0.625, "", 0.0, 10.0, lo_open=True),
    "projectile.material.melt_temperature": _num(1765.0, "K", 0.0, 1.0e4, lo_open=True),
    "projectile.material.room_temperature": _num(294.0, "K", 0.0, 1.0e4, lo_open=True),
    "projectile.material.reference_strain_rate": _pos(1.0, "1/s", 1.0e9),
    "projectile.material.specific_heat": _pos(470.0, "J/(kg K)", 1.0e5),
    "projectile.material.taylor_quinney": _num(0.9, "", 0.0, 1.0),
    "projectile.wear.efficiency": _num(1.0, "", 0.0, 1.0,
                                       doc="eta: the fraction of the interface heat that melts the surface off "
                                           "(effects.wear; docs/theory.md §14)"),
    "projectile.wear.friction": _num(_ABSENT, "", 0.0, 2.0,
                                     doc="mu of the interface heat mu sigma_n |v_t|; absent: target.friction"),
    "projectile.wear.latent_heat": _num(2.7e5, "J/kg", 0.0, 1.0e7, doc="latent heat of fusion of the steel"),
    "projectile.erosion.strain": _num(1.0, "", 0.0, 100.0, lo_open=True,
                                      doc="equivalent plastic strain at which a cell erodes (effects.erosion; "
                                          "docs/theory.md §15)"),
    "projectile.erosion.step_ratio": _num(0.1, "", 0.0, 1.0, hi_open=True,
                                          doc="a cell whose own stable step falls below this times the initial "
                                              "step erodes (effects.erosion; 0: never)"),
    "projectile.failure_strain": _num(_ABSENT, "", 0.0, 100.0, lo_open=True,
                                      doc="PEEQ at which a concrete-target run stops, beyond the method "
                                          "(docs/theory.md); absent: never (a mushrooming nose keeps running)"),
    # --- explosive charge (Table 4) ---
    "charge.material.density": _num(1850.0, "kg/m^3", 100.0, 30000.0),
    "charge.material.youngs_modulus": _num(10.1e9, "Pa", 1.0e5, 1.0e13),
    "charge.material.poisson_ratio": _num(0.3, "", 0.0, 0.5, hi_open=True),
    "charge.material.yield_stress": _pos(45.0e6, "Pa", 1.0e11),
    "charge.material.tangent_modulus": _num(600.0e6, "Pa", 0.0, 1.0e12),
    "charge.friction": _num(0.1, "", 0.0, 2.0),
    "charge.contact": _choice("frictional", "frictional", "tied", doc="shell-charge interface"),
    # --- target (Table 3; the law: docs/paper.md §4) ---
    "target.kind": _choice("concrete", "concrete", "rigid-wall",
                           doc="'concrete': a cavity-expansion target of target.material (or target.layers); "
                               "'rigid-wall': a Taylor test"),
    "target.material": _choice("concrete", *TARGETS, doc="a named target of fepen/data/targets.toml: its law's "
                               "family and every target constant not given explicitly (docs/theory.md §16)"),
    "target.layers": Key(list, _ABSENT, doc="[[target.layers]] tables front to back: material, thickness (m; "
                                            "absent on the last: semi-infinite), gap (m, the air gap after it), and "
                                            "any target constant overriding the material's (docs/theory.md §17)",
                         form="a list of tables {material, thickness, gap, ...}"),
    "target.yield_stress": _pos(_ABSENT, "Pa", 1.0e11, doc="Y of a metal target (strength_model 'metal')"),
    "target.hardening_exponent": _num(_ABSENT, "", 0.0, 1.0, hi_open=True,
                                      doc="n of a metal target's power-law hardening Y (E eps / Y)^n"),
    "target.compressive_strength": _num(40.0e6, "Pa", 1.0e5, 1.0e10),
    "target.density": _num(2400.0, "kg/m^3", 100.0, 30000.0),
    "target.youngs_modulus": _pos(_ABSENT, "Pa", 1.0e13, doc="absent: 4.7 sqrt(f_c / MPa) GPa (ACI 318)"),
    "target.tensile_strength": _pos(_ABSENT, "Pa", 1.0e10, doc="absent: compressive_strength / 10"),
    "target.pressure_hardening": _num(0.67, "", 0.0, 3.0, hi_open=True, doc="lambda of Mohr-Coulomb"),
    "target.crater_depth_factor": _num(2.37, "", 0.0, 50.0, doc="crater depth k over diameter"),
    "target.strength_model": _choice("scaled-S", "scaled-S", "forrestal-S", "cavity-expansion", "metal",
                                     doc="sigma_s = S fc with S = S_coefficient fc^-S_exponent / sqrt(1 + D/S_size) "
                                         "(fc in MPa): fepen's calibrated scaled-S or Forrestal's S = 82.6 "
                                         "fc^-0.544; or the paper's elastic-cracked-plastic cavity expansion; or "
                                         "'metal': Forrestal-Warren's power-law metal (yield_stress, "
                                         "hardening_exponent)"),
    "target.S_coefficient": _pos(_ABSENT, "", 1.0e4, doc="absent: the strength model's"),
    "target.S_exponent": _num(_ABSENT, "", 0.0, 2.0, doc="absent: the strength model's"),
    "target.S_size": _pos(_ABSENT, "m", 1.0e6, doc="Bazant's D0 of the size effect; absent: the strength model's"),
    "target.quasi_static_stress": _pos(_ABSENT, "Pa", 1.0e11,
                                       doc="overrides the strength model's sigma_s; absent: computed"),
    "target.inertial_factor": _num(1.0, "", 0.0, 10.0, doc="B of sigma_n = sigma_s + B rho (v.n)^2"),
    "target.friction": _num(0.1, "", 0.0, 2.0, doc="Coulomb (static) coefficient, used when effects.friction"),
    "target.friction_dynamic": _num(_ABSENT, "", 0.0, 2.0,
                                    doc="mu_d of mu(v_t) = mu_d + (mu - mu_d) exp(-c v_t); absent: target.friction"),
    "target.friction_decay": _num(0.0, "s/m", 0.0, 1.0e3, doc="c of the sliding law; 0: constant Coulomb mu"),
    "target.separation_angle_deg": _num(0.0, "deg", 0.0, 90.0, hi_open=True),
    "target.onset_angle_deg": _num(2.0, "deg", 0.0, 30.0,
                                   doc="sigma_s develops over this first surface angle (0: at once)"),
    "target.thickness": _pos(_ABSENT, "m", 100.0, doc="absent: semi-infinite"),
    "target.lock_density": _num(2650.0, "kg/m^3", 100.0, 30000.0,
                                doc="Q1, density of fully compacted concrete (energy crater)"),
    # --- striking conditions (Table 1; defaults are shot C3) ---
    "impact.velocity": _num(C3.v0, "m/s", 0.0, 3000.0, lo_open=True),
    "impact.obliquity_deg": _num(C3.obliquity_deg, "deg", 0.0, 90.0, hi_open=True),
    "impact.attack_deg": _num(C3.attack_deg, "deg", -90.0, 90.0, lo_open=True, hi_open=True),
    "impact.shot": Key(str, _ABSENT, choices=tuple(SHOTS), doc="fills the three above from Table 1"),
    # --- effects: what is off costs nothing ---
    "effects.fidelity": _choice("plastic", "rigid", "elastic", "plastic"),
    "effects.crater": _choice("energy", "none", "linear", "energy"),
    "effects.separation": _flag(True),
    "effects.free_surface": _flag(True),
    "effects.friction": _flag(False),
    "effects.wear": _flag(False, doc="nose wear: the interface heat melts mass off the surface (rigid fidelity: "
                                     "the mass loss; deformable: the surface recedes; docs/theory.md §14)"),
    "effects.erosion": _flag(False, doc="element erosion of the meshed projectile: cells past projectile.erosion.* "
                                        "are removed, the faces they expose loaded (docs/theory.md §15)"),
    "effects.thermal": _flag(True),
    "effects.strain_rate": _flag(True),
    "effects.charge": _flag(False),
    # --- mesh ---
    "mesh.size": _num(0.0025, "m", 2.0e-4, 0.05, doc="nominal element size"),
    "mesh.rigid_panel": _num(_ABSENT, "m", 2.0e-4, 0.5,
                             doc="meridian panel of the rigid fidelity's load rings; absent: diameter / 6"),
    "mesh.nose_size": _num(_ABSENT, "m", 2.0e-4, 0.05, doc="element size at the nose tip; absent: mesh.size"),
    "mesh.optimize": _choice("netgen", "none", "gmsh", "netgen",
                             doc="tetrahedron optimiser; the stable step is set by the worst element"),
    # --- run control ---
    "run.end_time": _pos(_ABSENT, "s", 1.0, doc="absent: until stopped, perforated or ricocheted"),
    "run.output_interval": _pos(5.0e-5, "s", 1.0),
    "run.safety_factor": _num(0.8, "", 0.0, 1.0, lo_open=True,
                              doc="stable step = factor * (the estimate of run.stable_step)"),
    "run.stable_step": _choice("eigenvalue", "altitude", "eigenvalue",
                               doc="eigenvalue: 2/omega_max of the discrete body (power iteration), tracked "
                                   "by h/c as it deforms; altitude: min h/c (conservative)"),
    "run.fields": _flag(True, doc="write fields.xdmf"),
    "run.acceleration_filter_hz": _num(1.0e4, "Hz", 0.0, 1.0e7,
                                       doc="low-pass cut-off of the filtered accelerations (accelerations.csv); "
                                           "0: none"),
    "run.checkpoint_interval": _num(1.0e-4, "s", 0.0, 1.0,
                                    doc="simulated time between checkpoints (fepen run --resume DIR); 0: none"),
    "run.rigid_step": _pos(_ABSENT, "s", 1e-3, doc="RK4 step of the rigid fidelity; absent: min(0.1 D/v0, t_stop/300)"),
}

SECTIONS = sorted({name.split(".")[0] for name in SCHEMA})

def _check_sections(name: str, value: Any) -> list:
    """projectile.cavity_sections: [[length, diameter], ...] of positive finite numbers (m)."""
    form = SCHEMA[name].allowed()
    if not isinstance(value, list) or not value:
        raise InputError(name, f"got {_shown(value)}, expected {form}")
    out = []
    for i, row in enumerate(value):
        if (not isinstance(row, list) or len(row) != 2
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in row)
                or not all(_finite(v) and v > 0 for v in row)):
            raise InputError(f"{name}[{i}]", f"got {_shown(row)}, expected [length, diameter] in metres, each > 0")
        out.append([float(row[0]), float(row[1])])
    return out


#: the keys of one [[target.layers]] table besides the target constants
LAYER_KEYS = ("material", "thickness", "gap", "crater", "family")


def _check_layers(name: str, value: Any) -> list:
    """target.layers: tables with material, thickness, gap and target constants, types and ranges checked."""
    if not isinstance(value, list) or not value or not all(isinstance(v, dict) for v in value):
        raise InputError(name, f"got {_shown(value)}, expected {SCHEMA[name].allowed()} ([[target.layers]] in TOML)")
    out = []
    for i, table in enumerate(value):
        here = f"{name}[{i}]"
        layer = {}
        for k, v in table.items():
            key = f"{here}.{_name(k)}"
            if k == "material":
                layer[k] = SCHEMA["target.material"].check(key, v)
            elif k == "thickness":
                layer[k] = SCHEMA["target.thickness"].check(key, v)
            elif k == "gap":
                layer[k] = Key(float, 0.0, "m", 0.0, 1.0e3).check(key, v)
            elif k == "crater":
                layer[k] = _choice("none", "none", "energy").check(key, v)
            elif k == "family":  # as a resolved scene writes it back: must be the material's
                layer[k] = _choice("concrete", *FAMILIES).check(key, v)
            elif k in CONSTANTS:
                layer[k] = SCHEMA[f"target.{k}"].check(key, v)
            else:
                close = difflib.get_close_matches(k, LAYER_KEYS + CONSTANTS, n=1, cutoff=0.5)
                raise InputError(key, "unknown key" + (f" (did you mean '{close[0]}'?)" if close else
                                                       f" (allowed: {', '.join(LAYER_KEYS + CONSTANTS)})"))
        layer.setdefault("material", "concrete")
        layer.setdefault("gap", 0.0)
        if "thickness" not in layer and i < len(value) - 1:
            raise InputError(f"{here}.thickness", "missing: every layer but the last needs a thickness (m)")
        if "thickness" not in layer and layer["gap"] > 0.0:
            raise InputError(f"{here}.gap", "a semi-infinite last layer has nothing after it: drop the gap")
        out.append(layer)
    return out


LIST_CHECKS = {"projectile.cavity_sections": _check_sections, "target.layers": _check_layers}



class Section:
    """Read-only attribute access to a part of a resolved scene (``scene.projectile.material.A``)."""

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
        import copy

        return copy.deepcopy(object.__getattribute__(self, "_values"))

    def get(self, dotted: str) -> Any:
        """Value of a dotted key, None when an optional key is absent."""
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

    ``scene.explicit`` is the set of dotted keys the user gave.
    """

    def __init__(self, source=None, sets=()):
        given = _given(source)
        items = sets.items() if isinstance(sets, dict) else (parse_set(item) for item in sets)
        for key, value in items:
            given[key] = value
        resolved = resolve(given)
        object.__setattr__(self, "_values", object.__getattribute__(resolved, "_values"))
        object.__setattr__(self, "explicit", resolved.explicit)

    @classmethod
    def _resolved(cls, values: dict[str, Any], explicit: set[str]) -> Scene:
        out = object.__new__(cls)
        Section.__init__(out, values)
        object.__setattr__(out, "explicit", frozenset(explicit))
        return out

    def with_sets(self, sets) -> Scene:
        """A new Scene: this one's given keys with more overrides (as ``sets`` above)."""
        return Scene(self, sets)

    def __repr__(self) -> str:
        given = {k: self.get(k) for k in sorted(self.explicit)}
        return f"fepen.Scene({given})"


def _given(source) -> dict[str, Any]:
    """The flat {dotted key: value} a user gave, from any Scene source."""
    if source is None:
        return {}
    if isinstance(source, Scene):
        return {k: source.get(k) for k in source.explicit}
    if isinstance(source, dict):
        return _flatten(source)
    if isinstance(source, Path) or (isinstance(source, str) and "\n" not in source and "=" not in source):
        return read_toml(source)
    if isinstance(source, str):
        try:
            tree = tomllib.loads(source)
        except ValueError as err:  # TOMLDecodeError, or an integer past Python's 4300 digits
            raise InputError("SCENE", f"the scene text is not valid TOML: {_name(str(err), 200)}") from None
        return _flatten(tree)
    raise InputError("SCENE", f"expected a TOML file, TOML text, a dict or a Scene, got {type(source).__name__}")


def _flatten(tree: dict, prefix: str = "") -> dict[str, Any]:
    flat = {}
    for k, v in tree.items():
        name = f"{prefix}{k}"
        if isinstance(v, dict):
            if not v:
                raise InputError(_name(name), "empty table")
            flat.update(_flatten(v, name + "."))
        else:
            flat[name] = v
    return flat


def _unknown(name: str) -> InputError:
    tail = name.split(".")[-1]
    same_leaf = [k for k in SCHEMA if k.split(".")[-1] == tail]  # a key in the wrong table, first
    close = difflib.get_close_matches(name, same_leaf, n=1, cutoff=0.0) or difflib.get_close_matches(
        name, SCHEMA.keys(), n=1, cutoff=0.5)
    hint = f" (did you mean '{close[0]}'?)" if close else f" (sections: {', '.join(SECTIONS)})"
    return InputError(_name(name), "unknown key" + hint)


def parse_set(item: str) -> tuple[str, Any]:
    """Parse one ``--set KEY=VALUE``: VALUE in TOML syntax, a bare word taken as a string.

    Args:
        item: the text after --set.

    Returns:
        (dotted key, value).
    """
    if "=" not in item:
        raise InputError("--set", f"expected KEY=VALUE, got {item!r}")
    key, text = (s.strip() for s in item.split("=", 1))
    if not key:
        raise InputError("--set", f"expected KEY=VALUE, got {item!r}")
    try:
        value = tomllib.loads(f"v = {text}")["v"]
    except ValueError:  # TOMLDecodeError, or an integer past Python's 4300 digits: a bare word
        value = text
    return key, value


def read_toml(path: str | Path) -> dict[str, Any]:
    """Read a scene file into a flat {dotted key: value} dict, without validating the keys."""
    p = Path(path)
    try:
        found = p.is_file()
    except (OSError, ValueError):  # a name too long, or holding a NUL
        found = False
    if not found:
        raise InputError("SCENE", f"no such scene file: {_name(str(p), 200)}")
    try:
        with open(p, "rb") as fh:
            tree = tomllib.load(fh)
    except ValueError as err:  # TOMLDecodeError, text that is not UTF-8, an integer past 4300 digits
        raise InputError("SCENE", f"{_name(str(p), 200)} is not valid TOML: {_name(str(err), 200)}") from None
    return _flatten(tree)


def resolve(given: dict[str, Any]) -> Scene:
    """Validate user-given keys and fill in every default.

    Args:
        given: flat {dotted key: value} from the file and --set options, later entries winning.

    Returns:
        The resolved, read-only Scene.
    """
    for name in given:
        if name not in SCHEMA:
            raise _unknown(name)
    flat: dict[str, Any] = {}
    for name, key in SCHEMA.items():
        if name in given:
            flat[name] = key.check(name, given[name])
        elif key.default is not _ABSENT:
            flat[name] = key.default

    _resolve_shot(flat, given)
    _resolve_steel(flat, given)
    _resolve_target(flat, given)
    _check_consistency(flat, given)

    tree: dict[str, Any] = {}
    for name, value in flat.items():
        node = tree
        parts = name.split(".")
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = value
    return Scene._resolved(tree, set(given))


def _resolve_shot(flat: dict, given: dict) -> None:
    name = flat.get("impact.shot")
    if name is None:
        return
    s = shot(name)
    for key, value in (("impact.velocity", s.v0), ("impact.obliquity_deg", s.obliquity_deg),
                       ("impact.attack_deg", s.attack_deg)):
        if key in given and flat[key] != value:
            raise InputError(key, f"conflicts with impact.shot = {name!r}, which sets it to {value:g}; "
                                  "give one of the two")
        flat[key] = value


def _resolve_steel(flat: dict, given: dict) -> None:
    """The named steel's constants for every projectile.material key the user did not give."""
    for key, value in STEELS[flat["projectile.material.name"]].items():
        name = f"projectile.material.{key}"
        if name in SCHEMA and name not in given:
            flat[name] = SCHEMA[name].check(name, value)


def _material_constants(name: str, given: dict, crater_given: str | None) -> dict:
    """Every target constant of a named material, the given ones winning, with the derived defaults
    (tensile strength f_c/10) and its crater (the scene's explicit effects.crater, else the material's)."""
    out = {k: v for k, v in TARGETS[name].items() if k in CONSTANTS}
    out.update(given)
    if "tensile_strength" not in out and "compressive_strength" in out:
        out["tensile_strength"] = 0.1 * out["compressive_strength"]
    out["crater"] = crater_given or TARGETS[name].get("crater", "energy")
    out["family"] = TARGETS[name]["family"]
    if out["family"] == "metal":
        for k in ("yield_stress", "hardening_exponent", "youngs_modulus"):
            if k not in out:
                raise InputError(f"target.{k}", f"a metal target ({name}) needs it")
    return out


def _resolve_target(flat: dict, given: dict) -> None:
    """The named target material's constants for every target key the user did not give; each layer's."""
    crater = flat["effects.crater"] if "effects.crater" in given else None
    name = flat["target.material"]
    if "target.layers" in flat:
        for key in ("target.material", "target.thickness"):
            if key in given:
                raise InputError(key, "give it per layer in [[target.layers]] (material, thickness), not both")
        if crater == "linear":
            raise InputError("effects.crater", "'linear' is Forrestal's crater of one target; with target.layers "
                                               "use 'energy' or 'none'")
        out = []
        for i, layer in enumerate(flat["target.layers"]):
            family = TARGETS[layer["material"]]["family"]
            if layer.get("family", family) != family:
                raise InputError(f"target.layers[{i}].family", f"{layer['family']!r}: {layer['material']!r} is "
                                                               f"a {family} (drop the key)")
            here = {**{k: v for k, v in layer.items() if k in ("material", "thickness", "gap")},
                    **_material_constants(layer["material"], {k: v for k, v in layer.items() if k in CONSTANTS},
                                          crater or layer.get("crater"))}
            _check_target(f"target.layers[{i}]", here, here["family"], set(layer))
            if here["crater"] == "energy" and here.get("lock_density", 2650.0) <= here["density"]:
                raise InputError(f"target.layers[{i}].lock_density", "must exceed the layer's density with the "
                                                                     "energy crater")
            out.append(here)
        flat["target.layers"] = out
        flat.pop("target.material", None)  # each layer names its own
        return
    mine = {k: flat[f"target.{k}"] for k in CONSTANTS if f"target.{k}" in given}
    constants = _material_constants(name, mine, crater)
    for k in CONSTANTS:
        if k in constants:
            flat[f"target.{k}"] = SCHEMA[f"target.{k}"].check(f"target.{k}", constants[k])
    flat["effects.crater"] = constants["crater"]


CAD_EXCLUDES = ("projectile.nose", "projectile.diameter", "projectile.length", "projectile.crh", "projectile.mass",
                "projectile.nose_length", "projectile.meplat_diameter", "projectile.boattail_length",
                "projectile.boattail_diameter", "projectile.profile", "projectile.inner_profile",
                "projectile.cavity_sections", "projectile.cavity_diameter", "projectile.cavity_length",
                "projectile.cavity_step_diameter", "projectile.cavity_step_length", "projectile.base_thickness")


def _check_geometry_keys(flat: dict, given: dict) -> None:
    """Which projectile keys go together (nose families, drawn profiles, cavity forms, CAD)."""
    if "projectile.cad" in flat:
        for key in CAD_EXCLUDES:
            if key in given:
                raise InputError(key, "the body is read from projectile.cad (its shape, and its mass from its mesh "
                                      "and projectile.material.density): drop this key")
        if flat["effects.charge"]:
            raise InputError("effects.charge", "a CAD body has no charge: it is meshed as one steel solid")
        flat["projectile.cavity_diameter"] = 0.0
        return
    nose = flat["projectile.nose"]
    if "projectile.profile" in flat:
        if "projectile.nose" in given and nose != "profile":
            raise InputError("projectile.profile", f"draws the whole outside: drop projectile.nose = {nose!r} (or "
                                                   "set it to 'profile')")
        flat["projectile.nose"] = nose = "profile"
        for key in ("projectile.diameter", "projectile.length", "projectile.crh", "projectile.nose_length",
                    "projectile.meplat_diameter", "projectile.boattail_length", "projectile.boattail_diameter"):
            if key in given:
                raise InputError(key, "is set by projectile.profile: drop it")
        if "projectile.mass" not in given and not any(k in given for k in (
                "projectile.cavity_diameter", "projectile.cavity_length", "projectile.cavity_sections",
                "projectile.inner_profile")):
            flat["projectile.cavity_diameter"] = 0.0  # the paper's cavity belongs to the paper's body
    elif nose == "profile":
        raise InputError("projectile.nose", "'profile' needs projectile.profile, the CSV of the outside")
    if nose in ("secant", "cone", "ellipsoid") and "projectile.nose_length" not in flat:
        raise InputError("projectile.nose_length", f"a {nose} nose needs its axial length (m)")
    if "projectile.nose_length" in given and nose not in ("secant", "cone", "ellipsoid"):
        raise InputError("projectile.nose_length", f"is for a secant, cone or ellipsoid nose, not {nose!r} (a "
                                                   "tangent ogive's length follows from projectile.crh)")
    if flat["projectile.meplat_diameter"] > 0.0 and nose in ("flat", "profile"):
        raise InputError("projectile.meplat_diameter", f"a {nose!r} nose has no tip to blunt: drop it")
    if flat["projectile.boattail_length"] > 0.0 and "projectile.boattail_diameter" not in flat:
        raise InputError("projectile.boattail_diameter", "a boat-tail (projectile.boattail_length > 0) needs its "
                                                         "rear diameter (m)")
    if "projectile.boattail_diameter" in given and flat["projectile.boattail_length"] == 0.0:
        raise InputError("projectile.boattail_length", "must be > 0 with projectile.boattail_diameter")
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


def _check_consistency(flat: dict, given: dict) -> None:
    """Checks that involve several keys. Geometry is checked in full by fepen.geometry.gmsh_model."""
    _check_geometry_keys(flat, given)
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
    if flat["effects.erosion"] and flat["effects.fidelity"] == "rigid":
        raise InputError("effects.erosion", "removes cells of the meshed projectile: use it with effects.fidelity "
                                            "= 'elastic' or 'plastic' (the rigid fidelity has the scalar wear)")
    if flat["effects.crater"] == "energy" and flat["target.lock_density"] <= flat["target.density"]:
        raise InputError("target.lock_density", f"{flat['target.lock_density']:g} kg/m^3: must exceed "
                                                f"target.density = {flat['target.density']:g} kg/m^3")
    if "target.tensile_strength" not in flat:
        flat["target.tensile_strength"] = 0.1 * flat["target.compressive_strength"]
    if flat.get("target.friction_dynamic", 0.0) > flat["target.friction"]:
        raise InputError("target.friction_dynamic", f"{flat['target.friction_dynamic']:g}: the sliding coefficient "
                                                    f"must be at most target.friction = {flat['target.friction']:g}")
    if "mesh.nose_size" in flat and flat["mesh.nose_size"] > flat["mesh.size"]:
        raise InputError("mesh.nose_size", f"must be at most mesh.size = {flat['mesh.size']:g} m")
    _check_physics(flat, given)
    if "target.layers" not in flat:
        _check_target("target", {k: flat[f"target.{k}"] for k in CONSTANTS if f"target.{k}" in flat},
                      TARGETS[flat["target.material"]]["family"], {k[7:] for k in given if k.startswith("target.")})


def _given_one(given: dict, *names: str) -> str:
    """The first of these keys the user gave, else the first: the key an error across keys names."""
    return next((n for n in names if n in given), names[0])


def _check_physics(flat: dict, given: dict) -> None:
    """Checks across keys a ballistics engineer makes at a glance (CROSS_CHECKS, docs/scenes.md)."""
    melt, room = flat["projectile.material.melt_temperature"], flat["projectile.material.room_temperature"]
    if melt <= room:
        key = _given_one(given, "projectile.material.melt_temperature", "projectile.material.room_temperature")
        raise InputError(key, f"melting temperature {melt:g} K must exceed room temperature {room:g} K "
                              "(projectile.material.*: Johnson-Cook's T* = (T - T_room)/(T_melt - T_room))")
    theta = flat["impact.obliquity_deg"] + flat["impact.attack_deg"]
    if theta >= 90.0:
        raise InputError(_given_one(given, "impact.attack_deg", "impact.obliquity_deg"),
                         f"obliquity + attack = {theta:g} deg turns the projectile's axis to or past the target "
                         "face (its tail would start inside the target): the sum must be < 90 deg")
    end = flat.get("run.end_time")  # (a field output interval past the end is harmless: the first and last states)
    key = "run.rigid_step"
    if end is not None and key in given and "run.end_time" in given and flat[key] > end:
        raise InputError(key, f"{flat[key]:g} s: must be at most run.end_time = {end:g} s")
    E, Et = flat["charge.material.youngs_modulus"], flat["charge.material.tangent_modulus"]
    if Et >= E:
        raise InputError(_given_one(given, "charge.material.tangent_modulus", "charge.material.youngs_modulus"),
                         f"the charge's tangent modulus {Et:g} Pa must be below its Young's modulus {E:g} Pa "
                         "(charge.material.*: bilinear hardening H = E Et / (E - Et))")


def _check_target(where: str, c: dict, family: str, given: set) -> None:
    """One target material's constants (c: target.* names without the prefix; given: those the user gave)
    make a law: a metal's law for a metal and only for it, its yield below 2E/3; a concrete's, rock's or soil's
    tensile strength below its compressive strength and a plastic zone wider than the cavity (docs/theory.md
    §8.1, §16)."""
    model = c.get("strength_model")
    if family == "metal" and model not in (None, "metal"):
        raise InputError(f"{where}.strength_model", f"got {model!r}: a metal target's law is 'metal' (drop the key)")
    if family != "metal" and model == "metal":
        raise InputError(f"{where}.strength_model", f"'metal' is the law of a metal target.material (6061-T6511, "
                                                    f"armour-steel), not of a {family} one")
    if family == "metal":
        Y, E = c.get("yield_stress"), c.get("youngs_modulus")
        if Y is not None and E is not None and 1.5 * Y >= E:
            key = _given_one(given, "yield_stress", "youngs_modulus")
            raise InputError(f"{where}.{key}", f"a metal target's yield stress {Y:g} Pa must be below 2/3 of its "
                                               f"Young's modulus {E:g} Pa (Forrestal-Warren: 3Y/(2E) < 1)")
        return
    fc, T = c["compressive_strength"], c["tensile_strength"]
    if T >= fc:
        key = _given_one(given, "tensile_strength", "compressive_strength")
        raise InputError(f"{where}.{key}", f"tensile strength {T:g} Pa must be below compressive strength "
                                           f"{fc:g} Pa")
    E = c.get("youngs_modulus") or 4.7e9 * math.sqrt(fc / 1e6)  # ACI 318, as fepen.laws.target's default
    ratio = 9.0 * fc / (4.0 * E) * math.sqrt(fc / (2.0 * T))
    if ratio >= 1.0:
        key = _given_one(given, "youngs_modulus", "tensile_strength", "compressive_strength")
        raise InputError(f"{where}.{key}", f"Young's modulus {E:g} Pa, compressive strength {fc:g} Pa and tensile "
                                           f"strength {T:g} Pa leave no plastic zone around the cavity: (9 fc/(4 "
                                           f"E)) sqrt(fc/(2 ft)) = {ratio:.3g} must be below 1")


def load(path: str | Path | None = None, sets: list[str] | tuple[str, ...] = ()) -> Scene:
    """Read a scene file (or none: all defaults), apply ``--set`` overrides, validate.

    Args:
        path: TOML scene file, or None for the default scene.
        sets: ``KEY=VALUE`` strings, applied after the file in order.

    Returns:
        The resolved Scene.
    """
    return Scene(Path(path) if path is not None else None, sets)


def to_toml(scene: Section) -> str:
    """The resolved scene as TOML text (every key, SI units), for results directories: the keys the user gave
    as values, the others (defaults, a named material's constants, what resolution derived) as comments, so
    that the text resolves to the same scene with the same given keys (``fepen run --resume``, api.load): the
    mass rule, a drawn or CAD body and a layer's own crater depend on which keys were given."""
    given = getattr(scene, "explicit", None)
    lines: list[str] = ["# fepen scene: the keys given as values; defaults and derived values as comments", ""]

    def tables(v) -> bool:
        return isinstance(v, list) and bool(v) and all(isinstance(x, dict) for x in v)

    def emit(prefix: str, node: dict) -> None:
        scalars = {k: v for k, v in node.items() if not isinstance(v, dict) and not tables(v)}
        if scalars:
            mine = {k for k in scalars if given is None or f"{prefix}.{k}" in given}
            lines.append(f"[{prefix}]" if mine else f"# [{prefix}]")
            lines.extend(("" if k in mine else "# ") + f"{k} = {_toml_value(v)}" for k, v in scalars.items())
            lines.append("")
        for k, v in node.items():
            if tables(v):  # an array of tables: [[prefix.k]]
                for table in v:
                    lines.append(f"[[{prefix}.{k}]]")
                    lines.extend(f"{kk} = {_toml_value(vv)}" for kk, vv in table.items() if vv is not None)
                    lines.append("")
        for k, v in node.items():
            if isinstance(v, dict):
                emit(f"{prefix}.{k}" if prefix else k, v)

    emit("", scene.as_dict())
    return "\n".join(lines)


def _toml_value(v) -> str:
    """A value in TOML syntax (strings escaped as TOML's basic strings want)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + "".join(f"\\{c}" if c in '"\\' else f"\\u{ord(c):04x}" if ord(c) < 0x20 or ord(c) == 0x7F
                             else c for c in v) + '"'
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return repr(v)


#: the checks across keys, as ``fepen keys`` lists them under the table (each refusal names the key)
CROSS_CHECKS = (
    "projectile.material.melt_temperature > projectile.material.room_temperature (Johnson-Cook's T*)",
    "charge.material.tangent_modulus < charge.material.youngs_modulus (bilinear hardening)",
    "impact.obliquity_deg + impact.attack_deg < 90 deg: the axis points into the target",
    "run.rigid_step at most run.end_time, when both are given",
    "a concrete, rock or soil target (or layer): tensile_strength < compressive_strength, and a plastic zone "
    "wider than the cavity, (9 fc/(4 E)) sqrt(fc/(2 ft)) < 1; strength_model 'metal' for metals only",
    "a metal target (or layer): yield_stress < 2/3 youngs_modulus (Forrestal-Warren)",
    "target.lock_density > target.density with the energy crater; target.friction_dynamic <= target.friction; "
    "mesh.nose_size <= mesh.size",
    "effects.charge needs a cavity (not a solid or CAD body); projectile.mass and projectile.cavity_length not "
    "both; neither with a solid body (projectile.cavity_diameter = 0)",
    "the projectile, built from its exact outside before any mesh: the nose shorter than the body, the meplat "
    "and boat-tail narrower than it, the cavity inside it with a wall of 5 % of the calibre and the base "
    "behind it, projectile.mass within the reach of the cavity (docs/theory.md §1.1)",
    "noted, not refused: a target (or a layer) thinner than the nose is long (the cavity-expansion law is a "
    "thick-target law)",
)


def describe() -> str:
    """A Markdown table of every scene key (default, unit, allowed values, meaning), then the checks across
    keys."""
    rows = ["| key | default | allowed | meaning |", "|---|---|---|---|"]
    for name, key in SCHEMA.items():
        if key.default is _ABSENT:
            default = "(absent)"
        elif isinstance(key.default, bool):
            default = str(key.default).lower()
        elif isinstance(key.default, str):
            default = f'"{key.default}"'
        else:
            default = f"{key.default:g}"
        rows.append(f"| `{name}` | {default} | {key.allowed()} | {key.doc} |")
    rows += ["", "Checks across keys, before anything is meshed (bad input, exit 2, naming the key):", ""]
    rows += [f"- {check}" for check in CROSS_CHECKS]
    return "\n".join(rows)
