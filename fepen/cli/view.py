"""``fepen view DIR [--png FILE] [--time T] [--field NAME]``: a run in ParaView (its view.py), or pyvista where
ParaView is absent (fepen.post.paraview.show)."""

from __future__ import annotations

from fepen.cli.common import say
from fepen.errors import InputError

HELP = "a run in ParaView (its view.py), or pyvista where ParaView is absent"


def add_arguments(parser) -> None:
    parser.add_argument("dir", help="results directory of a run with fields (finished, running or killed)")
    parser.add_argument("--png", help="render one picture to this file, offscreen, and exit")
    parser.add_argument("--time", type=float, help="output time (s); default the last")
    parser.add_argument("--field", default="von_mises_Pa",
                        help="the field to colour by (default von_mises_Pa): any field of the run's fields.xdmf, "
                             "drawn on the points or the cells as the file holds it")


def run(args) -> int:
    """Show the run DIR, or render it to --png.

    Returns:
        0 when shown or written; 2 without a display (and no --png), 4 when the ParaView GUI failed: each with
        one line ``fepen view: ...`` on stderr. The picture is titled with the field, its unit, the frame's
        time and the shot (fepen.post.paraview.view_title).

    Raises:
        InputError: ("dir") no fields.xdmf; ("--field") a field the run does not have (the line names those it
            has): exit 2, before any window or picture.
    """
    from pathlib import Path

    from fepen.post import paraview

    out = Path(args.dir)
    if not (out / "fields.xdmf").is_file():
        raise InputError("dir", paraview.missing_fields(out))
    paraview.field_centre(out, args.field)
    try:
        paraview.show(out, args.field, args.time, args.png)
    except (paraview.NoDisplay, paraview.ViewerFailed) as err:
        _error(f"fepen view: {err}")
        return err.exit_code
    say(f"written: {args.png}" if args.png else f"shown: {out}")
    return 0


def _error(line: str) -> None:
    """One line on stderr (rank 0), kept for fepen.log."""
    import sys

    from mpi4py import MPI

    from fepen.io import rundir

    if MPI.COMM_WORLD.rank == 0:
        print(line, file=sys.stderr, flush=True)
        rundir.log_line(line)
