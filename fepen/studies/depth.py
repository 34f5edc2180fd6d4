"""Depth of penetration against published tests (docs/validation-depth.md): data sets of normal (or
oblique) shots read from CSV, each predicted by the rigid fidelity (no mesh: a fraction of a second a
shot) and by Forrestal's closed form, with the errors per set, a table and a predicted-against-measured
figure.

A data set is one CSV file, one shot a row, with the columns (units in the names):

    shot, d_mm, m_kg, crh, L_mm, v_ms, fc_mpa, rho_kgm3, depth_m

and optionally ``obliquity_deg``, ``attack_deg`` (absent: 0), ``strength_basis`` (``cylinder`` or ``cube``:
what f_c was measured on; absent or empty: cylinder), and ``source``, ``compilation_row`` and ``notes`` (kept,
not read). The shipped sets are in ``fepen/data/depth/`` (their provenance: SOURCES.md there); ``table1`` is
the paper's eight shots (docs/paper.md).
"""

from __future__ import annotations

import csv
import functools
import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from fepen.data import SHOTS
from fepen.laws import target as tg
from fepen.studies.products import Picture, Table
from fepen.studies.study import Round, Study, register

__all__ = ["Row", "read_set", "table1_set", "shipped_sets", "scene_sets", "rigid_depth", "closed_form_depth",
           "errors", "shot_scenes", "predictions", "predict_sets", "gather_sets", "summary_table",
           "interval_coverage", "markdown", "ValidateDepth", "validate_depth",
           "COLUMNS", "STRENGTH_BASES", "METHODS", "DEPTH_CSV"]

COLUMNS = ("shot", "d_mm", "m_kg", "crh", "L_mm", "v_ms", "fc_mpa", "rho_kgm3", "depth_m")
#: what a set's f_c can have been measured on (column ``strength_basis``; absent or empty: the first)
STRENGTH_BASES = tg.STRENGTH_BASES


@dataclass(frozen=True)
class Row:
    """One shot of a depth data set (SI units).

    Attributes:
        name: the shot's label. D, L, mass, crh: projectile diameter, length (m), mass (kg), ogive CRH.
        V: striking speed (m/s). fc, rho: target strength (Pa) and density (kg/m^3). depth: measured
        depth of the nose (m). obliquity_deg, attack_deg: striking angles (degrees). strength_basis: what fc
        was measured on, "cylinder" or "cube" (STRENGTH_BASES); fc is kept as published, not converted.
    """

    name: str
    D: float
    L: float
    mass: float
    crh: float
    V: float
    fc: float
    rho: float
    depth: float
    obliquity_deg: float = 0.0
    attack_deg: float = 0.0
    strength_basis: str = "cylinder"

    @functools.cached_property
    def fc_cylinder(self) -> float:
        """fc on the cylinder basis the law takes (Pa): a cube strength converted once
        (fepen.laws.target.cylinder_strength)."""
        return tg.cylinder_strength(self.fc, self.strength_basis)


def read_set(path) -> list[Row]:
    """The rows of one CSV data set (columns: COLUMNS, optionally obliquity_deg, attack_deg and
    strength_basis; any other column, e.g. source, compilation_row, notes, is kept in the file and not read).

    Raises:
        ValueError naming the file, row and column of a missing or non-numeric value, or a strength_basis
        not in STRENGTH_BASES.
    """
    path = Path(path)
    rows = []
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        missing = [c for c in COLUMNS if c not in (reader.fieldnames or [])]
        if missing:
            raise ValueError(f"{path}: missing columns {', '.join(missing)} (needs {', '.join(COLUMNS)})")
        for i, r in enumerate(reader, start=2):
            try:
                num = {c: float(r[c]) for c in COLUMNS[1:]}
                basis = (r.get("strength_basis") or "").strip() or STRENGTH_BASES[0]
                if basis not in STRENGTH_BASES:
                    raise ValueError(f"strength_basis {basis!r}: must be one of {', '.join(STRENGTH_BASES)}")
                rows.append(Row(r["shot"], num["d_mm"] / 1e3, num["L_mm"] / 1e3, num["m_kg"], num["crh"],
                                num["v_ms"], num["fc_mpa"] * 1e6, num["rho_kgm3"], num["depth_m"],
                                float(r.get("obliquity_deg") or 0.0), float(r.get("attack_deg") or 0.0), basis))
            except (TypeError, ValueError) as err:
                raise ValueError(f"{path}:{i}: {err}") from None
    return rows


def table1_set() -> list[Row]:
    """The paper's eight shots (Table 1) with its projectile and target (docs/paper.md; its 40 MPa is the C40
    grade, a cube strength, docs/theory.md §8.1): depth = Hy."""
    return [Row(s.name, 0.0236, 0.144, 0.367, 3.0, s.v0, 40e6, 2400.0, s.Hy_mm / 1e3, s.obliquity_deg,
                s.attack_deg, "cube") for s in SHOTS.values()]


