"""The docs that are generated from the code match it: every scene key carries its meaning (its unit and
allowed values come from the schema itself), and docs/scenes.md is exactly what ``fepen keys`` prints
(regenerate it with ``(printf '# Scene keys\\n\\n'; python -m fepen keys) > docs/scenes.md``)."""

import json
import os
import sys
from pathlib import Path

import pytest

from fepen import scene
from fepen.cli import main

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("name", list(scene.SCHEMA))
def test_every_scene_key_has_a_meaning_that_fits_its_table_cell(name):
    """A doc of a few words at least, on one table row: no '|' (it would split the Markdown cell) and no
    newline."""
    doc = scene.SCHEMA[name].doc
    assert len(doc.split()) >= 3, f"{name}: no meaning in its doc ({doc!r})"
    assert "|" not in doc and "\n" not in doc


def test_every_row_of_the_key_table_has_four_cells_and_the_keys_in_schema_order():
    """The table `fepen keys` prints parses back: one row per key, in SCHEMA's order, each of four cells."""
    rows = [line for line in scene.describe().splitlines() if line.startswith("| `")]
    assert [r.split("`")[1] for r in rows] == list(scene.SCHEMA)
    assert all(r.count("|") == 5 for r in rows)


def test_docs_scenes_md_is_what_fepen_keys_prints(capsys):
    """docs/scenes.md = '# Scene keys', a blank line, then the output of ``fepen keys``."""
    assert main(["keys"]) == 0
    printed = capsys.readouterr().out
    assert (ROOT / "docs" / "scenes.md").read_text() == "# Scene keys\n\n" + printed, (
        "docs/scenes.md is stale: (printf '# Scene keys\\n\\n'; python -m fepen keys) > docs/scenes.md")


# ---- the mesh cache where meshes/README.md says ------------------------------------------------------------
def test_the_mesh_cache_of_a_source_checkout_is_its_meshes_cache(monkeypatch):
    """Run from this checkout (the README's editable install), meshes go to the checkout's meshes/cache."""
    from fepen.geometry import mesh_cache

    monkeypatch.delenv("FEPEN_MESH_CACHE", raising=False)
    assert mesh_cache.cache_dir() == ROOT / "meshes" / "cache"


def test_fepen_mesh_cache_comes_first_and_an_installed_fepen_caches_in_home(monkeypatch, tmp_path):
    """$FEPEN_MESH_CACHE wins; a fepen outside a checkout (site-packages: no pyproject.toml beside it, even
    with a meshes/ folder there) caches in ~/.cache/fepen/meshes."""
    from fepen.geometry import mesh_cache

    monkeypatch.setenv("FEPEN_MESH_CACHE", str(tmp_path / "mine"))
    assert mesh_cache.cache_dir() == tmp_path / "mine"
    monkeypatch.delenv("FEPEN_MESH_CACHE")
    site = tmp_path / "site-packages"
    (site / "fepen" / "geometry").mkdir(parents=True)
    (site / "meshes").mkdir()
    monkeypatch.setattr(mesh_cache, "__file__", str(site / "fepen" / "geometry" / "mesh_cache.py"))
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert mesh_cache.cache_dir() == tmp_path / "home" / ".cache" / "fepen" / "meshes"


# ---- fepen view: what it says without a display, when ParaView fails, and where a run has no fields --------
@pytest.fixture
def run_with_fields(tmp_path):
    """A directory that looks like a run with fields (fepen view checks for fields.xdmf first)."""
    out = tmp_path / "run"
    out.mkdir()
    (out / "fields.xdmf").write_text('<Xdmf><Domain><Grid><Attribute Name="von_mises_Pa" Center="Cell"/></Grid>'
                                     "</Domain></Xdmf>\n")
    return out


@pytest.fixture
def fake_paraview(tmp_path, monkeypatch):
    """A `paraview` on PATH that records its arguments and exits with the code given (a display is set)."""

    def make(code: int) -> Path:
        bin_dir, record = tmp_path / "bin", tmp_path / "paraview-args"
        bin_dir.mkdir(exist_ok=True)
        exe = bin_dir / "paraview"
        exe.write_text(f'#!/bin/sh\necho "$@" > "{record}"\nexit {code}\n')
        exe.chmod(0o755)
        monkeypatch.setenv("PATH", f"{bin_dir}:{os.environ['PATH']}")
        monkeypatch.setenv("DISPLAY", ":99")
        return record

    return make


def test_fepen_view_without_a_display_exits_2_with_one_line(run_with_fields, monkeypatch, capsys):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr(sys, "platform", "linux")
    assert main(["view", str(run_with_fields)]) == 2
    captured = capsys.readouterr()
    assert captured.err == "fepen view: no display: use --png FILE (an offscreen picture)\n"
    assert "shown" not in captured.out


def test_fepen_view_reports_a_paraview_that_fails_and_exits_4(run_with_fields, fake_paraview, capsys):
    record = fake_paraview(3)
    assert main(["view", str(run_with_fields)]) == 4
    captured = capsys.readouterr()
    assert captured.err == "fepen view: ParaView exited with code 3 (its messages are above)\n"
    assert "shown" not in captured.out
    assert record.read_text().split() == [f"--script={run_with_fields / 'view.py'}"]


def test_fepen_view_says_shown_when_paraview_ends_well(run_with_fields, fake_paraview, capsys):
    fake_paraview(0)
    assert main(["view", str(run_with_fields)]) == 0
    assert capsys.readouterr().out.strip() == f"shown: {run_with_fields}"


def test_the_display_rule_of_each_platform():
    from fepen.post.paraview import has_display

    assert not has_display({}, "linux")
    assert has_display({"DISPLAY": ":0"}, "linux") and has_display({"WAYLAND_DISPLAY": "wayland-0"}, "linux")
    assert has_display({}, "darwin") and has_display({}, "win32")


@pytest.mark.parametrize("summary, said", [
    ({"fidelity": "rigid", "scene": {"effects": {"fidelity": "rigid"}, "run": {"fields": True}}},
     "is a rigid run, which writes no fields"),
    ({"fidelity": "plastic", "scene": {"effects": {"fidelity": "plastic"}, "run": {"fields": False}}},
     "the run had run.fields = false"),
    ({"fidelity": "plastic", "scene": {"effects": {"fidelity": "plastic"}, "run": {"fields": True}}},
     "the run wrote no output time"),
    (None, "not a run's results directory"),
])
def test_fepen_view_of_a_run_without_fields_says_why_in_its_fidelitys_terms(tmp_path, capsys, summary, said):
    """A rigid run is not told about run.fields (which means nothing to it)."""
    if summary is not None:
        (tmp_path / "summary.json").write_text(json.dumps(summary))
    assert main(["view", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("fepen: bad input: dir: ") and said in err and err.count("\n") == 1
    assert ("run.fields" in err) == (said == "the run had run.fields = false")


def test_a_running_rigid_run_is_read_from_its_scene_toml(tmp_path, capsys):
    """Before summary.json exists, the given keys of scene.toml say what the run is."""
    (tmp_path / "scene.toml").write_text('[effects]\nfidelity = "rigid"\n\n[run]\n# fields = true\n')
    assert main(["view", str(tmp_path)]) == 2
    assert "is a rigid run, which writes no fields" in capsys.readouterr().err
