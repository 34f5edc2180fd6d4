"""Scenes: one TOML file in, typed and validated settings with every default filled in (docs/scenes.md).

The key names are the public interface of fepen. Every key is declared once in ``SCHEMA`` with its type,
default, unit and allowed range; nothing else is accepted. Bad input raises :class:`fepen.errors.InputError`
naming the key and what is allowed, before any solver work starts.

The package, bottom up: ``keys`` (the Key type and the checks of one value), ``schema`` (SCHEMA), ``reading``
(TOML, dicts and --set in), ``checks`` (the checks across keys), ``resolve`` (the named shot, steel and target
material; Scene), ``text`` (to_toml) and ``writing`` (the key table). Import from ``fepen.scene``: the names
below are its interface.
"""

from fepen.scene.keys import ABSENT, Key, display_name
from fepen.scene.resolve import (
    CAD_EXCLUDES,
    CHECKS_AFTER_RESOLUTION,
    CROSS_CHECKS,
    FILE_KEYS,
    SCENE_MAX,
    Scene,
    Section,
    cross_check,
    flatten,
    load,
    parse_set,
    read_capped,
    read_toml,
    registered_checks,
    resolve,
    set_item,
    unknown_key,
)
from fepen.scene.schema import LAYER_FIELDS, LAYER_KEYS, SCHEMA, SECTIONS
from fepen.scene.writing import describe, to_toml

__all__ = ["keys", "schema", "reading", "checks", "text", "writing", "Scene", "Section", "load", "resolve", "read_toml",
           "parse_set",
           "set_item", "flatten",
           "unknown_key", "to_toml", "describe", "SCHEMA", "SECTIONS", "LAYER_KEYS", "LAYER_FIELDS", "Key",
           "ABSENT", "display_name", "read_capped", "SCENE_MAX", "FILE_KEYS",
           "CROSS_CHECKS", "CHECKS_AFTER_RESOLUTION", "CAD_EXCLUDES", "cross_check", "registered_checks"]