def shipped_sets() -> dict[str, Path]:
    """The data sets shipped with fepen (fepen/data/depth/*.csv), by name."""
    base = Path(str(resources.files("fepen").joinpath("data/depth")))
    return {p.stem: p for p in sorted(base.glob("*.csv"))} if base.is_dir() else {}


def scene_sets(row: Row) -> list[str]:
    """The --set lines of a rigid scene for one shot: the projectile's outside and mass, the target's
    strength and density only (everything else from fepen's defaults), the striking conditions."""
    from fepen.scene import set_item

    return ["effects.fidelity=rigid", *(set_item(k, v) for k, v in (
        ("projectile.diameter", row.D), ("projectile.length", row.L), ("projectile.crh", row.crh),
        ("projectile.mass", row.mass), ("impact.velocity", row.V), ("impact.obliquity_deg", row.obliquity_deg),
        ("impact.attack_deg", row.attack_deg), ("target.compressive_strength", row.fc),
        ("target.strength_basis", row.strength_basis), ("target.density", row.rho)))]


def rigid_depth(row: Row, sets=()) -> float:
    """Depth of the nose (m) of the rigid fidelity for one shot (no mesh; this process only).

    Args:
        row: the shot. sets: further --set lines (e.g. a strength model), after the shot's own.
    """
    from fepen import scene
    from fepen.studies import engine

    (s,) = engine.summaries([scene.load(None, [*scene_sets(row), *sets])])
    if isinstance(s, Exception):
        raise s
    return s["Hy_mm"] / 1e3


def closed_form_depth(row: Row, S: float | None = None, k: float = 2.0) -> float:
    """Forrestal et al.'s (1994) closed form for a rigid ogive at normal incidence (m), with a crater k
    diameters deep in which the force grows linearly with depth:

        P = (m / (2π a² ρ N*)) ln(1 + N* ρ V1² / (S f_c)) + k D,
        V1² = (m V² − π a² k D S f_c) / (m + π a² k D N* ρ)   (P > k D; else the crater alone)

    with Forrestal's S = 82.6 f_c^−0.544 unless S is given, and k = 2 (their 4a); f_c the row's cylinder
    strength (Row.fc_cylinder).
    """
    fc = row.fc_cylinder
    S = tg.forrestal_S(fc) if S is None else S
    a, m, N, rho = 0.5 * row.D, row.mass, tg.ogive_nose_factor(row.crh), row.rho
    R, kD = S * fc, k * row.D
    V1sq = (m * row.V**2 - math.pi * a * a * kD * R) / (m + math.pi * a * a * kD * N * rho)
    if V1sq <= 0.0:  # stops in the crater, where the force is c z, c = π a² R/(k D): m V² = c P²
        return math.sqrt(m * row.V**2 * kD / (math.pi * a * a * R))
    return m / (2.0 * math.pi * a * a * rho * N) * math.log(1.0 + N * rho * V1sq / R) + kD


def errors(pred, meas) -> dict:
    """count, mean |error|, bias (mean error) and worst error of P_pred/P_meas − 1 (NaN predictions, shots
    that could not be built, are left out of all four)."""
    e = np.asarray(pred, dtype=float) / np.asarray(meas, dtype=float) - 1.0
    e = e[np.isfinite(e)]
    worst = float(e[np.argmax(np.abs(e))]) if len(e) else math.nan
    return {"count": len(e), "mean_abs": float(np.mean(np.abs(e))) if len(e) else math.nan,
            "bias": float(np.mean(e)) if len(e) else math.nan, "worst": worst}


#: the predictions compared: name -> extra --set lines of the rigid fidelity (None: the closed form)
METHODS = {"default": [], "forrestal-S": ["target.strength_model=forrestal-S"], "closed form": None}


def shot_scenes(sets: dict[str, list[Row]], extra=()) -> tuple[list, list]:
    """The rigid scenes of every shot by every rigid METHODS entry, and where each goes: ([Scene], [(set, row
    index, method)]); a shot fepen cannot build (an impossible mass) is left out (its prediction NaN)."""
    from fepen import scene
    from fepen.errors import InputError

    scenes, where = [], []
    for name, rows in sets.items():
        for i, row in enumerate(rows):
            for method, lines in METHODS.items():
                if lines is None:
                    continue
                try:
                    scenes.append(scene.load(None, [*scene_sets(row), *lines, *extra]))
                    where.append((name, i, method))
                except InputError:
                    pass
    return scenes, where


