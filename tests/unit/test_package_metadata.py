"""What the package says about itself: the releases of dolfinx it names, its declared dependencies, and
CITATION.cff's keys (CFF 1.2.0; cffconvert is not installed here, so the keys the format requires are checked
by hand)."""

import ast
import re
import tomllib
from pathlib import Path

import pytest

import fepen

yaml = pytest.importorskip("yaml")

ROOT = Path(__file__).resolve().parents[2]


def supported_dolfinx() -> tuple:
    """dolfinx_api.SUPPORTED, read from its source (importing the module would import dolfinx)."""
    tree = ast.parse((ROOT / "fepen" / "dolfinx_api.py").read_text())
    for node in tree.body:
        if isinstance(node, ast.Assign) and getattr(node.targets[0], "id", None) == "SUPPORTED":
            return ast.literal_eval(node.value)
    raise AssertionError("no SUPPORTED in fepen/dolfinx_api.py")


def test_the_package_docstring_names_every_supported_dolfinx_and_no_other():
    named = {tuple(int(x) for x in m) for m in re.findall(r"dolfinx (\d+)\.(\d+)", fepen.__doc__)}
    named |= {tuple(int(x) for x in m) for m in re.findall(r"\bor (\d+)\.(\d+)", fepen.__doc__)}
    assert named == set(supported_dolfinx()), (named, fepen.__doc__[:300])


def test_pandas_is_a_declared_dependency():
    """fepen.sweep and Result's tables return DataFrames: pandas is a dependency, not only a test tool."""
    deps = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["dependencies"]
    assert any(re.match(r"pandas\b", d) for d in deps), deps


def citation() -> dict:
    return yaml.safe_load((ROOT / "CITATION.cff").read_text())


def test_citation_has_the_keys_cff_1_2_requires():
    c = citation()
    assert c["cff-version"] == "1.2.0"
    for key in ("message", "title", "authors"):
        assert c.get(key), key
    assert all(isinstance(a, dict) and (a.get("family-names") or a.get("name")) for a in c["authors"])


def test_citation_preferred_citation_is_the_paper():
    """The message names a preferred-citation: the file has one, an article with its title, authors and journal
    (the paper fepen implements, docs/paper.md)."""
    c = citation()
    assert "preferred-citation" in c["message"]
    p = c["preferred-citation"]
    assert p["type"] == "article" and p["title"] and p["authors"]
    assert [a["family-names"] for a in p["authors"]] == ["Zhu", "Liu", "Sheng", "Deng", "Wang"]
    assert p["journal"] == "Latin American Journal of Solids and Structures"
    assert p["title"] in (ROOT / "docs" / "paper.md").read_text().replace("\n> ", " ")
    if "doi" in p:  # CFF's DOI pattern
        assert re.fullmatch(r"10\.\d{4,9}(\.\d+)?/[A-Za-z0-9:/_;\-\.\(\)\[\]\\]+", p["doi"])
    if "year" in p:
        assert isinstance(p["year"], int)
