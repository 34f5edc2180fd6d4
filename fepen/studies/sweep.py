"""``fepen sweep SWEEP.toml``: many shots of one base scene with some keys varied (docs/studies.md), read from a
sweep spec (fepen.studies.spec: a base scene and [grid], [monte_carlo] or [table]).

Writes to OUT: sweep.json (the sweep as run), shots.jsonl (one record per finished shot, appended as each
ends: what makes a killed sweep resumable), sweep.csv (one row per shot: the varied keys and every summary
figure; sweep.parquet too when pyarrow is installed), costs.csv (wall time and ranks per shot), sweep.md and
figures (fepen.post.study_figures). A Study (fepen.studies.study) of one round, on the one executor.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fepen.errors import InputError
from fepen.studies import products
from fepen.studies.products import Picture, Table
from fepen.studies.spec import DISTRIBUTIONS, IMPACT, MAX_SHOTS, monte_carlo, read, resized
from fepen.studies.spec import Spec as Sweep
from fepen.studies.study import Round, Study, register

__all__ = ["Sweep", "SweepStudy", "SweepPlan", "read", "run", "table_rows", "write_table", "resized",
           "DISTRIBUTIONS", "MAX_SHOTS", "IMPACT", "monte_carlo", "measured_shot"]

#: summary entries that describe the machine or the run's cost, not the shot (costs.csv holds some; a deformable
#: run's communication block depends on its ranks)
MACHINE = ("wall_s", "time_split_s", "peak_memory_bytes", "ranks", "scene", "versions", "communication")
#: what a sweep writes into its folder (fepen.io.rundir.study_directory)
SWEEP_NAMES = ("sweep.json", "shots.jsonl", "shots", "sweep.csv", "costs.csv", "sweep.parquet", "sweep.md", "sweep.png",
               "histograms.png")


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


def tables(sweep: Sweep, records: dict) -> tuple[list, list, list]:
    """sweep.csv (and sweep.parquet with pyarrow: the extra ``parquet``) and costs.csv, declared for the skeleton's
    writer (fepen.studies.products); (the tables, sweep.csv's columns, its rows).

    Args:
        sweep: the sweep. records: {shot: record}.
    """
    cols, rows = table_rows(sweep, records)
    costs = [[i, records[i].get("wall_s", float("nan")), records[i].get("ranks", "")] for i in sorted(records)]
    return ([Table("sweep.csv", cols, rows, sweep.digits, parquet=True),
             Table("costs.csv", ["shot", "wall_s", "ranks"], costs, sweep.digits)], cols, rows)


def write_table(sweep: Sweep, records: dict, out: Path, say=None) -> tuple[list, list]:
    """sweep.csv, sweep.parquet and costs.csv alone (the skeleton writes them with the rest); (columns, rows).

    Args:
        sweep: the sweep. records: {shot: record}. out: the results directory.
        say: prints the one line saying why sweep.parquet was not written (pyarrow absent, or failing to import,
            as a release built for numpy 2 does beside numpy 1.24), or None.
    """
    written, cols, rows = tables(sweep, records)
    products.write(out, None, "sweep", written, say=say)
    return cols, rows


# -------------------------------------------------------------------------------------------------- the study
@dataclass
class SweepPlan:
    """A sweep as planned: its spec and where it came from (None: given as a dict)."""

    spec: Sweep
    source: str | None


class _Scenes:
    """The shots' scenes, resolved when the executor asks for one."""

    def __init__(self, spec: Sweep):
        self.spec = spec

    def __len__(self) -> int:
        return len(self.spec.shots)

    def __getitem__(self, i: int):
        return self.spec.scene(i)


@register
class SweepStudy(Study):
    """``fepen sweep``: the spec's shots in one round; the table, its figures and its report."""

    name = "sweep"
    command = "sweep"
    help = "many shots of a base scene (grid, Monte Carlo or a table): sweep.csv, sweep.md, figures"
    names = SWEEP_NAMES
    out = "results/sweep"

    def plan(self, spec=None, sets=()) -> SweepPlan:
        """spec: a SWEEP.toml or its content as a dict; sets: --set overrides of the base scene."""
        if spec is None:
            raise InputError("SWEEP", "name the sweep file (docs/studies.md)")
        source = None if isinstance(spec, dict) else str(Path(spec).resolve())
        return SweepPlan(read(spec, sets), source)

    def digest(self, plan: SweepPlan) -> str:
        return plan.spec.digest

    def prepare(self, plan: SweepPlan, out: Path, comm) -> None:
        from mpi4py import MPI

        from fepen.io import files

        sw = plan.spec
        if comm.rank == 0:
            files.write_json(out / "sweep.json", {"file": plan.source, "digest": sw.digest, "kind": sw.kind,
                                                  "keys": sw.keys, "shots": len(sw.shots), "base": sw.base,
                                                  "spec": sw.spec}, MPI.COMM_SELF)

    def rounds(self, plan: SweepPlan):
        sw = plan.spec
        keep = sw.keep_results
        rigid = sw.base.get("effects.fidelity") == "rigid" and "effects.fidelity" not in sw.keys and not keep
        yield Round(_Scenes(sw), keep=lambda sc: keep or sc.effects.fidelity != "rigid", batch=rigid)

    def result(self, plan: SweepPlan, records: list[dict], info) -> dict:
        recs = records[0]
        statuses: dict = {}
        for r in recs.values():
            statuses[r["status"]] = statuses.get(r["status"], 0) + 1
        cols, rows = table_rows(plan.spec, recs)
        return {"shots": len(plan.spec.shots), "statuses": statuses, "_records": recs, "_cols": cols, "_rows": rows}

    def document(self, plan: SweepPlan, result: dict, info) -> None:
        return None

    def tables(self, plan: SweepPlan, result: dict, info) -> list:
        return tables(plan.spec, result["_records"])[0]

    def texts(self, plan: SweepPlan, result: dict, info) -> dict:
        return {"sweep.md": report(plan.spec, result["_rows"], info.wall_s, info.ran, info.ranks,
                                   info.ranks_per_shot)}

    def pictures(self, plan: SweepPlan, result: dict, info) -> list:
        return pictures(plan.spec, result["_cols"], result["_rows"])

    def lines(self, result: dict) -> list[str]:
        return []


def run(path, out, comm=None, ranks_per_shot: int = 1, sets=(), fresh: bool = False, say=print,
        progress: bool = True) -> dict:
    """Read the sweep, run its missing shots, write the table, summary and figures (fepen.studies.study.run of
    SweepStudy).

    Args:
        path: the SWEEP.toml, or its content as a dict (read). out: the results directory.
        comm: the communicator (None: COMM_WORLD).
        ranks_per_shot: ranks of each shot's group. sets: --set overrides of the base scene.
        fresh: run every shot again (what the sweep wrote in OUT is removed first, by its manifest).
        say: prints one line (rank 0).
        progress: the bar of shots done over the total (rank 0, where fepen.progress shows one).

    Returns:
        {"shots", "ran", "skipped", "wall_s", "statuses"} (every rank).
    """
    from fepen.studies import study

    st = SweepStudy()
    res = study.run(st, st.plan(path, sets), out, comm, ranks_per_shot, fresh, say, progress)
    return {"shots": res["shots"], "ran": res["ran"], "skipped": res["shots"] - res["ran"], "wall_s": res["wall_s"],
            "statuses": res["statuses"]}


# -------------------------------------------------------------------------------------------------- pictures
def measured_shot(sweep):
    """The Table 1 shot the sweep's base scene is (its striking speed, obliquity and attack angle those of a
    shot, and neither the projectile nor the target changed), or None: the sweep then varies keys around a
    measured test, whose values the figures mark."""
    from fepen import scene as fscene
    from fepen.data import SHOTS

    if any(k.startswith(("projectile.", "target.")) for k in sweep.base) or "impact.shot" in sweep.keys:
        return None
    try:
        sc = fscene.Scene(sweep.base)
    except Exception:  # noqa: BLE001 - a figure's mark, never an error
        return None
    if sc.get("impact.shot"):
        return SHOTS.get(sc.get("impact.shot"))
    v, ob, at = (sc.get(k) for k in ("impact.velocity", "impact.obliquity_deg", "impact.attack_deg"))
    for shot in SHOTS.values():
        if (shot.v0, shot.obliquity_deg, shot.attack_deg) == (v, ob, at):
            return shot
    return None


def key_axis(key: str) -> tuple[str, float]:
    """(axis label with its unit, factor from the scene's SI value) of a varied scene key, e.g.
    ("target.compressive_strength (MPa)", 1e-6)."""
    from fepen.post.study_figures import SHOWN_UNITS
    from fepen.scene import SCHEMA

    unit = SCHEMA[key].unit if key in SCHEMA else ""
    shown, factor = SHOWN_UNITS.get(unit, (unit, 1.0))
    return (f"{key} ({shown})" if shown else f"{key} (−)"), factor


def _test_x(sweep, shot, key):
    """The test shot's value of a varied key (SI): its own impact values, else the base scene's."""
    from fepen import scene as fscene

    own = {"impact.velocity": shot.v0, "impact.obliquity_deg": shot.obliquity_deg,
           "impact.attack_deg": shot.attack_deg}
    if key in own:
        return own[key]
    value = fscene.Scene(sweep.base).get(key)
    return value if isinstance(value, (int, float)) and not isinstance(value, bool) else None


def _title(sweep, rows) -> str:
    fid = {r.get("fidelity") for r in rows} - {None, ""}
    if not fid:
        from fepen import scene as fscene

        try:
            fid = {fscene.Scene(sweep.base).get("effects.fidelity")}
        except Exception:  # noqa: BLE001
            fid = set()
    return f"{sweep.kind} sweep, {len(rows)} shots" + (f", {', '.join(sorted(fid))} fidelity" if fid else "")


def pictures(sweep, cols, rows) -> list:
    """sweep.png and, for a Monte Carlo sample, histograms.png (fepen.post.study_figures), with what only the
    scene knows handed over: each varied key's axis label, unit factor and test value, the measured shot, the
    title (fepen.studies.products.Picture)."""
    from fepen.post import study_figures as sf

    shot = measured_shot(sweep)
    axes = [(k, *key_axis(k), _test_x(sweep, shot, k) if shot is not None else None) for k in sweep.keys]
    title = _title(sweep, rows)
    out = []
    size = sf.sweep_size(axes, rows)
    if size is not None:
        out.append(Picture("sweep.png", size, lambda fig: sf.sweep_figure(fig, axes, rows, shot, title)))
    names = sf.histogram_names(cols, rows) if sweep.kind == "monte-carlo" else []
    if names:
        out.append(Picture("histograms.png", (4.4 * len(names), 3.8),
                           lambda fig: sf.histograms(fig, names, rows, shot, title)))
    return out


def draw(sweep, cols, rows, out: Path) -> list[Path]:
    """The pictures of a sweep's table, written into ``out`` alone; the files written."""
    pics = pictures(sweep, cols, rows)
    products.write(out, None, "sweep", pictures=pics)
    return [Path(out) / p.file for p in pics]


def report(sweep, rows, wall_s: float, ran: int, ranks: int, ranks_per_shot: int) -> str:
    """sweep.md: what ran, the outcomes, quantiles of the main figures."""
    from fepen.post.study_figures import column, quantiles, summarised

    statuses, outcomes = {}, {}
    for r in rows:
        statuses[r["status"]] = statuses.get(r["status"], 0) + 1
        if r["status"] == "ok":
            outcomes[r.get("outcome")] = outcomes.get(r.get("outcome"), 0) + 1
    lines = [f"# Sweep ({sweep.kind}, {len(sweep.shots)} shots)", "",
             f"Varied: {', '.join(f'`{k}`' for k in sweep.keys)}. Ran {ran} shots now "
             f"({len(sweep.shots) - ran} recorded before) on {ranks} rank(s), {ranks_per_shot} per shot, in "
             f"{wall_s:.1f} s.", "",
             "Status: " + ", ".join(f"{k} {v}" for k, v in sorted(statuses.items())) + ". Outcomes: "
             + ", ".join(f"{k} {v}" for k, v in sorted(outcomes.items(), key=lambda kv: str(kv[0]))) + ".", ""]
    cols = list(rows[0]) if rows else []
    names = [*[k for k in sweep.keys if np.isfinite(column(rows, k)).all()], *summarised(cols, rows)]
    if names:
        lines += ["| figure | count | mean | std | min | P5 | P50 | P95 | max |",
                  "|---|---|---|---|---|---|---|---|---|"]
        for name in names:
            q = quantiles(column(rows, name))
            if q["count"]:
                label = f"`{name}`" + (" (perforated)" if name == "residual_speed_m_s" else "")
                lines.append(f"| {label} | {q['count']} | " + " | ".join(
                    f"{q[p]:.5g}" for p in ("mean", "std", "min", "P5", "P50", "P95", "max")) + " |")
    if sweep.kind == "monte-carlo" and outcomes:
        from fepen.stats.sampling import AXIS_BEYOND_DEG, designer_flags, proportion

        ok = [r for r in rows if r["status"] == "ok"]
        flags = designer_flags([{"outcome": r.get("outcome"), "final_axis_angle_deg": r.get("final_axis_angle_deg")}
                                for r in ok if r.get("final_axis_angle_deg") is not None])
        lines += ["", "| probability | shots | P | Wilson 95 % |", "|---|---|---|---|"]
        for key, what in (("perforation", "perforation"), ("ricochet", "ricochet"),
                          ("axis_beyond", f"final axis beyond {AXIS_BEYOND_DEG:g}°")):
            e = proportion(flags[key])
            if e["shots"]:
                lines.append(f"| {what} | {e['count']}/{e['shots']} | {e['probability']:.3f} | "
                             f"{e['wilson95'][0]:.3f}-{e['wilson95'][1]:.3f} |")
    lines += ["", "Files: sweep.csv (one row per shot), costs.csv (wall time per shot), shots.jsonl (the records, "
              "full precision), sweep.json, sweep.png" + (", histograms.png" if sweep.kind == "monte-carlo" else "")
              + ".", ""]
    return "\n".join(lines)
