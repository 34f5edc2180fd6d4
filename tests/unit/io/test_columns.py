"""history.csv's columns declared once (fepen.io.columns, issue 60): docs/results.md's tables are the
declarations' (make docs writes them; this fails when a column is declared but not documented, or the page was
edited by hand), every name is unique and carries its declared unit, and a run's header is the declared groups
it writes, in order."""

import re
from pathlib import Path

import pytest
from mpi4py import MPI

from fepen import scene
from fepen.io import columns, results
from fepen.runs.rigid import RigidRun

ROOT = Path(__file__).resolve().parents[3]
#: a name's unit suffix and the unit it must be declared with (longest suffix first)
SUFFIX_UNITS = (("_N_m_s", "N m s"), ("_N_m", "N m"), ("_N_s", "N s"), ("_rad_s", "rad/s"), ("_m_s", "m/s"),
                ("_m2", "m²"), ("_mm", "mm"), ("_kg", "kg"), ("_deg", "deg"), ("_J", "J"), ("_N", "N"), ("_g", "g"),
                ("_s", "s"))


def test_the_docs_tables_are_the_declarations():
    page = (ROOT / "docs" / "results.md").read_text()
    m = re.search(r"<!-- make docs: history-columns -->\n(?:<sub>Made by .*</sub>\n)?(.*?)\n"
                  r"<!-- /make docs: history-columns -->", page, re.S)
    assert m, "docs/results.md has no history-columns block"
    assert m.group(1) == columns.markdown(), "docs/results.md differs: python tools/make_docs.py --only history-columns"


def test_every_column_is_unique_and_carries_its_unit():
    names = [n for g in columns.HISTORY for n in g.columns]
    assert len(names) == len(set(names))
    for g in columns.HISTORY:
        for q in g.quantities:
            assert q.doc and q.unit
            for n in q.names:
                want = next((u for suffix, u in SUFFIX_UNITS if n.endswith(suffix)), "–")
                assert q.unit == want, (n, q.unit, want)


@pytest.mark.parametrize("sets, groups", [
    ([], ["base", "loads", "attitude"]),
    (["effects.wear=true"], ["base", "removal", "loads", "attitude"]),
])
def test_a_run_writes_the_declared_groups_it_has(tmp_path, sets, groups):
    out = tmp_path / "r"
    run = RigidRun(scene.load(None, ["effects.fidelity=rigid", "run.end_time=2e-5", *sets]), out, MPI.COMM_SELF)
    run.run()
    header = (out / "history.csv").read_text().splitlines()[0].split(",")
    want = [c for name in groups for g in columns.HISTORY if g.name == name for c in g.columns]
    assert header == want == run.columns
    assert results.HISTORY_COLUMNS == columns.BASE.columns


def test_every_row_value_is_declared_and_every_declaration_written(tmp_path):
    """A rigid run's rows are as long as its declared header, and every declared group of a rigid run computes
    its values from the declaration itself (only the deformable body's own columns come by name)."""
    out = tmp_path / "r"
    run = RigidRun(scene.load(None, ["effects.fidelity=rigid", "run.end_time=2e-5", "effects.wear=true"]), out,
                   MPI.COMM_SELF)
    run.run()
    lines = (out / "history.csv").read_text().splitlines()
    assert all(len(line.split(",")) == len(run.columns) for line in lines)
    for g in columns.HISTORY:
        if g.on(run):
            assert all(q.value is not None for q in g.quantities), g.name


class _Snap:
    extra = {"shell_acc_g": 1.0, "new_column_g": 2.0}


class _Charged:
    charged, frictional, removing, splitting = True, False, False, False


def test_a_body_column_written_but_not_declared_fails():
    with pytest.raises(ValueError, match="new_column_g"):
        columns.values(_Charged(), 0.0, _Snap())


def test_a_value_of_the_wrong_length_fails():
    q = columns.Quantity(("a_mm", "b_mm"), "mm", "two", lambda r: (1.0,))
    with pytest.raises(ValueError, match="a_mm"):
        q.values(columns.Row(0.0, _Snap(), None))


def test_a_new_declaration_is_a_new_column_in_both_fidelities(tmp_path, monkeypatch):
    """Adding a column is one declaration: a Quantity appended to a group writes its name in the header and its
    value in every row (here the nose's depth in cm, from the snapshot), with nothing else changed."""
    q = columns.Quantity(("nose_depth_cm",), "cm", "the nose's depth", lambda r: (-r.s.tip[1] * 1e2,))
    base = columns.Group(columns.BASE.name, "", columns.BASE.intro, columns.BASE.quantities + (q,))
    monkeypatch.setattr(columns, "HISTORY", (base, *columns.HISTORY[1:]))
    out = tmp_path / "r"
    RigidRun(scene.load(None, ["effects.fidelity=rigid", "run.end_time=2e-5"]), out, MPI.COMM_SELF).run()
    lines = (out / "history.csv").read_text().splitlines()
    header = lines[0].split(",")
    i, y = header.index("nose_depth_cm"), header.index("nose_y_mm")
    assert i == len(columns.BASE.columns)
    for line in lines[1:]:
        v = [float(x) for x in line.split(",")]
        assert v[i] == pytest.approx(v[y] / 10, rel=1e-8, abs=1e-12)


def test_the_run_tables_in_the_docs_are_their_declarations():
    """docs/results.md's tables of hazard.csv, strains.csv, accelerations.csv and charge_sections.csv are
    fepen.io.columns.TABLES (python tools/make_docs.py --only run-tables), and the writers use them."""
    from fepen.post import analyses

    page = (ROOT / "docs" / "results.md").read_text()
    m = re.search(r"<!-- make docs: run-tables -->\n(?:<sub>Made by .*</sub>\n)?(.*?)\n<!-- /make docs: run-tables -->",
                  page, re.S)
    assert m and m.group(1) == columns.tables_markdown(), "python tools/make_docs.py --only run-tables"
    assert analyses.HAZARD_COLUMNS == columns.table_columns("hazard.csv")
    for groups in columns.TABLES.values():
        for g in groups:
            for q in g.quantities:
                assert q.doc and q.unit and "|" not in q.doc
