"""Result's tables (fepen.run / fepen.load): probes.csv, accelerations.csv and strains.csv as pandas DataFrames
with the files' columns and the files' numbers to the bit, from a coarse short deformable shot with probes; a
rigid run, which writes none of the last two, says so."""

import csv

import numpy as np
import pytest

import fepen

DEFORMABLE = ["mesh.size=0.005", "run.end_time=3.05e-5", "run.output_interval=1e-5", "run.checkpoint_interval=0",
              "run.fields=false", "run.figures=false"]
PROBES = [{"name": "tail", "point": [0.0, 0.144, 0.0]}, {"name": "gauge", "point": [0.0, 0.144, 0.0],
                                                          "kind": "accelerometer"}]


def read_csv(path):
    """(header, rows as floats) by the csv module: what the file holds."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], np.array([[float(x) for x in r] for r in rows[1:]])


@pytest.fixture(scope="module")
def deformable(tmp_path_factory):
    out = tmp_path_factory.mktemp("api-tables") / "plastic"
    fepen.run(fepen.Scene({"output": {"probes": PROBES}}, DEFORMABLE), out=out, sensitivity=False)
    return fepen.load(out)


@pytest.mark.parametrize("name, attribute", [("probes.csv", "probes"), ("accelerations.csv", "accelerations"),
                                             ("strains.csv", "strains")])
def test_a_table_is_its_file_column_by_column(deformable, name, attribute):
    header, values = read_csv(deformable.out / name)
    frame = getattr(deformable, attribute)
    assert list(frame.columns) == header and header[0] == "t_s"
    assert frame.shape == values.shape and len(frame) > 30
    assert np.array_equal(frame.to_numpy(dtype=float), values)  # every number the file's double
    assert np.array_equal(frame["t_s"].to_numpy(), deformable.history["t_s"])  # a row per history row
    assert getattr(deformable, attribute) is frame  # read once


def test_the_tables_carry_their_physics(deformable):
    """The tail probe is the history's tail (mm against m); the filtered deceleration is a deceleration
    (positive, within the raw one's range); the gauges read compression at the nose's end of the shot."""
    h, p, a, s = deformable.history, deformable.probes, deformable.accelerations, deformable.strains
    assert np.allclose(-1e3 * (0.144 + p["tail_uy_m"].to_numpy()), h["tail_y_mm"], rtol=0, atol=2e-3)
    assert list(a.columns) == ["t_s", "decel_g", "decel_filtered_g"]
    assert a["decel_g"].max() > 1e4 and a["decel_filtered_g"].max() <= a["decel_g"].max()
    assert {"top_33pctL", "side-_50pctL"} <= set(s.columns)
    assert s.iloc[-1, 1:].mean() < 0.0  # shortened by the target's resistance


def test_a_rigid_run_says_which_tables_it_lacks(tmp_path):
    r = fepen.run({"effects": {"fidelity": "rigid"}}, out=tmp_path / "rigid", sensitivity=False)
    for attribute in ("accelerations", "strains"):
        with pytest.raises(FileNotFoundError, match="deformable runs only.*'rigid'"):
            getattr(r, attribute)
    with pytest.raises(FileNotFoundError, match=r"no \[\[output.probes\]\]"):
        _ = r.probes
    assert r.history_frame["nose_y_mm"].iloc[-1] == pytest.approx(r.summary["Hy_mm"], rel=1e-8)
