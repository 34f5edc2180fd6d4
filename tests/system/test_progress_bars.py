"""Progress where users run (issue 61): ``fepen run`` in a terminal shows its bar, under ``mpirun -n 2`` started
from a terminal too (once: rank 0's, though its stderr is a pipe to mpirun), in a notebook the cell's output holds
it; ``2> err.txt`` gets no bar and no control character; ``fepen.sweep`` prints nothing into a notebook's cell
(its lines go to the fepen logger). The terminal is a pseudo-terminal of 120 columns (os.openpty), on the
command's stdin, stdout and stderr as a user's shell gives them.

Before: no bar under mpirun (rank 0's stderr is a pipe, FEPEN_PROGRESS unset) and none in a notebook (ipykernel's
stderr is no terminal: tqdm disabled itself); fepen.sweep printed "shots: 2; 1 group of 1 rank" to stdout."""

import fcntl
import json
import logging
import os
import re
import select
import signal
import struct
import subprocess
import termios
import time

import pytest
from conftest import ROOT

from fepen.studies import processes

#: a rigid fepen run of the default shot (C3): its bar runs over 5e-5 s of simulated time, in µs
QUICK = ["run", "--set", "effects.fidelity=rigid", "--set", "run.figures=false", "--set", "run.fields=false"]
#: a frame of the run's bar (tqdm's text: "fepen:  40%|████      | 20000/50000 [...]")
BAR = re.compile(r"fepen: +\d+%\|[^|]*\| *\d+/50000 ")
#: the end of a bar that does not stay (leave=False): the line blanked, one per bar
CLEARED = re.compile(r"\r {20,}\r")


def _env() -> dict:
    env = processes.mpi_env()
    env.pop("FEPEN_PROGRESS", None)
    return env


def on_terminal(cmd: list, timeout: float = 180) -> tuple[int | None, str]:
    """``cmd`` on a new pseudo-terminal (120 columns, 40 rows; its stdin, stdout and stderr), in a session of its
    own: (its exit code, or None when it did not end within ``timeout`` s and was killed; all it wrote)."""
    master, slave = os.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 40, 120, 0, 0))
    proc = subprocess.Popen(list(map(str, cmd)), stdin=slave, stdout=slave, stderr=slave, env=_env(), cwd=ROOT,
                            start_new_session=True)
    os.close(slave)
    out, deadline = bytearray(), time.monotonic() + timeout
    try:
        while time.monotonic() < deadline:
            if select.select([master], [], [], 1.0)[0]:
                try:
                    chunk = os.read(master, 65536)
                except OSError:  # EIO: every process holding the terminal has closed it
                    break
                if not chunk:
                    break
                out += chunk
        code = proc.wait(timeout=max(1.0, deadline - time.monotonic()))
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)  # the session started here: the launcher and its ranks
        proc.wait()
        code = None
    finally:
        os.close(master)
    return code, out.decode(errors="replace")


def test_a_redirected_stderr_gets_no_bar(tmp_path):
    """``fepen run ... 2> err.txt`` typed in a terminal: no bar in the file, no control character."""
    err = tmp_path / "err.txt"
    cmd = " ".join(map(str, processes.command([*QUICK, "--out", tmp_path / "run"]))) + f" 2> {err}"
    code, text = on_terminal(["sh", "-c", cmd])
    assert code == 0, text[-2000:]
    assert "written:" in text  # its key = value lines, on the terminal
    assert err.exists() and not BAR.search(err.read_text())
    assert not re.search(r"[\r\x1b]", err.read_text()), repr(err.read_text()[:400])


def test_a_terminal_shows_the_bar(tmp_path):
    code, text = on_terminal(processes.command([*QUICK, "--out", tmp_path / "run"]))
    assert code == 0, text[-2000:]
    assert BAR.search(text), text[:2000]
    assert len(CLEARED.findall(text)) == 1  # one bar, gone at the end


@pytest.mark.parametrize("ranks", [2])  # marked two_ranks by tests/conftest.py
def test_mpirun_started_from_a_terminal_shows_rank_0_s_bar(tmp_path, ranks):
    """Open MPI's rank 0 writes its stderr into a pipe to mpirun even when mpirun's is a terminal: the bar shows
    (fepen.progress reads mpirun's stderr), once, rank 0's."""
    for _ in range(2):  # an MPI_Init that hangs here now and then: once more
        code, text = on_terminal(processes.command([*QUICK, "--out", tmp_path / "run", "--force"], ranks), 120)
        if code is not None:
            break
    assert code == 0, text[-2000:]
    assert json.loads((tmp_path / "run" / "summary.json").read_text())["ranks"] == 2
    assert BAR.search(text), text[:2000]
    assert len(CLEARED.findall(text)) == 1  # one bar: rank 0's (rank 1 draws none)


def test_a_notebook_shows_the_bar(tmp_path, monkeypatch):
    """A notebook (nbclient, an IPython kernel) running a rigid shot by the Python API: the cell's output holds
    the bar, a widget where ipywidgets is installed, else the text bar in its stderr stream."""
    nbclient = pytest.importorskip("nbclient", reason="the notebook tests need fepen[test] (nbclient, ipykernel)")
    nbformat = pytest.importorskip("nbformat")
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH")) if p))
    monkeypatch.delenv("FEPEN_PROGRESS", raising=False)
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(
        "import fepen\n"
        "scene = fepen.Scene(sets=['effects.fidelity=rigid', 'run.figures=false'])\n"
        f"r = fepen.run(scene, out={str(tmp_path / 'run')!r}, progress=True)\n"
        "print('depth_mm', r.summary['Hy_mm'], 'from', fepen.__file__)")]
    nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    outputs = nb.cells[0].outputs
    stdout = "".join(o.get("text", "") for o in outputs if o.get("name") == "stdout")
    assert f"from {ROOT}" in stdout  # this checkout's fepen ran
    assert 300 < float(re.search(r"depth_mm ([\d.]+)", stdout).group(1)) < 400  # C3 rigid: about 352 mm
    widget = any("application/vnd.jupyter.widget-view+json" in o.get("data", {}) for o in outputs)
    stderr = "".join(o.get("text", "") for o in outputs if o.get("name") == "stderr")
    assert widget or BAR.search(stderr), outputs
    assert "IProgress not found" not in stderr  # tqdm.auto's warning when ipywidgets is absent: not ours


def test_fepen_sweep_prints_nothing_into_the_cell(tmp_path, capsys, caplog):
    """The sweep's lines go to the fepen logger (INFO): a notebook's cell stays clean unless logging asks."""
    import fepen

    spec = {"base": {"effects.fidelity": "rigid", "run.figures": False}, "grid": {"impact.velocity": [500.0, 700.0]}}
    with caplog.at_level(logging.INFO, logger="fepen"):
        table = fepen.sweep(spec, out=tmp_path / "sweep")
    assert list(table["status"]) == ["ok", "ok"]
    out = capsys.readouterr().out
    assert "group" not in out and "shots:" not in out, out
    assert any("1 group of 1 rank" in r.getMessage() for r in caplog.records)  # asked for: it is there
