"""Docs that cannot drift (issues 46 and 61): every figure a page prints from a fepen command sits in a block that
`make docs` (tools/make_docs.py) writes, headed by the command that made it and the fepen that ran it. These re-run
the cheap blocks (make_docs.Block.cheap: the run tables' declarations, the studies' limit and ricochet, a run's
printed interval) on one rank and fail when any digit printed on the page moves (wall times masked); the long
ones (the plastic Table 1, the accuracy-cost ladder, the hard cases) are made again on demand (`make docs
ONLY=NAME`) and carry the version that made them. Before issue 46 the page gave the 150 mm slab's limit as
385.4 m/s when its command printed 311 m/s; before issue 61 the README quoted Table 1 means three releases old."""

import csv
import re
import sys
from pathlib import Path

import pytest
from mpi4py import MPI

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tools"))
import make_docs  # noqa: E402  (tools/ is not a package)

CHEAP = [name for name, b in make_docs.BLOCKS.items() if b.cheap]


@pytest.fixture
def one_rank(monkeypatch):
    """make docs as the drift test runs it: one rank (the same figures on any rank count), no pictures written."""
    monkeypatch.setattr(make_docs, "RANKS", 1)
    monkeypatch.setattr(make_docs, "FIGURES", False)


@pytest.mark.parametrize("name", CHEAP)
def test_a_cheap_block_on_its_page_is_what_its_command_prints_today(name, tmp_path, one_rank):
    stated, made = make_docs.remade(name, tmp_path)
    assert stated == made, (f"{make_docs.BLOCKS[name].page}'s block {name!r} has moved: `make docs ONLY={name}`\n"
                            f"--- page\n{stated}\n--- today\n{made}")


def test_every_block_names_its_command_and_version():
    for name, b in make_docs.BLOCKS.items():
        line = make_docs.stated_provenance(b.page, name)
        assert line is not None, f"{b.page}: block {name!r} has no provenance line (make docs ONLY={name})"
        m = re.fullmatch(r"<sub>Made by `(.+)` with fepen (\d+\.\d+\.\d+); `make docs ONLY=(\S+)` makes it "
                         r"again\.</sub>", line)
        assert m and m.group(1) == b.command and m.group(3) == name, line


def test_the_mask_hides_wall_times_only():
    text = "- **Cost:** 37 rigid shots, 12 s on 2 ranks; v_bl = 311.4 m/s; took 3 s on 1 rank."
    assert make_docs.masked(text) == ("- **Cost:** 37 rigid shots, … s on N ranks; v_bl = 311.4 m/s; took … s on "
                                      "N ranks.")


def test_the_rigid_table1_line_on_the_page_is_the_commands(tmp_path):
    """fepen validate in the rigid fidelity (8 s): the line under docs/validation.md's Table 1, made by the same
    function make docs uses, is the page's to every printed digit (nose, tail, axes, offsets)."""
    from fepen.studies import validate

    validate.validate(None, ["effects.fidelity=rigid"], tmp_path, MPI.COMM_SELF)
    with open(tmp_path / "validation.csv", newline="") as f:
        rows = {r["shot"]: r for r in csv.DictReader(f)}
    line = make_docs.means_line("rigid", rows)
    page = make_docs.block_text("docs/validation.md", "table1")
    stated = next(ln for ln in page.splitlines() if ln.startswith("rigid:"))
    assert line == stated
