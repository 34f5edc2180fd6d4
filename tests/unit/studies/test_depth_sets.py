"""Depth data sets (fepen.studies.depth) without running: reading, the closed form's limits, errors."""

import math

import pytest

from fepen.errors import InputError
from fepen.laws import target as tg
from fepen.studies import depth

HEADER = "shot,d_mm,m_kg,crh,L_mm,v_ms,fc_mpa,rho_kgm3,depth_m\n"


def test_read_set_and_its_units(tmp_path):
    f = tmp_path / "one.csv"
    f.write_text(HEADER + "a,26.9,0.906,2,242.4,277,35.2,2370,0.173\n")
    (r,) = depth.read_set(f)
    assert (r.D, r.L, r.mass, r.crh, r.V, r.fc, r.rho, r.depth) == (0.0269, 0.2424, 0.906, 2.0, 277.0, 35.2e6,
                                                                     2370.0, 0.173)
    assert r.obliquity_deg == 0.0


def test_bad_data_set_names_the_file_and_row(tmp_path):
    f = tmp_path / "bad.csv"
    f.write_text(HEADER + "a,26.9,0.906,2,,277,35.2,2370,0.173\n")
    with pytest.raises(ValueError, match="bad.csv:2"):
        depth.read_set(f)
    (tmp_path / "cols.csv").write_text("shot,d_mm\n")
    with pytest.raises(ValueError, match="missing columns"):
        depth.read_set(tmp_path / "cols.csv")
    with pytest.raises(InputError) as err:
        depth.gather_sets([tmp_path / "nowhere.csv"], shipped=False)
    assert err.value.key == "--data"


def test_closed_form_limits():
    """Forrestal's two-stage depth: continuous where the crater stage ends (P = k D = 4a at V1 = 0), and
    ln(1+x) -> x: P ~ m V1^2/(2 pi a^2 S fc) + k D for a slow tunnel stage; Forrestal et al. 1994's form
    (4 pi a^3 for the crater of two diameters)."""
    r = depth.Row("x", 0.0269, 0.242, 0.906, 2.0, 500.0, 35e6, 2370.0, 0.5)
    a, S = 0.5 * r.D, tg.forrestal_S(r.fc)
    V_crater = math.sqrt(4 * math.pi * a**3 * S * r.fc / r.mass)  # V1 = 0 at this striking speed
    for V in (V_crater * (1 - 1e-9), V_crater * (1 + 1e-9)):
        assert depth.closed_form_depth(depth.Row(**{**r.__dict__, "V": V})) == pytest.approx(4 * a, rel=1e-6)
    slow = depth.Row(**{**r.__dict__, "V": V_crater * 1.01})
    V1sq = (r.mass * slow.V**2 - 4 * math.pi * a**3 * S * r.fc) / (r.mass + 4 * math.pi * a**3 *
                                                                   tg.ogive_nose_factor(2.0) * r.rho)
    expect = r.mass * V1sq / (2 * math.pi * a * a * S * r.fc) + 4 * a
    assert depth.closed_form_depth(slow) == pytest.approx(expect, rel=1e-3)


def test_errors_summary():
    e = depth.errors([1.1, 0.8, 1.0], [1.0, 1.0, 1.0])
    assert e["count"] == 3 and e["mean_abs"] == pytest.approx(0.1) and e["bias"] == pytest.approx(-0.1 / 3)
    assert e["worst"] == pytest.approx(-0.2)


def test_table1_set_is_the_papers():
    rows = depth.table1_set()
    assert [r.name for r in rows] == [f"C{i}" for i in range(1, 9)]
    assert rows[2].V == 584.3 and rows[2].depth == pytest.approx(0.3496) and rows[2].obliquity_deg == 10.5
