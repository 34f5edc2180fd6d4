"""What each kind of record owns (fepen.io.layout, issue 57): removal by record and layout keeps every file a user
put anywhere inside, a temporary is recognised by its name only where fepen writes that name, and a record that
lists what its kind never writes is not trusted."""

import json
import os
import tempfile

from hypothesis import given, settings
from hypothesis import strategies as st

from fepen import atomic
from fepen.io import layout


def record(d, kind, files):
    d.mkdir(parents=True, exist_ok=True)
    (d / "run.json").write_text(json.dumps({"command": ["fepen"], "fepen": "x", "kind": kind, "files": files}))


def test_the_temporaries_fepen_writes_are_recognised_by_name(tmp_path):
    """Every temporary fepen.atomic.replacing makes (any pid, any of mkstemp's names, any suffix) is one of a
    declared name; a user's name that merely looks alike is not."""
    for name, suffix in (("run.json", ""), ("sweep.parquet", ".parquet"), ("history.png", ".png")):
        for _ in range(50):
            fd, path = tempfile.mkstemp(prefix=f"{name}.tmp{os.getpid()}-", suffix=suffix, dir=tmp_path)
            os.close(fd)
            assert layout.temporary_of(os.path.basename(path)) == name
            assert layout.RUN.temporary(os.path.basename(path)) or name.startswith("sweep")
    assert not layout.RUN.temporary("notes.txt.tmp1-abcdefgh")  # not a name a run writes
    assert not layout.RUN.temporary("summary.json.tmp-abcdefgh")  # no pid
    assert not layout.RUN.temporary("summary.json.tmp12-abcdefghi")  # not mkstemp's eight characters


def test_a_record_folder_is_removed_by_its_record_and_its_layout(tmp_path):
    """A run's folder inside a study's shots/: what its manifest lists, its checkpoint's steps and its
    temporaries go; a user's file in it, in its checkpoint/ and beside it stay, and so do the folders holding
    them."""
    shot = tmp_path / "shots" / "00003"
    record(shot, "run", ["run.json", "fepen.log", "summary.json", "checkpoint"])
    for n in ("fepen.log", "summary.json", "summary.json.tmp77-abcdefgh", "mine.txt"):
        (shot / n).write_text(n)
    (shot / "checkpoint").mkdir()
    for n in ("state.json", "step000000012-rank0.npz", "step000000012-rank1.npz", "step_notes.txt"):
        (shot / "checkpoint" / n).write_text(n)
    (tmp_path / "shots" / "README.md").write_text("mine")
    kept = layout.remove_owned(tmp_path, ["shots"], _study())
    assert kept == {"shots"}
    left = sorted(p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*") if p.is_file())
    assert left == ["shots/00003/checkpoint/step_notes.txt", "shots/00003/mine.txt", "shots/README.md"]


def _study() -> str:
    layout.declare("test-study", ("shots", "shots.jsonl", "table.csv"))
    return "test-study"


def test_a_record_listing_what_its_kind_never_writes_is_not_trusted(tmp_path):
    assert layout.undeclared("run", ["summary.json", "notes.txt", "thesis"]) == ["notes.txt", "thesis"]
    assert layout.undeclared("no-such-kind", ["summary.json"]) == ["summary.json"]
    shot = tmp_path / "shots" / "00000"
    record(shot, "run", ["run.json", "summary.json", "notes.txt"])  # a forged record inside a study's folder
    (shot / "summary.json").write_text("s")
    (shot / "notes.txt").write_text("mine")
    layout.remove_owned(tmp_path, ["shots"], _study())
    assert (shot / "notes.txt").read_text() == "mine" and (shot / "summary.json").exists()  # left whole


def test_a_folder_without_a_record_keeps_all_but_fepens_leftovers(tmp_path):
    """A shot's folder a kill left before its record was written: only its reserve, a temporary of its record and
    a stale lock are fepen's; a user's run.json that is not a record stays."""
    shot = tmp_path / "shots" / "00001"
    shot.mkdir(parents=True)
    (shot / layout.RESERVE).write_bytes(b"\0" * 10)
    (shot / "run.json.tmp5-abcdefgh").write_text("{")
    (shot / layout.LOCK).write_text(json.dumps({"host": os.uname().nodename, "pid": 2**22 + 12345}))
    layout.remove_owned(tmp_path, ["shots"], _study())
    assert not (tmp_path / "shots").exists()
    shot.mkdir(parents=True)
    (shot / "run.json").write_text("[1, 2]")  # not a record fepen wrote
    layout.remove_owned(tmp_path, ["shots"], _study())
    assert (shot / "run.json").read_text() == "[1, 2]"


def test_links_are_never_followed_or_removed_below_the_top(tmp_path):
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "data.csv").write_text("precious")
    study = tmp_path / "study"
    (study / "shots").mkdir(parents=True)
    os.symlink(outside, study / "shots" / "00000")
    layout.remove_owned(study, ["shots"], _study())
    assert (outside / "data.csv").read_text() == "precious" and os.path.islink(study / "shots" / "00000")


@settings(max_examples=40, deadline=None)
@given(st.lists(st.sampled_from(["a.txt", "00001", "00002/x.csv", "00002/summary.json.txt", "mine/run.json",
                                 "00003/checkpoint/notes", "00004/fields.d/000001.h5.bak"]), unique=True))
def test_any_user_files_among_the_shots_stay(files):
    """Whatever the user puts among a study's shots (under names fepen writes or not), it stays."""
    with tempfile.TemporaryDirectory() as tmp:
        from pathlib import Path

        out = Path(tmp)
        for i in range(5):
            record(out / "shots" / f"{i:05d}", "run", ["run.json", "summary.json", "checkpoint", "fields.d"])
            (out / "shots" / f"{i:05d}" / "summary.json").write_text("s")
        for f in files:
            (out / "shots" / f).parent.mkdir(parents=True, exist_ok=True)
            if not (out / "shots" / f).exists():
                (out / "shots" / f).write_text("user")
        before = {f: (out / "shots" / f).read_text() for f in files if (out / "shots" / f).is_file()}
        layout.remove_owned(out, ["shots"], _study())
        assert {f: (out / "shots" / f).read_text() for f in before} == before
        assert not any((out / "shots" / f"{i:05d}" / "summary.json").exists() for i in range(5))


def test_a_strict_claim_refuses_a_name_its_kind_does_not_declare(tmp_path):
    """A name fepen would write that its layout does not declare is a bug, refused before it is written (so every
    manifest lists only what its kind writes)."""
    import pytest

    c = atomic.claim(tmp_path, declared=lambda n: layout.RUN.node(n) is not None)
    try:
        with atomic.replacing(tmp_path / "summary.json") as tmp:
            tmp.write_text("{}")
        with pytest.raises(atomic.UndeclaredName), atomic.replacing(tmp_path / "surprise.csv") as tmp:
            tmp.write_text("x")
        assert not (tmp_path / "surprise.csv").exists() and "surprise.csv" not in c.owned
    finally:
        atomic.release(c)
