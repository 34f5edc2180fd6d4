"""The table of every key with the checks across keys (:func:`describe`: ``fepen keys``, docs/scenes.md), and a
resolved scene as TOML text (:func:`to_toml`, fepen.scene.text, for results directories)."""

from __future__ import annotations

from fepen.scene.keys import ABSENT
from fepen.scene.resolve import CROSS_CHECKS
from fepen.scene.schema import SCHEMA
from fepen.scene.text import to_toml

__all__ = ["to_toml", "describe"]


def describe() -> str:
    """A Markdown table of every scene key (default, unit, allowed values, meaning), then the checks across
    keys."""
    rows = ["| key | default | allowed | meaning |", "|---|---|---|---|"]
    for name, key in SCHEMA.items():
        if key.default is ABSENT:
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
