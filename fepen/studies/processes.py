"""Whole ``fepen`` processes and Python scripts, as a user would start them, under ``mpirun -n RANKS`` when
ranks > 1 (studies, demos, benchmarks and tests all start them here)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def mpi_env(**extra) -> dict:
    """The environment of a child process: OpenMPI allowed to run as root and to oversubscribe, and this
    source tree first on the Python path (a checkout runs its own fepen)."""
    path = os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH", "")) if p)
    return dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                OMPI_MCA_rmaps_base_oversubscribe="1", PYTHONPATH=path, **extra)


def launcher(python: str | Path | None = None) -> str | None:
    """The MPI launcher of a Python's MPI (default: this one's): ``mpiexec`` beside the interpreter when its
    environment holds an MPI of its own (PyPI's MPICH wheel, a conda environment), else ``mpirun`` on the PATH
    (Debian's Open MPI), else None. An Open MPI mpirun starting ranks linked to MPICH would start singletons, not
    one run."""
    import shutil

    here = Path(python or sys.executable).parent
    for name in ("mpiexec", "mpirun"):
        if (here / name).is_file() and os.access(here / name, os.X_OK):
            return str(here / name)
    return shutil.which("mpirun")


def command(args, ranks: int = 1, fepen: bool = True) -> list[str]:
    """``python -m fepen ARGS`` (or ``python ARGS`` with fepen=False), under the launcher when ranks > 1 (Open MPI's
    quietly: without the banner it prints after a rank's non-zero exit, or its note of a forwarded signal,
    below fepen's own line)."""
    cmd = [sys.executable, *(["-m", "fepen"] if fepen else []), *map(str, args)]
    if ranks <= 1:
        return cmd
    run = launcher() or "mpirun"
    return [run, *(["-q"] if _open_mpi(run) else []), "-n", str(ranks), *cmd]


def _open_mpi(run: str) -> bool:
    """The launcher is Open MPI's (which knows -q), by what it says of itself (remembered per path)."""
    if run not in _OPEN_MPI:
        try:
            text = subprocess.run([run, "--version"], capture_output=True, text=True, timeout=30).stdout
        except (OSError, subprocess.SubprocessError):
            text = ""
        _OPEN_MPI[run] = "Open MPI" in text or "OpenRTE" in text
    return _OPEN_MPI[run]


_OPEN_MPI: dict[str, bool] = {}


def rank_pids(launcher_pid: int) -> list[int]:
    """The ranks a launcher started: the Python processes below it, however deep (Open MPI's mpirun starts them
    as its children; MPICH's mpiexec under a hydra_pmi_proxy of its own). Linux (/proc); sorted."""
    children: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            text = stat.read_text()
        except OSError:  # gone meanwhile
            continue
        ppid = int(text.rsplit(")", 1)[1].split()[1])
        children.setdefault(ppid, []).append(int(stat.parent.name))
    out, todo = [], [launcher_pid]
    while todo:
        for pid in children.get(todo.pop(), []):
            todo.append(pid)
            try:
                if Path(f"/proc/{pid}/exe").resolve().name.startswith("python"):
                    out.append(pid)
            except OSError:
                pass
    return sorted(out)


def run(args, ranks: int = 1, fepen: bool = True, cwd=None, timeout: float | None = None, check: bool = False):
    """Run a whole process to its end; its CompletedProcess (output captured as text)."""
    return subprocess.run(command(args, ranks, fepen), cwd=cwd or ROOT, capture_output=True, text=True,
                          env=mpi_env(), timeout=timeout, check=check)


def start(args, ranks: int = 1, fepen: bool = True, cwd=None) -> subprocess.Popen:
    """Start a whole process in a session of its own (so that its process group can be signalled)."""
    return subprocess.Popen(command(args, ranks, fepen), cwd=cwd or ROOT, env=mpi_env(), start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


def run_fepen_process(args: list[str], ranks: int = 1) -> tuple[int, float, str]:
    """Run ``python -m fepen ARGS`` as a whole process.

    Returns:
        (exit code, wall seconds, the last "fepen:" line of its stderr, or its tail).
    """
    t0 = time.perf_counter()
    r = run(args, ranks)
    wall = time.perf_counter() - t0
    lines = [ln for ln in r.stderr.strip().splitlines() if ln.startswith("fepen:")]
    return r.returncode, wall, (lines[-1] if lines else r.stderr.strip()[-400:])


#: the signals a relaunching command passes on to the ranks it started (as SIGUSR1, which the launcher forwards
#: to every rank without ending them: fepen.runs.interrupts)
FORWARDED = (signal.SIGTERM, signal.SIGINT, signal.SIGHUP)


def relaunch(argv: list, workers: int) -> int:
    """A study command started without mpirun on a machine that has it (``fepen sweep``, ``fepen validate``,
    ``fepen validate-depth``): the same command again as ``mpirun -n WORKERS python -m fepen ARGV --workers 1``,
    whose ranks share the shots (the caller checked its input first; rank 0's bar shows where the launcher's
    stderr, this process's, is a terminal: fepen.progress).

    The launcher runs in a session of its own, so that Ctrl-C and a scheduler's signal reach this process only,
    which passes SIGTERM, SIGINT and SIGHUP on as SIGUSR1: Open MPI's mpirun and MPICH's mpiexec forward SIGUSR1
    to every rank (their own SIGTERM would end the ranks within a second), and every rank stops at its next shot
    boundary, records the study resumable and ends; this process waits for them. A second SIGINT (Ctrl-C twice)
    is passed on as SIGTERM: the ranks end at once. Should this process be killed outright, the kernel sends the
    launcher SIGUSR1 (PR_SET_PDEATHSIG, Linux): its ranks stop the same way, never left running into OUT.

    Returns:
        The launcher's exit code.
    """
    from fepen.errors import RELAUNCHED

    proc = subprocess.Popen(command([*map(str, argv), "--workers", "1"], workers), env=mpi_env(**{RELAUNCHED: "1"}),
                            start_new_session=True, preexec_fn=_usr1_when_parent_dies)
    caught: list[int] = []

    def forward(signum, frame) -> None:
        second = signum == signal.SIGINT and signal.SIGINT in caught
        caught.append(signum)
        try:
            proc.send_signal(signal.SIGTERM if second else signal.SIGUSR1)
        except OSError:  # gone meanwhile
            pass

    previous = {}
    if threading.current_thread() is threading.main_thread():
        previous = {sig: signal.signal(sig, forward) for sig in FORWARDED}
    try:
        while True:
            try:
                return proc.wait()
            except KeyboardInterrupt:  # a handler of a caller's: keep waiting for the ranks
                continue
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def _usr1_when_parent_dies() -> None:
    """In the launcher's process before it starts: SIGUSR1 to it when the relaunching process dies (Linux)."""
    try:
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGUSR1, 0, 0, 0)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):  # not Linux: the signal handlers alone
        pass


def relaunch_sweep(sweep_file, out, ranks_per_shot: int, workers: int, sets=(), fresh: bool = False) -> int:
    """``fepen sweep`` started without mpirun on a machine that has it: ``relaunch`` of the same sweep, whose ranks
    share the shots in groups of ``ranks_per_shot``. Returns that process's exit code."""
    argv = ["sweep", sweep_file, "--out", out, "--ranks-per-shot", str(ranks_per_shot),
            *(["--fresh"] if fresh else []), *[f"--set={s}" for s in sets]]
    return relaunch(argv, workers)
