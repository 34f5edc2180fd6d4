"""A deformable run whose accelerations are filtered by SAE J211-1's CFC 1000 (run.acceleration_filter, issue 61):
accelerations.csv's and the accelerometer probe's filtered columns are that class's filter of their raw ones
(not the default 10 kHz Butterworth), their peaks at most the raw ones, and summary.json names the class and
its corner frequency (F_N = 1650 Hz)."""

import csv
import json

import numpy as np
import pytest
from mpi4py import MPI

from fepen import scene
from fepen.post import signals
from fepen.runs.deformable import DeformableRun

SETS = ["mesh.size=0.006", "run.end_time=6e-5", "run.checkpoint_interval=0", "run.fields=false",
        "run.figures=false", 'run.acceleration_filter="CFC1000"']
PROBE = {"output": {"probes": [{"name": "gauge", "point": [0.0, 0.14, 0.0], "kind": "accelerometer"}]}}


def columns(path) -> dict[str, np.ndarray]:
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return {name: np.array([float(r[j]) for r in rows[1:]]) for j, name in enumerate(rows[0])}


def test_a_cfc1000_run_filters_its_accelerations_by_the_class_and_says_so(tmp_path):
    out = tmp_path / "r"
    DeformableRun(scene.Scene(PROBE, SETS), out, MPI.COMM_SELF).run()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["acceleration_filter"] == "CFC1000" and summary["acceleration_filter_hz"] == 1650.0
    assert summary["scene"]["run"]["acceleration_filter"] == "CFC1000"

    acc = columns(out / "accelerations.csv")
    t, raw, filt = acc["t_s"], acc["decel_g"], acc["decel_filtered_g"]
    assert len(t) > 30 and np.abs(raw).max() > 1e3  # a record that decelerates
    assert np.abs(filt).max() <= np.abs(raw).max()
    assert np.allclose(filt, signals.acceleration_filter(t, raw, "CFC1000", 1e4), rtol=1e-7, atol=1e-6)
    butterworth = signals.lowpass(t, raw, 1e4)
    assert np.abs(filt - butterworth).max() > 0.05 * np.abs(raw).max()  # not the default's numbers
    peak = summary["peak_accelerations"]["decel"]
    assert abs(peak["filtered_g"]) <= abs(peak["raw_peak_g"])
    assert peak["filtered_g"] == pytest.approx(filt[np.argmax(np.abs(filt))], rel=1e-8)

    probe = columns(out / "probes.csv")
    raw_p, filt_p = probe["gauge_axial_g_raw"], probe["gauge_axial_g"]
    assert np.abs(filt_p).max() <= np.abs(raw_p).max()
    assert np.allclose(filt_p, signals.acceleration_filter(probe["t_s"], raw_p, "CFC1000", 1e4), rtol=1e-7,
                       atol=1e-6)
