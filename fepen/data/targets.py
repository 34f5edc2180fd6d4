"""fepen's named target materials (``target.material``; ``material`` of each ``[[target.layers]]``), shipped as
fepen/data/targets.toml: the family of each one's law and its constants under the target.* key names, with
its source (docs/theory.md §16). A key the user gives explicitly overrides the named material's value."""

from __future__ import annotations

import tomllib
from importlib import resources

__all__ = ["TARGETS", "FAMILIES", "CONSTANTS"]


def _read() -> dict[str, dict]:
    return tomllib.loads(resources.files("fepen.data").joinpath("targets.toml").read_text())


#: name -> {target key (without "target."): value, "family", "source", "crater"}
TARGETS: dict[str, dict] = _read()

#: the law families (fepen.runs.setup builds each one's TargetLaw)
FAMILIES = ("concrete", "rock", "metal", "soil")

#: the target.* keys a material (or a layer's table) may set
CONSTANTS = ("density", "compressive_strength", "youngs_modulus", "tensile_strength", "pressure_hardening",
             "strength_model", "S_coefficient", "S_exponent", "S_size", "quasi_static_stress", "inertial_factor",
             "yield_stress", "hardening_exponent", "crater_depth_factor", "lock_density", "crush_strain",
             "free_surface_range", "strength_basis", "separation_angle_deg")
