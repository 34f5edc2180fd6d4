"""``fepen sweep`` as a user runs it: the same table serially and on two MPI ranks (rigid Monte Carlo, and
deformable shots on groups of 1 and 2 ranks), and a sweep killed with SIGKILL half way that, started again,
runs only its missing shots and ends with the uninterrupted table."""

import json
import os
import signal
import time

import pytest
from conftest import run_fepen

from fepen.studies import processes, sweep

#: one pytest-xdist worker runs this module (make test: -n 2 --dist loadgroup), so that its module-scoped
#: runs are made once, not once per worker
pytestmark = pytest.mark.xdist_group("test_sweep")

DEMO = processes.ROOT / "demos" / "studies" / "c3_scatter.toml"  # the shipped C3 scatter, resized
N = 60  # rigid shots: enough to kill a sweep half way and resume it (120 made each of its four sweeps 5-6 s longer)


@pytest.fixture(scope="module")
def mc(tmp_path_factory):
    """The sweep file and its uninterrupted serial run."""
    d = tmp_path_factory.mktemp("mc")
    (d / "mc.toml").write_text(sweep.resized(DEMO, N, seed=11))
    r = run_fepen("sweep", d / "mc.toml", "--out", d / "serial", "--workers", "1")
    assert r.returncode == 0, r.stderr
    return d


def records(out):
    return [json.loads(line) for line in (out / "shots.jsonl").read_text().splitlines() if line.endswith("}")]


def test_serial_table_has_every_shot(mc):
    text = (mc / "serial" / "sweep.csv").read_text().splitlines()
    assert len(text) == N + 1
    head = text[0].split(",")
    for col in ("shot", "impact.velocity", "target.compressive_strength", "status", "outcome", "depth_mm",
                "residual_speed_m_s"):
        assert col in head
    assert "wall_s" not in head  # the machine's figures are in costs.csv
    assert sorted(r["shot"] for r in records(mc / "serial")) == list(range(N))
    assert (mc / "serial" / "histograms.png").stat().st_size > 10_000
    assert (mc / "serial" / "sweep.png").stat().st_size > 10_000


def test_two_ranks_give_the_same_table(mc):
    """--workers 2 runs the sweep under mpirun -n 2: two groups taking shots from the queue."""
    r = run_fepen("sweep", mc / "mc.toml", "--out", mc / "two", "--workers", "2")
    assert r.returncode == 0, r.stderr
    assert "2 groups of 1 rank" in r.stdout
    assert (mc / "two" / "sweep.csv").read_text() == (mc / "serial" / "sweep.csv").read_text()
    assert {r["ranks"] for r in records(mc / "two")} == {1}


def test_killed_sweep_runs_only_the_missing_shots(mc):
    out = mc / "killed"
    proc = processes.start(["sweep", mc / "mc.toml", "--out", out, "--workers", "1"])
    t0 = time.time()
    while time.time() - t0 < 300:
        if (out / "shots.jsonl").is_file() and len((out / "shots.jsonl").read_text().splitlines()) >= N // 2:
            break
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    done = {r["shot"] for r in records(out)}
    assert N // 2 <= len(done) < N, "the sweep was not stopped half way"
    assert not (out / "sweep.csv").exists()
    r = run_fepen("sweep", mc / "mc.toml", "--out", out, "--workers", "1")
    assert r.returncode == 0, r.stderr
    assert f"{N - len(done)} run now, {len(done)} recorded before" in r.stdout
    shots = [r["shot"] for r in records(out)]
    assert sorted(shots) == list(range(N)), "a finished shot ran twice, or one is missing"
    assert (out / "sweep.csv").read_text() == (mc / "serial" / "sweep.csv").read_text()


def test_another_sweep_into_the_same_directory_is_refused(mc, tmp_path):
    other = tmp_path / "other.toml"
    other.write_text(sweep.resized(DEMO, N + 1, seed=11))
    r = run_fepen("sweep", other, "--out", mc / "serial", "--workers", "1")
    assert r.returncode == 2
    assert "--out" in r.stderr and "sweep made of other inputs (its shots" in r.stderr and "Traceback" not in r.stderr


GRID = """scene = "{root}/scenes/default.toml"
[base]
mesh.size = 0.004
run.end_time = 4e-5
run.fields = false
run.figures = false
run.checkpoint_interval = 0.0
[grid]
"impact.shot" = ["C1", "C7"]
"""


def test_deformable_shots_on_groups_of_one_and_two_ranks(tmp_path):
    """Two plastic shots under mpirun -n 2: each on 2 ranks, or both at once on 1 rank each; same table to
    the printed digits."""
    (tmp_path / "grid.toml").write_text(GRID.format(root=processes.ROOT))
    tables = {}
    for k in (1, 2):
        r = run_fepen("sweep", tmp_path / "grid.toml", "--out", tmp_path / f"k{k}", "--ranks-per-shot", k,
                      ranks=2)
        assert r.returncode == 0, r.stderr
        tables[k] = (tmp_path / f"k{k}" / "sweep.csv").read_text()
        assert (tmp_path / f"k{k}" / "shots" / "00001" / "summary.json").is_file()
    cols = tables[1].splitlines()[0].split(",")
    rows = {k: [line.split(",") for line in t.splitlines()[1:]] for k, t in tables.items()}
    assert len(rows[1]) == 2
    for a, b in zip(rows[1], rows[2]):
        for c, x, y in zip(cols, a, b):
            if c != "energy_error":  # a residual of large sums: its last digits are round-off
                assert x == y, (c, x, y)
