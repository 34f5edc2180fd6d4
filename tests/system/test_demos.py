"""Demos are plain scripts; here they run on coarse settings through subprocess."""

import os
import subprocess
import sys

import pytest
from conftest import ROOT

from fepen.studies import processes


def test_taylor_demo_against_the_4340_experiment(tmp_path):
    """Acceptance 3 on the coarsest mesh: the 4340 steel Taylor rod's final length within 5 % of the test."""
    r = subprocess.run([sys.executable, "demos/verification/taylor.py", "--sizes", "1.2", "--out", str(tmp_path),
                        "--cases", "4340 steel, 208 m/s"], cwd=ROOT, capture_output=True, text=True,
                       env=dict(os.environ, PYTHONPATH=str(ROOT)), timeout=600)
    assert r.returncode == 0, r.stderr
    row = [ln for ln in r.stdout.splitlines() if ln.startswith("4340")][0].split()
    error_percent = float(row[-3])
    assert abs(error_percent) < 5.0


def test_mpi_shot_demo(tmp_path):
    """The MPI demo on a coarse mesh and a short time: runs on 2 ranks and draws the deformed projectile."""
    r = subprocess.run([sys.executable, "demos/shot_mpi.py", "--out", str(tmp_path), "--set", "mesh.size=0.004",
                        "--set", "run.end_time=6e-5", "--set", "run.output_interval=2e-5"], cwd=ROOT,
                       capture_output=True, text=True, env=dict(os.environ, PYTHONPATH=str(ROOT)), timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    assert "'ranks': 2" in r.stdout and (tmp_path / "demo.png").stat().st_size > 5000


def test_hard_cases_demo(tmp_path):
    """demos/hard_cases/run_all.py on one case, a coarse mesh, 2 ranks: one table row, the slab perforated (6 s;
    the ricochet case took 87 s to its end here, and tests/system/test_hard_cases.py runs it)."""
    r = subprocess.run([sys.executable, "demos/hard_cases/run_all.py", "--cases", "slab_perforation", "--sizes",
                        "0.006", "--ranks", "2", "--out", str(tmp_path), "--markdown", str(tmp_path / "t.md")],
                       cwd=ROOT, capture_output=True, text=True, env=dict(os.environ, PYTHONPATH=str(ROOT)),
                       timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    rows = [ln for ln in (tmp_path / "t.md").read_text().splitlines() if ln.startswith("| slab_perforation")]
    assert len(rows) == 1 and "| perforated |" in rows[0]


def test_charge_demo_tied_against_frictional(tmp_path):
    """demos/charge/charge_800.py --quick on 2 ranks: both contacts run, every picture is written, and the
    comparison shows what the contact changes: the frictional charge, free to slide and to open at its
    rear, rings harder (a higher raw peak acceleration) than the bonded one; the shells' peaks agree
    within 3 %; friction dissipates energy, the wall opens and slides but never interpenetrates."""
    import json

    r = subprocess.run([sys.executable, "demos/charge/charge_800.py", "--quick", "--ranks", "2", "--out", str(tmp_path),
                        "--docs", str(tmp_path / "img")], capture_output=True, text=True, cwd=ROOT,
                       env=dict(os.environ, PYTHONPATH=str(ROOT)), timeout=900)
    assert r.returncode == 0, r.stderr
    tied, fric = json.loads((tmp_path / "comparison.json").read_text())
    # harder by 7.6 % at --quick with the law of issue 58 (over 10 % before it; 10.6 % in docs/charge.md's full runs)
    assert fric["charge_raw_peak_g"] < 1.05 * tied["charge_raw_peak_g"] < 0
    assert fric["shell_peak_g"] == pytest.approx(tied["shell_peak_g"], rel=3e-2)
    assert fric["friction_J"] > 0 and fric["slip_max_mm"] > 0.01 and fric["gap_max_mm"] > 0.01
    assert fric["penetration_max_mm"] < 0.01 * 4.0
    assert len(list((tmp_path / "img").glob("charge-*.png"))) == 8
    # the safety verdict tells the contacts apart: the sliding charge is driven harder onto the cavity's step
    # (measured 0.74 against the bonded 1.07, its yield passed), the bonded one is pulled by its wall instead
    # (tension 0.86 against 1.48: the sliding charge's rear opens rather than pulls)
    assert fric["strength_margin"] < tied["strength_margin"]
    assert fric["tension_margin"] > tied["tension_margin"]


@pytest.mark.parametrize("ranks", [1, 2])
def test_layered_structure_demo(tmp_path, ranks):
    """Two slabs 1 m apart over soil, rigid, on 1 and 2 ranks: perforates both, stops in the soil."""
    cmd = [sys.executable, "demos/targets/layered_structure.py", "--out", str(tmp_path)]
    if ranks > 1:
        cmd = [processes.launcher(), "-n", str(ranks), *cmd]
    r = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, env=dict(os.environ, PYTHONPATH=str(ROOT)),
                       timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    assert "outcome: embedded" in r.stdout
    rows = [ln.split() for ln in r.stdout.splitlines() if ln.startswith(("concrete", "soil"))]
    assert [row[0] for row in rows] == ["concrete", "concrete", "soil"]
    assert rows[0][5] != "-" and rows[1][5] != "-" and rows[2][5] == "-"  # slabs left, soil not


@pytest.mark.parametrize("ranks", [1, 2])
def test_metal_plate_demo(tmp_path, ranks):
    """The rod into 6061-T6511 at 800 m/s: within 1 % of Forrestal and Warren's closed form."""
    cmd = [sys.executable, "demos/targets/metal_plate.py", "--out", str(tmp_path), "--speeds", "800"]
    if ranks > 1:
        cmd = [processes.launcher(), "-n", str(ranks), *cmd]
    r = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, env=dict(os.environ, PYTHONPATH=str(ROOT)),
                       timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    row = [ln.split() for ln in r.stdout.splitlines() if ln.strip().startswith("800")][0]
    assert abs(float(row[3].rstrip("%"))) < 1.0
