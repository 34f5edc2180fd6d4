"""What a study's record (its folder's run.json, fepen.io.rundir) says of it: what its results are made of
(``inputs_of``: its shots' digest, fepen's version, the shipped data and the files its shots read, so that a
continued study refuses other inputs, naming them), and whether it failed (``failed``: none of its shots
finished)."""

from __future__ import annotations

from pathlib import Path

__all__ = ["inputs_of", "scene_files", "canonical_digest", "failed"]


def inputs_of(study, plan) -> dict:
    """What a study's results are made of, for its record (run.json "inputs"): the study's own digest (its
    shots' given keys, fepen.studies.study.Study.digest), fepen's version, every data file fepen ships
    (fepen.data.digests: the named targets, steels and explosives the shots resolve to) and every file the
    shots read (a drawn profile, a CAD body) by content; ``sha256`` of them all. A continued study refuses a
    folder whose inputs differ (fepen.io.rundir), naming what changed, before any shot runs.

    Returns:
        {"sha256", "study", "fepen", "data": {path: sha}, "files": {path: sha}}.
    """
    import hashlib
    import json

    from fepen import data
    from fepen.atomic import sha256_file
    from fepen.errors import InputError
    from fepen.version import __version__

    files = {}
    for key, path in scene_files(plan):
        try:
            files[path] = sha256_file(path)
        except OSError as err:
            raise InputError(key, f"cannot be read: {err.strerror or err} ({path})") from None
    parts = {"study": study.digest(plan), "fepen": __version__, "data": data.digests(), "files": files}
    blob = json.dumps(parts, sort_keys=True, default=str)
    return {"sha256": hashlib.sha256(blob.encode()).hexdigest()[:16], **parts}


def scene_files(plan) -> list[tuple[str, str]]:
    """(key, absolute path) of every file the plan's scenes name (fepen.runs.setup.FILE_KEYS: a drawn profile, a
    CAD body), found in its fields: Scenes, a sweep's spec (its base and shots), dicts and lists of them."""
    import os
    from dataclasses import fields, is_dataclass

    from fepen.runs.setup import FILE_KEYS
    from fepen.scene import Scene

    found: dict[str, str] = {}

    def given(values: dict) -> None:
        for k in FILE_KEYS:
            if isinstance(values.get(k), str) and values[k]:
                found.setdefault(os.path.abspath(values[k]), k)

    def visit(obj, depth: int = 0) -> None:
        if depth > 4:
            return
        if isinstance(obj, Scene):
            given({k: obj.get(k) for k in FILE_KEYS})
        elif isinstance(obj, dict):
            given(obj)
            for v in obj.values():
                if isinstance(v, (Scene, dict, list, tuple)) or is_dataclass(v):
                    visit(v, depth + 1)
        elif isinstance(obj, (list, tuple)):
            for v in obj[:1] if obj and not isinstance(obj[0], (Scene, dict)) else obj:
                visit(v, depth + 1)
        elif is_dataclass(obj) and not isinstance(obj, type):
            for f in fields(obj):
                visit(getattr(obj, f.name), depth + 1)

    visit(plan)
    return sorted((k, p) for p, k in found.items())


def canonical_digest(*parts) -> str:
    """A digest of a study's own inputs (its plan's scenes resolved, flat; numbers, texts, lists, dicts) for
    ``Study.digest``: the same inputs, the same 16 hex digits on any machine."""
    import hashlib
    import json

    from fepen.scene import Scene, flatten

    def plain(x):
        if isinstance(x, Scene):
            return flatten(x.as_dict())
        if hasattr(x, "__dataclass_fields__"):
            return {k: plain(getattr(x, k)) for k in x.__dataclass_fields__}
        if isinstance(x, dict):
            return {str(k): plain(v) for k, v in x.items()}
        if isinstance(x, (list, tuple)):
            return [plain(v) for v in x]
        return x

    def other(x):
        if isinstance(x, Path):
            return str(x)
        if hasattr(x, "item") and hasattr(x, "dtype"):  # a numpy scalar
            return x.item()
        raise TypeError(f"a study's digest holds plain values, not {type(x).__name__}")

    blob = json.dumps(plain(list(parts)), sort_keys=True, default=other)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def failed(records: list) -> Exception | None:
    """The error of a study none of whose shots finished (every one refused, stopped or failed), or None.

    Args:
        records: the rounds' records ({shot: record} each, fepen.studies.engine).

    Returns:
        InputError (exit 2) when the first failed shot was refused, SimulationError (3) when it stopped,
        MachineFault (4) when its process failed; its message names the counts and the first shot's reason.
    """
    from fepen.errors import InputError, MachineFault, SimulationError

    shots = [r for recs in records if isinstance(recs, dict) for r in recs.values()
             if isinstance(r, dict) and "status" in r]
    if not shots or any(r["status"] == "ok" for r in shots):
        return None
    first = min(shots, key=lambda r: r.get("shot", 0))
    counts = {}
    for r in shots:
        counts[r["status"]] = counts.get(r["status"], 0) + 1
    what = ", ".join(f"{n} {k}" for k, n in sorted(counts.items()))
    reason = first.get("message") or first["status"]
    message = f"no shot finished ({what}); shot {first.get('shot', 0)}: {reason}"
    if first["status"] == "bad-input":
        return InputError("study", message)
    if first["status"] == "stopped":
        return SimulationError(message)
    return MachineFault(message)
