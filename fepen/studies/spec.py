"""The sweep spec (docs/studies.md): a base scene and the keys to vary, read from a SWEEP.toml or a dict, checked
before any shot runs. Public: fepen sweep, the uncertainty study and any other study read the same file the same
way. Three ways to vary:

    scene = "../scenes/default.toml"      # the base scene (absent: the default scene), relative to this file
    [base]                                # scene keys over it, written as in a scene file
    effects.fidelity = "rigid"

    [grid]                                # every combination (the first key varies slowest)
    "impact.velocity" = [500.0, 600.0, 700.0]
    "impact.obliquity_deg" = { start = 0.0, stop = 30.0, num = 4 }

    [monte_carlo]                         # or: a seeded sample
    samples = 2000
    seed = 1
    latin_hypercube = false
    [monte_carlo.vary]                    # mean absent: the base scene's value
    "impact.velocity" = { distribution = "normal", std = 20.0 }
    "target.compressive_strength" = { distribution = "normal", std_percent = 10.0 }

    [table]                               # or: one shot per row of a CSV whose header names scene keys
    file = "shots.csv"

    [output]
    keep_results = false                  # each shot's results directory (deformable shots: always)
    digits = 6                            # significant digits of the numbers in sweep.csv

Every number of the spec is checked by a fepen.scene.keys.Key (a range's bounds, a distribution's parameters, the
counts), every varied key against the schema, and every shot's scene resolved (each distinct projectile built
once): bad input is one line naming the spec's key, or the shot and the scene key.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fepen import scene as fscene
from fepen.errors import InputError
from fepen.scene.keys import Key, check_nesting, display_name
from fepen.scene.resolve import given_twice, toml_error
from fepen.studies.monte_carlo import DISTRIBUTIONS, FINITE, POSITIVE, distribution, monte_carlo
from fepen.studies.shot_table import CELL_MAX, TABLE_MAX, check_key, read_table

__all__ = ["Spec", "read", "load", "sections", "base_keys", "flat_leaves", "distribution", "sample", "monte_carlo",
           "expand_shot", "keep_basis", "resized", "MAX_SHOTS", "TABLE_MAX", "CELL_MAX", "DISTRIBUTIONS", "IMPACT"]

MAX_SHOTS = 200_000
IMPACT = ("impact.velocity", "impact.obliquity_deg", "impact.attack_deg")


@dataclass
class Spec:
    """A sweep spec as read from its file.

    Attributes:
        kind: "grid", "monte-carlo" or "table".
        base: the base scene's given keys (flat, dotted).
        keys: the varied scene keys, in the file's order.
        shots: one {key: value} per shot, in shot order.
        keep_results: keep every shot's results directory.
        digits: significant digits of sweep.csv's numbers.
        spec: the sweep file's content (for sweep.json and the digest).
    """

    kind: str
    base: dict
    keys: list
    shots: list
    keep_results: bool = False
    digits: int = 6
    spec: dict = field(default_factory=dict)

    @property
    def digest(self) -> str:
        """A digest of the base and the shots: a results directory of another sweep is not resumed."""
        text = json.dumps([self.base, self.shots, self.keep_results], sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def scene(self, i: int) -> fscene.Scene:
        """The resolved scene of shot i (InputError naming the shot and the key)."""
        try:
            return fscene.Scene({**self.base, **self.shots[i]})
        except InputError as err:
            raise InputError(f"shot {i}: {err.key}", err.message) from None


def resized(path, samples: int, seed: int | None = None) -> str:
    """The text of a Monte Carlo sweep file with another sample size (and seed), its base scene made absolute:
    for tests and benchmarks of a shipped sweep file."""
    import re

    path = Path(path).resolve()
    text = path.read_text()
    text = re.sub(r"(?m)^scene = \"(.*)\"", lambda m: f'scene = "{(path.parent / m.group(1)).resolve()}"', text)
    text = re.sub(r"(?m)^samples = \d+", f"samples = {samples}", text)
    if seed is not None:
        text = re.sub(r"(?m)^seed = \d+", f"seed = {seed}", text)
    return text


def flat_leaves(tree: dict, is_leaf, prefix: str = "", where: str = "") -> dict:
    """{dotted key: leaf} of a TOML table whose keys may be quoted ("impact.velocity") or nested.

    Args:
        tree: the table ([grid], [monte_carlo.vary]). is_leaf: whether a table is a leaf (a range, a distribution)
            rather than a table of keys. prefix: put before every key (used by the recursion).
        where: the table's name, which the error of a key given twice starts with ("grid").

    Returns:
        The flat dict. InputError naming ``where.KEY`` for a key given twice (a quoted dotted key beside the
        same key in nested tables: TOML reads them as two keys).
    """
    out = {}
    for k, v in tree.items():
        name = f"{prefix}{k}"
        items = flat_leaves(v, is_leaf, name + ".", where).items() if isinstance(v, dict) and not is_leaf(v) else (
            (name, v),)
        for leaf, value in items:
            if leaf in out:
                raise InputError(f"{where}.{display_name(leaf)}" if where else display_name(leaf), given_twice(leaf))
            out[leaf] = value
    return out


#: the checks of the spec's own numbers, as the scene's keys are checked (fepen.scene.keys.Key)
COUNT = Key(int, None, lo=1, hi=100_000)
SAMPLES = Key(int, None, lo=1, hi=MAX_SHOTS)
SEED = Key(int, 0, lo=0)
FLAG = Key(bool, False)
DIGITS = Key(int, 6, lo=3, hi=17)


def _number(where: str, value, positive: bool = False) -> float:
    """A finite number (a positive one), checked as a scene key is: InputError naming ``where``."""
    return (POSITIVE if positive else FINITE).check(where, value)


def _grid_values(name: str, spec) -> list:
    where = f"grid.{name}"
    if isinstance(spec, list):
        if not spec:
            raise InputError(where, "an empty list: give at least one value")
        return list(spec)
    if isinstance(spec, dict):
        unknown = set(spec) - {"start", "stop", "num", "step"}
        if unknown or "start" not in spec or "stop" not in spec or ("num" in spec) == ("step" in spec):
            raise InputError(where, "a range is {start, stop, num} or {start, stop, step} (stop included)")
        a, b = _number(f"{where}.start", spec["start"]), _number(f"{where}.stop", spec["stop"])
        if "num" in spec:
            num = COUNT.check(f"{where}.num", spec["num"])
            return [float(x) for x in np.linspace(a, b, num)]
        step = _number(f"{where}.step", spec["step"], positive=True)
        num = int(math.floor(abs(b - a) / step + 1e-9)) + 1
        if num > 100000:
            raise InputError(f"{where}.step", f"gives {num} values; at most 100000")
        return [float(a + math.copysign(step, b - a) * i) for i in range(num)]
    raise InputError(where, f"a list of values or a range table {{start, stop, num}}, got {spec!r}")


def read(path, sets=()) -> Spec:
    """Read and check a sweep file; every shot's scene is resolved, so bad input stops here.

    Args:
        path: the SWEEP.toml, or its content as a dict (``{"base": {...}, "grid": {"impact.velocity": [...]}}``;
            a relative ``scene`` or table ``file`` is then taken from the working directory).
        sets: --set KEY=VALUE overrides of the base scene.

    Returns:
        The Spec.

    Raises:
        InputError: naming the sweep key (or the shot and the scene key) and what is allowed.
    """
    if isinstance(path, dict):
        spec, path = sections(dict(path), "the sweep"), Path.cwd() / "sweep.toml"
    else:
        path = Path(path)
        spec = load(path)
    kinds = [k for k in ("grid", "monte_carlo", "table") if k in spec]
    if len(kinds) != 1:
        raise InputError("SWEEP", "give exactly one of [grid], [monte_carlo] and [table]")
    base = base_keys(path, spec, sets)
    resolved = fscene.Scene(base)  # the base alone must be a valid scene
    kind = kinds[0]
    if kind == "grid":
        keys, shots = _grid(spec["grid"])
    elif kind == "monte_carlo":
        keys, shots = sample(spec["monte_carlo"], resolved)
    else:
        tab = spec["table"]
        if not isinstance(tab, dict) or not isinstance(tab.get("file"), str):
            raise InputError("table.file", "the CSV file of shots (a string)")
        keys, shots = read_table((path.parent / tab["file"]).resolve(), MAX_SHOTS)
    keep_basis(base, keys, resolved)
    if any(k in IMPACT for k in keys):
        base = expand_shot(base)
    keep, digits = _output(spec.get("output", {}))
    out = Spec(kind.replace("_", "-"), base, keys, shots, keep, digits, spec)
    check_shots(out)
    return out


def keep_basis(base: dict, keys, resolved) -> None:
    """A varied concrete strength keeps the base scene's basis (the default concrete's 40 MPa is a cube
    strength); given alone, each shot's value would be read as a cylinder strength (theory.md §8.1): the one
    place this is decided, for every study that varies it. ``base`` gains target.strength_basis when needed."""
    if ("target.compressive_strength" in keys and "target.strength_basis" not in base
            and "target.strength_basis" not in keys and not resolved.get("target.layers")):
        base["target.strength_basis"] = resolved.get("target.strength_basis")


def expand_shot(base: dict) -> dict:
    """The base with impact.shot replaced by its speed and angles, so that a varied key or a --set may change
    them (a new dict; the base as it is when it names no shot)."""
    if "impact.shot" not in base:
        return base
    resolved = fscene.Scene(base)
    out = {k: v for k, v in base.items() if k != "impact.shot"}
    for k in IMPACT:
        out.setdefault(k, resolved.get(k))
    return out


def load(path: Path) -> dict:
    """The sections of a sweep file, read and checked by name (:func:`sections`).

    Args:
        path: the SWEEP.toml: a regular file (not a pipe or a device, checked without blocking) of at most
            fepen.scene.SCENE_MAX bytes.

    Returns:
        The parsed file. InputError (SWEEP) when it cannot be read, is not TOML, or nests too deep.
    """
    import tomllib

    name = display_name(str(path), 200)
    data = fscene.read_capped(path, fscene.SCENE_MAX, "SWEEP", "a sweep file",
                              missing=f"cannot read {name}: no such file")
    try:
        spec = tomllib.loads(data.decode())
    except (ValueError, RecursionError) as err:  # TOMLDecodeError, not UTF-8; arrays nested thousands deep
        raise toml_error(err, "SWEEP", name) from None
    return sections(spec, name)


def sections(spec: dict, where: str) -> dict:
    """The sweep's sections, checked by name (InputError naming an unknown one) and by depth (SWEEP: tables
    and arrays nested at most fepen.scene.keys.DEPTH_MAX deep)."""
    check_nesting(spec, "SWEEP", where, level=0)
    known = {"scene", "base", "grid", "monte_carlo", "table", "output"}
    for k in spec:
        if k not in known:
            raise InputError(k, f"not a sweep section of {where}; allowed: {', '.join(sorted(known))}")
    return spec


def base_keys(path: Path, spec: dict, sets) -> dict:
    """The base scene's given keys: the scene file, then [base], then --set."""
    base = {}
    if "scene" in spec:
        if not isinstance(spec["scene"], str):
            raise InputError("scene", "the base scene's file name (a string)")
        scene_path = (path.parent / spec["scene"]).resolve()
        base.update(fscene.read_toml(scene_path, key="scene"))
    if "base" in spec:
        if not isinstance(spec["base"], dict):
            raise InputError("base", "a table of scene keys")
        base.update(fscene.flatten(spec["base"]))
    for item in sets:
        k, v = fscene.parse_set(item)
        base[k] = v
    for k in base:
        if k not in fscene.SCHEMA:
            raise fscene.unknown_key(k)
    return base


