"""make docs' generators of docs/accuracy-cost.md, docs/hard-cases.md and docs/wear.md (tools/docs_cost.py): what
they read from a study's or a run's outputs and how they print it, on made-up outputs (the commands themselves
run in `make docs`; the cheap blocks are re-run by tests/system/test_docs_figures.py)."""

import csv
import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tools"))
import make_docs  # noqa: E402  (tools/ is not a package; it imports docs_cost and registers its blocks)

docs_cost = sys.modules["docs_cost"]


def _study_csv(path: Path, rows: list[dict]) -> Path:
    from fepen.studies.accuracy_cost import COLUMNS

    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, COLUMNS)
        w.writeheader()
        for r in rows:
            w.writerow(r)
    return path


def _run(shot, name, group, h, process_s, H_vs_finest, nose_error, max_peeq, ranks=2):
    return {"shot": shot, "name": name, "group": group, "h_mm": h, "ranks": ranks, "process_s": process_s,
            "H_vs_finest": H_vs_finest, "nose_error": nose_error, "max_peeq": max_peeq, "cells": 100, "steps": 10}


def test_the_settings_table_quotes_each_questions_run(tmp_path):
    rows = []
    for shot, k in (("C3", 1.0), ("C7", 2.0)):
        rows += [_run(shot, "default-2.5mm", "mesh", 2.5, 16.3 * k, 0.0123 * k, 0.036, 0.0002 * k),
                 _run(shot, "default-1.6mm", "mesh", 1.6, 61.6 * k, 0.0041 * k, 0.037, 0.0004 * k),
                 _run(shot, "default-1.2mm", "mesh", 1.2, 174.6 * k, 0.0, 0.038, 0.0008 * k),
                 _run(shot, "rigid", "fidelity", 2.5, 2.4 * k, 0.0066 * k, 0.039, 0.0),
                 _run(shot, "altitude-step-1.2mm", "costlier", 1.2, 250.0, 0.004, 0.039, 0.0007 * k),
                 _run(shot, "default-2.5mm-1rank", "ranks", 2.5, 23.3, 0.0123, 0.036, 0.0002, ranks=1)]
    rows.append({"shot": "C7", "name": "graded-4mm-nose1.6mm", "group": "cheaper", "h_mm": 4, "ranks": 2,
                 "failed": "exit 1"})
    table = docs_cost.settings_table(docs_cost.read_study_rows(_study_csv(tmp_path / "study.csv", rows)))
    lines = table.splitlines()
    assert lines[0] == "| question | setting | cost (C3 / C7, 2 ranks) | accuracy |"
    rigid = next(ln for ln in lines if ln.startswith("| depth only"))
    assert "| 2.4 s / 4.8 s |" in rigid and "within 0.7 % / 1.3 % of the finest" in rigid
    assert "Table 1 nose error 3.9 % / 3.9 %" in rigid
    assert next(ln for ln in lines if ln.startswith("| the same, converged")).endswith(
        "| 62 s / 123 s | 0.4 % / 0.8 % from the finest run |")
    deformation = next(ln for ln in lines if ln.startswith("| deformation"))
    assert "plastic at 1.2 mm" in deformation
    assert "max PEEQ 0.0008 / 0.0016 (altitude step: 0.0007 / 0.0014); at 2.5 mm 0.0002 / 0.0004" in deformation


def test_the_settings_table_leaves_out_the_questions_a_quick_study_does_not_answer(tmp_path):
    rows = [_run("C3", "default-8mm", "mesh", 8, 5.0, 0.02, 0.05, 0.0, ranks=1),
            _run("C3", "default-6mm", "mesh", 6, 6.0, 0.0, 0.04, 0.0, ranks=1),
            _run("C3", "rigid", "fidelity", 6, 2.0, 0.01, 0.04, 0.0, ranks=1),
            _run("C3", "altitude-step-6mm", "costlier", 6, 7.0, 0.001, 0.04, 0.0, ranks=1)]
    lines = docs_cost.settings_table(docs_cost.read_study_rows(_study_csv(tmp_path / "s.csv", rows))).splitlines()
    assert lines[0] == "| question | setting | cost (C3, 1 rank) | accuracy |"
    assert [ln.split(" | ")[0] for ln in lines[2:]] == ["| depth only (Hy), a first trajectory",
                                                       "| deformation (max PEEQ, hazard map, gauges)"]
    assert "at 2.5 mm" not in lines[-1]


