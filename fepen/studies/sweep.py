"""``fepen sweep SWEEP.toml``: many shots of one base scene with some keys varied (docs/studies.md).

A sweep file names a base scene and the keys to vary, in one of three ways:

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
    "impact.obliquity_deg" = { distribution = "truncated-normal", std = 1.0, low = 0.0 }
    "target.compressive_strength" = { distribution = "normal", std_percent = 10.0 }

    [table]                               # or: one shot per row of a CSV whose header names scene keys
    file = "shots.csv"

    [output]
    keep_results = false                  # each shot's results directory (deformable shots: always)
    digits = 6                            # significant digits of the numbers in sweep.csv

Writes to OUT: sweep.json (the sweep as run), shots.jsonl (one record per finished shot, appended as each
ends: what makes a killed sweep resumable), sweep.csv (one row per shot: the varied keys and every summary
figure; sweep.parquet too when pyarrow is installed), costs.csv (wall time and ranks per shot), sweep.md and
figures. The shots run on fepen.studies.engine (MPI groups taking shots from a shared queue).
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fepen import scene as fscene
from fepen.errors import InputError

__all__ = ["Sweep", "read", "run", "table_rows", "resized", "DISTRIBUTIONS"]

#: the most shots of one sweep: each shot's record is held in memory (about 5 kB), and every shot's scene is
#: checked before the first runs; a larger study is several sweeps (another seed, or part of the grid each)
MAX_SHOTS = 200_000
#: the largest table of shots read (bytes)
TABLE_MAX = 64 << 20
#: distribution name: its parameters (mean absent: the base scene's value)
DISTRIBUTIONS = {"normal": ("mean", "std"), "uniform": ("low", "high"),
                 "truncated-normal": ("mean", "std", "low", "high")}
#: summary entries that describe the machine or the run's cost, not the shot (costs.csv holds some)
MACHINE = ("wall_s", "time_split_s", "peak_memory_bytes", "ranks", "scene", "versions")
IMPACT = ("impact.velocity", "impact.obliquity_deg", "impact.attack_deg")


@dataclass
class Sweep:
    """A sweep as read from its file.

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


def _flat_leaves(tree: dict, is_leaf, prefix: str = "") -> dict:
    """{dotted key: leaf} of a TOML table whose keys may be quoted ("impact.velocity") or nested."""
    out = {}
    for k, v in tree.items():
        name = f"{prefix}{k}"
        if isinstance(v, dict) and not is_leaf(v):
            out.update(_flat_leaves(v, is_leaf, name + "."))
        else:
            out[name] = v
    return out


def _check_key(section: str, name: str) -> None:
    if name not in fscene.SCHEMA:
        err = fscene.unknown_key(name)
        raise InputError(f"{section}.{name}", f"not a scene key ({err.message})")


