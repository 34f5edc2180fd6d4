"""Every summary carries the envelope verdict and the intervals (docs/uncertainty.md), and a shot outside the
envelope says so in one line, from the command line and from the API."""

import json
import logging
import subprocess
import sys

import pytest

import fepen


def _cli(tmp_path, *sets):
    out = tmp_path / "run"
    args = [sys.executable, "-m", "fepen", "run", "--out", str(out), "--set", "effects.fidelity=rigid"]
    for s in sets:
        args += ["--set", s]
    p = subprocess.run(args, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    return p, json.loads((out / "summary.json").read_text())


def test_the_c3_summary_brackets_the_test(tmp_path):
    p, s = _cli(tmp_path)
    lo, hi = s["depth_interval_mm"]
    assert lo < s["depth_mm"] < hi and lo < 349.6 < hi  # Table 1's C3: 349.6 mm deep
    assert 0.6 < lo / s["depth_mm"] < 0.8 and 1.1 < hi / s["depth_mm"] < 1.35
    llo, lhi = s["lateral_interval_mm"]
    assert llo < 81.4 < lhi
    assert s["envelope"]["inside"] and s["envelope"]["outside"] == []
    assert s["interval"]["levels"] == [0.1, 0.9] and s["interval"]["extrapolated"] is False
    assert "171 shots in 13 public sets" in s["interval"]["depth"]
    assert f"depth_interval_mm = {lo:.4g} to {hi:.4g}" in p.stdout
    assert "inside the validated envelope" in p.stdout
    assert "outside" not in p.stderr


def test_a_shot_outside_says_so_once_before_it_runs(tmp_path):
    p, s = _cli(tmp_path, "impact.velocity=2100", "projectile.crh=8")
    lines = [line for line in p.stderr.splitlines() if "outside the validated envelope" in line]
    assert len(lines) == 1
    assert "striking speed 2100 m/s" in lines[0] and "ogive CRH 8 is 33.3 % above" in lines[0]
    assert not s["envelope"]["inside"]
    assert {o["key"] for o in s["envelope"]["outside"]} == {"impact.velocity", "projectile.crh"}
    assert s["interval"]["extrapolated"] is True
    assert "extrapolated" in p.stdout


def test_a_perforation_has_no_depth_interval_and_says_why(tmp_path):
    _, s = _cli(tmp_path, "target.thickness=0.1")
    assert s["outcome"] == "perforated"
    assert s["depth_interval_mm"] is None
    assert s["interval"]["depth"].startswith("none: the shot's outcome is perforated")
    assert not s["envelope"]["inside"]


def test_the_api_says_it_in_one_line_too(tmp_path, caplog):
    with caplog.at_level(logging.WARNING, logger="fepen"):
        r = fepen.run({"effects": {"fidelity": "rigid"}, "impact": {"velocity": 2100.0}}, out=tmp_path / "api")
    lines = [m for m in caplog.messages if "outside the validated envelope" in m]
    assert len(lines) == 1 and "\n" not in lines[0]
    assert "inside_envelope=False" in repr(r)
    assert r.summary["depth_interval_mm"][0] < r.summary["depth_mm"]


@pytest.mark.parametrize("sets", [["target.material=granite"], ["target.strength_model=cavity-expansion"]])
def test_no_interval_without_errors_on_data(tmp_path, sets):
    _, s = _cli(tmp_path, *sets)
    assert s["depth_interval_mm"] is None and s["interval"]["depth"].startswith("none")
