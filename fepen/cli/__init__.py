"""The ``fepen`` command (docs/scenes.md, docs/results.md, docs/studies.md).

    fepen run [SCENE.toml] [--out DIR] [--set KEY=VALUE ...] [--force]
    fepen run --resume DIR
    fepen mesh [SCENE.toml] [--out DIR] [--set KEY=VALUE ...]
    fepen validate [SCENE.toml] [--out DIR] [--set KEY=VALUE ...]
    fepen validate-depth [--data PATH ...] [--only] [--set KEY=VALUE ...] [--out DIR] [--workers W]
    fepen study accuracy-cost [--out DIR] [--ranks N] [--quick] [--fresh]
    fepen study ballistic-limit [SCENE.toml] [--out DIR] [--speeds LOW,HIGH] [--tol M/S] [--ranks-per-shot K]
                                [--set KEY=VALUE ...] [--fresh]
    fepen study ricochet [SCENE.toml] [--out DIR] [--speeds V,...] [--tol DEG] [--obliquity-max DEG]
                         [--ranks-per-shot K] [--set KEY=VALUE ...] [--fresh]
    fepen study uncertainty [SCENE.toml] [--scatter SWEEP.toml] [--samples N] [--seed S] [--no-model-scatter]
                            [--set KEY=VALUE ...] [--out DIR] [--ranks-per-shot K] [--fresh]
    fepen sweep SWEEP.toml [--out DIR] [--ranks-per-shot K] [--workers W] [--set KEY=VALUE ...] [--fresh]
    fepen view DIR [--png FILE] [--time T] [--field NAME]
    fepen keys
    fepen envelope [SCENE.toml] [--set KEY=VALUE ...]
    fepen --version
    fepen --debug COMMAND ...    (a traceback with every error, for developers)

One module per command (``fepen.cli.run``, ``mesh``, ``validate``, ``validate_depth``, ``study``, ``sweep``,
``view``, ``keys``, ``envelope``), each with a docstring, ``HELP`` (its line in ``fepen --help``),
``add_arguments(parser)`` and ``run(args) -> int``; ``COMMANDS`` below is the registry the parser is built from.
A new command is a new module and one line there.

Exit codes (fepen.errors, docs/results.md): 0 success; 2 bad input (one line naming the key or argument and
what is allowed, before anything is written); 3 the simulation cannot go on (what, where, when); 4 a fault of
the machine (disk full, permission, a signal that stopped the run after a checkpoint); 1 a bug in fepen. Every
error is one line on stderr; --debug adds the traceback.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys

from fepen.cli import envelope, keys, mesh, run, study, sweep, validate, validate_depth, view
from fepen.cli.common import say
from fepen.errors import (
    OUTCOMES,
    InputError,
    Interrupted,
    MachineFault,
    SimulationError,
    below_load_floor,
    catch_early_stop,
    describe_os_error,
    out_of_memory,
    start_within_limits,
    stop_outcome,
)

__all__ = ["main", "COMMANDS", "version_line", "stack_line", "common", "run", "mesh", "validate", "validate_depth",
           "study", "sweep", "keys", "view", "envelope"]

#: the command modules by name, in the order of "name a command: ..."
_MODULES = {"run": run, "mesh": mesh, "validate": validate, "validate-depth": validate_depth, "study": study,
            "sweep": sweep, "keys": keys, "view": view, "envelope": envelope}
#: what main calls: command name -> its module's run(args) -> exit code
COMMANDS = {name: module.run for name, module in _MODULES.items()}
#: the order of the commands in ``fepen --help`` and in argparse's "invalid choice" line
_HELP_ORDER = ("run", "validate", "mesh", "validate-depth", "study", "sweep", "keys", "envelope", "view")


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2, as for every other bad input
        raise InputError("command line", message)


def _parser(argv: list[str] | None = None) -> argparse.ArgumentParser:
    """The parser: the global options and one sub-parser per command, from its module's add_arguments; given the
    command line ``argv`` whose first word is a command, that command's sub-parser alone (a rigid ``fepen run``
    does not import every study's module to build ``fepen study``'s options: 0.5 s of a 1 s process)."""
    ap = _Parser(prog="fepen", description="Projectile penetrating concrete, projectile-target separation.",
                 epilog="Exit codes: 0 success, 2 bad input, 3 the simulation cannot go on, 4 a fault of the "
                        "machine (disk full, permission, memory, no C compiler, a signal after a checkpoint), 1 a bug. "
                        "--debug (anywhere): tracebacks.")
    ap.add_argument("--version", action="store_true", help="print fepen's version and code revision, and the "
                    "dolfinx, PETSc, MPI, numpy and Python it runs on, and exit")
    sub = ap.add_subparsers(dest="command", parser_class=_Parser)
    first = next((a for a in argv or () if not a.startswith("-")), None)
    for name in (first,) if first in _MODULES else _HELP_ORDER:
        _MODULES[name].add_arguments(sub.add_parser(name, help=_MODULES[name].HELP))
    return ap


def version_line() -> str:
    """``fepen 0.3.0 (revision abc123…)``: the version and the code revision of this source tree."""
    from fepen.io.rundir import revision
    from fepen.version import __version__

    rev = revision()
    return f"fepen {__version__}" + (f" (revision {rev})" if rev else "")


def stack_line() -> str:
    """``dolfinx 0.5.2 (supported), PETSc 3.18.5, Open MPI v4.1.4, mpi4py 3.1.4, numpy 1.24.2, Python 3.11.2``: the
    software this fepen runs on (fepen.dolfinx_api.stack); an unsupported dolfinx names the supported ones."""
    from fepen import dolfinx_api as dx

    s = dx.stack()
    names = " and ".join(f"{a}.{b}" for a, b in dx.SUPPORTED)
    head = f"dolfinx {s['dolfinx']}" if "supported" not in s else \
        f"dolfinx {s['dolfinx']} ({'supported' if s['supported'] else 'not supported: fepen runs on ' + names}), " \
        f"PETSc {s['petsc']}"
    return f"{head}, {s['mpi']}, mpi4py {s['mpi4py']}, numpy {s['numpy']}, Python {s['python']}"


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``fepen`` console script and of ``python -m fepen``. Returns the exit code
    (fepen.errors): every error is one line on stderr, with its traceback only under --debug."""
    argv = list(sys.argv[1:] if argv is None else argv)
    start_within_limits()  # before numpy, MPI or gmsh is loaded
    too_small = below_load_floor()
    if too_small is not None:  # MPI would abort or crash as it loads, not say why
        return _failed(too_small, "--debug" in argv)
    catch_early_stop()  # a relaunched rank: a stop asked for while it loads is kept for its study
    added = singleton_mpi()
    try:  # MPI and numpy load here: a fault of the machine (memory under ulimit -v) is one line already
        from fepen.io import rundir
    except BaseException as err:  # noqa: B036 - every way out is one line and a documented code
        return _failed(err, "--debug" in argv)
    finally:
        for key in added:  # MPI has read them: the processes the command starts (mpirun) choose their own
            os.environ.pop(key, None)
    rundir.begin_command(["fepen", *map(str, argv)])  # run.json's "command"
    rundir._in_cli = True  # the API calls of the command keep this line
    try:
        return _main(argv)
    finally:
        rundir._in_cli = False


