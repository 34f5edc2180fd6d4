"""What a run writes (contract): history.csv, summary.json with the Table 1 comparison, figures."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
from mpi4py import MPI

from fepen.data import shot
from fepen.errors import OUTCOMES, SimulationError
from fepen.io import columns, files, table
from fepen.version import SUMMARY_FORMAT

G0 = columns.G0  # m/s^2, for accelerations in g

#: history.csv's column groups, declared once with their units and meanings in fepen.io.columns (the lists
#: below are their names, for the code that reads a history by position)
HISTORY_COLUMNS = columns.BASE.columns
COL = {k: i for i, k in enumerate(HISTORY_COLUMNS)}
ATTITUDE_COLUMNS = columns.ATTITUDE.columns
CHARGE_COLUMNS = columns.ACCELERATIONS.columns
BODY_COLUMNS = columns.BODIES.columns
RESULTANT_COLUMNS = columns.RESULTANT.columns
REMOVAL_COLUMNS = columns.REMOVAL.columns
LOAD_COLUMNS = columns.LOADS.columns
INTERFACE_COLUMNS = columns.INTERFACE.columns


#: history.csv's line end: the csv module's own (RFC 4180's CRLF), as history.csv has been written since 0.1
HISTORY_NEWLINE = "\r\n"


def history_rows() -> table.Rows:
    """A run's history rows, each formatted once (fepen.io.table.Rows: history.csv is replaced whole at every
    output, and formatting every row again each time made a long run's outputs grow as the square of its rows)."""
    return table.Rows(digits=table.DIGITS, newline=HISTORY_NEWLINE)


def write_history(rows, out: Path, comm=MPI.COMM_WORLD, columns=None, text: table.Rows | None = None) -> None:
    """history.csv (rank 0, atomically, through fepen.io.table; collective: a failed write raises MachineFault on
    every rank, and the file keeps its last complete version).

    Args:
        rows: the history rows. out: the results directory. comm: the run's communicator. columns: the header
            (the run's declared groups, fepen.io.columns; default HISTORY_COLUMNS). text: the run's
            ``history_rows()`` (its rows formatted once), or None.
    """

    def write():
        files.inject("history")
        files.write_text(Path(out) / "history.csv", table.text(columns or HISTORY_COLUMNS, rows, table.DIGITS,
                                                               HISTORY_NEWLINE, text), comm)

    files.agree(comm, f"{Path(out) / 'history.csv'}", write)


def write_summary(out: Path, summary: dict, comm=MPI.COMM_WORLD) -> None:
    """summary.json (rank 0, atomically; collective like write_history)."""

    def write():
        files.inject("summary")
        files.write_json(Path(out) / "summary.json", summary, comm)

    files.agree(comm, f"{Path(out) / 'summary.json'}", write)


def stop_summary(scene: dict, rows, outcome: str, reason: str, where: dict, extra: dict) -> dict:
    """The summary.json of a run that stopped before its end (no collective call: the stop may have come
    from one rank). It reports no result (no Hx_mm, depth_mm, ...): where the run was when it stopped is in
    ``stop_where``.

    Args:
        scene: the resolved scene as a dict (Scene.as_dict()).
        rows: the history rows so far (possibly none).
        outcome: a stop's name in fepen.errors.OUTCOMES ("stopped", "interrupted", "fault", "error", ...),
            which gives its exit code and whether it is resumable.
        reason: the one line the console showed.
        where: step, time and place of the stop (step, t_s, nose_y_mm, ...).
        extra: further keys (steps, ranks, ...).
    """
    where = dict(where)
    if rows:  # the last recorded state, as a place: no result is reported for a run that did not end
        last = rows[-1]
        where.update({"history_t_s": last[COL["t_s"]], "nose_x_mm": last[COL["nose_x_mm"]],
                      "nose_y_mm": last[COL["nose_y_mm"]], "speed_m_s": last[COL["speed_m_s"]]})
    o = OUTCOMES[outcome]
    out = {"outcome": outcome, "stop_reason": reason, "stop_time_s": where.get("t_s"), "stop_where": where,
           "exit_code": o.exit_code, "resumable": o.resumable}
    out.update(extra)
    out["scene"] = scene
    out["versions"] = {"fepen": files.__version__}
    out["format_version"] = SUMMARY_FORMAT
    return out


