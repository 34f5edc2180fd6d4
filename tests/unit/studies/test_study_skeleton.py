"""The study skeleton (fepen.studies.study): a new study is one file of under 60 lines (toy_study.py), run by
fepen.study like every study the command line runs, into a folder it owns; the registry names every study the
command line has; a study resumes from its records and refuses another study's folder."""

import json
import math
import sys
from pathlib import Path

import pytest

import fepen
from fepen.errors import InputError
from fepen.studies import study

sys.path.insert(0, str(Path(__file__).parent))
TOY = Path(__file__).with_name("toy_study.py")


def test_a_new_study_is_one_short_file_that_fepen_study_runs(tmp_path):
    import toy_study  # noqa: F401 - registers itself

    assert len(TOY.read_text().splitlines()) < 60
    out = tmp_path / "toy"
    res = fepen.study("toy-ladder", out=out, speeds=[400.0, 800.0])
    assert res["ran"] == 2 and res["depth_mm"][1] > 1.5 * res["depth_mm"][0]  # deeper when faster
    assert 1.0 < res["slope"] < 2.0  # between the inertial (P ~ ln v) and the strength-free (P ~ v²) limits
    assert {"toy_ladder.json", "toy_ladder.md", "toy_ladder.png", "shots.jsonl", "run.json"} <= {
        p.name for p in out.iterdir()}
    assert json.loads((out / "run.json").read_text())["kind"] == "toy-ladder"
    again = fepen.study("toy-ladder", out=out, speeds=[400.0, 800.0])  # resumed from its records: no shot runs
    assert again["ran"] == 0 and again["depth_mm"] == res["depth_mm"]
    with pytest.raises(InputError, match="toy-ladder made of other inputs"):
        fepen.study("toy-ladder", out=out, speeds=[500.0])
    assert math.isfinite(fepen.study("toy-ladder", out=out, fresh=True, speeds=[500.0, 600.0])["depth_mm"][0])


def test_the_registry_holds_every_study_the_command_line_runs():
    from fepen.cli import _parser

    sub = next(a for a in _parser()._actions if getattr(a, "choices", None) and "study" in a.choices)
    studies = next(a for a in sub.choices["study"]._actions if getattr(a, "choices", None)).choices
    assert set(studies) == set(study.study_names("study"))
    assert {"sweep", "validate", "validate-depth"} <= set(study.STUDIES)
    for name in study.STUDIES:
        assert study.get(name).name == name


def test_an_unknown_study_is_one_line():
    with pytest.raises(InputError, match="no study 'nope'"):
        fepen.study("nope")