#: Open MPI's settings for a process started without a launcher (a singleton: one rank, no mpirun): no helper
#: daemon started (ess_singleton_isolated) and the point-to-point layer that needs no network probe (ob1), which
#: take MPI_Init from about 0.32 s to 0.04 s of a 1-rank process. Under mpirun or srun they are not set: there the
#: launcher and the site choose.
SINGLETON_MPI = {"OMPI_MCA_ess_singleton_isolated": "1", "OMPI_MCA_pml": "ob1"}
#: the environment a launcher gives its ranks (Open MPI, PMIx, MPICH's Hydra, Slurm)
_LAUNCHED = ("OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE", "SLURM_PROCID")


def singleton_mpi() -> list[str]:
    """Before MPI loads in a process no launcher started: SINGLETON_MPI's settings the user has not made.

    Returns:
        The keys it put into the environment (main takes them out again once MPI has read them)."""
    if "mpi4py.MPI" in sys.modules or any(k in os.environ for k in _LAUNCHED):
        return []
    added = [k for k in SINGLETON_MPI if k not in os.environ]
    os.environ.update({k: SINGLETON_MPI[k] for k in added})
    return added


def console() -> None:
    """The ``fepen`` command as a process (the console script, ``python -m fepen``): main, then a quick exit.

    When main returns, everything the command wrote is closed (its files replaced atomically, the fields'
    HDF5 files closed, the bars closed). What Python would still do is unload its modules (dolfinx, numba,
    matplotlib): 0.35 s of a 2-rank run's 11 s. So the streams are flushed, the logs shut down, MPI finalised
    (every rank of the command reaches it), and the process ends with main's exit code."""
    code = main()
    for finish in (sys.stdout.flush, sys.stderr.flush, logging.shutdown):
        try:
            finish()
        except Exception:  # noqa: BLE001 - a closed pipe (fepen keys | head): the exit code still stands
            pass
    try:
        mpi = sys.modules.get("mpi4py.MPI")
        if mpi is not None and mpi.Is_initialized() and not mpi.Is_finalized():
            if code == 1 and mpi.COMM_WORLD.size > 1:  # a bug on this rank: the others may wait for it for ever
                import time

                time.sleep(1.0)  # the launcher forwards the rank's line before the abort ends it (it was lost)
                mpi.COMM_WORLD.Abort(1)
            mpi.Finalize()
    finally:
        os._exit(code if isinstance(code, int) else 1)


def _main(argv: list[str]) -> int:
    """main's command, with ``argv`` the command line's arguments."""
    debug = "--debug" in argv
    argv = [a for a in argv if a != "--debug"]
    try:
        args = _parser(argv).parse_args(argv)
        if args.version:
            say(version_line(), stack_line())
            return 0
        if args.command is None:
            raise InputError("command line", "name a command: " + ", ".join(COMMANDS) + " (fepen --help)")
        _quiet()
        return COMMANDS[args.command](args)
    except BaseException as err:  # noqa: B036 - every way out is one line and a documented code
        if isinstance(err, SystemExit):
            return err.code if isinstance(err.code, int) else 0  # --help
        return _failed(err, debug)