def _hard(case, h, **kw):
    row = {"case": case, "h_mm": h, "exit": 0, "process_s": 3.0, "outcome": "embedded", "energy_error": 2.1e-7,
           "steps": 100, "dt_s": 1.054e-7, "Hx_mm": 10.0, "Hy_mm": 400.0, "Tx_mm": 5.0, "Ty_mm": 300.0,
           "residual_speed_m_s": 2.0, "max_peeq": 0.05}
    row.update(kw)
    return row


def test_a_hard_case_beyond_the_method_prints_its_line_in_a_row_as_wide_as_the_others():
    stop = {"case": "soft_breaks", "h_mm": 2.5, "exit": 3, "process_s": 6.0,
            "message": "fepen: simulation stopped: beyond the method: ..."}
    lines = docs_cost.hard_table([_hard("oblique_900_45", 2.5), stop]).splitlines()
    assert {ln.count("|") for ln in lines} == {13}
    assert lines[3].startswith("| soft_breaks | 2.5 | exit 3: fepen: simulation stopped")
    assert "wall" not in lines[0]  # the machine's figure is said once, masked


def test_the_hard_cases_cost_line_is_masked_and_names_the_largest_energy_error():
    stop = {"case": "soft_breaks", "h_mm": 2.5, "exit": 3, "process_s": 6.0, "message": "x"}
    line = docs_cost._cost_line([_hard("a", 2.5, energy_error=3e-7), _hard("b", 4, energy_error=9.8e-7), stop], 2)
    assert "largest energy balance error of the 2 that end: 9.8e-07 (goal 1 %); 1 stopped" in line
    assert make_docs.masked(line) != line  # its wall time is the drift test's masked pattern


def test_the_end_points_and_their_changes_coarsest_first():
    by = {0.004: {"oblique_900_45": _hard("oblique_900_45", 4, Hx_mm=503.6, Hy_mm=414.2)},
          0.0025: {"oblique_900_45": _hard("oblique_900_45", 2.5, Hx_mm=530.4, Hy_mm=426.4)},
          0.0016: {"oblique_900_45": _hard("oblique_900_45", 1.6, Hx_mm=556.7, Hy_mm=427.2)}}
    for h in by:
        for case in ("attack_900_5", "ricochet_250_75"):
            by[h][case] = {"case": case, "exit": 3}  # stopped: no end point, no row
    lines = docs_cost.endpoint_table(by).splitlines()
    assert lines[0] == "| case | 4 mm | 2.5 mm | 1.6 mm | change 4 → 2.5 | change 2.5 → 1.6 |"
    assert lines[2:] == ["| 45° obliquity, 900 m/s | 503.6, 414.2 | 530.4, 426.4 | 556.7, 427.2 | +26.8, +12.2 | "
                         "+26.3, +0.8 |"]
    assert [docs_cost._signed(v) for v in (-0.04, -18.94)] == ["+0.0", "−18.9"]  # no "−0.0", a true minus


def _validation(folder: Path, nose: float, tail: float, axis: float, loss=None) -> Path:
    folder.mkdir()
    fields = ["shot", "v0_m_s", "nose_error", "tail_error", "axis_deg", "axis_error_deg"]
    with open(folder / "validation.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fields)
        w.writeheader()
        for i, shot in enumerate(("C7", "C8")):
            w.writerow({"shot": shot, "v0_m_s": 820 + 73 * i, "nose_error": nose + 0.01 * i, "tail_error": tail,
                        "axis_deg": 20.0 - 19 * i, "axis_error_deg": -axis})
            if loss is not None:
                (folder / shot).mkdir()
                (folder / shot / "summary.json").write_text(json.dumps(
                    {"mass_loss_percent": loss + i, "length_change_mm": -8.4 - i}))
    return folder


@pytest.mark.parametrize("grow, verdict", [(0.009, "within the rule"), (0.011, "beyond the rule (nose)")])
def test_the_wear_tables_means_line_judges_the_fidelity_by_the_one_point_rule(tmp_path, grow, verdict):
    off = make_docs.read_validation(_validation(tmp_path / "off", 0.10, 0.12, 7.8) / "validation.csv")
    on = docs_cost.read_wear(_validation(tmp_path / "on", 0.10 + grow, 0.12, 7.9, loss=3.5))
    text = docs_cost.wear_table("rigid", off, on)
    assert "| C8 | 893 | 4.50 | -9.40 | 11.0 → " in text
    means = text.splitlines()[-1]
    assert means.startswith("Means, rigid: nose 10.5 → ")
    assert means.endswith(f"+0.1°: {verdict}).")
    assert "the largest 4.50 % (C8); the bodies shorten by 8.4–9.4 mm (C7 8.4, C8 9.4 mm)" in docs_cost._losses(
        "Rigid", on)
