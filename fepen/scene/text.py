"""A resolved scene as TOML text (:func:`to_toml`): what a run writes into its results directory as scene.toml,
and what resolution measures to hold it within the size it is read back with (fepen.scene.resolve)."""

from __future__ import annotations

__all__ = ["to_toml"]


def to_toml(scene) -> str:
    """The resolved scene as TOML text (every key, SI units), for results directories: the keys the user gave
    as values, the others (defaults, a named material's constants, what resolution derived) as comments, so
    that the text resolves to the same scene with the same given keys (``fepen run --resume``, api.load): the
    mass rule, a drawn or CAD body and a layer's own crater depend on which keys were given.

    Args:
        scene: a resolved Scene (a Section without ``explicit``: every key as a value).

    Returns:
        The TOML text.
    """
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
    """A value in TOML syntax (strings escaped as TOML's basic strings want).

    Args:
        v: a bool, str, int, float or a list of them.

    Returns:
        The TOML text of the value.
    """
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + "".join(f"\\{c}" if c in '"\\' else f"\\u{ord(c):04x}" if ord(c) < 0x20 or ord(c) == 0x7F
                             else c for c in v) + '"'
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return repr(v)
