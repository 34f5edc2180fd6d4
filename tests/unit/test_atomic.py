"""Files that are never half-written (fepen.atomic): all of the new content or all of the old, no debris."""

import pytest

from fepen.atomic import replacing


def test_replacing_writes_the_whole_file_and_leaves_nothing_beside_it(tmp_path):
    target = tmp_path / "history.csv"
    target.write_text("old\n")
    with replacing(target) as tmp:
        tmp.write_text("new\n")
        assert target.read_text() == "old\n"  # readers see the old file until the rename
    assert target.read_text() == "new\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["history.csv"]


def test_a_failed_write_keeps_the_old_file_and_removes_the_partial_one(tmp_path):
    target = tmp_path / "state.json"
    target.write_text("complete\n")
    with pytest.raises(OSError), replacing(target, ".json") as tmp:
        tmp.write_text("half")
        raise OSError(28, "No space left on device")
    assert target.read_text() == "complete\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["state.json"]


def test_a_claimed_directory_refuses_foreign_files_and_links_and_records_new_names(tmp_path):
    """In a claimed directory a write over a file fepen did not write, or through a link, is refused (the file
    and the link's target untouched); a new name is fepen's from then on and its owner is told at once."""
    import os

    from fepen import atomic

    (tmp_path / "mine.csv").write_text("the user's")
    outside = tmp_path.parent / f"{tmp_path.name}-outside.txt"
    outside.write_text("elsewhere")
    d = tmp_path / "run"
    d.mkdir()
    os.symlink(outside, d / "summary.json")
    (d / "notes.txt").write_text("the user's notes")
    told = []
    claim = atomic.claim(d, owned={"history.csv"}, on_new=told.append)
    try:
        for name, why in (("summary.json", "symbolic link"), ("notes.txt", "did not write")):
            with pytest.raises(atomic.ForeignFile, match=why):
                with replacing(d / name) as tmp:
                    tmp.write_text("fepen's")
        assert outside.read_text() == "elsewhere" and (d / "notes.txt").read_text() == "the user's notes"
        with replacing(d / "history.csv") as tmp:  # owned: replaced
            tmp.write_text("rows")
        with replacing(d / "new.png") as tmp:  # new: written and recorded
            tmp.write_bytes(b"png")
        assert told == ["new.png"] and {"history.csv", "new.png"} <= claim.owned
        with pytest.raises(atomic.ForeignFile):  # a link planted inside a directory fepen made
            atomic.make_dir(d / "checkpoint")
            os.symlink(outside, d / "checkpoint" / "state.json")
            with replacing(d / "checkpoint" / "state.json") as tmp:
                tmp.write_text("{}")
        with pytest.raises(atomic.ForeignFile):
            with atomic.open_append(d / "summary.json") as f:
                f.write("log")
        assert outside.read_text() == "elsewhere"
    finally:
        atomic.release(claim)
    with replacing(tmp_path / "mine.csv") as tmp:  # outside any claim: the caller's choice
        tmp.write_text("replaced")
    assert not [p for p in d.iterdir() if ".tmp" in p.name]


def test_temporary_files_are_made_exclusively_with_the_usual_permissions(tmp_path):
    """The temporary file is a new one (a planted name beside the target cannot redirect the write) and the
    finished file gets open()'s permissions, not mkstemp's 0600."""
    import os
    import stat

    target = tmp_path / "history.csv"
    planted = tmp_path / f"history.csv.tmp{os.getpid()}"
    os.symlink(tmp_path / "victim", planted)
    with replacing(target) as tmp:
        assert tmp != planted and not tmp.is_symlink()
        tmp.write_text("rows")
    assert not (tmp_path / "victim").exists() and target.read_text() == "rows"
    mask = os.umask(0)
    os.umask(mask)
    assert stat.S_IMODE(target.stat().st_mode) == 0o666 & ~mask
