"""``fepen sweep SWEEP.toml [--out DIR] [--ranks-per-shot K] [--workers W] [--set KEY=VALUE ...] [--fresh]``:
many shots of a base scene (fepen.studies.sweep) on the MPI ranks it was started on; started without mpirun,
it runs itself again under ``mpirun -n W`` (fepen.studies.processes.relaunch_sweep)."""

from __future__ import annotations

from fepen.cli.common import fresh_argument, say, set_argument, written_line
from fepen.errors import InputError

HELP = ("many shots of a base scene (grid, Monte Carlo or a table): sweep.csv, sweep.md, figures; resumable; MPI "
        "groups (docs/studies.md)")


def add_arguments(parser) -> None:
    parser.add_argument("sweep", help="the sweep file (TOML)")
    parser.add_argument("--out", default="results/sweep", help="results directory (default results/sweep)")
    parser.add_argument("--ranks-per-shot", type=int, default=1, metavar="K",
                        help="ranks of each shot's MPI group (default 1; must divide the number of ranks)")
    parser.add_argument("--workers", type=int, default=None, metavar="W",
                        help="without mpirun: run under mpirun -n W (default: one per core; 1: in this process)")
    set_argument(parser, "override a key of the base scene")
    fresh_argument(parser)


def run(args) -> int:
    """The sweep here, or under mpirun -n W when started on one rank with W > 1 workers and mpirun at hand."""
    import os

    from mpi4py import MPI

    from fepen.studies import engine, processes, sweep

    world = MPI.COMM_WORLD
    if args.workers is not None and args.workers < 1:
        raise InputError("--workers", f"must be at least 1, got {args.workers}")
    workers = args.workers if args.workers is not None else (os.cpu_count() or 1)
    if world.size == 1 and workers > 1 and processes.launcher():
        engine.check_ranks_per_shot(args.ranks_per_shot, workers)
        sweep.read(args.sweep, args.sets)  # bad input here, in one line, before mpirun starts
        return processes.relaunch_sweep(args.sweep, args.out, args.ranks_per_shot, workers, args.sets, args.fresh)
    engine.check_ranks_per_shot(args.ranks_per_shot, world.size)
    res = sweep.run(args.sweep, args.out, world, args.ranks_per_shot, args.sets, args.fresh, say=say)
    say(f"shots: {res['shots']} ({res['ran']} run now, {res['skipped']} recorded before); "
        + ", ".join(f"{k} {v}" for k, v in sorted(res["statuses"].items())) + f"; wall {res['wall_s']:.1f} s",
        written_line(args.out))
    return 0
