"""The progress bars' switch (rank 0, stderr): off when asked, FEPEN_PROGRESS=1 on (a run under an mpirun started
from a terminal), 0 off, else tqdm's own test of a terminal; the mesh's bar only within fepen.geometry.mesh.progress."""

import pytest

from fepen.geometry import mesh
from fepen.studies import engine


@pytest.mark.parametrize("env,progress,disabled", [(None, True, None), ("1", True, False), ("0", True, True),
                                                   ("1", False, True), (None, False, True)])
def test_the_bars_follow_the_switch_and_the_environment(monkeypatch, env, progress, disabled):
    if env is None:
        monkeypatch.delenv("FEPEN_PROGRESS", raising=False)
    else:
        monkeypatch.setenv("FEPEN_PROGRESS", env)
    assert engine.bar_disabled(progress) is disabled
    if progress:
        assert mesh.bar_disabled() is disabled


def test_the_mesh_bar_is_on_only_within_its_switch():
    assert not mesh._PROGRESS["on"]
    with mesh.progress(True):
        assert mesh._PROGRESS["on"]
        with mesh.progress(False):
            assert not mesh._PROGRESS["on"]
        assert mesh._PROGRESS["on"]
    assert not mesh._PROGRESS["on"]
