"""fepen's named projectile steels (``projectile.material.name``), shipped as fepen/data/steels.toml: every
``projectile.material`` key per steel, with its source. A key the user gives explicitly overrides the named
steel's value (docs/theory.md §4)."""

from __future__ import annotations

import tomllib
from importlib import resources

__all__ = ["STEELS", "names"]


def _read() -> dict[str, dict]:
    return tomllib.loads(resources.files("fepen.data").joinpath("steels.toml").read_text())


#: name -> {material key (without "projectile.material."): value, "source": text}
STEELS: dict[str, dict] = _read()


def names() -> tuple[str, ...]:
    """The library's steel names, the paper's first."""
    return tuple(STEELS)