def _number(where: str, value, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise InputError(where, f"must be a finite number, got {value!r}")
    if positive and value <= 0:
        raise InputError(where, f"must be > 0, got {value!r}")
    return float(value)


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
            num = spec["num"]
            if isinstance(num, bool) or not isinstance(num, int) or not 1 <= num <= 100000:
                raise InputError(f"{where}.num", f"must be an integer in [1, 100000], got {num!r}")
            return [float(x) for x in np.linspace(a, b, num)]
        step = _number(f"{where}.step", spec["step"], positive=True)
        num = int(math.floor(abs(b - a) / step + 1e-9)) + 1
        if num > 100000:
            raise InputError(f"{where}.step", f"gives {num} values; at most 100000")
        return [float(a + math.copysign(step, b - a) * i) for i in range(num)]
    raise InputError(where, f"a list of values or a range table {{start, stop, num}}, got {spec!r}")


def _distribution(name: str, spec, base_value) -> tuple:
    """(kind, parameters) of one Monte Carlo key, checked."""
    where = f"monte_carlo.vary.{name}"
    if not isinstance(spec, dict) or spec.get("distribution") not in DISTRIBUTIONS:
        raise InputError(f"{where}.distribution", f"one of {', '.join(map(repr, DISTRIBUTIONS))}")
    kind = spec["distribution"]
    allowed = {"distribution", *DISTRIBUTIONS[kind], *(("std_percent",) if "std" in DISTRIBUTIONS[kind] else ())}
    unknown = sorted(set(spec) - allowed)
    if unknown:
        raise InputError(f"{where}.{unknown[0]}", f"not a parameter of {kind!r}; allowed: {', '.join(sorted(allowed))}")
    p = {}
    if kind == "uniform":
        for k in ("low", "high"):
            if k not in spec:
                raise InputError(f"{where}.{k}", "required by 'uniform'")
            p[k] = _number(f"{where}.{k}", spec[k])
        if not p["low"] < p["high"]:
            raise InputError(f"{where}.high", f"must be above low = {p['low']:g}")
        return kind, p
    mean = spec.get("mean", base_value)
    if mean is None:
        raise InputError(f"{where}.mean", "required: the base scene gives this key no value")
    p["mean"] = _number(f"{where}.mean", mean)
    if ("std" in spec) == ("std_percent" in spec):
        raise InputError(f"{where}.std", "give one of std (in the key's unit) and std_percent (of the mean)")
    p["std"] = (_number(f"{where}.std", spec["std"], positive=True) if "std" in spec
                else abs(p["mean"]) * _number(f"{where}.std_percent", spec["std_percent"], positive=True) / 100)
    if kind == "truncated-normal":
        p["low"] = _number(f"{where}.low", spec.get("low", -math.inf)) if "low" in spec else -math.inf
        p["high"] = _number(f"{where}.high", spec["high"]) if "high" in spec else math.inf
        if not p["low"] < p["high"]:
            raise InputError(f"{where}.high", f"must be above low = {p['low']:g}")
    return kind, p


def _quantile(kind: str, p: dict, u: np.ndarray) -> np.ndarray:
    """The distribution's values at probabilities u (inverse CDF: the same u gives the same value)."""
    from scipy.special import ndtr, ndtri

    if kind == "uniform":
        return p["low"] + (p["high"] - p["low"]) * u
    if kind == "normal":
        return p["mean"] + p["std"] * ndtri(u)
    a, b = ndtr((p["low"] - p["mean"]) / p["std"]), ndtr((p["high"] - p["mean"]) / p["std"])
    return p["mean"] + p["std"] * ndtri(a + u * (b - a))


def monte_carlo(distributions: dict, samples: int, seed: int, latin_hypercube: bool) -> list[dict]:
    """The sample: one {key: value} per shot, from numpy's default_rng(seed), keys in the given order.

    Args:
        distributions: {key: (kind, parameters)} (_distribution).
        samples: number of shots. seed: the generator's seed.
        latin_hypercube: stratify each key's probabilities into `samples` equal bins, in a random order.

    Returns:
        The shots' values.
    """
    rng = np.random.default_rng(seed)
    keys = list(distributions)
    if latin_hypercube:
        u = np.stack([(rng.permutation(samples) + rng.random(samples)) / samples for _ in keys], axis=1)
    else:
        u = rng.random((samples, len(keys)))
    u = np.clip(u, 1e-12, 1.0 - 1e-12)
    cols = [_quantile(*distributions[k], u[:, j]) for j, k in enumerate(keys)]
    return [{k: float(cols[j][i]) for j, k in enumerate(keys)} for i in range(samples)]


def _read_table(path: Path) -> tuple[list, list]:
    """Keys and shots of a CSV table (header: scene keys; values in TOML syntax, bare words strings)."""
    try:
        text = fscene.read_capped(path, TABLE_MAX, "table.file", "a table of shots").decode()
    except UnicodeDecodeError:
        raise InputError("table.file", f"{path} is not UTF-8 text") from None
    rows = list(csv.reader(io.StringIO(text)))
    rows = [r for r in rows if r and not r[0].lstrip().startswith("#")]
    if len(rows) < 2:
        raise InputError("table.file", f"{path} needs a header of scene keys and at least one row")
    if len(rows) - 1 > MAX_SHOTS:
        raise InputError("table.file", f"{path} holds {len(rows) - 1} shots; a sweep holds at most {MAX_SHOTS}")
    keys = [k.strip() for k in rows[0]]
    for k in keys:
        _check_key("table.file", k)
    shots = []
    for n, r in enumerate(rows[1:], start=2):
        if len(r) != len(keys):
            raise InputError("table.file", f"{path} line {n}: {len(r)} values for {len(keys)} keys")
        shots.append({k: fscene.parse_set(f"{k}={v.strip()}")[1] for k, v in zip(keys, r)})
    return keys, shots


def read(path, sets=()) -> Sweep:
    """Read and check a sweep file; every shot's scene is resolved, so bad input stops here.

    Args:
        path: the SWEEP.toml, or its content as a dict (``{"base": {...}, "grid": {"impact.velocity": [...]}}``;
            a relative ``scene`` or table ``file`` is then taken from the working directory).
        sets: --set KEY=VALUE overrides of the base scene.

    Returns:
        The Sweep.

    Raises:
        InputError: naming the sweep key (or the shot and the scene key) and what is allowed.
    """
    if isinstance(path, dict):
        spec, path = _sections(dict(path), "the sweep"), Path.cwd() / "sweep.toml"
    else:
        path = Path(path)
        spec = _load(path)
    kinds = [k for k in ("grid", "monte_carlo", "table") if k in spec]
    if len(kinds) != 1:
        raise InputError("SWEEP", "give exactly one of [grid], [monte_carlo] and [table]")
    base = _base_keys(path, spec, sets)
    resolved = fscene.Scene(base)  # the base alone must be a valid scene
    kind = kinds[0]
    if kind == "grid":
        keys, shots = _grid(spec["grid"])
    elif kind == "monte_carlo":
        keys, shots = _monte_carlo(spec["monte_carlo"], resolved)
    else:
        tab = spec["table"]
        if not isinstance(tab, dict) or not isinstance(tab.get("file"), str):
            raise InputError("table.file", "the CSV file of shots (a string)")
        keys, shots = _read_table((path.parent / tab["file"]).resolve())
    if ("target.compressive_strength" in keys and "target.strength_basis" not in base
            and "target.strength_basis" not in keys and resolved.get("target.layers") is None):
        # a varied strength is on the base scene's basis (the default concrete's 40 MPa is a cube strength);
        # given alone, each shot's value would be read as a cylinder strength (theory.md §8.1)
        base["target.strength_basis"] = resolved.get("target.strength_basis")
    if any(k in IMPACT for k in keys) and "impact.shot" in base:
        # the shot's three impact values become plain keys, so that the varied ones may replace them
        del base["impact.shot"]
        for k in IMPACT:
            base.setdefault(k, resolved.get(k))
    keep, digits = _output(spec.get("output", {}))
    sweep = Sweep(kind.replace("_", "-"), base, keys, shots, keep, digits, spec)
    _check_shots(sweep)
    return sweep


def _load(path: Path) -> dict:
    import tomllib

    if not path.is_file():
        raise InputError("SWEEP", f"cannot read {fscene.display_name(str(path), 200)}: no such file")
    data = fscene.read_capped(path, fscene.SCENE_MAX, "SWEEP", "a sweep file")
    try:
        spec = tomllib.loads(data.decode())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
        raise InputError("SWEEP", f"{path} is not valid TOML: {err}") from None
    return _sections(spec, str(path))


def _sections(spec: dict, where: str) -> dict:
    """The sweep's sections, checked by name (InputError naming an unknown one)."""
    known = {"scene", "base", "grid", "monte_carlo", "table", "output"}
    for k in spec:
        if k not in known:
            raise InputError(k, f"not a sweep section of {where}; allowed: {', '.join(sorted(known))}")
    return spec


def _base_keys(path: Path, spec: dict, sets) -> dict:
    """The base scene's given keys: the scene file, then [base], then --set."""
    base = {}
    if "scene" in spec:
        if not isinstance(spec["scene"], str):
            raise InputError("scene", "the base scene's file name (a string)")
        scene_path = (path.parent / spec["scene"]).resolve()
        if not scene_path.is_file():
            raise InputError("scene", f"no such file: {scene_path}")
        base.update(fscene.read_toml(scene_path))
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
    values = _flat_leaves(grid, lambda d: "start" in d)
    for k in values:
        _check_key("grid", k)
    values = {k: _grid_values(k, v) for k, v in values.items()}
    keys = list(values)
    count = math.prod(len(v) for v in values.values())
    if count > MAX_SHOTS:
        sizes = " x ".join(f"{len(v)} ({k})" for k, v in values.items())
        raise InputError("grid", f"{sizes} = {count} shots; a sweep holds at most {MAX_SHOTS}: split it into several "
                                 "sweeps, or use [monte_carlo]")
    return keys, [dict(zip(keys, combo)) for combo in _product([values[k] for k in keys])]


def _monte_carlo(mc, resolved) -> tuple[list, list]:
    allowed = {"samples", "seed", "latin_hypercube", "vary"}
    for k in mc:
        if k not in allowed:
            raise InputError(f"monte_carlo.{k}", f"not a key of [monte_carlo]; allowed: {', '.join(sorted(allowed))}")
    n = mc.get("samples")
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_SHOTS:
        raise InputError("monte_carlo.samples", f"an integer in [1, {MAX_SHOTS}] (split a larger study into sweeps of "
                                                f"other seeds), got {fscene.display_name(repr(n), 40)}")
    seed = mc.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise InputError("monte_carlo.seed", f"a non-negative integer, got {seed!r}")
    lhs = mc.get("latin_hypercube", False)
    if not isinstance(lhs, bool):
        raise InputError("monte_carlo.latin_hypercube", f"true or false, got {lhs!r}")
    vary = mc.get("vary")
    if not isinstance(vary, dict) or not vary:
        raise InputError("monte_carlo.vary", "a table of scene keys, each with its distribution")
    specs = _flat_leaves(vary, lambda d: "distribution" in d)
    for k in specs:
        _check_key("monte_carlo.vary", k)
    dists = {k: _distribution(k, v, resolved.get(k)) for k, v in specs.items()}
    return list(dists), monte_carlo(dists, n, seed, lhs)


def _output(output) -> tuple[bool, int]:
    if not isinstance(output, dict) or set(output) - {"keep_results", "digits"}:
        raise InputError("output", "a table of keep_results (true or false) and digits (3 to 17)")
    keep = output.get("keep_results", False)
    if not isinstance(keep, bool):
        raise InputError("output.keep_results", f"true or false, got {keep!r}")
    digits = output.get("digits", 6)
    if isinstance(digits, bool) or not isinstance(digits, int) or not 3 <= digits <= 17:
        raise InputError("output.digits", f"an integer in [3, 17], got {digits!r}")
    return keep, digits


def _product(lists):
    if not lists:
        yield ()
        return
    for v in lists[0]:
        for rest in _product(lists[1:]):
            yield (v, *rest)


def _check_shots(sweep: Sweep) -> None:
    """Resolve every shot's scene and build each distinct projectile once: bad input before any shot runs."""
    from fepen.runs import setup

    seen = set()
    for i in range(len(sweep.shots)):
        sc = sweep.scene(i)
        try:
            key = setup.body_key(sc)
            if key not in seen or (sc.effects.fidelity == "rigid" and sc.target.kind != "concrete"):
                seen.add(key)
                setup.check_supported(sc)  # builds the projectile: once per distinct one
        except InputError as err:
            raise InputError(f"shot {i}: {err.key}", err.message) from None


# -------------------------------------------------------------------------------------------------- table
#: the summary's words that the sweep table leaves to each shot's summary.json (the same on every row)
WORDS = ("envelope.law", "envelope.checked_on", "envelope.line", "interval.depth", "interval.lateral")


def _flatten_summary(summary: dict) -> dict:
    out = {}
    for k, v in summary.items():
        if k in MACHINE:
            continue
        if k.endswith("_interval_mm"):  # [low, high] (or null): two columns
            low, high = v if v is not None else (None, None)
            out[f"{k}.low"], out[f"{k}.high"] = low, high
        elif isinstance(v, dict):
            for k2, v2 in v.items():
                if not isinstance(v2, (dict, list)) and f"{k}.{k2}" not in WORDS:
                    out[f"{k}.{k2}"] = v2
        elif not isinstance(v, list) and v is not None:
            out[k] = v
    return out


def table_rows(sweep: Sweep, records: dict) -> tuple[list, list]:
    """(columns, rows) of sweep.csv: shot, the varied keys, status, then every summary figure.

    Args:
        sweep: the Sweep. records: {shot index: record} (fepen.studies.engine).
    """
    cols = ["shot", *sweep.keys, "status", "message"]
    rows = []
    for i in sorted(records):
        r = records[i]
        row = {"shot": i, **{k: sweep.shots[i][k] for k in sweep.keys}, "status": r["status"],
               "message": r.get("message", "")}
        for k, v in _flatten_summary(r.get("summary") or {}).items():
            if k not in cols:
                cols.append(k)
            row[k] = v
        rows.append(row)
    return cols, rows


def _fmt(v, digits: int) -> str:
    if isinstance(v, bool):
        return str(v).lower()
    if isinstance(v, float):
        return f"{v:.{digits}g}"
    return "" if v is None else str(v)


def write_table(sweep: Sweep, records: dict, out: Path, say=None) -> tuple[list, list]:
    """sweep.csv (and sweep.parquet with pyarrow: the extra ``parquet``) and costs.csv; (columns, rows).

    Args:
        sweep: the sweep. records: {shot: record}. out: the results directory.
        say: prints the one line saying why sweep.parquet was not written (pyarrow absent, or failing to import,
            as a release built for numpy 2 does beside numpy 1.24), or None.
    """
    from fepen.atomic import replacing

    cols, rows = table_rows(sweep, records)
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(cols)
    for r in rows:
        w.writerow([_fmt(r.get(c), sweep.digits) for c in cols])
    with replacing(out / "sweep.csv", ".csv") as tmp:
        tmp.write_text(buf.getvalue())
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["shot", "wall_s", "ranks"])
    for i in sorted(records):
        w.writerow([i, f"{records[i].get('wall_s', float('nan')):.4g}", records[i].get("ranks", "")])
    with replacing(out / "costs.csv", ".csv") as tmp:
        tmp.write_text(buf.getvalue())
    why = parquet_unavailable()
    if why is None:
        import pyarrow as pa
        import pyarrow.parquet as pq

        with replacing(out / "sweep.parquet", ".parquet") as tmp:
            pq.write_table(pa.table({c: [r.get(c) for r in rows] for c in cols}), str(tmp))
    elif say is not None:
        say(f"sweep.parquet not written: {why}")
    return cols, rows


