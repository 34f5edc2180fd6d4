"""fepen.progress, the one decision of every bar (issue 61): rank 0 only; FEPEN_PROGRESS=1 shows, 0 hides; unset:
a terminal on stderr, the terminal of the mpirun or mpiexec that started the ranks (found through /proc: here a
made-up /proc of the chains a user starts), or a Jupyter kernel (a widget with ipywidgets, else the text bar in
the cell's stderr); nothing into a file or a pipe."""

import io
import os
import sys
import types

import pytest

from fepen import progress


class Stream(io.StringIO):
    def __init__(self, tty: bool):
        super().__init__()
        self.tty = tty

    def isatty(self) -> bool:
        return self.tty


@pytest.fixture
def plain(monkeypatch):
    """No switch, no kernel, no launcher above."""
    monkeypatch.delenv(progress.ENV, raising=False)
    monkeypatch.setattr(progress, "in_kernel", lambda: False)
    monkeypatch.setattr(progress, "launcher_on_terminal", lambda: False)
    return monkeypatch


@pytest.mark.parametrize("env,tty,launcher,rank,expected", [
    (None, True, False, 0, True), (None, False, False, 0, False), (None, False, True, 0, True),
    (None, True, False, 1, False), ("1", False, False, 0, True), ("1", True, False, 1, False),
    ("0", True, True, 0, False), ("sometimes", False, False, 0, False), ("sometimes", True, False, 0, True)])
def test_the_switch_the_terminal_the_launcher_and_the_rank(plain, env, tty, launcher, rank, expected):
    if env is not None:
        plain.setenv(progress.ENV, env)
    plain.setattr(progress, "launcher_on_terminal", lambda: launcher)
    assert progress.shown(rank, Stream(tty)) is expected


def _proc(root, chain):
    """A /proc of the parents: chain = [(comm, fd 2's target), ...] from the first parent up; pids 100, 101, ..."""
    for i, (comm, target) in enumerate(chain):
        d = root / str(100 + i)
        (d / "fd").mkdir(parents=True)
        (d / "comm").write_text(comm + "\n")
        (d / "stat").write_text(f"{100 + i} ({comm} x) S {101 + i} 1 1 0 -1\n")
        os.symlink(target, d / "fd" / "2")
    return str(root)


@pytest.mark.parametrize("chain,expected", [
    ([("mpirun", "/dev/pts/3"), ("bash", "/dev/pts/3")], True),  # mpirun -n 2 fepen run, in a terminal
    ([("mpirun", "/tmp/err.txt"), ("bash", "/dev/pts/3")], False),  # mpirun ... 2> err.txt
    ([("mpirun", "pipe:[4242]"), ("bash", "/dev/pts/3")], False),  # mpirun ... 2>&1 | tee log
    ([("mpirun", "/dev/null"), ("sbatch", "/dev/null")], False),
    ([("hydra_pmi_proxy", "pipe:[1]"), ("mpiexec.hydra", "/dev/pts/0"), ("zsh", "/dev/pts/0")], True),  # MPICH
    ([("orted", "/dev/null"), ("sshd", "socket:[9]")], False),  # a rank on another node than mpirun
    ([("mpirun", "/dev/pts/1"), ("python3", "/dev/pts/1")], True),  # fepen sweep relaunched under mpirun
    ([("bash", "/dev/pts/3")], False),  # fepen run 2>&1 | cat: no launcher, the shell's terminal is not ours
    ([("python3", "/dev/tty1")], False),
])
def test_the_launcher_s_terminal(tmp_path, chain, expected):
    assert progress.launcher_on_terminal(100, _proc(tmp_path, chain)) is expected


def test_no_proc_no_launcher(tmp_path):
    assert progress.launcher_on_terminal(100, str(tmp_path / "absent")) is False


@pytest.fixture
def kernel(monkeypatch):
    """A Jupyter kernel (as ipykernel's shell has a kernel)."""
    shell = types.SimpleNamespace(kernel=object())
    monkeypatch.setitem(sys.modules, "ipykernel", types.ModuleType("ipykernel"))
    monkeypatch.setitem(sys.modules, "IPython", types.SimpleNamespace(get_ipython=lambda: shell))
    monkeypatch.delenv(progress.ENV, raising=False)
    monkeypatch.setattr(progress, "launcher_on_terminal", lambda: False)
    return monkeypatch


def test_a_kernel_is_recognised(kernel):
    assert progress.in_kernel()
    assert progress.shown(0, Stream(False)) and not progress.shown(1)


def test_a_kernel_without_ipywidgets_gets_the_text_bar_in_its_stderr(kernel):
    from tqdm import notebook

    stream = Stream(False)  # the kernel's stderr, the cell's output: no terminal
    kernel.setattr(sys, "stderr", stream)  # in the test: pytest's capture sets sys.stderr after the fixtures
    kernel.setattr(notebook, "IProgress", None)
    bar = progress.bar(total=100, desc="fepen", unit="µs", leave=False)
    bar.update(40)
    bar.refresh()
    bar.close()
    assert "fepen:  40%|" in stream.getvalue()


def test_a_kernel_with_ipywidgets_gets_the_widget(kernel):
    from tqdm import notebook

    stream = Stream(False)
    kernel.setattr(sys, "stderr", stream)
    made = []
    kernel.setattr(notebook, "IProgress", object)
    kernel.setattr(notebook, "tqdm", lambda **kw: made.append(kw) or "widget")
    assert progress.bar(total=3, desc="shots", file=sys.stderr) == "widget"
    assert made == [{"disable": False, "total": 3, "desc": "shots"}]
    assert stream.getvalue() == ""


def test_off_by_the_caller_or_the_rank_draws_nothing(plain):
    stream = Stream(True)
    plain.setattr(sys, "stderr", stream)
    for bar in (progress.bar(False, total=10, desc="shots"), progress.bar(rank=1, total=10, desc="shots")):
        bar.update(5)
        bar.close()
    assert stream.getvalue() == ""
    bar = progress.bar(total=10, desc="shots")
    bar.update(5)
    bar.close()
    assert "shots:" in stream.getvalue()