def predictions(sets: dict[str, list[Row]], where: list, summaries) -> dict[str, list[dict]]:
    """Every shot of every set by every METHODS entry: name -> list of per-shot dicts (the row's fields, the
    measured and predicted depths in m), from the rigid shots' summaries (in the order of ``where``; an
    InputError: NaN) and the closed form."""
    out: dict[str, list[dict]] = {name: [dict(row.__dict__) for row in rows] for name, rows in sets.items()}
    for name, rows in sets.items():
        for i, row in enumerate(rows):
            for method, lines in METHODS.items():
                out[name][i][method] = closed_form_depth(row) if lines is None else math.nan
    for (name, i, method), s in zip(where, summaries):
        if isinstance(s, dict):
            out[name][i][method] = s["Hy_mm"] / 1e3
    for name in out:  # the methods in their order after the row's fields
        out[name] = [{**{k: v for k, v in d.items() if k not in METHODS}, **{m: d[m] for m in METHODS}}
                     for d in out[name]]
    return out


def predict_sets(sets: dict[str, list[Row]], extra=(), comm=None) -> dict[str, list[dict]]:
    """Every shot of every set by every METHODS entry, here and now (fepen.studies.engine.summaries: the rigid
    shots batched). Returns predictions()."""
    from fepen.studies import engine

    scenes, where = shot_scenes(sets, extra)
    return predictions(sets, where, engine.summaries(scenes, comm))


def gather_sets(paths=(), shipped: bool = True) -> dict[str, list[Row]]:
    """The data sets to run: table1 and the shipped sets (unless shipped is False), then every CSV file
    given or found in a given folder, by file stem.

    Raises:
        InputError (key --data) on a path that is not there or a file that is not a data set.
    """
    from fepen.errors import InputError

    files: dict[str, Path] = dict(shipped_sets()) if shipped else {}
    for p in paths:
        p = Path(p)
        if p.is_dir():
            found = sorted(p.glob("*.csv"))
            if not found:
                raise InputError("--data", f"{p}: no .csv data set in this folder")
            files.update({f.stem: f for f in found})
        elif p.is_file():
            files[p.stem] = p
        else:
            raise InputError("--data", f"{p}: no such file or folder")
    out = {"table1": table1_set()} if shipped else {}
    for name, f in files.items():
        try:
            out[name] = read_set(f)
        except ValueError as err:
            raise InputError("--data", str(err)) from None
    return out


def summary_table(results: dict[str, list[dict]], law: str | None = "scaled-S") -> list[dict]:
    """Per set and method: count, mean |error|, bias, worst; and, for the default method, how many measured
    depths its 10-90 % interval holds ("interval inside", "interval shots": interval_coverage)."""
    rows = []
    for name, shots in results.items():
        row = {"set": name, "count": len(shots)}
        for method in METHODS:
            e = errors([s[method] for s in shots], [s["depth"] for s in shots])
            row.update({f"{method} {k}": v for k, v in e.items() if k != "count"})
        row.update(interval_coverage(name, shots, law))
        rows.append(row)
    return rows


def interval_coverage(name: str, shots: list[dict], law: str | None) -> dict:
    """How many of a set's measured depths lie in the 10-90 % interval of the default method's depth
    (fepen.stats.interval), the model fitted without the set when the shipped errors hold a set of that name.

    Returns:
        {"interval inside": count, "interval shots": count} (shots the method could predict), or {} when the
        law has no error model.
    """
    from fepen.data import prediction_errors
    from fepen.stats import interval

    if law is None:
        return {}
    rows = [r for r in prediction_errors.read() if r["set"] != name]
    try:
        m = interval.fit(rows, "depth", law, "rigid")
    except ValueError:  # no errors of this law
        return {}
    inside = n = 0
    for s in shots:
        if math.isfinite(s["default"]):
            lo, hi = interval.interval(m, s["default"], s["V"])
            inside += lo <= s["depth"] <= hi
            n += 1
    return {"interval inside": inside, "interval shots": n}


def markdown(table: list[dict], header: str = "") -> str:
    """The summary table as Markdown: per set, mean |error| / bias / worst of each method."""
    cols = " | ".join(f"{m}: mean abs / bias / worst" for m in METHODS)
    cover = all("interval shots" in r for r in table)
    extra = " default: in its 10-90 % interval |" if cover else ""
    lines = ([header, ""] if header else []) + [f"| set | shots | {cols} |{extra}",
                                                 "|---|---|" + "---|" * (len(METHODS) + cover)]
    for r in table:
        cells = " | ".join(f"{100 * r[f'{m} mean_abs']:.1f} % / {100 * r[f'{m} bias']:+.1f} % / "
                           f"{100 * r[f'{m} worst']:+.1f} %" for m in METHODS)
        tail = f" {r['interval inside']} of {r['interval shots']} |" if cover else ""
        lines.append(f"| {r['set']} | {r['count']} | {cells} |{tail}")
    return "\n".join(lines) + "\n"


