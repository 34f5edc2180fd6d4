"""What a run reports about itself (issue 61): the final nose signed like the tail (a ricochet's nose above the
face has Hy_mm < 0), wall_s the whole process up to summary.json (the figure included), and a run cut by
run.end_time not compared with its test as if it had finished."""

import json
import math
import time

import pytest
from mpi4py import MPI

from fepen import scene
from fepen.io.results import COL
from fepen.runs.rigid import RigidRun
from tests.conftest import run_fepen

RIGID = ["--set", "effects.fidelity=rigid", "--set", "impact.shot=C3", "--no-sensitivity"]


def rigid_run(*sets):
    """A rigid run with ``sets``, in this process: (its summary, its last history row)."""
    run = RigidRun(scene.load(None, ["effects.fidelity=rigid", *sets]), None, MPI.COMM_SELF)
    summary = run.run()
    return summary, run.rows[-1]


def test_a_ricochets_nose_above_the_face_has_a_negative_Hy_mm():
    """docs/studies.md's ricochet map puts the boundary at 600 m/s at 77 deg: the default shot (584.3 m/s) at
    80 deg ricochets, its nose ends above the face, and Hy_mm says so with the sign of Ty_mm and the history's
    nose_y_mm (it was the magnitude: 56 mm, as if below the face)."""
    s, last = rigid_run("impact.obliquity_deg=80")
    assert s["outcome"] == "ricochet"
    assert last[COL["nose_y_mm"]] < -10.0  # the body left the target: its nose is above the face
    assert s["Hy_mm"] == last[COL["nose_y_mm"]] and s["Hx_mm"] == last[COL["nose_x_mm"]]
    assert s["Hy_mm"] < 0 and s["Ty_mm"] < 0 and s["depth_mm"] > 0
    # the final axis is that of the nose and tail as written
    axis = math.degrees(math.atan2(s["Hx_mm"] - s["Tx_mm"], s["Hy_mm"] - s["Ty_mm"]))
    assert s["final_axis_angle_deg"] == pytest.approx(axis, abs=1e-9)


def test_an_embedded_shots_Hy_mm_is_its_depth_below_the_face():
    """The sign changes nothing for a nose below the face: C3 embeds, Hy_mm > 0 and near Table 1's 349.6 mm."""
    s, last = rigid_run('impact.shot="C3"')
    assert s["outcome"] == "embedded"
    assert s["Hy_mm"] == last[COL["nose_y_mm"]] > 0 and s["Hx_mm"] > 0
    assert s["experiment"]["Hy_mm"] == 349.6
    assert s["experiment"]["Hy_error"] == pytest.approx(s["Hy_mm"] / 349.6 - 1, rel=1e-12)
    assert abs(s["experiment"]["Hy_error"]) < 0.3


@pytest.fixture(scope="module")
def c3(tmp_path_factory):
    """`fepen run` of the rigid C3 shot, timed around its process: (CompletedProcess, summary, seconds)."""
    out = tmp_path_factory.mktemp("c3") / "run"
    t0 = time.perf_counter()
    r = run_fepen("run", *RIGID, "--out", str(out))
    wall = time.perf_counter() - t0
    assert r.returncode == 0, r.stderr
    return r, json.loads((out / "summary.json").read_text()), wall


def test_a_rigid_runs_wall_s_is_its_whole_process(c3):
    """wall_s covers the process up to summary.json (the interpreter, the imports, the run, the figure): the
    sum of its parts, and within 15 % of the process's wall time measured around it (what follows summary.json
    is run.json, the printed lines and the exit). It left out the figure, 35-40 % of a rigid run."""
    r, s, wall = c3
    split = s["time_split_s"]
    assert s["wall_s"] >= sum(split.values()) - 1e-9
    assert s["wall_s"] <= wall + 0.02  # /proc counts in 10 ms ticks
    assert s["wall_s"] >= 0.85 * wall, (s["wall_s"], wall, split)


def test_a_finished_run_is_compared_with_its_test(c3):
    r, s, _ = c3
    assert "nose error" in r.stdout and "not compared" not in r.stdout
    assert s["experiment"]["compared"] is True


def test_a_run_cut_by_its_end_time_is_not_compared(tmp_path):
    """run.end_time = 0.1 ms cuts C3 (2.5 ms) in the target: fepen run says it was cut and prints no error."""
    out = tmp_path / "cut"
    r = run_fepen("run", *RIGID, "--set", "run.end_time=1e-4", "--out", str(out))
    assert r.returncode == 0, r.stderr
    s = json.loads((out / "summary.json").read_text())
    assert s["outcome"] == "ended" and s["end_time_s"] == pytest.approx(1e-4, rel=0.1)
    assert "nose error" not in r.stdout and "tail error" not in r.stdout
    line = [ln for ln in r.stdout.splitlines() if "Table 1 C3" in ln]
    assert len(line) == 1 and "not compared" in line[0] and "run.end_time" in line[0], r.stdout
    assert s["experiment"]["compared"] is False and s["experiment"]["Hy_mm"] == 349.6
