"""A history column is one declaration (issue 60, acceptance 1), in the deformable fidelity too: a Quantity
appended to fepen.io.columns' base group is written in the header and computed in every row of a plastic run,
and a charged run's body columns are exactly the declared ones (written == declared, by name)."""

import pytest
from mpi4py import MPI

from fepen import scene
from fepen.io import columns
from fepen.runs.deformable import DeformableRun

SETS = ["mesh.size=0.006", "run.end_time=2e-5", "run.checkpoint_interval=0"]


def test_a_new_declaration_is_a_new_deformable_column(tmp_path, monkeypatch):
    q = columns.Quantity(("nose_depth_cm",), "cm", "the nose's depth", lambda r: (-r.s.tip[1] * 1e2,))
    base = columns.Group(columns.BASE.name, "", columns.BASE.intro, columns.BASE.quantities + (q,))
    monkeypatch.setattr(columns, "HISTORY", (base, *columns.HISTORY[1:]))
    out = tmp_path / "r"
    run = DeformableRun(scene.load(None, SETS), out, MPI.COMM_SELF)
    run.run()
    for file in ("hazard.csv", "strains.csv", "accelerations.csv"):  # the other tables: their declared columns
        assert (out / file).read_text().splitlines()[0].split(",") == columns.table_columns(file, run), file
    lines = (out / "history.csv").read_text().splitlines()
    header = lines[0].split(",")
    i, y = header.index("nose_depth_cm"), header.index("nose_y_mm")
    assert i == len(columns.BASE.columns) and len(lines) > 5
    for line in lines[1:]:
        v = [float(x) for x in line.split(",")]
        assert v[i] == pytest.approx(v[y] / 10, rel=1e-8, abs=1e-12)


def test_a_charged_body_writes_exactly_its_declared_columns(tmp_path):
    import re

    run = DeformableRun(scene.load(None, [*SETS, "effects.charge=true"]), tmp_path / "c", MPI.COMM_SELF)
    run.run()
    body = [n for g in columns.HISTORY if g.on(run) for q in g.quantities if q.value is None for n in q.names]
    assert run.charged and run.frictional
    assert sorted(run.snapshot().extra) == sorted(body)
    head = (tmp_path / "c" / "accelerations.csv").read_text().splitlines()[0].split(",")
    assert head == columns.table_columns("accelerations.csv", run)
    declared = [re.escape(n).replace(re.escape("<point>"), r"[a-z0-9_]+") for n in columns.CHARGE_SECTIONS.columns]
    head = (tmp_path / "c" / "charge_sections.csv").read_text().splitlines()[0].split(",")
    assert len(head) > 10 and all(any(re.fullmatch(d, c) for d in declared) for c in head), head