#: what fepen validate-depth writes into its folder
DEPTH_NAMES = ("shots.jsonl", "depth.csv", "depth.md", "depth.png")

#: depth.csv's columns: (name, unit: "text" not a number, "–" dimensionless; predictions()' key or METHODS name)
DEPTH_CSV = (("set", "text", "set"), ("shot", "text", "name"), ("diameter_m", "m", "D"), ("length_m", "m", "L"),
             ("mass_kg", "kg", "mass"), ("crh", "–", "crh"), ("velocity_m_s", "m/s", "V"), ("fc_Pa", "Pa", "fc"),
             ("density_kg_m3", "kg/m^3", "rho"), ("depth_m", "m", "depth"), ("obliquity_deg", "deg", "obliquity_deg"),
             ("attack_deg", "deg", "attack_deg"), ("strength_basis", "text", "strength_basis"), ("default_depth_m",
             "m", "default"), ("forrestal_S_depth_m", "m", "forrestal-S"), ("closed_form_depth_m", "m", "closed form"))


@dataclass
class DepthPlan:
    """The data sets, the --set lines and the law of the interval."""

    sets: dict
    extra: tuple
    law: str


@register
class ValidateDepth(Study):
    """``fepen validate-depth``: every shot of the data sets by the rigid fidelity (both laws, batched on the
    one executor) and the closed form; the errors per set and the interval's coverage."""

    name = "validate-depth"
    command = "validate-depth"
    help = "depth data sets by the rigid fidelity and Forrestal's closed form: depth.csv, depth.md, depth.png"
    names = DEPTH_NAMES
    out = "results/validate-depth"

    def plan(self, paths=(), sets=(), shipped: bool = True) -> DepthPlan:
        from fepen import scene

        law = scene.load(None, ["effects.fidelity=rigid", *sets]).target.strength_model  # bad --set here
        return DepthPlan(gather_sets(paths, shipped), tuple(sets), law)

    def digest(self, plan: DepthPlan) -> str:
        import hashlib
        import json

        blob = json.dumps([{n: [r.__dict__ for r in rows] for n, rows in plan.sets.items()}, plan.extra],
                          sort_keys=True)
        return hashlib.sha256(blob.encode()).hexdigest()[:16]

    def rounds(self, plan: DepthPlan):
        scenes, where = shot_scenes(plan.sets, plan.extra)
        yield Round(scenes, keep=lambda sc: False, label="shots")
        return where

    def result(self, plan: DepthPlan, records: list, info) -> dict:
        from fepen.errors import SimulationError

        summaries = []
        for i in range(len(records[0])):
            r = records[0][i]
            if r["status"] == "stopped":
                raise SimulationError(r["message"])
            summaries.append(r["summary"] if r["status"] == "ok" else None)
        results = predictions(plan.sets, info.found, summaries)
        return {"table": summary_table(results, plan.law), "_results": results}

    @property
    def json_name(self) -> str:
        """Its files' stem: depth.csv, depth.md, depth.png."""
        return "depth"

    def document(self, plan: DepthPlan, result: dict, info) -> None:
        return None

    def tables(self, plan: DepthPlan, result: dict, info) -> list:
        rows = [{c: s.get(k, name) for c, _, k in DEPTH_CSV} for name, ss in result["_results"].items() for s in ss]
        return [Table("depth.csv", [c for c, _, _ in DEPTH_CSV], rows, digits=None)]  # the set: its name

    def texts(self, plan: DepthPlan, result: dict, info) -> dict:
        note = (f"Rigid fidelity, default scene but for each shot's projectile, target strength and density"
                f"{' and ' + ', '.join(plan.extra) if plan.extra else ''}; errors P_pred/P_meas - 1.")
        return {"depth.md": markdown(result["table"], note)}

    def pictures(self, plan: DepthPlan, result: dict, info) -> list:
        from fepen.post import study_figures

        return [Picture("depth.png", (6.6, 6.4), lambda fig: study_figures.depth(fig, result["_results"]), 130)]


def validate_depth(paths=(), sets=(), out="results/validate-depth", shipped: bool = True, comm=None) -> list[dict]:
    """Run the data sets (gather_sets) by every method (ValidateDepth); write DIR/depth.csv (per shot),
    DIR/depth.md (the table per set) and DIR/depth.png (predicted against measured); return the table."""
    from fepen.studies import study

    st = ValidateDepth()
    return study.run(st, st.plan(paths, sets, shipped), out, comm, say=lambda *ls: None)["table"]
