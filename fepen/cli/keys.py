"""``fepen keys``: every scene key with its default, unit and allowed values (a Markdown table)."""

from __future__ import annotations

from fepen.cli.common import say

HELP = "list every scene key with its default, unit and allowed values"


def add_arguments(parser) -> None:
    """No options."""


def run(args) -> int:
    """Print the scene-key table (Markdown)."""
    from fepen import scene as fscene

    say(fscene.describe())
    return 0