def comparison(name: str | None, summary: dict) -> dict | None:
    """Errors against Table 1 when a shot is named (impact.shot): nose error |H_sim − H_exp| / |H_exp| with
    H = (Hx, Hy) 2-vectors, likewise the tail; and each component's relative error."""
    if name is None:
        return None
    s = shot(name)
    H_exp, T_exp = np.array([s.Hx_mm, s.Hy_mm]), np.array([s.Tx_mm, s.Ty_mm])
    H = np.array([summary["Hx_mm"], summary["Hy_mm"]])
    T = np.array([summary["Tx_mm"], summary["Ty_mm"]])
    axis = float(final_axis_deg(s.Hx_mm, s.Hy_mm, s.Tx_mm, s.Ty_mm))
    return {"shot": name, "Hx_mm": s.Hx_mm, "Hy_mm": s.Hy_mm, "Tx_mm": s.Tx_mm, "Ty_mm": s.Ty_mm,
            "final_axis_angle_deg": axis, "axis_error_deg": float(summary["final_axis_angle_deg"] - axis),
            "nose_offset_mm": nose_offset_mm(s.Hx_mm, s.Hy_mm, s.obliquity_deg),
            "nose_error": float(np.linalg.norm(H - H_exp) / np.linalg.norm(H_exp)),
            "tail_error": float(np.linalg.norm(T - T_exp) / np.linalg.norm(T_exp)),
            "Hy_error": float(summary["Hy_mm"] / s.Hy_mm - 1), "Ty_error": float(summary["Ty_mm"] / s.Ty_mm - 1)}


#: the axis at the end from the nose and tail positions (declared with the history columns)
final_axis_deg = columns.final_axis_deg


def nose_offset_mm(Hx_mm: float, Hy_mm: float, obliquity_deg: float) -> float:
    """How far the nose ended from the line of fire (mm): its distance from the line through the impact point at
    the obliquity from the face's normal, in the plane of the shot."""
    ob = math.radians(obliquity_deg)
    return float(abs(Hx_mm * math.cos(ob) - Hy_mm * math.sin(ob)))


def summary(scene: dict, experiment: str | None, rows, outcome: str, extra: dict) -> dict:
    """summary.json content (contract keys first).

    Args:
        scene: the resolved scene as a dict (Scene.as_dict()). experiment: the Table 1 shot compared with, or
            None. rows: the history rows. outcome: fepen.errors.OUTCOMES' name. extra: further keys.
    """
    last = rows[-1]
    out = {"Hx_mm": last[COL["nose_x_mm"]], "Hy_mm": last[COL["nose_y_mm"]],  # signed: above the face < 0
           "Tx_mm": last[COL["tail_x_mm"]], "Ty_mm": last[COL["tail_y_mm"]],
           "depth_mm": max(r[COL["nose_y_mm"]] for r in rows), "length_mm": last[COL["length_mm"]],
           "residual_speed_m_s": last[COL["speed_m_s"]], "outcome": outcome,
           "energy_error": max(r[COL["energy_error"]] for r in rows), "max_peeq": last[COL["max_peeq"]]}
    if len(last) >= len(HISTORY_COLUMNS) + len(ATTITUDE_COLUMNS):  # across the plane of fire (z), signed
        a = len(last) - len(ATTITUDE_COLUMNS)
        out["Hz_mm"], out["Tz_mm"] = float(last[a]), float(last[a + 1])
    out["final_axis_angle_deg"] = float(final_axis_deg(last[COL["nose_x_mm"]], last[COL["nose_y_mm"]],
                                                       last[COL["tail_x_mm"]], last[COL["tail_y_mm"]]))
    out["nose_offset_mm"] = nose_offset_mm(last[COL["nose_x_mm"]], last[COL["nose_y_mm"]],
                                           scene.get("impact", {}).get("obliquity_deg", 0.0))
    out.update(extra)
    out["experiment"] = comparison(experiment, out)
    out["scene"] = scene
    out["versions"] = files.versions()
    out["format_version"] = SUMMARY_FORMAT
    return out


