"""What the command modules share: the lines they print (``say``), the scene arguments of ``run``, ``mesh``
and ``validate``, and lists of numbers given as one option."""

from __future__ import annotations

from fepen.errors import InputError


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


def set_argument(parser, help: str) -> None:
    """--set KEY=VALUE, repeatable, into ``args.sets``."""
    parser.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE", help=help)


def numbers(option: str, text: str) -> list[float]:
    """The positive finite numbers of a comma-separated option value; InputError naming ``option`` else."""
    import math

    try:
        values = [float(x) for x in text.split(",")]
    except ValueError:
        values = []
    if not values or not all(math.isfinite(v) and v > 0 for v in values):
        raise InputError(option, f"comma-separated positive numbers, got {text!r}")
    return values
