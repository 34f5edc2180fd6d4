"""``fepen validate-depth [--data PATH ...] [--only] [--set KEY=VALUE ...] [--out DIR] [--workers W] [--fresh]``: depth
data sets by the rigid fidelity and Forrestal's closed form (fepen.studies.depth.ValidateDepth), one line per
set; under ``mpirun -n W`` when started without mpirun with W > 1."""

from __future__ import annotations

from fepen.cli.common import fresh_argument, say, set_argument

HELP = "depth data sets by the rigid fidelity and Forrestal's closed form: depth.csv, depth.md, depth.png"


def add_arguments(parser) -> None:
    parser.add_argument("--data", action="append", default=[], metavar="PATH",
                        help="a depth data set (CSV, docs/validation-depth.md) or a folder of them; repeatable")
    parser.add_argument("--only", action="store_true", help="run only the --data sets (not table1 and the shipped)")
    set_argument(parser, "override a scene key in every rigid run (e.g. target.strength_model=forrestal-S)")
    parser.add_argument("--out", default="results/validate-depth", help="results directory")
    parser.add_argument("--workers", type=int, default=1, help="ranks at once, under mpirun (default 1)")
    fresh_argument(parser)


def run(args) -> int:
    """Depth data sets: the table per set and the predicted-against-measured figure."""
    from mpi4py import MPI

    from fepen.cli.common import written_line
    from fepen.cli.validate import workers_count
    from fepen.studies import depth, processes, study

    st = depth.ValidateDepth()
    plan = st.plan(args.data, args.sets, shipped=not args.only)  # bad input here, before anything is written
    workers = workers_count(args)
    if MPI.COMM_WORLD.size == 1 and workers > 1 and processes.launcher():
        argv = ["validate-depth", *[a for d in args.data for a in ("--data", d)], *(["--only"] if args.only else []),
                "--out", args.out, *[f"--set={s}" for s in args.sets], *(["--fresh"] if args.fresh else [])]
        return processes.relaunch(argv, workers)
    table = study.run(st, plan, args.out, MPI.COMM_WORLD, 1, args.fresh, lambda *ls: None)["table"]
    say(*(f"{r['set']}: {r['count']} shots; mean |error| default {100 * r['default mean_abs']:.1f} % "
          f"(bias {100 * r['default bias']:+.1f} %), forrestal-S {100 * r['forrestal-S mean_abs']:.1f} %, "
          f"closed form {100 * r['closed form mean_abs']:.1f} %" + _covered(r) for r in table),
        written_line(args.out))
    return 0


def _covered(row: dict) -> str:
    """"; 10-90 % interval holds N of M" (the interval fitted without a set of the same name), or ""."""
    if "interval shots" not in row:
        return ""
    return f"; its 10-90 % interval holds {row['interval inside']} of {row['interval shots']}"
