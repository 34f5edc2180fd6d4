"""What the user gave, read into a flat {dotted key: value} dict before it is resolved: TOML files and text
(capped in size, never through a link out of its directory), nested tables, dicts and ``--set KEY=VALUE``; the
messages for a key that is unknown, given twice or not TOML.
"""

from __future__ import annotations

import difflib
import tomllib
from pathlib import Path
from typing import Any

from fepen.errors import InputError
from fepen.inputs import read_capped
from fepen.scene.keys import DEPTH_MAX, check_nesting, display_name, shown
from fepen.scene.schema import REMOVED, SCHEMA, SECTIONS

#: the largest scene file read (bytes): a scene is a page of text; a larger file is refused before it is parsed
#: (the scene fepen writes into its results is held within it too: written_scene_fits)
SCENE_MAX = 1 << 20
#: the top-level keys of a sweep file (docs/studies.md) that no scene has: its base scene, overrides and kinds
SWEEP_ONLY = ("scene", "base", "grid", "monte_carlo", "table")


# ---------------------------------------------------------------------------------------------------------
# what the user gave: files, text, dicts, --set
# ---------------------------------------------------------------------------------------------------------
def flatten(tree: dict, prefix: str = "") -> dict[str, Any]:
    """A nested table of scene keys as a flat {dotted key: value} dict, without validating the keys.

    Args:
        tree: nested dicts as TOML reads them ({"impact": {"velocity": 700.0}}); dotted keys pass as they are.
        prefix: put before every key (used by the recursion).

    Returns:
        The flat dict. InputError for an empty table, for a key given twice (a quoted dotted key,
        ``"impact.velocity" = 900.0``, beside the same key in nested tables, ``[impact] velocity = 500.0``:
        TOML reads them as two keys, fepen as one), and for tables and arrays nested more than DEPTH_MAX deep.
    """
    if not prefix:  # the whole tree (the recursion below is as deep as the tree: at most DEPTH_MAX)
        check_nesting(tree, "SCENE", "the scene", level=0)
    flat: dict[str, Any] = {}
    for k, v in tree.items():
        name = f"{prefix}{k}"
        if isinstance(v, dict):
            if not v:
                raise InputError(display_name(name), "empty table")
            items = flatten(v, name + ".").items()
        else:
            items = ((name, v),)
        for leaf, value in items:
            if leaf in flat:
                raise InputError(display_name(leaf), given_twice(leaf))
            flat[leaf] = value
    return flat


def given_twice(name: str) -> str:
    """The message of a key given twice in one table, once as a quoted dotted key and once in nested tables
    (flatten; a sweep's [grid] and [monte_carlo.vary]: fepen.studies.spec.flat_leaves).

    Args:
        name: the dotted key.

    Returns:
        The message.
    """
    head, _, leaf = display_name(name).rpartition(".")
    return (f'given twice: as a quoted dotted key ("{head}.{leaf}" = ...) and in nested tables ([{head}] {leaf} = '
            "...), which name the same key: give it once")


def unknown_key(name: str) -> InputError:
    """The error for a name that is not a scene key, with the closest key as a hint.

    Args:
        name: the dotted name the user gave.

    Returns:
        The InputError (to raise, or to quote).
    """
    if name in REMOVED:
        return InputError(name, REMOVED[name])
    parts = name.split(".")
    if parts[0] in ("grid", "monte_carlo", "table"):  # a sweep's spec given where a scene is read
        return InputError(display_name(name), f"[{parts[0]}] is a sweep's table, not a scene key: run the file "
                                              "with fepen sweep FILE")
    for k in range(len(parts) - 1, 0, -1):  # a key's value given as a table: {…} for [[…]], or a.b.c = 1
        head = ".".join(parts[:k])
        if head in SCHEMA:
            return InputError(head, f"got a table ({display_name(name)}), expected {SCHEMA[head].allowed()}"
                                    + (f" ([[{head}]] in TOML)" if "list" in SCHEMA[head].allowed() else ""))
    tail = parts[-1]
    same_leaf = [k for k in SCHEMA if k.split(".")[-1] == tail]  # a key in the wrong table, first
    close = difflib.get_close_matches(name, same_leaf, n=1, cutoff=0.0) or difflib.get_close_matches(
        name, SCHEMA.keys(), n=1, cutoff=0.5)
    hint = f" (did you mean '{close[0]}'?)" if close else f" (sections: {', '.join(SECTIONS)})"
    return InputError(display_name(name), "unknown key" + hint)


