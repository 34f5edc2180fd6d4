"""The C kernels' cache (fepen.native): a library is built once per machine and reused, but never loaded from
where another user could have put it (issue 43: caches that cannot lie)."""

import logging
import os

import pytest

from fepen import native

SOURCE = """double twice(double x) { return 2.0 * x; }\n"""


@pytest.fixture
def source(tmp_path):
    path = tmp_path / "twice.c"
    path.write_text(SOURCE)
    return path


def test_a_private_cache_builds_once_and_reuses(tmp_path, source, monkeypatch):
    monkeypatch.setenv("FEPEN_KERNEL_CACHE", str(tmp_path / "cache"))
    lib, why = native.load(source)
    assert why is None and lib.twice.__call__ is not None
    (built,) = (tmp_path / "cache").glob("twice-*.so")
    stamp = built.stat().st_mtime_ns
    native.load(source)
    assert built.stat().st_mtime_ns == stamp  # reused, not rebuilt


def test_a_cache_others_can_write_is_not_loaded_from(tmp_path, source, monkeypatch, caplog):
    """A shared (world-writable) cache: one warning, the library built in a private folder instead, and a
    planted library of the same name never loaded."""
    shared = tmp_path / "shared"
    shared.mkdir()
    os.chmod(shared, 0o777)
    monkeypatch.setenv("FEPEN_KERNEL_CACHE", str(shared))
    monkeypatch.setattr(native, "_own_dir", [])
    import ctypes

    lib, why = native.load(source)
    assert why is None
    lib.twice.restype = ctypes.c_double
    lib.twice.argtypes = [ctypes.c_double]
    assert lib.twice(2.5) == 5.0
    assert not list(shared.glob("*.so")) and native._own_dir and native._own_dir[0] != shared
    assert any("can be written by other users" in r.getMessage() for r in caplog.records
               if r.levelno >= logging.WARNING)


def test_a_library_others_can_write_is_rebuilt(tmp_path, source, monkeypatch):
    monkeypatch.setenv("FEPEN_KERNEL_CACHE", str(tmp_path / "cache"))
    native.load(source)
    (built,) = (tmp_path / "cache").glob("twice-*.so")
    os.chmod(built, 0o666)
    stamp = built.stat().st_mtime_ns
    native.load(source)
    assert built.stat().st_mtime_ns != stamp and not built.stat().st_mode & 0o022
