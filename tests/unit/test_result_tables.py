"""Result's tables without a run: a results directory written by hand. Its numbers read back to the bit, a
table that is not there names why, and a machine without pandas gets one line saying so."""

import sys

import numpy as np
import pytest

import fepen
from fepen.scene import to_toml

PROBES = "t_s,tip_uy_m,tip_vy_m_s\n0.0,-0.1,-584.3\n1e-06,-0.10058430000000001,-583.9999999999999\n"


def results_dir(path, summary='{"outcome": "embedded", "Hx_mm": 1.5, "Hy_mm": 12.25}', probes=True):
    sc = fepen.Scene({"output": {"probes": [{"name": "tip", "point": [0.0, 0.0, 0.0]}]}} if probes else {},
                     ["effects.fidelity=plastic"])
    (path / "scene.toml").write_text(to_toml(sc))
    (path / "summary.json").write_text(summary)
    (path / "history.csv").write_text("t_s,nose_x_mm,nose_y_mm\n0,0,0\n1e-06,1,8\n")
    if probes:
        (path / "probes.csv").write_text(PROBES)
    return fepen.load(path)


def test_probes_read_back_to_the_bit(tmp_path):
    frame = results_dir(tmp_path).probes
    assert list(frame.columns) == ["t_s", "tip_uy_m", "tip_vy_m_s"]
    assert frame["tip_uy_m"].iloc[1] == -0.10058430000000001  # pandas' default parser is a bit off here
    assert frame["tip_vy_m_s"].iloc[1] == float("-583.9999999999999")
    assert np.array_equal(frame["t_s"].to_numpy(), [0.0, 1e-06])


def test_a_missing_table_says_why(tmp_path):
    r = results_dir(tmp_path)
    with pytest.raises(FileNotFoundError, match="strains.csv is not there: the run wrote none"):
        _ = r.strains
    stopped = tmp_path / "stopped"
    stopped.mkdir()
    r = results_dir(stopped, '{"outcome": "stopped", "stop_reason": "inverted element 12 at t = 3 us"}')
    with pytest.raises(FileNotFoundError, match="did not finish .*'stopped'.*inverted element 12"):
        _ = r.accelerations
    bare = tmp_path / "bare"
    bare.mkdir()
    with pytest.raises(FileNotFoundError, match=r"no \[\[output.probes\]\]"):
        _ = results_dir(bare, probes=False).probes


def test_without_pandas_one_line_says_so(tmp_path, monkeypatch):
    r = results_dir(tmp_path)
    monkeypatch.setitem(sys.modules, "pandas", None)  # import pandas raises ImportError
    for call, what in ((lambda: r.probes, "probes.csv"), (lambda: r.history_frame, "Result.history_frame"),
                       (lambda: fepen.sweep({"grid": {"impact.velocity": [500.0]}}, out=tmp_path / "s"),
                        "fepen.sweep")):
        with pytest.raises(ImportError) as err:
            call()
        message = str(err.value)
        assert what in message and "pip install 'pandas" in message and "\n" not in message
        assert err.value.__cause__ is None and err.value.__suppress_context__
    assert not (tmp_path / "s").exists()  # the sweep refused before writing anything
