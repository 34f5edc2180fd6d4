"""One scene key: its type, default, unit and allowed values (:class:`Key`), and the checks of one value: its
type, its range or choices, and the two list keys' rows (``projectile.cavity_sections``, ``target.layers``).

A value that fails raises :class:`fepen.errors.InputError` naming the key and what is allowed. Checks that
involve several keys are in fepen.scene.resolve.
"""

from __future__ import annotations

import difflib
import math
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from fepen.errors import InputError

__all__ = ["ABSENT", "Key", "number", "positive", "choice", "flag", "finite", "shown", "display_name",
           "check_sections", "check_layers", "check_nesting", "DEPTH_MAX"]

#: marks an optional key whose absence means something (e.g. semi-infinite target)
ABSENT = object()


@dataclass(frozen=True)
class Key:
    """One scene key: its type, default, unit and allowed values.

    ``rows`` checks the value of a list key: ``rows(key, name, value)`` returns the list converted, or raises.
    """

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
    rows: Callable[[Key, str, Any], list] | None = field(default=None, compare=False, repr=False)

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
        """The value converted to the key's type, or InputError.

        Args:
            name: the key as the error names it (a dotted key, or ``target.layers[0].density``).
            value: what the user gave.

        Returns:
            The value as the key's type (an int of a float key as float; a list key's rows checked).
        """
        if self.kind is list:
            return self.rows(self, name, value)
        if not self._typed(value):
            expected = "true or false" if self.kind is bool else self.allowed()
            raise InputError(name, f"got {shown(value)}, expected {expected}")
        if self.kind is float:
            value = float(value)
        if self.choices and value not in self.choices:
            raise InputError(name, f"got {shown(value)}, expected {self.allowed()}")
        if self.kind in (int, float):
            bad_lo = self.lo is not None and (value < self.lo or (self.lo_open and value == self.lo))
            bad_hi = self.hi is not None and (value > self.hi or (self.hi_open and value == self.hi))
            if bad_lo or bad_hi:
                raise InputError(name, f"got {shown(value)}, expected {self.allowed()}")
        return value

    def _typed(self, value: Any) -> bool:
        """Whether the value has the key's type (a float key: any finite number, not a bool; a path: text
        that open() can take, not blank and without NUL)."""
        if self.kind is float:
            return not isinstance(value, bool) and isinstance(value, (int, float)) and finite(value)
        if self.kind is int:
            return not isinstance(value, bool) and isinstance(value, int)
        if self.kind is bool:
            return isinstance(value, bool)
        if self.kind is str:
            return isinstance(value, str) and not (self.form and (not value.strip() or "\x00" in value))
        return True


def number(default, unit, lo=None, hi=None, lo_open=False, hi_open=False, doc="") -> Key:
    """A float key in [lo, hi] (either end open, or None: unbounded).

    Args:
        default: the value when the key is not given (ABSENT: the key is optional).
        unit: SI unit as the key table shows it.
        lo, hi: the bounds; lo_open, hi_open: exclude the bound itself.
        doc: the meaning, as docs/scenes.md shows it.

    Returns:
        The Key.
    """
    return Key(float, default, unit, lo, hi, lo_open, hi_open, doc=doc)


def positive(default, unit, hi=None, doc="") -> Key:
    """A strictly positive float key, at most ``hi`` (Args as :func:`number`).

    Returns:
        The Key.
    """
    return Key(float, default, unit, 0.0, hi, lo_open=True, doc=doc)


def choice(default, *choices, doc="") -> Key:
    """A string key taking one of ``choices``.

    Args:
        default: the value when the key is not given.
        choices: the allowed strings, in the order the key table lists them.
        doc: the meaning.

    Returns:
        The Key.
    """
    return Key(str, default, choices=choices, doc=doc)


def flag(default, doc="") -> Key:
    """A true-or-false key.

    Args:
        default: the value when the key is not given.
        doc: the meaning.

    Returns:
        The Key.
    """
    return Key(bool, default, doc=doc)


def finite(value: int | float) -> bool:
    """A finite number, as a float can hold it (TOML integers have no bound: 10**400 is not).

    Args:
        value: an int or a float.

    Returns:
        True when finite.
    """
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


def shown(value: Any, limit: int = 60) -> str:
    """A value as an error line shows it: floats as %g, others by repr, long ones cut, always one line.

    Args:
        value: anything a user gave.
        limit: the most characters shown.

    Returns:
        The text.
    """
    if isinstance(value, float):
        return f"{value:g}"
    try:
        text = repr(value)
    except ValueError:  # an int past Python's 4300-digit limit of conversion to text
        text = f"an integer of more than {sys.get_int_max_str_digits()} digits"
    text = " ".join(text.split())
    return text if len(text) <= limit else text[:limit - 3] + "..."


