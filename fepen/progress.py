"""Whether a progress bar shows, and which tqdm draws it: the one decision of every fepen bar (a run's simulated
time, the mesh's stages, a study's shots; docs/results.md, "Progress").

    FEPEN_PROGRESS=1   the bar shows on rank 0, wherever its stderr goes
    FEPEN_PROGRESS=0   no bar
    unset              on rank 0 only: when its stderr is a terminal; under mpirun or mpiexec when the launcher's
                       stderr is one (a rank's own stderr is then a pipe to the launcher: Open MPI's always); in
                       a Jupyter kernel, as a widget (ipywidgets) or else as text in the cell's output; never
                       into a file or a pipe (``2> err.txt``, a Slurm .err file, ``| tee``)

The launcher is found by its process (Linux's /proc): the parents of this process named as an MPI launcher or
its node daemon (LAUNCHERS), the outermost of them, the one the user started, holding the terminal or not.
"""

from __future__ import annotations

import os
import re
import sys
import warnings

#: the switch: "1" shows the bars, "0" hides them; anything else is as unset
ENV = "FEPEN_PROGRESS"

#: the processes that start MPI ranks or stand between them and the launcher's stdio (Open MPI 4 and 5, MPICH's
#: and Intel MPI's hydra), by their name in /proc/PID/comm (at most 15 characters)
LAUNCHERS = frozenset({"mpirun", "mpiexec", "orterun", "orted", "prterun", "prted", "mpiexec.hydra",
                       "hydra_pmi_proxy", "pmi_proxy"})

_TERMINAL = re.compile(r"/dev/(pts/\d+|tty\w*|console)")


def shown(rank: int = 0, stream=None) -> bool:
    """Whether a bar shows (the module's rule).

    Args:
        rank: this process's rank in the bar's communicator (a bar shows on rank 0 only).
        stream: the stream it would write to (None: sys.stderr).

    Returns:
        True when the bar is to be drawn.
    """
    if rank != 0:
        return False
    env = os.environ.get(ENV)
    if env in ("0", "1"):
        return env == "1"
    if in_kernel():
        return True
    stream = sys.stderr if stream is None else stream
    try:
        if stream.isatty():
            return True
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return False
    return launcher_on_terminal()


def in_kernel() -> bool:
    """Whether this process is a Jupyter kernel (an IPython shell with a kernel: ipykernel's)."""
    if "ipykernel" not in sys.modules or "IPython" not in sys.modules:
        return False
    get_ipython = getattr(sys.modules["IPython"], "get_ipython", None)
    shell = get_ipython() if get_ipython is not None else None
    return getattr(shell, "kernel", None) is not None


def launcher_on_terminal(pid: int | None = None, proc: str = "/proc") -> bool:
    """Whether the MPI launcher that started this process writes its stderr to a terminal: of the chain of
    parents named in LAUNCHERS (a launcher, and a node daemon or proxy between it and the ranks), the outermost
    one's fd 2. False when the parent is no launcher, or where /proc cannot tell.

    Args:
        pid: the first parent to look at (None: this process's parent). proc: the proc file system's root.

    Returns:
        True when that stderr is a terminal (/dev/pts/N, /dev/ttyN, /dev/tty, /dev/console).
    """
    pid = os.getppid() if pid is None else pid
    verdict = False
    for _ in range(8):  # a launcher, a daemon, a proxy: a few levels at most
        try:
            with open(f"{proc}/{pid}/comm") as f:
                if f.read().strip() not in LAUNCHERS:
                    break
            verdict = bool(_TERMINAL.fullmatch(os.readlink(f"{proc}/{pid}/fd/2")))
            with open(f"{proc}/{pid}/stat") as f:
                pid = int(f.read().rsplit(")", 1)[1].split()[1])  # the parent: after the name, the state
        except (OSError, ValueError, IndexError):
            break
    return verdict


def bar(on: bool = True, rank: int = 0, **kwargs):
    """A tqdm bar, drawn where ``shown`` says (else a disabled one, which counts and draws nothing): tqdm's
    notebook widget in a Jupyter kernel with ipywidgets, else tqdm's text bar on sys.stderr (in a kernel
    without ipywidgets: the cell's stderr output).

    Args:
        on: the caller's own switch (False: a disabled bar). rank: as for ``shown``.
        kwargs: tqdm's (total, desc, unit, leave, bar_format, ...).

    Returns:
        The tqdm instance.
    """
    draw = on and shown(rank)
    if draw and in_kernel():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            from tqdm import notebook
        if notebook.IProgress is not None:  # ipywidgets: the notebook's widget
            kwargs.pop("file", None)
            return notebook.tqdm(disable=False, **kwargs)
    from tqdm import tqdm

    kwargs.setdefault("file", sys.stderr)
    return tqdm(disable=not draw, **kwargs)