def check_sets(source, sets) -> None:
    """``--set KEY VALUE`` (a space for the '='): the value became the scene file's name. Said as that, naming
    the key, before the file is looked for."""
    for item in sets:
        if isinstance(item, str) and "=" not in item:
            hint = ""
            if isinstance(source, (str, Path)) and "\n" not in str(source):
                try:
                    missing = not Path(source).is_file()
                except (OSError, ValueError):
                    missing = True
                if missing:
                    hint = f" (did you mean --set {display_name(item)}={display_name(str(source), 60)}?)"
            raise InputError("--set", f"expected KEY=VALUE, got {shown(item)}{hint}")


def parse_set(item: str) -> tuple[str, Any]:
    """Parse one ``--set KEY=VALUE``: VALUE in TOML syntax, a bare word taken as a string.

    Args:
        item: the text after --set.

    Returns:
        (dotted key, value).
    """
    if "=" not in item:
        raise InputError("--set", f"expected KEY=VALUE, got {shown(item)}")
    key, text = (s.strip() for s in item.split("=", 1))
    if not key:
        raise InputError("--set", f"expected KEY=VALUE, got {shown(item)}")
    try:
        value = tomllib.loads(f"v = {text}")["v"]
    except ValueError:  # TOMLDecodeError, or an integer past Python's 4300 digits: a bare word
        value = text
    except RecursionError:  # arrays or inline tables nested thousands deep
        raise toml_error(RecursionError(), display_name(key), "the value") from None
    check_nesting(value, display_name(key), "the value")
    return key, value


def set_item(key: str, value) -> str:
    """``KEY=VALUE`` as ``--set`` and ``Scene(sets=...)`` read it: a number (numpy's too: numpy 2 writes its
    scalars as ``np.float64(...)``, which TOML does not read), a boolean or a text, in TOML.

    Args:
        key: the dotted scene key. value: bool, int, float (or a numpy scalar of them) or str.

    Returns:
        The item, e.g. ``"impact.velocity=800.0"``.
    """
    import json
    import numbers

    import numpy as np

    if isinstance(value, (bool, np.bool_)):
        text = "true" if value else "false"
    elif isinstance(value, numbers.Integral):
        text = str(int(value))
    elif isinstance(value, numbers.Real):
        text = repr(float(value))  # nan and inf are TOML's words too
    elif isinstance(value, str):
        text = json.dumps(value)  # a TOML basic string
    else:
        raise TypeError(f"{key}: a scene value is a number, a boolean or a text, not {type(value).__name__}")
    return f"{key}={text}"


def toml_error(err: Exception, key: str, where: str) -> InputError:
    """The error of TOML tomllib could not read, naming ``key``: not TOML (TOMLDecodeError, text that is not
    UTF-8, an integer past Python's 4300 digits: a ValueError), or nested too deep for it to read (RecursionError:
    arrays or inline tables thousands deep).

    Args:
        err: the exception. key: the key the error names. where: the file or text, as the message says it.

    Returns:
        The InputError (to raise).
    """
    if isinstance(err, RecursionError):
        return InputError(key, f"{where} nests tables and arrays too deep to read, one inside another: a scene or "
                               f"sweep nests them at most {DEPTH_MAX} levels")
    return InputError(key, f"{where} is not valid TOML: {display_name(str(err), 200)}")


def read_toml(path: str | Path, key: str = "SCENE") -> dict[str, Any]:
    """Read a scene file into a flat {dotted key: value} dict, without validating the keys.

    Args:
        path: the TOML file: a regular file of at most SCENE_MAX bytes (read_capped).
        key: the key its errors name (a sweep's ``scene``).

    Returns:
        The flat dict.
    """
    p = Path(path)
    name = display_name(str(p), 200)
    data = read_capped(p, SCENE_MAX, key, "a scene file", missing=f"no such scene file: {name}")
    try:
        tree = tomllib.loads(data.decode())
    except (ValueError, RecursionError) as err:
        raise toml_error(err, key, name) from None
    check_nesting(tree, key, name, level=0)
    if any(k in tree for k in SWEEP_ONLY):  # before any of its keys is called unknown
        raise InputError(key, f"{name} is a sweep file: run it with `fepen sweep {name}`")
    return flatten(tree)
