"""What the command modules share: the lines they print (``say``), the scene arguments of ``run``, ``mesh``
and ``validate``, and lists of numbers given as one option."""

from __future__ import annotations


def say(*lines: str) -> None:
    """Print lines on rank 0 and keep them for fepen.log (fepen.io.rundir.log_line)."""
    from mpi4py import MPI

    from fepen.io import rundir

    if MPI.COMM_WORLD.rank == 0:
        print(*lines, sep="\n", flush=True)
        for line in lines:
            rundir.log_line(line)


def written_line(out) -> str:
    """``written: OUT/ a, b, c``: the files the directory's manifest lists (run.json's "files"), as they are."""
    import os
    from pathlib import Path

    from fepen.io import rundir

    record, _ = rundir.read_record(Path(out))
    names = sorted(n for n in (rundir.manifest(record) or ()) if os.path.lexists(Path(out) / n)
                   and n != rundir.RESERVE) if record else []
    return f"written: {out}/ " + ", ".join(n + ("/" if (Path(out) / n).is_dir() else "") for n in names)


def scene_arguments(parser, out_default: str) -> None:
    """SCENE (optional), --out (default ``out_default``) and --set."""
    parser.add_argument("scene", nargs="?", help="scene file (TOML); absent: the default scene")
    parser.add_argument("--out", default=out_default, help=f"results directory (default {out_default})")
    set_argument(parser, "override a dotted scene key; VALUE in TOML syntax, bare words are strings")


def workers_argument(parser, help: str) -> None:
    """--workers W: a study started without mpirun runs under ``mpirun -n W`` (1: in this process)."""
    parser.add_argument("--workers", type=int, default=None, metavar="W", help=help)


#: --fresh's help, the same for every study command
FRESH = "remove what the study wrote in --out first (exactly that) and run every shot again"


def fresh_argument(parser) -> None:
    """--fresh: a study's folder replaced, not continued (fepen.studies.study.run)."""
    parser.add_argument("--fresh", action="store_true", help=FRESH)


def set_argument(parser, help: str) -> None:
    """--set KEY=VALUE, repeatable, into ``args.sets`` (fepen.studies.study.set_option)."""
    from fepen.studies.study import set_option

    set_option(parser, help)


def numbers(option: str, text: str) -> list[float]:
    """The positive finite numbers of a comma-separated option value (fepen.studies.study.numbers)."""
    from fepen.studies.study import numbers as _numbers

    return _numbers(option, text)
