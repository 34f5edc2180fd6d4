"""docs/results.md against what runs write: every summary.json key and every history.csv column that a run of
any fidelity or effect writes is in the docs' tables, and every name in those tables is written by some run.

The docs' tables are machine-readable: a table whose first header cell is a file name in backticks followed by
``key`` or ``column`` (``| `summary.json` key | unit | meaning |``) lists that file's names, in backticks, in
its first column. Nested summary keys are dotted (``time_split_s.mesh``), ``[]`` standing for each element of a
list (``layers[].material``); a nested key is checked where the docs list the keys at its level (the keys of
``scene`` are docs/scenes.md's and are not repeated). A new table for another file (``| `probes.csv` column |
...``) is checked the same way, with no change here.

The runs, cheap (about 10 s of CPU with the meshes cached, 35 s without): the rigid fidelity on Table 1's C3,
with wear, and on a layered target; the plastic and elastic fidelities, a charge in frictional and in tied
contact, wear and erosion on the meshed projectile (5 mm mesh, 30 µs; the plastic one with a node and a cell
probe); a plastic run stopped by a full disk.
"""

import csv
import json
import re
from pathlib import Path

import pytest

import fepen
from fepen.io import files

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.xdist_group("test_docs_results")

#: a deformable run kept short and coarse: no fields, no checkpoints
SHORT = ["mesh.size=0.005", "run.end_time=3e-5", "run.fields=false", "run.checkpoint_interval=0"]
LAYERS = {"target": {"layers": [{"material": "concrete", "thickness": 0.1, "gap": 0.05}, {"material": "concrete"}]}}
#: a node, a cell and an accelerometer probe (probes.csv); the docs write a probe's name as <name>
PROBES = {"output": {"probes": [{"name": "nose", "point": [0.0, 0.005, 0.0], "kind": "node"},
                                {"name": "wall", "point": [0.009, 0.07, 0.0], "kind": "cell"},
                                {"name": "gauge", "point": [0.0, 0.14, 0.0], "kind": "accelerometer"}]}}
PROBE_NAMES = re.compile(r"^(nose|wall|gauge)_")

#: name -> (scene source, --set overrides): together every fidelity and every effect that adds an output
RUNS = {
    "rigid-C3": (None, ["effects.fidelity=rigid", "impact.shot=C3"]),
    "rigid-wear": (None, ["effects.fidelity=rigid", "effects.wear=true"]),
    "rigid-layers": (LAYERS, ["effects.fidelity=rigid"]),
    "plastic": (PROBES, SHORT),
    "elastic": (None, [*SHORT, "effects.fidelity=elastic"]),
    "charge-frictional": (None, [*SHORT, "effects.charge=true", "charge.contact=frictional"]),
    "charge-tied": (None, [*SHORT, "effects.charge=true", "charge.contact=tied"]),
    "wear-erosion": (None, [*SHORT, "effects.wear=true", "effects.erosion=true"]),
}

HEADER = re.compile(r"^\|\s*`([^`]+)`\s+(?:key|column)\s*\|")
CELL = re.compile(r"(?<!\\)\|")  # a cell border, not an escaped \| inside a cell


def documented(text: str) -> dict[str, set[str]]:
    """The names each file's tables list: {file: {name, ...}}.

    Args:
        text: the Markdown of docs/results.md.

    Returns:
        For every table headed ``| `FILE` key |`` or ``| `FILE` column |``, the backticked names of the first
        column of its rows, united over the tables of one file.
    """
    out: dict[str, set[str]] = {}
    names = None
    for line in text.splitlines():
        header = HEADER.match(line)
        if header:
            names = out.setdefault(header.group(1), set())
        elif names is not None and line.startswith("|"):
            first = CELL.split(line)[1]
            if set(first.strip()) - set("-: "):  # not the |---| line
                names.update(re.findall(r"`([^`]+)`", first))
        else:
            names = None
    return out


