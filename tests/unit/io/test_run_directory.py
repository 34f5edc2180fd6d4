"""Results that cannot be mistaken (issue 18, items 1, 6 and 7): a second run into a finished run's directory
refuses, --force clears only what fepen writes, a live lock keeps a second run out and a stale one is taken
over, run.json and fepen.log record the run, --version, --debug, and every error is one line with its code.
Rigid runs, in this process (a tenth of a second each)."""

import json
import os
import socket
import subprocess
import sys

import pytest

from fepen import cli
from fepen.errors import MachineFault
from fepen.io import rundir

RIGID = ["--set", "effects.fidelity=rigid"]


def fepen(capsys, *argv):
    """(exit code, stdout, the stderr lines) of ``fepen ARGV`` in this process."""
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, [ln for ln in err.splitlines() if ln.strip()]


def test_second_run_into_a_finished_run_refuses_then_force_clears(tmp_path, capsys):
    out = tmp_path / "run"
    assert fepen(capsys, "run", *RIGID, "--out", out)[0] == 0
    record = json.loads((out / "run.json").read_text())
    (out / "hazard.csv").write_text("a file the earlier run wrote")  # as if that run had written one more file
    (out / "run.json").write_text(json.dumps({**record, "files": [*record["files"], "hazard.csv"]}))
    (out / "notes.txt").write_text("mine")  # the user's own file
    code, _, err = fepen(capsys, "run", *RIGID, "--set", "impact.velocity=700", "--out", out)
    assert code == 2 and len(err) == 1 and err[0].startswith("fepen: bad input: --out:")
    assert "--force" in err[0] and "--resume" in err[0]
    assert json.loads((out / "summary.json").read_text())["scene"]["impact"]["velocity"] != 700.0  # untouched
    code, _, err = fepen(capsys, "run", *RIGID, "--set", "impact.velocity=700", "--out", out, "--force")
    assert code == 0, err
    assert not (out / "hazard.csv").exists() and (out / "notes.txt").read_text() == "mine"
    assert json.loads((out / "summary.json").read_text())["scene"]["impact"]["velocity"] == 700.0
    assert "notes.txt" not in json.loads((out / "run.json").read_text())["files"]


def test_run_json_and_log_record_the_run(tmp_path, capsys):
    out = tmp_path / "run"
    code, stdout, _ = fepen(capsys, "run", *RIGID, "--out", out)
    assert code == 0
    rec = json.loads((out / "run.json").read_text())
    assert rec["command"] == ["fepen", "run", *RIGID, "--out", str(out)]
    assert rec["ranks"] == 1 and rec["fepen"] and rec["host"] == socket.gethostname()
    assert rec["outcome"] == "finished" and rec["exit_code"] == 0 and rec["start"] <= rec["end"]
    assert "revision" in rec
    log = (out / "fepen.log").read_text()
    for line in stdout.splitlines():  # what the console showed is in the log
        assert line in log
    assert not (out / rundir.LOCK).exists()  # released


def test_live_lock_refuses_and_stale_lock_is_taken_over(tmp_path, capsys):
    out = tmp_path / "run"
    out.mkdir()
    other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        (out / rundir.LOCK).write_text(json.dumps({"host": socket.gethostname(), "pid": other.pid, "start": "x"}))
        code, _, err = fepen(capsys, "run", *RIGID, "--out", out)
        assert code == 2 and len(err) == 1 and "in use by another run" in err[0] and str(other.pid) in err[0]
        assert not (out / "summary.json").exists()
    finally:
        other.kill()
        other.wait()
    code, _, err = fepen(capsys, "run", *RIGID, "--out", out)  # its process is gone: a stale lock
    assert code == 0, err
    assert "stale lock" in (out / "fepen.log").read_text()
    (out / rundir.LOCK).write_text(json.dumps({"host": "another-host", "pid": 1, "start": "x"}))
    code, _, err = fepen(capsys, "run", "--resume", out)
    assert code == 2 and "another-host" in err[0] and "delete" in err[0]


