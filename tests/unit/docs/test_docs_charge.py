"""tools/docs_charge.py's generators read what the scripts write: taylor.py's printed rows and the table made
from them, the charged shot's comparison words (which way each figure moved, the pictures' figures from the
history), the tension's "at the stop" and the rigid checks' rows (from small synthetic outputs, not runs)."""

import importlib
import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT / "tools"))
import make_docs  # noqa: E402  (it imports docs_charge and registers its blocks)

docs_charge = importlib.import_module("docs_charge")

TAYLOR = """case                      h_mm   cells L_final_mm L_exp_mm error_% energy_err  wall_s
4340 steel, 208 m/s       1.20    3302     22.570    22.48   +0.40    9.0e-04    26.0
4340 steel, 208 m/s       0.80    9799     22.557    22.48   +0.35    3.0e-04     9.7
OFHC copper, 146 m/s      1.20    3302     19.702    18.69   +5.39    9.7e-04     7.8
OFHC copper, 146 m/s      0.80    9799     19.704    18.69   +5.40    7.5e-04    35.7
"""


def test_taylor_rows_and_table():
    rows = docs_charge.read_taylor(TAYLOR)
    assert [r["case"] for r in rows] == ["4340 steel, 208 m/s"] * 2 + ["OFHC copper, 146 m/s"] * 2
    assert rows[1]["cells"] == 9799 and rows[1]["final"] == pytest.approx(22.557) and rows[3]["error"] == 5.40
    text = docs_charge.taylor_block(TAYLOR, 80.0)
    assert "| 4340 steel, 208 m/s | 0.8 | 9,799 | 22.557 | 22.48 | +0.35 % | 3.0e-04 | 10 s on 1 rank |" in text
    # the two finest meshes of steel differ by |22.557/22.570 - 1| = 0.058 %
    assert "4340 steel, 208 m/s: +0.35 to +0.40 % over the meshes, 0.06 % between the two finest" in text
    assert "OFHC copper, 146 m/s: +5.39 to +5.40 %" in text and "80 s on 1 rank in all" in text
    masked = make_docs.masked(text)
    assert "on 1 rank" not in masked  # every wall time is the machine's: masked by the drift test


def _row(contact, shell, charge, raw, mid, gap=None):
    r = {"contact": contact, "depth_mm": 586.8, "shell_peak_g": shell, "shell_peak_t_us": 156.0,
         "shell_peak_depth_mm": 120.2, "shell_raw_peak_g": shell * 1.01, "charge_peak_g": charge,
         "charge_peak_t_us": 99.0 if gap else 156.0, "charge_peak_depth_mm": 77.7 if gap else 120.2,
         "charge_raw_peak_g": raw, "axis_front_min_MPa": -80.0, "axis_mid_min_MPa": mid}
    if gap:
        r.update(gap_max_mm=gap, slip_max_mm=0.31)
    return r


def _summaries(tmp_path):
    (tmp_path / "frictional").mkdir(exist_ok=True)
    hist = ["t_s,interface_slip_max_mm,interface_gap_max_mm"]
    hist += [f"{t * 1e-6},{s},{g}" for t, s, g in ((0, 0, 0), (50, 0.1, 0.1), (110, 0.30, 0.29), (200, 0.31, 0.30),
                                                    (1500, 0.27, 0.26))]
    (tmp_path / "frictional" / "history.csv").write_text("\n".join(hist) + "\n")
    mid = {"tied": {"charge_mean": -2.3e-3, "max": -2.0e-3}, "frictional": {"charge_mean": -5.1e-3, "max": -2.1e-3}}
    return {c: {"folder": tmp_path / c, "charge": {"cross_sections": {"mid": mid[c]}}} for c in ("tied", "frictional")}


def test_contact_words_say_which_way_each_figure_moved(tmp_path):
    rows = {"tied": _row("tied", -66000.0, -66003.3, -77600.0, -31.0),
            "frictional": _row("frictional", -66000.0, -68904.0, -83420.0, -67.0, gap=0.307)}
    words = docs_charge.contact_words(rows, _summaries(tmp_path), 2.5)
    assert "the shell's to 0.005 %" in words
    assert "4.4 % above the shell's" in words and "7 % above the bonded charge's" in words
    assert "2.2 times the bonded charge's" in words and "0.12 of the 2.5 mm element" in words
    # the slip reaches 95 % of its largest (0.31 mm) at the first row at or above 0.2945 mm: 110 µs
    assert "95 % of its largest at 110 µs and ends at 0.27 mm, the gap at 0.26 mm" in words
    assert "the sliding charge's mean axial strain is −5.1e-3" in words
    rows["frictional"]["charge_peak_g"] = -65000.0
    assert "1.5 % below the shell's" in docs_charge.contact_words(rows, _summaries(tmp_path), 2.5)


def test_tension_at_the_stop():
    c = {"margin": 0.632, "demand": 8.71e6, "where": {"behind_tip_mm": 40.4}, "time_s": 1.816e-3}
    assert docs_charge._tension(c, 1.82e-3) == "0.632 (8.71 MPa at 40.4 mm, at the stop, 1816 µs)"
    c["time_s"] = 3.8e-5
    assert docs_charge._tension(c, 1.82e-3) == "0.632 (8.71 MPa at 40.4 mm, 38 µs)"


def test_rigid_checks_rows(tmp_path, monkeypatch):
    def fake(*args, ranks=1):
        out = Path(args[args.index("--out") + 1])
        out.mkdir(parents=True)
        ricochet = "impact.obliquity_deg=75" in args
        (out / "summary.json").write_text(json.dumps({"outcome": "ricochet" if ricochet else "perforated",
                                                      "residual_speed_m_s": 183.06 if ricochet else 707.4}))
        return 1.0

    monkeypatch.setattr(make_docs, "fepen", fake)
    text = docs_charge.rigid_checks(tmp_path)
    assert "| 250 m/s at 75° | ricochet, leaving at 183 m/s | ricochet |" in text
    assert ("| 800 m/s into a 150 mm slab | perforated, leaving at 707 m/s | perforated, residual speed reported |"
            in text)


def test_the_blocks_are_registered():
    for name in ("charge-contact", "charge-mesh", "charge-console", "charge-quick", "charge-angles",
                 "charge-safety-mesh", "mesh-quality", "taylor", "rigid-checks"):
        assert make_docs.BLOCKS[name].make.__module__ == "docs_charge"
    cheap = [n for n, b in make_docs.BLOCKS.items() if b.make.__module__ == "docs_charge" and b.cheap]
    assert cheap == ["rigid-checks"]
