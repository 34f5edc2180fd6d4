"""`fepen validate-depth` end to end on a small data set: the rigid fidelity against the closed form it
reduces to, the files it writes, bad input."""

import csv
import math

import pytest

from fepen.laws import target as tg
from fepen.studies import depth

HEADER = "shot,d_mm,m_kg,crh,L_mm,v_ms,fc_mpa,rho_kgm3,depth_m\n"
ROWS = "a,26.9,0.906,2,242.4,277,35.2,2370,0.173\nb,30.5,1.6,3,305,800,51,2300,0.9\n"


def test_validate_depth_writes_table_and_figure(fepen_cli, tmp_path):
    data = tmp_path / "mine.csv"
    data.write_text(HEADER + ROWS)
    out = tmp_path / "out"
    r = fepen_cli("validate-depth", "--data", data, "--only", "--out", out, "--set", "effects.crater=linear",
                  "--set", "target.crater_depth_factor=2", "--set", "target.separation_angle_deg=0",
                  "--set", "effects.free_surface=false")
    assert r.returncode == 0, r.stderr
    assert "mine: 2 shots" in r.stdout
    for name in ("depth.csv", "depth.md", "depth.png"):
        assert (out / name).stat().st_size > 0
    rows = list(csv.DictReader(open(out / "depth.csv")))
    assert [row["name"] for row in rows] == ["a", "b"]
    for row in rows:
        P = float(row["depth"])
        # Forrestal-S in the rigid fidelity with the closed form's linear crater (k = 2), no separation angle and
        # no free face is the closed form's law: within 3 % (the nose entering and the onset angle differ)
        rel = 0.03
        assert float(row["forrestal-S"]) == pytest.approx(float(row["closed form"]), rel=rel)
        assert P > 0 and math.isfinite(float(row["default"]))
    e = depth.errors([float(x["default"]) for x in rows], [float(x["depth"]) for x in rows])
    assert f"{100 * e['mean_abs']:.1f} %" in (out / "depth.md").read_text()


def test_scaled_S_at_the_calibration_size_is_forrestal_scaled():
    """The default law in the rigid fidelity: a deeper shot for a weaker target and, at one strength and
    speed, a relatively deeper shot for a bigger geometrically scaled projectile (the size effect)."""
    small = depth.Row("s", 0.0203, 0.1585, 0.214, 2.0, 450.0, 40e6, 2400.0, 0.17)
    big = depth.Row("b", 0.203, 1.585, 214.0, 2.0, 450.0, 40e6, 2400.0, 2.4)
    Ps, Pb = depth.rigid_depth(small), depth.rigid_depth(big)
    S = lambda D: tg.strength_S(40e6, D, *tg.S_MODELS["scaled-S"])  # noqa: E731
    assert S(0.203) < S(0.0203)
    assert Pb / big.D > 1.2 * Ps / small.D
    weak = depth.Row("w", 0.0203, 0.1585, 0.214, 2.0, 450.0, 15e6, 2400.0, 0.17)
    assert depth.rigid_depth(weak) > 1.3 * Ps


def test_validate_depth_bad_input_exits_2(fepen_cli, tmp_path):
    r = fepen_cli("validate-depth", "--data", tmp_path / "none.csv", "--out", tmp_path / "o")
    assert r.returncode == 2 and "--data" in r.stderr and "Traceback" not in r.stderr
    r = fepen_cli("validate-depth", "--set", "target.strength_model=magic", "--out", tmp_path / "o")
    assert r.returncode == 2 and "target.strength_model" in r.stderr
