"""The Python API's scenes (fepen.Scene): every source gives the same resolved scene; bad input names the key."""

import subprocess
import sys

import pytest

import fepen
from fepen.experiments import shot
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