def _grid(grid) -> tuple[list, list]:
    if not isinstance(grid, dict) or not grid:
        raise InputError("grid", "a table of scene keys, each with a list or a range")
    values = flat_leaves(grid, lambda d: "start" in d, where="grid")
    for k in values:
        check_key("grid", k)
    values = {k: _grid_values(k, v) for k, v in values.items()}
    keys = list(values)
    count = math.prod(len(v) for v in values.values())
    if count > MAX_SHOTS:
        sizes = " x ".join(f"{len(v)} ({k})" for k, v in values.items())
        raise InputError("grid", f"{sizes} = {count} shots; a sweep holds at most {MAX_SHOTS}: split it into several "
                                 "sweeps, or use [monte_carlo]")
    return keys, [dict(zip(keys, combo)) for combo in _product([values[k] for k in keys])]


def sample(mc, resolved) -> tuple[list, list]:
    """(keys, shots) of a [monte_carlo] table: its checked distributions drawn (monte_carlo), each key's mean
    the resolved base scene's value unless given."""
    allowed = {"samples", "seed", "latin_hypercube", "vary"}
    for k in mc:
        if k not in allowed:
            raise InputError(f"monte_carlo.{k}", f"not a key of [monte_carlo]; allowed: {', '.join(sorted(allowed))}")
    if "samples" not in mc:
        raise InputError("monte_carlo.samples", f"required: an integer in [1, {MAX_SHOTS}]")
    n = SAMPLES.check("monte_carlo.samples", mc["samples"])  # a larger study: several sweeps of other seeds
    seed = SEED.check("monte_carlo.seed", mc.get("seed", 0))
    lhs = FLAG.check("monte_carlo.latin_hypercube", mc.get("latin_hypercube", False))
    vary = mc.get("vary")
    if not isinstance(vary, dict) or not vary:
        raise InputError("monte_carlo.vary", "a table of scene keys, each with its distribution")
    specs = flat_leaves(vary, lambda d: "distribution" in d, where="monte_carlo.vary")
    for k in specs:
        check_key("monte_carlo.vary", k)
    dists = {k: distribution(k, v, resolved.get(k)) for k, v in specs.items()}
    return list(dists), monte_carlo(dists, n, seed, lhs)


def _output(output) -> tuple[bool, int]:
    if not isinstance(output, dict) or set(output) - {"keep_results", "digits"}:
        raise InputError("output", "a table of keep_results (true or false) and digits (3 to 17)")
    keep = FLAG.check("output.keep_results", output.get("keep_results", False))
    digits = DIGITS.check("output.digits", output.get("digits", 6))
    return keep, digits


def _product(lists):
    if not lists:
        yield ()
        return
    for v in lists[0]:
        for rest in _product(lists[1:]):
            yield (v, *rest)


def check_shots(spec: Spec) -> None:
    """Resolve every shot's scene and build each distinct projectile once: bad input before any shot runs."""
    from fepen.runs import setup, targets

    seen = set()
    for i in range(len(spec.shots)):
        sc = spec.scene(i)
        try:
            key = setup.body_key(sc)
            if key not in seen:
                seen.add(key)
                setup.check_supported(sc)  # builds the projectile: once per distinct one
            else:
                targets.of(sc).check(sc)  # the target's own checks, shot by shot
        except InputError as err:
            raise InputError(f"shot {i}: {err.key}", err.message) from None
