"""run.acceleration_filter (issue 61): the filter of the filtered accelerations, "butterworth" (the default: the
numbers fepen published stay as they are) or one of SAE J211-1's channel frequency classes; anything else is one
line naming the key and what it allows, exit 2, before anything is written. The run is handed the plain value
(fepen.runs.shot.OutputSettings), never the scene."""

import re

import pytest

from fepen import cli, scene
from fepen.post import signals
from fepen.runs.shot import resolve
from fepen.scene.schema import SCHEMA


def test_the_key_allows_exactly_the_filters_the_signals_module_has():
    key = SCHEMA["run.acceleration_filter"]
    assert key.default == "butterworth" and tuple(key.choices) == signals.FILTERS
    assert set(key.choices) == {"butterworth", "CFC60", "CFC180", "CFC600", "CFC1000"}


@pytest.mark.parametrize("bad", ["CFC999", "cfc1000", "CFC 1000", "butterworth_10kHz"])
def test_an_unknown_class_is_one_line_and_exit_2(tmp_path, capsys, bad_input_line, bad):
    code = cli.main(["run", "--set", "effects.fidelity=rigid", "--set", f'run.acceleration_filter="{bad}"',
                     "--out", str(tmp_path / "a")])
    bad_input_line(code, capsys.readouterr().err, "run.acceleration_filter",
                   f"^got {re.escape(repr(bad))}, expected one of 'butterworth', 'CFC60', 'CFC180', 'CFC600', "
                   "'CFC1000'$")
    assert not (tmp_path / "a").exists()


@pytest.mark.parametrize("given, expected", [(None, "butterworth"), ("CFC60", "CFC60"), ("CFC1000", "CFC1000")])
def test_the_shot_carries_the_plain_value(given, expected):
    sets = ["effects.fidelity=rigid"] + ([f'run.acceleration_filter="{given}"'] if given else [])
    outputs = resolve(scene.load(None, sets), toml=False).outputs
    assert outputs.acceleration_filter == expected and isinstance(outputs.acceleration_filter, str)
    assert outputs.acceleration_filter_hz == 1.0e4