def _failed(err: BaseException, debug: bool) -> int:
    """The exit code of an error that ended the command, its one line said (and its traceback, with --debug).
    Memory that ran out is given back first (the locals of the frames the traceback holds), and a line that still
    cannot be said, or kept in fepen.log, leaves the exit code as it is."""
    import traceback

    if out_of_memory(err) is not None:
        traceback.clear_frames(err.__traceback__)
    try:
        code, line = _verdict(err)
    except MemoryError:
        code, line = OUTCOMES["fault"].exit_code, "fepen: stopped by a fault of the machine: out of memory"
    try:
        if debug:
            traceback.print_exc()
        _error(line, code)
    except MemoryError:
        pass
    return code


#: the longest error line: a longer one (a value of megabytes echoed) keeps its start, which names the key, and
#: its end, which says what is allowed
LINE_MAX = 500


def _verdict(err: BaseException) -> tuple[int, str]:
    """The exit code and the one line of an error (whitespace, newlines in a path included, collapsed; cut in
    the middle to LINE_MAX characters)."""
    code, line = _verdict_line(err)
    line = " ".join(line.split())
    if len(line) > LINE_MAX:
        line = f"{line[:LINE_MAX - 160]} [... {len(line) - LINE_MAX + 9} characters cut ...] {line[-140:]}"
    return code, line


def _verdict_line(err: BaseException) -> tuple[int, str]:
    """The exit code (fepen.errors.stop_outcome, the one classification) and the line before its whitespace is
    collapsed."""
    code = stop_outcome(err).exit_code
    if isinstance(err, ValueError) and "null byte" in str(err):  # a path holding NUL, from a script
        return code, "fepen: bad input: a file name holds a NUL byte"
    if isinstance(err, InputError):
        return code, f"fepen: bad input: {err}"
    if isinstance(err, SimulationError):
        return code, f"fepen: simulation stopped: {err}"
    if isinstance(err, Interrupted):
        return code, f"fepen: interrupted: {err}"
    memory = out_of_memory(err)  # a MemoryError, a library that cannot be mapped (ulimit -v): exit 4, not a bug
    if memory is not None:
        return code, f"fepen: stopped by a fault of the machine: {memory}"
    if isinstance(err, MachineFault):
        return code, f"fepen: stopped by a fault of the machine: {err}"
    if isinstance(err, OSError):
        return code, f"fepen: stopped by a fault of the machine: {describe_os_error(err)}"
    if isinstance(err, KeyboardInterrupt):
        return code, "fepen: interrupted (SIGINT) before the run had anything to keep"
    text = " ".join(str(err).split())[:300]
    return code, (f"fepen: internal error (a bug in fepen; run again with --debug for the traceback and report "
                  f"it): {type(err).__name__}: {text}")


class _Console(logging.StreamHandler):
    """fepen's console: the process's stderr as it is at each record (an in-process caller, a notebook or a test,
    may have swapped it since the first command: a handler that kept the first one would write to a closed file)."""

    fepen_console = True

    @property
    def stream(self):
        return sys.stderr

    @stream.setter
    def stream(self, value) -> None:
        pass


def _quiet() -> None:
    """The console speaks only for fepen: the "fepen" logger's records as ``fepen: ...`` lines on stderr; every
    other package's records (ffcx's compiler lines, matplotlib's font cache and warnings, Python's warnings) go
    to fepen.log only (rundir.ChatterToLog), never to the console."""
    import logging

    from fepen.io import rundir

    logging.getLogger("dolfinx").setLevel(logging.WARNING)
    own = logging.getLogger("fepen")
    own.setLevel(logging.INFO)
    own.propagate = False  # not through the root logger's handlers
    if not any(getattr(h, "fepen_console", False) for h in own.handlers):
        console = _Console()
        console.setFormatter(logging.Formatter("fepen: %(message)s"))
        own.addHandler(console)
    rundir.chatter_to_log()


def _error(line: str, code: int = 0) -> None:
    """The one line of an error, on stderr (rank 0), kept for fepen.log; a bug (code 1) on another rank is said
    by that rank too, named (the ranks agree on every other error; a bug may be one rank's alone, and that rank
    then ends the job: console). Without MPI when MPI did not load (no memory for it): the rank is then mpirun's
    (OMPI_COMM_WORLD_RANK, PMI_RANK)."""
    mpi = sys.modules.get("mpi4py.MPI")
    if mpi is not None and mpi.Is_initialized():
        rank = mpi.COMM_WORLD.rank
    else:
        rank = int(os.environ.get("OMPI_COMM_WORLD_RANK", os.environ.get("PMI_RANK", "0")) or 0)
    if rank != 0 and code == 1:
        print(line.replace("fepen:", f"fepen (rank {rank}):", 1), file=sys.stderr, flush=True)
    if rank == 0:
        print(line, file=sys.stderr, flush=True)
        rundir = sys.modules.get("fepen.io.rundir")
        if rundir is not None:
            rundir.log_line(line)
