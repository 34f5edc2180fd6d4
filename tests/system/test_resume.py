"""Interruption: a run killed midway (SIGKILL) leaves valid files, and ``fepen run --resume`` ends with the
very results of an uninterrupted run; serially and on 2 ranks (the runs are subprocesses)."""

import json
import os
import signal
import time
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from conftest import run_fepen

from fepen.studies import processes

SETS = ["--set", "mesh.size=0.005", "--set", "run.end_time=1.2e-4", "--set", "run.output_interval=1e-5",
        "--set", "run.checkpoint_interval=1.5e-5", "--set", 'impact.shot="C7"']


#: the charged projectile, its charge sliding in frictional contact (the interface's work and the
#: contact accelerations must be restored too)
CHARGED = ["--set", "effects.charge=true", "--set", 'charge.contact="frictional"']


#: wear and erosion on, a softer steel whose nose cells erode: the moved reference, the eroded cells, the
#: loaded surface and the wear heat must be restored
WORN = ["--set", "effects.wear=true", "--set", "effects.erosion=true", "--set", "projectile.material.A=3e8",
        "--set", "projectile.material.B=1e8", "--set", "projectile.erosion.strain=0.01"]


#: a node and a cell probe: probes.csv must come out whole across the kill and the resume
PROBES = ["--set", 'output.probes=[{name = "tail", point = [0.0, 0.144, 0.0]}, '
                   '{name = "wall", point = [0.0, 0.07, 0.009], kind = "cell"}]']


def start(out, ranks, extra=()):
    return processes.start(["run", *SETS, *extra, "--out", out], ranks)


def kill_after_checkpoints(proc, out, n=2, timeout=300):
    """SIGKILL the whole process group once the n-th checkpoint is complete; returns its time."""
    state = out / "checkpoint" / "state.json"
    t0 = time.time()
    seen = set()
    while time.time() - t0 < timeout:
        if state.exists():
            try:
                seen.add(json.loads(state.read_text())["step"])
            except (json.JSONDecodeError, OSError):  # being replaced: read it again
                pass
        if len(seen) >= n:
            break
        assert proc.poll() is None, f"the run ended before it could be killed: {proc.stderr.read()}"
        time.sleep(0.01)
    time.sleep(0.05)
    ranks = processes.rank_pids(proc.pid)  # the launcher may give them groups of their own
    os.killpg(proc.pid, signal.SIGKILL)
    for pid in ranks:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    proc.wait()
    while any(os.path.exists(f"/proc/{pid}") for pid in ranks):  # gone, as a killed job's ranks are
        time.sleep(0.01)
    return json.loads(state.read_text())["t_s"]


def check_valid_fields(out):
    """fields.xdmf parses and every dataset it names reads, with the right shape, from the file it names
    (fields.h5 once the run has ended; the per-time files of fields.d while it runs or after a kill)."""
    import h5py

    root = ET.parse(out / "fields.xdmf").getroot()
    items = [d for d in root.iter("DataItem")]
    assert len(items) > 2
    for d in items:
        name, path = d.text.strip().split(":", 1)
        dims = tuple(int(v) for v in d.get("Dimensions").split())
        with h5py.File(out / name, "r") as h5:
            data = h5[path][()]
        assert data.reshape(dims).shape == dims and np.all(np.isfinite(data))
    return sum(1 for g in root.iter("Grid") if g.get("GridType") == "Uniform")  # one grid per output time


#: the 2-rank case carries every kind of state at once, charged and worn: a plain run's state (fields, history,
#: the filter of the stresses) is a part of it, so one run checks what the plain, the charged and the worn 2-rank
#: runs each checked (one 2-rank run where there were three; the serial run checks the probes)
CHARGED_WORN = [*CHARGED, *WORN]


@pytest.mark.parametrize("ranks,extra", [(1, PROBES), (2, CHARGED_WORN)], ids=["1-probes", "2-charged-worn"])
def test_killed_run_resumes_to_the_same_results(tmp_path, ranks, extra):
    whole, cut = tmp_path / "whole", tmp_path / "cut"
    done = run_fepen("run", *SETS, *extra, "--out", whole, ranks=ranks)
    assert done.returncode == 0, done.stderr
    proc = start(cut, ranks, extra)
    t_ckpt = kill_after_checkpoints(proc, cut)
    # what the killed run left is valid up to its last output time
    n_out = check_valid_fields(cut)
    assert n_out >= 2
    hist = np.genfromtxt(cut / "history.csv", delimiter=",", names=True)
    assert hist["t_s"][-1] >= t_ckpt - 1e-6 and np.all(np.isfinite(hist["nose_y_mm"]))
    assert not (cut / "summary.json").exists()
    if ranks == 2:  # resuming on another rank count is refused, cleanly
        wrong = run_fepen("run", "--resume", cut, ranks=1)
        assert wrong.returncode == 2 and "2 ranks" in wrong.stderr and "Traceback" not in wrong.stderr
    res = run_fepen("run", "--resume", cut, ranks=ranks)
    assert res.returncode == 0, res.stderr
    a = json.loads((whole / "summary.json").read_text())
    b = json.loads((cut / "summary.json").read_text())
    for k in ("Hx_mm", "Hy_mm", "Tx_mm", "Ty_mm", "depth_mm", "residual_speed_m_s", "energy_error",
              "max_peeq", "steps", "dt_s", "outcome", "mass_loss_kg", "eroded_cells", "length_change_mm"):
        assert a[k] == b[k], k  # the same operations: equal, not merely close
    assert a.get("charge_safety") == b.get("charge_safety")  # the friction heat and the stresses' filter resumed
    assert (whole / "history.csv").read_text() == (cut / "history.csv").read_text()
    if extra is PROBES:
        rows = (whole / "probes.csv").read_text().splitlines()
        assert len(rows) == len((whole / "history.csv").read_text().splitlines()) > 100
        assert (cut / "probes.csv").read_text() == "\n".join(rows) + "\n"
    if extra is CHARGED_WORN:  # cells did erode, and the charge was judged
        assert a["eroded_cells"] > 0 and a["mass_loss_kg"] > 0.0 and a["charge_safety"]["margin"] > 0.0
    assert check_valid_fields(cut) == check_valid_fields(whole) > n_out
    assert not (cut / "checkpoint").exists() and not (cut / "fields.d").exists()


def test_resume_needs_a_checkpoint(tmp_path):
    """A finished run (its checkpoint removed) and a directory that is no run: exit 2, one line."""
    res = run_fepen("run", "--resume", tmp_path)
    assert res.returncode == 2 and "no scene.toml" in res.stderr
    assert run_fepen("run", *SETS[:4], "--set", "run.end_time=2e-5", "--out", tmp_path).returncode == 0
    res = run_fepen("run", "--resume", tmp_path)
    assert res.returncode == 2 and "holds no checkpoint" in res.stderr and "Traceback" not in res.stderr
    res = run_fepen("run", "--resume", tmp_path, "--set", "mesh.size=0.003")
    assert res.returncode == 2 and "--resume" in res.stderr