def flat_names(obj: dict, prefix: str = ""):
    """Every key of a JSON object as a dotted name, nested ones too; ``[]`` for each element of a list of
    objects."""
    for key, value in obj.items():
        name = prefix + key
        yield name
        if isinstance(value, dict):
            yield from flat_names(value, name + ".")
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for v in value:
                yield from flat_names(v, name + "[].")


def parent(name: str) -> str:
    """The dotted name one level up ('' for a top-level name)."""
    return name.rsplit(".", 1)[0] if "." in name else ""


def written_names(path: Path) -> set[str]:
    """The names a file holds: a JSON file's keys (flat_names), a CSV file's header (a probe's name as
    ``<name>``, a charge section's point as ``<point>``)."""
    if path.suffix == ".json":
        return set(flat_names(json.loads(path.read_text())))
    with path.open(newline="") as f:
        header = next(csv.reader(f))
    if path.name == "charge_sections.csv":  # the docs write a section point's name as <point>
        return {re.sub(r"^.+_(axial|shear)_Pa$", r"<point>_\1_Pa", c) for c in header}
    return {PROBE_NAMES.sub("<name>_", c) for c in header} if path.name == "probes.csv" else set(header)


@pytest.fixture(scope="module")
def run_dirs(tmp_path_factory) -> dict[str, Path]:
    """The runs of RUNS and one stopped run, each in its own directory."""
    base = tmp_path_factory.mktemp("docs-runs")
    dirs = {}
    for name, (source, sets) in RUNS.items():
        result = fepen.run(fepen.Scene(source, sets), out=base / name)
        assert result.summary["outcome"] in ("embedded", "ended"), name
        dirs[name] = base / name
    # a deformable run stopped by a full disk at its second checkpoint: the stop's summary.json
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("FEPEN_INJECT_FAULT", "checkpoint:2")
        mp.setattr(files, "_writes", {})
        with pytest.raises(fepen.MachineFault):
            fepen.run(fepen.Scene(None, [*SHORT, "run.checkpoint_interval=1e-5"]), out=base / "stopped")
    assert json.loads((base / "stopped" / "summary.json").read_text())["outcome"] == "fault"
    dirs["stopped"] = base / "stopped"
    return dirs


@pytest.fixture(scope="module")
def docs() -> dict[str, set[str]]:
    tables = documented((ROOT / "docs" / "results.md").read_text())
    assert {"summary.json", "history.csv"} <= set(tables)
    return tables


@pytest.fixture(scope="module")
def written(run_dirs, docs) -> dict[str, dict[str, set[str]]]:
    """{file: {run: names}} for every documented file each run wrote."""
    return {f: {run: written_names(d / f) for run, d in run_dirs.items() if (d / f).is_file()} for f in docs}


def test_every_name_a_run_writes_is_in_the_docs(docs, written):
    missing = {}
    for f, runs in written.items():
        expanded = {parent(name) for name in docs[f]}  # the levels the docs list
        missing.update({f"{f}: {name}": run for run, names in runs.items() for name in sorted(names)
                        if parent(name) in expanded and name not in docs[f]})
    assert not missing, f"written but not in docs/results.md (file: name -> a run that writes it): {missing}"


def test_every_name_in_the_docs_is_written_by_some_run(docs, written):
    unwritten = {f: sorted(names - set().union(set(), *written[f].values())) for f, names in docs.items()}
    unwritten = {f: names for f, names in unwritten.items() if names}
    assert not unwritten, f"in docs/results.md but written by no run: {unwritten}"


def test_the_parser_reads_the_tables_it_should():
    """documented() on a small page: two tables of one file united, escaped pipes kept in a cell, the rows of
    another kind of table (its first header cell not a file) left out."""
    page = "\n".join([
        "| `a.json` key | unit | meaning |", "|---|---|---|", "| `x`, `y.z` | m | \\|H\\| `not this` |", "",
        "text", "| `a.json` key | meaning |", "|---|---|", "| `w` | a |", "",
        "| field | kind |", "|---|---|", "| `f` | g |", "",
        "| `b.csv` column | unit |", "|---|---|", "| `c` | s |"])
    assert documented(page) == {"a.json": {"x", "y.z", "w"}, "b.csv": {"c"}}
