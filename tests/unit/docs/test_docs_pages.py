"""tools/docs_pages.py's generators read a study's files as the study writes them: bands.csv's truth values and
figures, the page's band table with its typographic minus, and the rigid block's coverage and acceptance words
(made from a small synthetic bands.csv, not a run)."""

import importlib
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT / "tools"))
import make_docs  # noqa: E402  (it imports docs_pages and registers its blocks)

docs_pages = importlib.import_module("docs_pages")

QUANTITIES = ("Hx_mm", "Hy_mm", "Tx_mm", "Ty_mm", "final_axis_angle_deg", "nose_offset_mm", "depth_mm")


def _bands(path: Path, shots: dict) -> Path:
    """A bands.csv: shot -> (p10, p50, p90, test) for every quantity."""
    lines = ["shot,quantity,p10,p50,p90,test,inside"]
    for shot, (lo, mid, hi, test) in shots.items():
        for q in QUANTITIES:
            lines.append(f"{shot},{q},{lo},{mid},{hi},{test},{'true' if lo <= test <= hi else 'false'}")
    path.mkdir(parents=True, exist_ok=True)
    (path / "bands.csv").write_text("\n".join(lines) + "\n")
    return path


def test_read_bands_and_the_table(tmp_path):
    b = docs_pages.read_bands(_bands(tmp_path, {"C1": (-0.04, 0.5, 1.1, 0.6), "C2": (2.0, 3.0, 4.0, 9.0)})
                              / "bands.csv")
    assert b["C1"]["depth_mm"]["inside"] is True and b["C2"]["Hx_mm"]["inside"] is False
    assert b["C1"]["final_axis_angle_deg"]["p10"] == -0.04
    row = docs_pages.bands_table(b).splitlines()[2]
    assert row == "| C1 | −0.0–1.1 | 0.6 | −0.0–1.1 | 0.6 | −0–1 | 0.6 | −0–1 | 0.6 |"


def test_the_rigid_block_counts_coverage_and_judges_the_acceptance(tmp_path, monkeypatch):
    """Six of eight tests inside every band: the acceptance is met; the depth bands' misses are named."""
    shots = {f"C{i}": (100.0, 110.0, 120.0, 115.0) for i in range(1, 7)}
    shots |= {"C7": (100.0, 110.0, 120.0, 90.0), "C8": (100.0, 110.0, 120.0, 130.0)}
    bands = _bands(tmp_path / "b", shots)
    rows = "\n".join(f"{s},800,0,0,0,0,0,0,1,1,1,1,0.1,0.2,0,0,0,0,0,embedded,1" for s in shots)
    (tmp_path / "v").mkdir()
    (tmp_path / "v" / "validation.csv").write_text(
        "shot,v0_m_s,obliquity_deg,attack_deg,Hx_mm,Hy_mm,Tx_mm,Ty_mm,Hx_exp_mm,Hy_exp_mm,Tx_exp_mm,Ty_exp_mm,"
        "nose_error,tail_error,axis_deg,axis_exp_deg,axis_error_deg,nose_offset_mm,nose_offset_exp_mm,outcome,wall_s\n"
        + rows + "\n")
    made = {docs_pages.BANDS_RIGID: (bands, 12.0), make_docs.VALIDATE_RIGID: (tmp_path / "v", 1.0)}
    monkeypatch.setattr(make_docs, "made", lambda *args, ranks=1: made[args])
    monkeypatch.setattr(make_docs, "FIGURES", False)
    text = docs_pages.bands_rigid(tmp_path)
    assert "ran 1,600 rigid members in 12 s on" in text
    assert "final axis on 6 of 8 shots, the nose offset 6 of 8, Hx 6, Hy 6, Tx 6, Ty 6 and the depth 6 of 8" in text
    assert "Tx: met.**" in text
    assert "C7 go deeper than their tests, C8 shallower" in text
    assert "the deterministic line has 10.0 % and 20.0 %" in text
