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
