"""What a `fepen` process loads before its command runs (issue 62: a rigid shot's process starts in what it
needs): the parser of the command named alone, and Open MPI's quick settings for a process no launcher started."""

import subprocess
import sys

from fepen import cli


def _imports_after(code: str) -> set:
    out = subprocess.run([sys.executable, "-c", code + "\nimport sys; print(' '.join(sorted(sys.modules)))"],
                         capture_output=True, text=True, check=True).stdout
    return set(out.split())


def test_the_run_command_builds_its_parser_without_the_studies():
    mods = _imports_after("from fepen import cli; cli._parser(['run', 'x.toml']).parse_args(['run', 'x.toml'])")
    assert "fepen.studies.charge_safety" not in mods and "numba" not in mods and "matplotlib" not in mods
    mods = _imports_after("from fepen import cli; cli._parser([])")  # fepen --help: every command's options
    assert "fepen.studies.charge_safety" in mods


def test_every_command_still_parses_when_named_alone():
    for name in cli.COMMANDS:
        sub = next(a for a in cli._parser([name])._actions if getattr(a, "choices", None))
        assert list(sub.choices) == [name]


def test_singleton_settings_only_without_a_launcher(monkeypatch):
    for k in (*cli._LAUNCHED, *cli.SINGLETON_MPI):
        monkeypatch.delenv(k, raising=False)
    monkeypatch.delitem(sys.modules, "mpi4py.MPI", raising=False)
    monkeypatch.setenv("OMPI_MCA_pml", "ucx")  # the user's own choice stays
    added = cli.singleton_mpi()
    assert added == ["OMPI_MCA_ess_singleton_isolated"]
    import os

    assert os.environ["OMPI_MCA_pml"] == "ucx" and os.environ["OMPI_MCA_ess_singleton_isolated"] == "1"
    monkeypatch.delenv("OMPI_MCA_ess_singleton_isolated")
    monkeypatch.setenv("OMPI_COMM_WORLD_SIZE", "2")  # under mpirun: the launcher's settings alone
    assert cli.singleton_mpi() == [] and "OMPI_MCA_ess_singleton_isolated" not in os.environ


def test_the_settings_do_not_reach_what_the_command_starts(tmp_path):
    code = ("import os, sys; sys.argv = ['fepen', 'keys']\nfrom fepen import cli\n"
            "cli.main(['keys'])\nprint('LEFT', [k for k in cli.SINGLETON_MPI if k in os.environ])")
    env = {k: v for k, v in __import__("os").environ.items() if k not in (*cli._LAUNCHED, *cli.SINGLETON_MPI)}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True).stdout
    assert "LEFT []" in out