def finite_row(row, step, t) -> None:
    """Raise SimulationError if a history row holds a non-finite number."""
    if not all(math.isfinite(v) for v in row):
        raise SimulationError(f"non-finite state at step {step}, t = {t * 1e6:.3f} us")


# ---------------------------------------------------------------------------------------------------------
# reading a results directory back: one reader for fepen.load, the figures, ParaView and the tools
# ---------------------------------------------------------------------------------------------------------
class RunFiles:
    """What a run's results directory holds, read one way for everyone who reads one (fepen.load, the
    figures, ParaView's help, tools/compare_*). Nothing is read until asked; a file that is absent or does not
    parse reads as None (or empty), so that a running or killed run's directory can be described too.

    Args:
        out: the results directory.
    """

    def __init__(self, out):
        self.out = Path(out)

    @property
    def finished(self) -> bool:
        """Whether the run finished (it wrote summary.json)."""
        return (self.out / "summary.json").is_file()

    def summary(self) -> dict | None:
        """summary.json as a dict, or None."""
        import json

        try:
            return json.loads((self.out / "summary.json").read_text())
        except (OSError, ValueError):
            return None

    def history(self) -> np.ndarray:
        """history.csv as a numpy structured array (``h["nose_y_mm"]``; columns as written, docs/results.md)."""
        return np.atleast_1d(np.genfromtxt(self.out / "history.csv", delimiter=",", names=True, deletechars=""))

    def history_text(self) -> tuple[list[str], list[list[str]]]:
        """history.csv as text: (the header's columns, the rows), every figure as written (for comparisons to
        the character)."""
        with (self.out / "history.csv").open(newline="") as f:
            rows = list(csv.reader(f))
        return rows[0], rows[1:]

    def table(self, name: str):
        """One of the run's CSV tables (RUN_TABLES: probes.csv, accelerations.csv, strains.csv, hazard.csv,
        charge_sections.csv; history.csv too) as a pandas DataFrame, its columns named as in the file (units in
        the names, docs/results.md), every number the double the file holds (read back to the bit).

        Raises:
            ImportError: pandas is missing (one line). FileNotFoundError: the run wrote no such table; the
                message says why (a rigid run writes no strains.csv, a run without [[output.probes]] no
                probes.csv, a stopped run none of the closing tables).
        """
        pd = pandas(f"the table {name}")
        path = self.out / name
        if not path.is_file():
            raise FileNotFoundError(f"{path} is not there: {self.absent_why(name)}")
        return pd.read_csv(path, float_precision="round_trip")

    def absent_why(self, name: str) -> str:
        """Why a run's directory holds no ``name`` (one of RUN_TABLES), from its scene and summary."""
        keys, summary = self.scene_keys(), self.summary() or {}
        outcome = summary.get("outcome")
        if name == "probes.csv" and not any(k.startswith("output.probes") for k in keys) \
                and "[[output.probes]]" not in self._scene_text():
            return "the run has no [[output.probes]] (docs/scenes.md)"
        if name != "probes.csv" and keys.get("effects.fidelity") == "rigid":
            return f"{name} is written by deformable runs only (this run's effects.fidelity is 'rigid')"
        if name == "charge_sections.csv" and keys.get("effects.charge") is False:
            return "charge_sections.csv is written by charged runs only (this run's effects.charge is false)"
        if "Hx_mm" not in summary:
            return f"the run did not finish (outcome {outcome!r}): {summary.get('stop_reason') or 'no summary.json'}"
        return f"the run wrote none (outcome {outcome!r}; docs/results.md says which runs write it)"

    def _scene_text(self) -> str:
        try:
            return (self.out / "scene.toml").read_text()
        except (OSError, UnicodeDecodeError):
            return ""

    def given_scene(self) -> dict:
        """The keys the user gave, as the scene.toml in the directory holds them (nested TOML tables), or {}."""
        import tomllib

        try:
            return tomllib.loads((self.out / "scene.toml").read_text())
        except (OSError, ValueError, UnicodeDecodeError, RecursionError):
            return {}

    def scene_keys(self) -> dict:
        """Every key of the run's scene, flat and dotted: scene.toml's (the given keys as values, every resolved
        key as a comment line, written_scene), else summary.json's scene; {} when neither is there."""
        flat = written_scene(self.out / "scene.toml")
        if flat:
            return flat
        tree = (self.summary() or {}).get("scene")
        if not isinstance(tree, dict):
            return {}
        stack = [("", tree)]
        while stack:
            prefix, node = stack.pop()
            for k, v in node.items():
                if isinstance(v, dict):
                    stack.append((f"{prefix}{k}.", v))
                else:
                    flat[f"{prefix}{k}"] = v
        return flat

    def fields(self) -> Path | None:
        """fields.xdmf, or None when the run wrote none."""
        p = self.out / "fields.xdmf"
        return p if p.is_file() else None

    def figures(self) -> dict[str, Path]:
        """The run's pictures, by name: {"history": .../history.png, ...}."""
        return {p.stem: p for p in sorted(self.out.glob("*.png"))}


