"""The path figure of the oblique shots (fepen.post.paths) on tiny fake results directories, no simulation:
one panel per oblique shot, the nose path drawn is the history's, a missing shot or directory is skipped."""

import math

import numpy as np
import pytest
from matplotlib.image import imread

from fepen.data import SHOTS
from fepen.io.results import HISTORY_COLUMNS
from fepen.post import paths

OBLIQUE = ["C1", "C3", "C4", "C5", "C6", "C7"]


def fake_history(d, name: str, rows: int = 5) -> np.ndarray:
    """d/history.csv with HISTORY_COLUMNS (the nose along a slightly bent line at the shot's angle), read back."""
    d.mkdir(parents=True, exist_ok=True)
    s = SHOTS[name]
    t = np.linspace(0.0, 1.0, rows)
    data = np.zeros((rows, len(HISTORY_COLUMNS)))
    col = {k: i for i, k in enumerate(HISTORY_COLUMNS)}
    data[:, col["t_s"]] = t * 1e-3
    data[:, col["nose_y_mm"]] = s.Hy_mm * t
    data[:, col["nose_x_mm"]] = s.Hy_mm * t * math.tan(math.radians(s.obliquity_deg)) + 5.0 * t ** 2
    data[:, col["tail_y_mm"]] = data[:, col["nose_y_mm"]] - 140.0
    data[:, col["tail_x_mm"]] = data[:, col["nose_x_mm"]] - 30.0
    np.savetxt(d / "history.csv", data, delimiter=",", header=",".join(HISTORY_COLUMNS), comments="", fmt="%.9g")
    return np.loadtxt(d / "history.csv", delimiter=",", skiprows=1)  # as written, to 9 digits


def nose_line(ax, label):
    lines = [ln for ln in ax.get_lines() if ln.get_gid() == f"{label}:nose"]
    assert len(lines) <= 1
    return lines[0] if lines else None


def test_the_oblique_shots_are_the_six_of_five_degrees_or_more():
    assert paths.oblique_shots() == OBLIQUE


def test_one_panel_per_oblique_shot_and_the_nose_path_is_the_history(tmp_path, monkeypatch):
    run = tmp_path / "rigid"
    histories = {name: fake_history(run / name, name) for name in OBLIQUE}
    drawn = {}
    real_panel = paths._panel

    def spy(ax, name, p, colours):
        drawn[name] = ax
        real_panel(ax, name, p, colours)

    monkeypatch.setattr(paths, "_panel", spy)
    out = paths.paths_figure({"rigid": run}, tmp_path / "paths.png")
    assert out.is_file() and imread(out).ndim == 3
    assert list(drawn) == OBLIQUE
    fig = drawn["C1"].figure
    assert len(fig.axes) == 6
    col = {k: i for i, k in enumerate(HISTORY_COLUMNS)}
    for name, ax in drawn.items():
        assert ax.get_title().startswith(f"{name}: ")
        line = nose_line(ax, "rigid")
        np.testing.assert_allclose(line.get_xdata(), histories[name][:, col["nose_x_mm"]], rtol=0, atol=0)
        np.testing.assert_allclose(line.get_ydata(), histories[name][:, col["nose_y_mm"]], rtol=0, atol=0)
        assert ax.yaxis_inverted()  # depth downward
    assert len(fig.legends) == 1  # the legend once


def test_a_missing_shot_or_directory_is_skipped(tmp_path, monkeypatch):
    run = tmp_path / "rigid"
    for name in ("C1", "C7"):
        fake_history(run / name, name)
    drawn = {}
    real_panel = paths._panel
    monkeypatch.setattr(paths, "_panel", lambda ax, name, p, c: (drawn.update({name: ax}), real_panel(ax, name, p, c)))
    out = paths.paths_figure({"rigid": run, "deformable": tmp_path / "absent"}, tmp_path / "p.png",
                             shots=["C1", "C3", "C7", "C9"])
    assert out.is_file()
    assert list(drawn) == ["C1", "C3", "C7"]  # C9 is no Table 1 shot
    assert nose_line(drawn["C1"], "rigid") is not None
    assert nose_line(drawn["C3"], "rigid") is None  # no C3 directory: the test and the straight line only
    assert [ln.get_gid() for ln in drawn["C3"].get_lines() if ln.get_gid() in ("straight", "test:final")] \
        == ["straight", "test:final"]
    assert all(nose_line(ax, "deformable") is None for ax in drawn.values())


def test_the_test_projectile_and_the_straight_line(tmp_path, monkeypatch):
    drawn = {}
    real_panel = paths._panel
    monkeypatch.setattr(paths, "_panel", lambda ax, name, p, c: (drawn.update({name: ax}), real_panel(ax, name, p, c)))
    paths.paths_figure({}, tmp_path / "p.png", shots=["C7"])
    ax = drawn["C7"]
    s = SHOTS["C7"]
    (test,) = [ln for ln in ax.get_lines() if ln.get_gid() == "test:final"]
    assert list(test.get_xdata()) == [s.Tx_mm, s.Hx_mm] and list(test.get_ydata()) == [s.Ty_mm, s.Hy_mm]
    (straight,) = [ln for ln in ax.get_lines() if ln.get_gid() == "straight"]
    x, y = straight.get_xdata(), straight.get_ydata()
    assert math.degrees(math.atan2(x[1] - x[0], y[1] - y[0])) == pytest.approx(20.0)


def test_offsets_sign_and_angle():
    """Past the straight line is positive; the axis angle is from the face normal."""
    off, angle = paths.offsets((0.0, 0.0, 10.0, 10.0), 0.0)
    assert off == pytest.approx(10.0) and angle == pytest.approx(45.0)
    off, _ = paths.offsets((0.0, 0.0, 0.0, 100.0), 10.0)
    assert off < 0


def test_main_writes_the_figure(tmp_path, capsys):
    fake_history(tmp_path / "a" / "C6", "C6")
    out = tmp_path / "sub" / "both.png"
    assert paths.main([str(out), f"rigid={tmp_path / 'a'}", f"deformable={tmp_path / 'b'}"]) == 0
    assert out.is_file() and "written" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        paths.main([str(out), "no-label"])
