"""Every sweep file fepen ships, given to ``fepen run`` (or ``fepen mesh``) by mistake: one line saying it is a
sweep file and how to run it, exit 2, before anything is meshed, run or written."""

import tomllib
from pathlib import Path

import pytest

from fepen import cli
from fepen.runs import setup

ROOT = Path(__file__).resolve().parents[3]
#: the kinds of sweep (fepen.studies.spec): a file with one of these tables is a sweep file
KINDS = ("grid", "monte_carlo", "table")


def shipped_sweeps() -> list[Path]:
    """Every TOML file shipped (scenes, demos, benchmarks, the package's data) with a sweep's table."""
    found = []
    for p in sorted(p for d in ("scenes", "demos", "benchmarks", "fepen") for p in (ROOT / d).rglob("*.toml")):
        rel = p.relative_to(ROOT)
        try:
            tree = tomllib.loads(p.read_text())
        except (ValueError, UnicodeDecodeError):
            continue
        if any(k in tree for k in KINDS):
            found.append(rel)
    return found


SWEEPS = shipped_sweeps()


def test_the_sweep_files_are_found():
    assert len(SWEEPS) >= 3 and Path("demos/studies/c3_scatter.toml") in SWEEPS, SWEEPS


@pytest.mark.parametrize("command", ["run", "mesh"])
@pytest.mark.parametrize("path", SWEEPS, ids=str)
def test_a_sweep_file_given_as_a_scene_says_how_to_run_it(path, command, tmp_path, monkeypatch, capsys,
                                                          bad_input_line):
    def meshed(*args, **kwargs):
        raise AssertionError("meshed")

    monkeypatch.setattr(setup, "mesh", meshed)
    monkeypatch.chdir(ROOT)
    code = cli.main([command, str(path), "--out", str(tmp_path / "out")])
    captured = capsys.readouterr()
    bad_input_line(code, captured.err, "SCENE", rf"^{path} is a sweep file: run it with `fepen sweep {path}`$")
    assert captured.out == "" and not (tmp_path / "out").exists()