#: the run's CSV tables a Result reads by name (fepen.io.columns.TABLES' files and probes.csv)
RUN_TABLES = ("probes.csv", *columns.TABLES)


def pandas(what: str):
    """pandas, or ImportError with one line naming what needed it and how to get it (no traceback from deep in
    pandas' callers)."""
    try:
        import pandas as pd
    except ImportError:
        raise ImportError(f"{what} needs pandas, a dependency of fepen that is not installed here: "
                          "pip install 'pandas>=1.5'") from None
    return pd


def read(out) -> RunFiles:
    """The reader of a results directory (RunFiles)."""
    return RunFiles(out)


def finished_runs(folder) -> list[Path]:
    """The finished runs in a folder: the folder itself when it is one, else its subfolders that are, by name."""
    folder = Path(folder)
    if RunFiles(folder).finished:
        return [folder]
    return [d for d in sorted(folder.iterdir()) if d.is_dir() and RunFiles(d).finished]


def written_scene(path) -> dict:
    """Every key of a scene.toml as fepen writes it into a results directory (the given keys as values, every
    other resolved key as a comment line "# key = value" under its "# [section]"), flat and dotted; without
    fepen.scene (reading files, not resolving scenes). Lines that are neither are skipped, and so are the
    [[target.layers]] tables.

    Args:
        path: the scene.toml.

    Returns:
        {"impact.velocity": 584.3, ...}; empty when the file cannot be read.
    """
    import re
    import tomllib

    try:
        lines = Path(path).read_text().splitlines()
    except (OSError, UnicodeDecodeError):
        return {}
    header = re.compile(r"^(?:# )?\[([A-Za-z0-9_.]+)\]\s*$")
    key = re.compile(r"^(?:# )?([A-Za-z_][A-Za-z0-9_]*) = (.+)$")
    flat, section = {}, None
    for line in lines:
        if line.lstrip("# ").startswith("[["):
            section = None
        elif m := header.match(line):
            section = m.group(1)
        elif section is not None and (m := key.match(line)):
            try:
                flat[f"{section}.{m.group(1)}"] = tomllib.loads(f"v = {m.group(2)}")["v"]
            except tomllib.TOMLDecodeError:
                continue
    return flat
