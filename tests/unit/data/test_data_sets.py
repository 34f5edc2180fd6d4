"""fepen's shipped data (fepen/data): every published measurement carries its original publication and where
it was transcribed from, the values are physical, and the libraries resolve as scenes take them."""

import csv
import math
from importlib import resources

import pytest

from fepen import data
from fepen.data import SHOTS, STEELS, TARGETS

DEPTH = resources.files("fepen.data") / "depth"
SETS = sorted(p.name for p in DEPTH.iterdir() if p.name.endswith(".csv"))


def test_table1_is_the_papers_eight_shots():
    assert list(SHOTS) == [f"C{i}" for i in range(1, 9)]
    for s in SHOTS.values():
        assert 400.0 < s.v0 < 1000.0 and 0.0 <= s.obliquity_deg < 30.0 and 0.0 <= s.attack_deg < 5.0
        # the nose ends deeper and further along the face than the tail (both from the impact point)
        assert s.Hy_mm > s.Ty_mm > 0.0 and s.Hx_mm >= s.Tx_mm >= 0.0


@pytest.mark.parametrize("name", SETS)
def test_every_depth_row_names_its_publication_and_transcription(name):
    rows = list(csv.DictReader((DEPTH / name).open()))
    assert rows, name
    shots = [r["shot"] for r in rows]
    assert len(set(shots)) == len(shots), f"{name}: a shot listed twice"
    for r in rows:
        where = f"{name} {r['shot']}"
        assert r["source"].strip() and r["compilation_row"].strip(), f"{where}: no source or compilation row"
        assert "@" in r["notes"] or r["notes"].strip(), f"{where}: where it was transcribed from"
        d, m, v, fc, rho, depth = (float(r[k]) for k in ("d_mm", "m_kg", "v_ms", "fc_mpa", "rho_kgm3", "depth_m"))
        assert 5.0 < d < 600.0 and 0.01 < m < 3000.0 and 50.0 < v < 3000.0, where
        assert 5.0 < fc < 250.0 and 1500.0 < rho < 3200.0 and 0.0 < depth < 10.0, where
        # a projectile denser than steel or lighter than a hollow shell would be a transcription slip
        L = float(r["L_mm"]) * 1e-3
        bulk = m / (math.pi / 4.0 * (d * 1e-3) ** 2 * L)
        assert 1500.0 < bulk < 20000.0, f"{where}: mean density {bulk:.0f} kg/m^3"
        assert r.get("strength_basis", "cylinder") in ("", "cylinder", "cube"), where


def test_every_named_steel_and_target_says_where_its_numbers_come_from():
    for name, steel in STEELS.items():
        assert steel.get("source"), name
        assert 7000.0 < steel["density"] < 9000.0 and steel["A"] > 0.0 and 0.0 < steel["n"] < 1.0
        assert steel["melt_temperature"] > steel["room_temperature"] > 0.0
    for name, target in TARGETS.items():
        assert target["family"] in data.FAMILIES, name
        assert 500.0 < target["density"] < 9000.0, name


def test_the_prediction_errors_say_what_made_them():
    text = (resources.files("fepen.data") / "prediction_errors.csv").read_text().splitlines()
    assert text[0].startswith("# fepen") and "prediction-errors" in text[0]  # fepen study prediction-errors
    rows = list(csv.DictReader(line for line in text if not line.startswith("#")))
    assert len(rows) > 50
