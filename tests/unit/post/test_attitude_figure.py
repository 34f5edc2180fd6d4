"""The attitude and the depth interval in a run's figures (issue 61): attitude.png draws history.csv's attitude
columns as they are (the axis in the plane of fire, the yaw) with the Table 1 test's final axis; whoever draws
history.png draws it; and the predicted depth interval of summary.json is a band on the trajectory figure and
on history.png's depth panels, absent when the summary has none.

Synthetic results (test_figures' box projectile and analytic history), no solver run."""

import json

import numpy as np
import pytest
from mpi4py import MPI
from test_figures import write_fields, write_history, write_scene

from fepen.post import figures


def with_attitude(out, n=200):
    """history.csv with the attitude columns (the axis turning from 10.6° to 14°, a yaw rising and settling);
    returns the file's columns."""
    write_history(out, n)
    h = np.genfromtxt(out / "history.csv", delimiter=",", names=True)
    t = h["t_s"]
    cols = {k: h[k] for k in h.dtype.names}
    cols["axis_angle_deg"] = 10.6 + 3.4 * (t / t[-1]) ** 2
    cols["yaw_deg"] = 0.1 + 4.0 * np.sin(np.pi * t / t[-1]) ** 2
    np.savetxt(out / "history.csv", np.column_stack(list(cols.values())), delimiter=",", header=",".join(cols),
               comments="", fmt="%.9g")
    return np.genfromtxt(out / "history.csv", delimiter=",", names=True)  # the columns as the file holds them


def capture(monkeypatch):
    """figures.save_figure's figures, by file name (still written)."""
    drawn = {}
    save = figures.save_figure

    def keep(fig, path, *args, **kwargs):
        drawn[path.name] = fig
        return save(fig, path, *args, **kwargs)

    monkeypatch.setattr(figures, "save_figure", keep)
    return drawn


def test_the_attitude_curves_are_the_history_columns(tmp_path, monkeypatch):
    """attitude.png's two curves are axis_angle_deg and yaw_deg against t in µs, value for value, and the C3
    test's final axis (atan2(Hx − Tx, Hy − Ty) of Table 1) is the dashed line."""
    from fepen.data import shot

    write_scene(tmp_path, fidelity="rigid")
    cols = with_attitude(tmp_path)
    drawn = capture(monkeypatch)
    path = figures.attitude_figure(tmp_path)
    assert path == tmp_path / "attitude.png" and path.stat().st_size > 10_000
    axis, yaw = drawn["attitude.png"].axes
    curve = axis.lines[0]
    np.testing.assert_allclose(curve.get_xdata(), cols["t_s"] * 1e6, rtol=1e-12)
    np.testing.assert_allclose(curve.get_ydata(), cols["axis_angle_deg"], rtol=1e-12)
    np.testing.assert_allclose(yaw.lines[0].get_xdata(), cols["t_s"] * 1e6, rtol=1e-12)
    np.testing.assert_allclose(yaw.lines[0].get_ydata(), cols["yaw_deg"], rtol=1e-12)
    c3 = shot("C3")
    test_axis = np.degrees(np.arctan2(c3.Hx_mm - c3.Tx_mm, c3.Hy_mm - c3.Ty_mm))
    assert axis.lines[1].get_ydata()[0] == pytest.approx(test_axis, abs=1e-9) and 13.0 < test_axis < 15.0
    assert "C3" in drawn["attitude.png"].texts[0].get_text() and "(µs)" in yaw.get_xlabel()


def test_whoever_draws_history_png_draws_attitude_png(tmp_path):
    """history_figure writes attitude.png beside history.png; a history without the attitude columns (an older
    run) gets history.png alone."""
    old, new = tmp_path / "old", tmp_path / "new"
    for d in (old, new):
        d.mkdir()
        write_scene(d, fidelity="rigid")
    write_history(old)
    with_attitude(new)
    for d in (old, new):
        figures.history_figure(d, None, MPI.COMM_SELF)
    assert (new / "history.png").is_file() and (new / "attitude.png").stat().st_size > 10_000
    assert (old / "history.png").is_file() and not (old / "attitude.png").exists()


def test_attitude_png_is_a_declared_run_file():
    """attitude.png is among the names a run may write (fepen.io.layout), as every other figure."""
    from fepen.io import layout

    assert "attitude.png" in layout.RUN_NAMES and layout.RUN.node("attitude.png") is layout.LEAF


def bands(ax) -> list:
    """The axes' shaded horizontal bands: (low, high) in data y."""
    from matplotlib.patches import Polygon, Rectangle

    found = []
    for p in ax.patches:
        if isinstance(p, (Polygon, Rectangle)) and p.get_label().startswith("predicted depth"):
            y = p.get_path().transformed(p.get_patch_transform()).vertices[:, 1] if isinstance(p, Rectangle) \
                else p.get_xy()[:, 1]
            found.append((float(np.min(y)), float(np.max(y))))
    return found


@pytest.mark.parametrize("interval", [[312.4, 398.1], None])
def test_the_depth_interval_is_a_band_on_the_trajectory_and_history(tmp_path, monkeypatch, interval):
    """summary.json's depth_interval_mm is a band from its low to its high end on trajectory.png and on
    history.png's depth panels, labelled with its probabilities; none when the summary has no interval."""
    from fepen.post import slices

    write_scene(tmp_path)
    with_attitude(tmp_path)
    write_fields(tmp_path)
    (tmp_path / "summary.json").write_text(json.dumps({"depth_interval_mm": interval,
                                                       "interval": {"levels": [0.1, 0.9]}}))
    drawn = capture(monkeypatch)
    slices.trajectory_figure(tmp_path, tmp_path / "trajectory.png")
    figures.history_figure(tmp_path, None, MPI.COMM_SELF)
    trajectory = drawn["trajectory.png"].axes[0]
    depth, _, path, _ = drawn["history.png"].axes[:4]
    for ax in (trajectory, depth, path):
        if interval is None:
            assert bands(ax) == []
            continue
        assert bands(ax) == [pytest.approx(tuple(interval), abs=1e-9)]
        labels = ax.get_legend_handles_labels()[1]
        assert "predicted depth, 10–90 %: 312–398 mm" in labels
        lo, hi = sorted(ax.get_ylim())
        assert lo <= interval[0] and interval[1] <= hi  # in view


def test_a_summary_given_by_the_run_is_used_before_summary_json_exists(tmp_path, monkeypatch):
    """A run draws its figures before it writes summary.json: the summary it passes gives the band."""
    write_scene(tmp_path, fidelity="rigid")
    with_attitude(tmp_path)
    drawn = capture(monkeypatch)
    figures.history_figure(tmp_path, None, MPI.COMM_SELF, summary={"depth_interval_mm": [300.0, 420.0]})
    assert not (tmp_path / "summary.json").exists()
    assert bands(drawn["history.png"].axes[0]) == [pytest.approx((300.0, 420.0))]
