"""``fepen study accuracy-cost --quick``: the study's machinery end to end on coarse meshes (the full study
is a long run: docs/accuracy-cost.md)."""

import csv
import json

import pytest
from conftest import run_fepen


def test_quick_study(tmp_path):
    r = run_fepen("study", "accuracy-cost", "--quick", "--out", tmp_path, "--ranks", "1")
    assert r.returncode == 0, r.stderr
    rows = {row["name"]: row for row in csv.DictReader((tmp_path / "study.csv").open())}
    assert set(rows) == {"default-8mm", "default-6mm", "rigid", "altitude-step-6mm"}
    assert not any(row["failed"] for row in rows.values())
    num = {k: {c: float(v) for c, v in row.items() if c in ("steps", "dt_s", "Hy_mm", "cells", "loop_s")}
           for k, row in rows.items()}
    # the rigid fidelity integrates the body, not the mesh: far fewer steps
    assert num["rigid"]["steps"] < num["default-6mm"]["steps"] / 10
    # the default eigenvalue step: larger steps than the altitude step's on the same mesh, the same
    # penetration within 1 %
    assert num["default-6mm"]["dt_s"] > 1.5 * num["altitude-step-6mm"]["dt_s"]
    assert num["altitude-step-6mm"]["Hy_mm"] == pytest.approx(num["default-6mm"]["Hy_mm"], rel=0.01)
    assert num["default-6mm"]["cells"] > num["default-8mm"]["cells"]
    assert (tmp_path / "pareto.png").stat().st_size > 10000
    assert "time loop ~ h^-" in (tmp_path / "study.md").read_text()
    assert "exponents" in json.loads((tmp_path / "study.json").read_text())


def test_study_refuses_bad_ranks(tmp_path):
    r = run_fepen("study", "accuracy-cost", "--ranks", "0", "--out", tmp_path)
    assert r.returncode == 2 and "--ranks" in r.stderr and "Traceback" not in r.stderr
