"""A run writes attitude.png (issue 61): both fidelities, beside history.png, listed in the run's manifest, and
drawn from the history the run wrote (its curves are history.csv's attitude columns)."""

import json

import numpy as np
import pytest
from conftest import run_fepen

FIDELITIES = {"rigid": ["--set", "effects.fidelity=rigid"],
              "plastic": ["--set", "mesh.size=0.006", "--set", "run.end_time=6e-5", "--set",
                          "run.output_interval=3e-5"]}


@pytest.mark.parametrize("fidelity", list(FIDELITIES))
def test_a_run_writes_its_attitude_figure(tmp_path, monkeypatch, fidelity):
    out = tmp_path / fidelity
    r = run_fepen("run", "--set", "impact.shot=C3", *FIDELITIES[fidelity], "--out", str(out))
    assert r.returncode == 0, r.stderr[-2000:]
    assert (out / "attitude.png").stat().st_size > 10_000
    assert "attitude.png" in json.loads((out / "run.json").read_text())["files"]
    assert "attitude.png" in [line for line in r.stdout.splitlines() if line.startswith("written:")][0]
    # redrawn from the run's own files: the curves are the history's columns
    from fepen.post import figures

    drawn = {}
    monkeypatch.setattr(figures, "save_figure", lambda fig, path, *a, **k: drawn.setdefault(path.name, fig))
    figures.attitude_figure(out)
    h = np.genfromtxt(out / "history.csv", delimiter=",", names=True)
    axis, yaw = drawn["attitude.png"].axes
    np.testing.assert_array_equal(axis.lines[0].get_ydata(), h["axis_angle_deg"])
    np.testing.assert_array_equal(yaw.lines[0].get_ydata(), h["yaw_deg"])
    assert abs(h["axis_angle_deg"][0] - 10.6) < 0.05  # C3: obliquity 10.5° plus its 0.1° of attack


@pytest.mark.parametrize("fidelity", ["rigid", "plastic"])
def test_a_fresh_runs_figures_band_the_interval_its_summary_gives(tmp_path, monkeypatch, fidelity):
    """A run draws history.png (and a deformable run trajectory.png) before summary.json exists: the depth
    interval they band is the one the summary then gives. Before, a fresh run's figures had no band (they read a
    summary.json not yet written), only a figure redrawn later did."""
    import fepen
    from fepen.post import figures, slices

    given = {}
    real_history, real_trajectory = figures.history_figure, slices.trajectory_figure
    monkeypatch.setattr(figures, "history_figure", lambda out, exp=None, comm=None, summary=None:
                        given.setdefault("history", summary) and real_history(out, exp, comm, summary))
    monkeypatch.setattr(slices, "trajectory_figure", lambda out, path, exp=None, outlines=6, summary=None:
                        given.setdefault("trajectory", summary) and real_trajectory(out, path, exp, outlines, summary))
    sets = {"rigid": ["effects.fidelity=rigid"],
            "plastic": ["mesh.size=0.008", "impact.velocity=150", "impact.obliquity_deg=0", "impact.attack_deg=0"]}
    result = fepen.run(fepen.Scene(sets=sets[fidelity]), out=tmp_path / fidelity)
    interval = result.summary["depth_interval_mm"]
    assert interval is not None and interval[0] < result.summary["depth_mm"] < interval[1]
    for name in ("history",) + (("trajectory",) if fidelity == "plastic" else ()):
        assert given[name]["depth_interval_mm"] == interval, name