@pytest.mark.parametrize("argv,pattern", [
    (["run", "--out", "/etc/hostname"], "--out: /etc/hostname is a file"),
    (["run", "--out", "/proc/fepen/x"], "--out: cannot create the directory /proc/fepen/x"),
    (["run", "--resume", "/nonexistent/dir"], "--resume: /nonexistent/dir is not a results directory"),
    (["run", "--resume", "."], "--resume"),
    ([], "name a command"),
    (["frobnicate"], "invalid choice"),
], ids=["out-file", "out-uncreatable", "resume-missing", "resume-not-a-run", "no-command", "unknown-command"])
def test_bad_command_lines_are_one_line_exit_2(argv, pattern, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, _, err = fepen(capsys, *argv, *(RIGID if argv[:1] == ["run"] and "--resume" not in argv else []))
    assert code == 2 and len(err) == 1 and err[0].startswith("fepen: bad input:") and pattern in err[0], err
    assert not any("Traceback" in ln for ln in err)


def test_version_and_debug(capsys, tmp_path):
    code, out, err = fepen(capsys, "--version")
    assert code == 0 and out.startswith("fepen ") and not err
    import dolfinx
    import numpy as np
    from petsc4py import PETSc

    stack = out.splitlines()[1]  # the software it runs on: dolfinx (supported), PETSc, the MPI library, numpy
    assert stack.startswith(f"dolfinx {dolfinx.__version__} (supported), PETSc {PETSc.Sys.getVersion()[0]}.")
    assert ("Open MPI" in stack or "MPICH" in stack) and f"numpy {np.__version__}" in stack
    code, _, err = fepen(capsys, "--debug", "run", "--out", "/etc/hostname", *RIGID)
    assert code == 2 and any("Traceback" in ln for ln in err) and err[-1].startswith("fepen: bad input:")


def test_a_fault_of_the_machine_is_exit_4_and_one_line(tmp_path, capsys, monkeypatch):
    """A full disk (injected at the first summary.json write): exit 4, one line; summary.json says so."""
    monkeypatch.setenv("FEPEN_INJECT_FAULT", "summary:1")
    monkeypatch.setattr("fepen.io.files._writes", {})
    out = tmp_path / "run"
    code, _, err = fepen(capsys, "run", *RIGID, "--out", out)
    assert code == MachineFault.exit_code == 4 and len(err) == 1
    assert err[0].startswith("fepen: stopped by a fault of the machine: no space left on device")
    summary = json.loads((out / "summary.json").read_text())  # written by the stop, which did not fail
    assert summary["outcome"] == "fault" and summary["exit_code"] == 4 and "Hy_mm" not in summary
    assert json.loads((out / "run.json").read_text())["exit_code"] == 4
    monkeypatch.delenv("FEPEN_INJECT_FAULT")
    code, _, err = fepen(capsys, "run", "--resume", out)  # space freed: a rigid run runs again
    assert code == 0, err
    assert json.loads((out / "summary.json").read_text())["outcome"] == "embedded"
    assert json.loads((out / "run.json").read_text())["final_exit_code"] == 0


def test_an_internal_error_is_one_line_exit_1(capsys, monkeypatch):
    def broken(args):
        raise ZeroDivisionError("a bug")

    monkeypatch.setitem(cli.COMMANDS, "keys", broken)
    code, _, err = fepen(capsys, "keys")
    assert code == 1 and len(err) == 1 and "internal error" in err[0] and "--debug" in err[0]


def test_lock_records_this_process(tmp_path):
    from mpi4py import MPI

    with rundir.RunDirectory(tmp_path / "d", MPI.COMM_SELF, "new", ["fepen", "x"]):
        lock = json.loads((tmp_path / "d" / rundir.LOCK).read_text())
        assert lock["pid"] == os.getpid() and lock["host"] == socket.gethostname()
    assert not (tmp_path / "d" / rundir.LOCK).exists()