def parquet_unavailable() -> str | None:
    """Why sweep.parquet cannot be written here (one line), or None when pyarrow imports."""
    try:
        import pyarrow  # noqa: F401
        import pyarrow.parquet  # noqa: F401
    except ModuleNotFoundError:
        return "pyarrow is not installed (pip install 'fepen[parquet]': a pyarrow that works with numpy 1.24)"
    except Exception as err:  # noqa: BLE001 - an ImportError of a build for numpy 2, or anything it raises
        text = " ".join(str(err).split()) or type(err).__name__
        return f"pyarrow failed to import ({text}); pip install 'pyarrow>=14,<26' (the extra 'parquet')"
    return None


# -------------------------------------------------------------------------------------------------- run
def run(path, out, comm=None, ranks_per_shot: int = 1, sets=(), fresh: bool = False, say=print,
        progress: bool = True) -> dict:
    """Read the sweep, run its missing shots on fepen.studies.engine, write the table, summary and figures.

    Args:
        path: the SWEEP.toml, or its content as a dict (read). out: the results directory.
        comm: the communicator (None: COMM_WORLD).
        ranks_per_shot: ranks of each shot's group. sets: --set overrides of the base scene.
        fresh: run every shot again (the records in OUT are discarded).
        say: prints one line (rank 0).
        progress: the bar of shots done over the total (rank 0, stderr; fepen.studies.engine.bar_disabled).

    Returns:
        {"shots", "ran", "skipped", "wall_s", "statuses"} (every rank).
    """
    import time

    from mpi4py import MPI

    from fepen.io import rundir
    from fepen.studies import engine

    comm = MPI.COMM_WORLD if comm is None else comm
    t0 = time.perf_counter()
    sweep = read(path, sets)
    out = Path(out)
    err = comm.bcast(engine.check_directory(out, sweep.digest, fresh) if comm.rank == 0 else None, root=0)
    if err:
        raise InputError(*err)
    with rundir.study_directory(out, comm, fresh, "sweep", SWEEP_NAMES):
        return _run(sweep, path, out, comm, ranks_per_shot, say, progress, t0)


