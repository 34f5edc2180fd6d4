"""The docs that are generated from the code match it: every scene key carries its meaning (its unit and
allowed values come from the schema itself), and docs/scenes.md is exactly what ``fepen keys`` prints
(regenerate it with ``(printf '# Scene keys\\n\\n'; python -m fepen keys) > docs/scenes.md``)."""

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
    from fepen.geometry import mesh

    monkeypatch.delenv("FEPEN_MESH_CACHE", raising=False)
    assert mesh.cache_dir() == ROOT / "meshes" / "cache"


def test_fepen_mesh_cache_comes_first_and_an_installed_fepen_caches_in_home(monkeypatch, tmp_path):
    """$FEPEN_MESH_CACHE wins; a fepen outside a checkout (site-packages: no pyproject.toml beside it, even
    with a meshes/ folder there) caches in ~/.cache/fepen/meshes."""
    from fepen.geometry import mesh

    monkeypatch.setenv("FEPEN_MESH_CACHE", str(tmp_path / "mine"))
    assert mesh.cache_dir() == tmp_path / "mine"
    monkeypatch.delenv("FEPEN_MESH_CACHE")
    site = tmp_path / "site-packages"
    (site / "fepen" / "geometry").mkdir(parents=True)
    (site / "meshes").mkdir()
    monkeypatch.setattr(mesh, "__file__", str(site / "fepen" / "geometry" / "mesh.py"))
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert mesh.cache_dir() == tmp_path / "home" / ".cache" / "fepen" / "meshes"
