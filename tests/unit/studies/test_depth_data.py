"""The shipped depth sets (fepen/data/depth, SOURCES.md there) without running: every file reads, holds the
compilation rows and shot counts of docs/validation-depth.md, names its source, and has depths in metres."""

import csv

import pytest

from fepen.studies import depth

#: set -> (first, last) compilation row (Data.xlsx "Number"), docs/validation-depth.md
RANGES = {
    "forrestal1994_d26.9mm": (39, 55), "forrestal1994_d76.2mm": (56, 70), "frew2006": (71, 93),
    "feng2018": (24, 38), "geng2020": (118, 129), "gu2004": (168, 173), "forrestal1996": (236, 276),
    "oneil1999": (541, 548), "sun2010": (628, 638), "wu2020": (693, 699), "yao2025": (886, 891),
    "zhai2021": (892, 893),
}
COUNTS = {"forrestal1994_d26.9mm": 17, "forrestal1994_d76.2mm": 15, "frew2006": 23, "feng2018": 15,
          "geng2020": 12, "gu2004": 6, "forrestal1996": 41, "oneil1999": 8, "sun2010": 11, "wu2020": 7,
          "yao2025": 6, "zhai2021": 2}
US_SETS = {"forrestal1994_d26.9mm", "forrestal1994_d76.2mm", "frew2006", "forrestal1996", "oneil1999"}


def _raw(name):
    with open(depth.shipped_sets()[name], newline="") as f:
        return list(csv.DictReader(f))


def test_the_twelve_sets_ship_with_the_docs_counts():
    shipped = depth.shipped_sets()
    assert set(shipped) == set(RANGES)
    assert {name: len(depth.read_set(path)) for name, path in shipped.items()} == COUNTS
    assert sum(COUNTS.values()) + len(depth.table1_set()) == 171
    assert len(depth.gather_sets()) == 13  # table1 and the twelve, no --data


@pytest.mark.parametrize("name", sorted(RANGES))
def test_every_row_names_its_source_and_compilation_row(name):
    first, last = RANGES[name]
    raw = _raw(name)
    assert [int(r["compilation_row"]) for r in raw] == list(range(first, last + 1))
    for r in raw:
        assert r["source"].strip() and r["notes"].strip()
        assert r["shot"] == f"zyh#{r['compilation_row']}"


@pytest.mark.parametrize("name", sorted(RANGES))
def test_strength_basis_is_one_per_set(name):
    rows = depth.read_set(depth.shipped_sets()[name])
    bases = {r.strength_basis for r in rows}
    assert bases <= set(depth.STRENGTH_BASES) and len(bases) == 1
    assert bases == ({"cylinder"} if name in US_SETS else {"cube"})


@pytest.mark.parametrize("name", sorted(RANGES))
def test_values_are_in_si_and_plausible(name):
    for r in depth.read_set(depth.shipped_sets()[name]):
        assert 0.01 <= r.depth <= 5.0  # metres, not millimetres
        assert 0.005 <= r.D <= 0.25 and r.L > r.D and 0.01 <= r.mass <= 250.0 and r.crh > 0
        assert 100.0 <= r.V <= 2000.0 and 5e6 <= r.fc <= 200e6 and 1900.0 <= r.rho <= 2500.0
        assert r.obliquity_deg == 0.0 and r.attack_deg == 0.0


def test_no_compilation_row_is_in_two_sets():
    rows = [int(r["compilation_row"]) for name in RANGES for r in _raw(name)]
    assert len(rows) == len(set(rows)) == 163


def test_strength_basis_column_is_optional_and_checked(tmp_path):
    head = "shot,d_mm,m_kg,crh,L_mm,v_ms,fc_mpa,rho_kgm3,depth_m"
    f = tmp_path / "plain.csv"
    f.write_text(f"{head}\na,26.9,0.906,2,242.4,277,35.2,2370,0.173\n")
    assert depth.read_set(f)[0].strength_basis == "cylinder"
    f.write_text(f"{head},strength_basis,source\na,26.9,0.906,2,242.4,277,35.2,2370,0.173,cube,x\n"
                 f"b,26.9,0.906,2,242.4,277,35.2,2370,0.173,,x\n")
    assert [r.strength_basis for r in depth.read_set(f)] == ["cube", "cylinder"]
    assert depth.read_set(f)[0].fc == 35.2e6  # kept as published, not converted
    f.write_text(f"{head},strength_basis\na,26.9,0.906,2,242.4,277,35.2,2370,0.173,prism\n")
    with pytest.raises(ValueError, match="plain.csv:2: strength_basis 'prism'"):
        depth.read_set(f)
