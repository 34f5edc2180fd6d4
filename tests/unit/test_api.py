"""The Python API's scenes (fepen.Scene): every source gives the same resolved scene; bad input names the key."""

import subprocess
import sys

import pytest

import fepen
from fepen.data import shot
from fepen.scene import to_toml

ROOT_TOML = """
[impact]
shot = "C5"

[effects]
fidelity = "rigid"
"""


def test_a_scene_from_a_file_text_nested_or_flat_dict_is_the_same(tmp_path):
    f = tmp_path / "s.toml"
    f.write_text(ROOT_TOML)
    scenes = [fepen.Scene(f), fepen.Scene(str(f)), fepen.Scene(ROOT_TOML),
              fepen.Scene({"impact": {"shot": "C5"}, "effects": {"fidelity": "rigid"}}),
              fepen.Scene({"impact.shot": "C5", "effects.fidelity": "rigid"}),
              fepen.Scene(None, sets=["impact.shot=C5", "effects.fidelity=rigid"]),
              fepen.Scene({"impact": {"shot": "C5"}}, sets={"effects.fidelity": "rigid"})]
    text = {to_toml(s) for s in scenes}
    assert len(text) == 1
    c5 = shot("C5")
    assert (scenes[0].impact.velocity, scenes[0].impact.obliquity_deg) == (c5.v0, c5.obliquity_deg)
    assert scenes[0].explicit == {"impact.shot", "effects.fidelity"}


def test_with_sets_overrides_and_keeps_what_was_given():
    s = fepen.Scene({"effects": {"fidelity": "rigid"}}).with_sets(["impact.velocity=700"])
    assert s.impact.velocity == 700.0 and s.effects.fidelity == "rigid"
    assert fepen.Scene(to_toml(s)).impact.velocity == 700.0  # the resolved TOML round-trips


@pytest.mark.parametrize("source, sets, key", [
    ({"impact": {"velocity": -5.0}}, (), "impact.velocity"),
    ({"impact": {"velocty": 5.0}}, (), "impact.velocty"),
    (None, ["effects.fidelity=wobbly"], "effects.fidelity"),
    ("[impact\nvelocity = 3", (), "SCENE"),
])
def test_bad_input_raises_input_error_naming_the_key(source, sets, key):
    with pytest.raises(fepen.InputError) as err:
        fepen.Scene(source, sets)
    assert err.value.key == key


def test_importing_fepen_is_cheap():
    """``import fepen`` loads neither dolfinx nor MPI: the API comes on first use."""
    code = "import sys, fepen; print('dolfinx' in sys.modules, 'mpi4py' in sys.modules, fepen.Scene.__name__)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["False", "False", "Scene"]


def test_load_gives_the_summary_the_history_by_column_and_a_dataframe(tmp_path):
    """A results directory read back: history.csv by column name (numpy), the same as a DataFrame, the
    resolved scene, and the figures and fields found there."""
    sc = fepen.Scene({"effects": {"fidelity": "rigid"}})
    (tmp_path / "scene.toml").write_text(to_toml(sc))
    (tmp_path / "summary.json").write_text('{"outcome": "embedded", "Hx_mm": 1.5, "Hy_mm": 12.25}')
    (tmp_path / "history.csv").write_text("t_s,nose_x_mm,nose_y_mm\n0,0,0\n1e-05,1,8\n2e-05,1.5,12.25\n")
    (tmp_path / "history.png").write_bytes(b"png")
    r = fepen.load(tmp_path)
    assert r.history["nose_y_mm"][-1] == r.summary["Hy_mm"]
    assert r.history.dtype.names == ("t_s", "nose_x_mm", "nose_y_mm")
    assert r.scene.as_dict() == sc.as_dict()
    assert r.fields is None and set(r.figures) == {"history"}
    frame = r.history_frame
    assert list(frame.columns) == ["t_s", "nose_x_mm", "nose_y_mm"] and frame["nose_x_mm"].iloc[-1] == 1.5
    with pytest.raises(fepen.InputError):
        fepen.load(tmp_path / "nothing")


def test_mesh_refuses_a_run_directory_before_meshing(tmp_path, monkeypatch):
    """fepen.mesh into a run's results: InputError, nothing meshed or written (the run's scene.toml kept)."""
    from fepen.runs import setup

    def meshed(*args, **kwargs):
        raise AssertionError("meshed")

    monkeypatch.setattr(setup, "mesh", meshed)
    (tmp_path / "summary.json").write_text("{}")
    (tmp_path / "scene.toml").write_text("# the run's")
    with pytest.raises(fepen.InputError) as err:
        fepen.mesh(fepen.Scene(), tmp_path)
    assert err.value.key == "--out" and "scene.toml" in err.value.message  # a file fepen did not write
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.toml", "summary.json"]
    assert (tmp_path / "scene.toml").read_text() == "# the run's"
    assert "mesh" in fepen.__all__ and fepen.mesh is fepen.api.mesh


def test_dir_lists_the_api():
    import fepen

    assert dir(fepen) == sorted(fepen.__all__)
    assert {"run", "load", "resume", "mesh", "sweep", "Scene", "Result"} <= set(dir(fepen))
    assert callable(fepen.sweep)
