"""One outcome table (issue 28, acceptance 3): for every documented exit code, the command's exit code, the one
stderr line, summary.json's outcome, exit_code and resumable, and run.json's outcome and exit code agree with
fepen.errors.OUTCOMES; a bug is exit 1 everywhere. Rigid runs in this process, the error raised from the
Run skeleton's step at step 5."""

import errno
import json

import pytest

from fepen import cli
from fepen.errors import OUTCOMES, InputError, Interrupted, MachineFault, SimulationError
from fepen.runs.rigid import RigidRun

RIGID = ["--set", "effects.fidelity=rigid"]

CASES = {  # what the step raises -> (outcome, the start of the console line)
    "error": (ZeroDivisionError("a bug"), "fepen: internal error"),
    "stopped": (SimulationError("non-finite state at step 5"), "fepen: simulation stopped:"),
    "interrupted": (Interrupted("SIGTERM at step 5"), "fepen: interrupted:"),
    "fault": (OSError(errno.ENOSPC, "No space left on device", "x.csv"), "fepen: stopped by a fault of the machine"),
    "bad-input": (InputError("--resume", "a refusal inside the run"), "fepen: bad input:"),
}


def fepen(capsys, *argv):
    code = cli.main([str(a) for a in argv])
    _, err = capsys.readouterr()
    return code, [ln for ln in err.splitlines() if ln.strip()]


@pytest.mark.parametrize("outcome", sorted(CASES))
def test_a_stop_agrees_in_exit_code_summary_and_run_json(outcome, tmp_path, capsys, monkeypatch):
    error, line = CASES[outcome]
    step = RigidRun.step

    def failing(self):
        if self.step_count == 5:
            raise error
        step(self)

    monkeypatch.setattr(RigidRun, "step", failing)
    out = tmp_path / "run"
    code, err = fepen(capsys, "run", *RIGID, "--out", out)
    expected = OUTCOMES[outcome]
    assert code == expected.exit_code
    assert len(err) == 1 and err[0].startswith(line), err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["outcome"] == outcome
    assert summary["exit_code"] == code and summary["resumable"] is expected.resumable
    assert "Hy_mm" not in summary and summary["stop_where"]["step"] == 5
    record = json.loads((out / "run.json").read_text())
    assert record["outcome"] == outcome and record["exit_code"] == code
    assert (out / "history.csv").read_text().count("\n") == 7  # header, t = 0 and steps 1-5


def test_a_finished_run_is_exit_0_with_its_physical_outcome(tmp_path, capsys):
    out = tmp_path / "run"
    code, err = fepen(capsys, "run", *RIGID, "--out", out)
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert OUTCOMES[summary["outcome"]].exit_code == 0 and OUTCOMES[summary["outcome"]].result
    record = json.loads((out / "run.json").read_text())
    assert record["outcome"] == "finished" and record["exit_code"] == 0


def test_every_outcome_is_documented_with_its_code():
    text = open("docs/results.md").read()
    for o in OUTCOMES.values():
        assert f"`\"{o.name}\"`" in text, o.name
    assert {o.exit_code for o in OUTCOMES.values()} == {0, 1, 2, 3, 4}
    assert all(isinstance(e, BaseException) for e, _ in CASES.values()) and MachineFault.exit_code == 4
