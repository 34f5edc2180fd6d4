"""sweep.parquet: written when pyarrow imports, else one line saying why (pyarrow absent, or a release built for
numpy 2 failing to import beside numpy 1.24); sweep.csv either way (fepen.studies.sweep.write_table)."""

import importlib.abc
import sys

import pytest

from fepen.studies import sweep

RIGID = '[base]\neffects.fidelity = "rigid"\n[grid]\n"impact.velocity" = [500.0, 600.0]\n'
RECORDS = {i: {"status": "ok", "message": "", "summary": {"depth_mm": 100.0 + i}, "wall_s": 0.01, "ranks": 1}
           for i in range(2)}


class _Numpy2Only(importlib.abc.MetaPathFinder):
    """Imports of pyarrow fail as pyarrow 26 does beside numpy 1.24."""

    def find_spec(self, name, path, target=None):
        if name.split(".")[0] == "pyarrow":
            raise ImportError("pyarrow requires NumPy 2.0 or newer, found 1.24.2")
        return None


@pytest.fixture
def sw(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text(RIGID)
    return sweep.read(p)


def _without_pyarrow(monkeypatch):
    for name in [m for m in sys.modules if m.split(".")[0] == "pyarrow"]:
        monkeypatch.delitem(sys.modules, name)


def test_absent_pyarrow_is_said_in_one_line(sw, tmp_path, monkeypatch):
    _without_pyarrow(monkeypatch)
    monkeypatch.setitem(sys.modules, "pyarrow", None)
    said = []
    sweep.write_table(sw, RECORDS, tmp_path, said.append)
    assert (tmp_path / "sweep.csv").is_file() and not (tmp_path / "sweep.parquet").exists()
    assert len(said) == 1 and "\n" not in said[0] and "not installed" in said[0] and "fepen[parquet]" in said[0]


def test_a_pyarrow_that_fails_to_import_is_said_in_one_line(sw, tmp_path, monkeypatch):
    _without_pyarrow(monkeypatch)
    monkeypatch.setattr(sys, "meta_path", [_Numpy2Only(), *sys.meta_path])
    said = []
    sweep.write_table(sw, RECORDS, tmp_path, said.append)
    assert not (tmp_path / "sweep.parquet").exists()
    assert len(said) == 1 and "NumPy 2.0" in said[0] and "<26" in said[0]


def test_parquet_holds_the_table_when_pyarrow_imports(sw, tmp_path):
    pq = pytest.importorskip("pyarrow.parquet")
    said = []
    cols, rows = sweep.write_table(sw, RECORDS, tmp_path, said.append)
    assert said == []
    table = pq.read_table(tmp_path / "sweep.parquet").to_pydict()
    assert table["shot"] == [0, 1] and table["depth_mm"] == [100.0, 101.0]