#: what a sweep writes into its folder (fepen.io.rundir.study_directory)
SWEEP_NAMES = ("sweep.json", "shots.jsonl", "shots", "sweep.csv", "costs.csv", "sweep.parquet", "sweep.md", "sweep.png",
               "histograms.png")


def _run(sweep: Sweep, path, out: Path, comm, ranks_per_shot: int, say, progress: bool, t0: float) -> dict:
    """run's body, in the sweep's claimed folder."""
    import time

    from mpi4py import MPI

    from fepen.io import files
    from fepen.studies import engine

    out = files.prepare(out, comm)
    if comm.rank == 0:
        source = None if isinstance(path, dict) else str(Path(path).resolve())  # None: given as a dict
        files.write_json(out / "sweep.json", {"file": source, "digest": sweep.digest,
                                              "kind": sweep.kind, "keys": sweep.keys, "shots": len(sweep.shots),
                                              "base": sweep.base, "spec": sweep.spec}, MPI.COMM_SELF)
    keep = sweep.keep_results
    rigid = sweep.base.get("effects.fidelity") == "rigid" and "effects.fidelity" not in sweep.keys and not keep
    records, ran = engine.execute(len(sweep.shots), sweep.scene, out, comm, ranks_per_shot,
                                  keep=lambda sc: keep or sc.effects.fidelity != "rigid", say=say,
                                  batch=engine.BATCH if rigid else 1,  # rigid shots in batches
                                  progress=progress)
    wall = time.perf_counter() - t0
    statuses = {}
    if comm.rank == 0:
        for r in records.values():
            statuses[r["status"]] = statuses.get(r["status"], 0) + 1
        cols, rows = write_table(sweep, records, out, say)
        from fepen.studies import sweep_figures

        sweep_figures.write(sweep, cols, rows, out)
        files.write_text(out / "sweep.md", sweep_figures.report(sweep, rows, wall, ran, comm.size,
                                                                ranks_per_shot), MPI.COMM_SELF)
    statuses = comm.bcast(statuses, root=0)
    return {"shots": len(sweep.shots), "ran": ran, "skipped": len(sweep.shots) - ran, "wall_s": wall,
            "statuses": statuses}
