"""The progress bars of a run, of the mesh and of a study are fepen.progress's (its one decision: rank 0, the
terminal, mpirun's terminal, a notebook, FEPEN_PROGRESS; tests/unit/test_progress_switch.py); the mesh's bar only
within fepen.geometry.mesh.progress."""

import io
import sys

from fepen import progress
from fepen.geometry import mesh
from fepen.runs import outputs
from fepen.scene import Scene
from fepen.studies import engine


class Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_every_bar_is_drawn_by_fepen_progress(monkeypatch):
    made = []
    real = progress.bar

    def bar(on=True, rank=0, **kwargs):
        made.append((on, kwargs.get("desc")))
        return real(on, rank, **kwargs)

    monkeypatch.setattr(progress, "bar", bar)
    monkeypatch.setenv(progress.ENV, "0")
    outputs.Progress(5e-5, 0.0).close(None, True)
    mesh._MeshBar("mesh: building").close()
    scene = Scene(sets=["effects.fidelity=rigid", "run.figures=false"])
    records, ran, _ = engine.execute(1, lambda i: scene, None, desc="shots", progress=False)
    assert ran == 1 and records[0]["status"] == "ok"
    assert made == [(True, "fepen"), (True, "mesh: building"), (False, "shots")]


def test_a_study_s_bar_is_off_when_its_caller_says_so(monkeypatch):
    monkeypatch.delenv(progress.ENV, raising=False)
    tty = Tty()
    monkeypatch.setattr(sys, "stderr", tty)
    for on in (False, True):
        bar = progress.bar(on, total=3, unit="shot", desc="shots", leave=False)
        bar.update(1)
        bar.close()
        assert ("shots:" in tty.getvalue()) is on


def test_the_mesh_bar_is_on_only_within_its_switch():
    assert not mesh._PROGRESS["on"]
    with mesh.progress(True):
        assert mesh._PROGRESS["on"]
        with mesh.progress(False):
            assert not mesh._PROGRESS["on"]
        assert mesh._PROGRESS["on"]
    assert not mesh._PROGRESS["on"]