def display_name(name: str, limit: int = 80) -> str:
    """A key or a path as the user wrote it, shown on one line (TOML allows any character in a quoted key).

    Args:
        name: the key or path.
        limit: the most characters shown as is; longer ones are shown as :func:`shown` cuts them.

    Returns:
        The text.
    """
    return name if name.isprintable() and len(name) <= limit else shown(name, limit)


#: the deepest nesting of tables and arrays read from a scene or a sweep (a document's top-level keys at level
#: 1): a scene uses 4 at most ([[output.probes]] point = [x, y, z]), a sweep 6 (a [grid] of probe lists)
DEPTH_MAX = 16


def check_nesting(value: Any, key: str, what: str, level: int = 1) -> None:
    """Refuse tables and arrays nested more than DEPTH_MAX deep, one inside another (InputError naming ``key``):
    no scene or sweep needs them, and every reader after this one may follow them down. Walked without recursion,
    depth first, so that a structure that holds itself (a dict given to fepen.Scene) is refused too.

    Args:
        value: a parsed TOML document, a table or a value (dicts, lists and scalars).
        key: the key the error names (SCENE, SWEEP, or the scene key given the value).
        what: the thing nested, as the message says it ("the value", a file's name).
        level: the depth of ``value`` itself: 0 for a whole document (its keys are at level 1), 1 for a value.
    """
    if not isinstance(value, (dict, list, tuple)):
        return
    stack = [(value, level)]
    while stack:
        node, depth = stack.pop()
        if depth > DEPTH_MAX:
            raise InputError(key, f"{what} nests tables and arrays more than {DEPTH_MAX} levels deep, one inside "
                                  f"another: a scene or sweep nests them at most {DEPTH_MAX} levels")
        children = node.values() if isinstance(node, dict) else node
        stack.extend((c, depth + 1) for c in children if isinstance(c, (dict, list, tuple)))


def check_sections(key: Key, name: str, value: Any) -> list:
    """projectile.cavity_sections: [[length, diameter], ...] of positive finite numbers (m).

    Args:
        key: the list key (for its allowed form).
        name: the key's name.
        value: what the user gave.

    Returns:
        The rows as [float, float].
    """
    form = key.allowed()
    if not isinstance(value, list) or not value:
        raise InputError(name, f"got {shown(value)}, expected {form}")
    out = []
    for i, row in enumerate(value):
        if (not isinstance(row, list) or len(row) != 2
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in row)
                or not all(finite(v) and v > 0 for v in row)):
            raise InputError(f"{name}[{i}]", f"got {shown(row)}, expected [length, diameter] in metres, each > 0")
        out.append([float(row[0]), float(row[1])])
    return out


def check_layers(key: Key, name: str, value: Any, fields: Mapping[str, Key]) -> list:
    """target.layers: tables of material, thickness, gap and target constants, types and ranges checked.

    Args:
        key: the list key (for its allowed form).
        name: the key's name.
        value: what the user gave: a list of tables.
        fields: the keys one table may hold, each with its Key (fepen.scene.schema.LAYER_FIELDS).

    Returns:
        The tables, each value checked, with material "concrete" and gap 0 when not given.
    """
    if not isinstance(value, list) or not value or not all(isinstance(v, dict) for v in value):
        raise InputError(name, f"got {shown(value)}, expected {key.allowed()} ([[target.layers]] in TOML)")
    out = []
    for i, table in enumerate(value):
        here = f"{name}[{i}]"
        layer = {}
        for k, v in table.items():
            where = f"{here}.{display_name(k)}"
            if k not in fields:
                close = difflib.get_close_matches(k, tuple(fields), n=1, cutoff=0.5)
                raise InputError(where, "unknown key" + (f" (did you mean '{close[0]}'?)" if close else
                                                         f" (allowed: {', '.join(fields)})"))
            layer[k] = fields[k].check(where, v)
        layer.setdefault("material", "concrete")
        layer.setdefault("gap", 0.0)
        if "thickness" not in layer and i < len(value) - 1:
            raise InputError(f"{here}.thickness", "missing: every layer but the last needs a thickness (m)")
        if "thickness" not in layer and layer["gap"] > 0.0:
            raise InputError(f"{here}.gap", "a semi-infinite last layer has nothing after it: drop the gap")
        out.append(layer)
    return out
