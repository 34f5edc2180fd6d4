"""The fepen command is built from its registry: one module per command with add_arguments and run, every
study of fepen.studies reachable as ``fepen study NAME`` (or its own command), and --help lists them all."""

from fepen import cli
from fepen.studies import study


def test_every_command_has_a_module_with_its_three_parts():
    assert set(cli.COMMANDS) == set(cli._HELP_ORDER)
    for name, module in cli._MODULES.items():
        assert callable(module.add_arguments) and callable(module.run) and module.HELP, name


def test_help_lists_every_command_and_exits_0(capsys):
    assert cli.main(["--help"]) == 0
    text = capsys.readouterr().out
    assert all(name in text for name in cli.COMMANDS)


def test_every_study_runs_from_the_command_line(capsys):
    """fepen study --help names every registered study the CLI's one handler runs; sweep, validate (and its
    ensembles, validate --samples) and validate-depth have commands of their own."""
    assert cli.main(["study", "--help"]) == 0
    text = capsys.readouterr().out
    own = {"sweep", "validate", "validate-bands", "validate-depth"}
    for name in study.study_names():
        assert name in own or name in text, name


def test_a_missing_command_is_one_line_exit_2(capsys):
    assert cli.main([]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("fepen: bad input: command line:")


def test_the_console_writes_to_the_stderr_of_the_moment(monkeypatch):
    """fepen's console handler follows sys.stderr (a notebook or a test swaps it between commands): a record
    after the first stream was closed goes to the new one, with no logging error."""
    import io
    import logging

    from fepen import cli as fcli

    first, second = io.StringIO(), io.StringIO()
    monkeypatch.setattr("sys.stderr", first)
    fcli._quiet()
    logging.getLogger("fepen").warning("one")
    first.close()
    monkeypatch.setattr("sys.stderr", second)
    fcli._quiet()
    logging.getLogger("fepen").warning("two")
    assert second.getvalue() == "fepen: two\n"
