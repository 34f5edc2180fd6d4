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
    assert [row["shot"] for row in rows] == ["a", "b"]
    for row in rows:
        P = float(row["depth_m"])
        # Forrestal-S in the rigid fidelity with the closed form's linear crater (k = 2), no separation angle and
        # no free face is the closed form's law: within 3 % (the nose entering and the onset angle differ)
        rel = 0.03
        assert float(row["forrestal_S_depth_m"]) == pytest.approx(float(row["closed_form_depth_m"]), rel=rel)
        assert P > 0 and math.isfinite(float(row["default_depth_m"]))
    e = depth.errors([float(x["default_depth_m"]) for x in rows], [float(x["depth_m"]) for x in rows])
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


#: the unit suffix of each unit depth.csv declares (fepen.studies.depth.DEPTH_CSV)
SUFFIX = {"m": "_m", "mm": "_mm", "m/s": "_m_s", "kg": "_kg", "deg": "_deg", "Pa": "_Pa", "s": "_s", "J": "_J",
          "kg/m^3": "_kg_m3"}


def test_every_number_of_depth_csv_carries_its_unit(tmp_path):
    """depth.csv's header is DEPTH_CSV's; a column with a number in it is declared with a unit its name ends in,
    or declared dimensionless ("–"), and holds the shot's SI value (the data set's mm, MPa read as m, Pa)."""
    data = tmp_path / "mine.csv"
    data.write_text(HEADER + ROWS)
    depth.validate_depth([data], out=tmp_path / "out", shipped=False)
    with open(tmp_path / "out" / "depth.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    header = list(rows[0])
    assert header == [c for c, _, _ in depth.DEPTH_CSV]
    unit = {c: u for c, u, _ in depth.DEPTH_CSV}
    for c in header:
        numeric = all(_number(r[c]) for r in rows)
        assert numeric == (unit[c] != "text"), c
        if numeric and unit[c] != "–":
            assert c.endswith(SUFFIX[unit[c]]), (c, unit[c])
    assert [c for c in header if unit[c] == "–"] == ["crh"]
    a = rows[0]
    assert (a["set"], a["shot"], a["strength_basis"]) == ("mine", "a", "cylinder")
    for c, want in (("diameter_m", 0.0269), ("length_m", 0.2424), ("mass_kg", 0.906), ("crh", 2.0),
                    ("velocity_m_s", 277.0), ("fc_Pa", 35.2e6), ("density_kg_m3", 2370.0), ("depth_m", 0.173),
                    ("obliquity_deg", 0.0)):
        assert float(a[c]) == pytest.approx(want, rel=1e-12), c
    assert 0.05 < float(a["default_depth_m"]) < 0.5 and 0.05 < float(a["closed_form_depth_m"]) < 0.5


def _number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True
