"""fepen's named explosives (``charge.explosive``), shipped as fepen/data/explosives.toml: the thresholds of the
charge-safety criteria (fepen.laws.explosive) for each, every value with its publication and where it was
transcribed from (docs/theory.md §20). A ``charge.safety.*`` key the user gives overrides the named explosive's
value."""

from __future__ import annotations

import tomllib
from importlib import resources

__all__ = ["EXPLOSIVES", "THRESHOLDS", "names"]


def _read() -> dict[str, dict]:
    return tomllib.loads(resources.files("fepen.data").joinpath("explosives.toml").read_text())


#: name -> {threshold key (without "charge.safety."): value, "<key>_source": text, "name", "source"}
EXPLOSIVES: dict[str, dict] = _read()

#: the charge.safety.* keys a named explosive may set, one per criterion of fepen.laws.explosive
THRESHOLDS = ("strength", "tensile_strength", "friction_work", "friction_power", "gap", "closure_speed",
              "acceleration_g")


def names() -> tuple[str, ...]:
    """The library's explosive names, the paper's first."""
    return tuple(EXPLOSIVES)
