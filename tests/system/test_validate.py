"""The Table 1 sweep and a run through the command line, with the rigid projectile."""

import csv
import json

import pytest


def test_validate_rigid_writes_table_1(fepen_cli, tmp_path):
    r = fepen_cli("validate", "--set", "effects.fidelity=rigid", "--out", tmp_path, timeout=900)
    assert r.returncode == 0, r.stderr
    rows = {row["shot"]: row for row in csv.DictReader(open(tmp_path / "validation.csv"))}
    assert sorted(rows) == [f"C{i}" for i in range(1, 9)]
    assert all(row["outcome"] == "embedded" for row in rows.values())
    depth = {k: float(v["Hy_mm"]) for k, v in rows.items()}
    # deeper with speed, at near-normal incidence and at ~10 degrees
    assert depth["C2"] < depth["C8"]
    assert depth["C3"] < depth["C4"] < depth["C5"]
    for k, v in rows.items():  # within a factor of the test everywhere (no tuning)
        assert 0.7 < float(v["Hy_mm"]) / float(v["Hy_exp_mm"]) < 1.3, k
    for f in ("validation.md", "validation.png", "C3/summary.json", "C3/history.csv", "C3/history.png"):
        assert (tmp_path / f).is_file()
    assert "| C7 |" in (tmp_path / "validation.md").read_text()
    import math  # the attitude: the final axis from the row's own nose and tail, the test's from Table 1's

    for k, v in rows.items():
        f = {c: float(v[c]) for c in ("Hx_mm", "Hy_mm", "Tx_mm", "Ty_mm", "Hx_exp_mm", "Hy_exp_mm", "Tx_exp_mm",
                                       "Ty_exp_mm", "axis_deg", "axis_exp_deg", "axis_error_deg")}
        own = math.degrees(math.atan2(f["Hx_mm"] - f["Tx_mm"], f["Hy_mm"] - f["Ty_mm"]))
        assert f["axis_deg"] == pytest.approx(own, abs=1e-3), k
        assert f["axis_exp_deg"] == pytest.approx(math.degrees(math.atan2(f["Hx_exp_mm"] - f["Tx_exp_mm"],
                                                                          f["Hy_exp_mm"] - f["Ty_exp_mm"])), abs=1e-3)
        assert f["axis_error_deg"] == pytest.approx(f["axis_deg"] - f["axis_exp_deg"], abs=1e-3)
    assert float(rows["C7"]["axis_exp_deg"]) == pytest.approx(41.5, abs=0.05)


def test_validate_refuses_impact_overrides(fepen_cli, tmp_path):
    r = fepen_cli("validate", "--set", "impact.velocity=600", "--out", tmp_path)
    assert r.returncode == 2 and "impact.velocity" in r.stderr and "Traceback" not in r.stderr


def test_run_names_the_experiment_errors(fepen_cli, tmp_path):
    r = fepen_cli("run", "--set", "effects.fidelity=rigid", "--set", "impact.shot=C6", "--out", tmp_path)
    assert r.returncode == 0, r.stderr
    s = json.loads((tmp_path / "summary.json").read_text())
    e = s["experiment"]
    assert e["shot"] == "C6" and e["Hy_mm"] == 316.0
    H = (s["Hx_mm"] - 154.9, s["Hy_mm"] - 316.0)
    assert e["nose_error"] == pytest.approx((H[0] ** 2 + H[1] ** 2) ** 0.5 / (154.9**2 + 316.0**2) ** 0.5)
    assert s["scene"]["impact"]["velocity"] == 594.7 and s["outcome"] == "embedded"
    for k in ("Hx_mm", "Hy_mm", "Tx_mm", "Ty_mm", "depth_mm", "residual_speed_m_s", "steps", "dt_s", "wall_s",
              "energy_error", "max_peeq", "mass_kg", "cells", "ranks", "versions"):
        assert k in s
    header = (tmp_path / "history.csv").read_text().splitlines()[0].split(",")
    for k in ("t_s", "nose_x_mm", "nose_y_mm", "tail_x_mm", "tail_y_mm", "speed_m_s", "decel_g", "contact_area_m2"):
        assert k in header
    import numpy as np

    h = np.genfromtxt(tmp_path / "history.csv", delimiter=",", names=True)
    # loaded area: at most the nose's lateral area plus the shank side, at least some of the nose
    assert 1e-4 < h["contact_area_m2"].max() < 6e-3
