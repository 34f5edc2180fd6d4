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
    m = re.search(r"<!-- make docs: history-columns -->\n(.*?)\n<!-- /make docs: history-columns -->", page, re.S)
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
