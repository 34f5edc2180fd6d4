"""``fepen validate-depth [--data PATH ...] [--only] [--set KEY=VALUE ...] [--out DIR] [--workers W]``: depth
data sets by the rigid fidelity and Forrestal's closed form (fepen.studies.depth), one line per set."""

from __future__ import annotations

from fepen.cli.common import say, set_argument

HELP = "depth data sets by the rigid fidelity and Forrestal's closed form: depth.csv, depth.md, depth.png"


def add_arguments(parser) -> None:
    parser.add_argument("--data", action="append", default=[], metavar="PATH",
                        help="a depth data set (CSV, docs/validation-depth.md) or a folder of them; repeatable")
    parser.add_argument("--only", action="store_true", help="run only the --data sets (not table1 and the shipped)")
    set_argument(parser, "override a scene key in every rigid run (e.g. target.strength_model=forrestal-S)")
    parser.add_argument("--out", default="results/validate-depth", help="results directory")
    parser.add_argument("--workers", type=int, default=1, help="processes at once (default 1)")


def run(args) -> int:
    """Depth data sets: the table per set and the predicted-against-measured figure."""
    from fepen.studies import depth

    table = depth.validate_depth(args.data, args.sets, args.out, args.workers, shipped=not args.only)
    say(*(f"{r['set']}: {r['count']} shots; mean |error| default {100 * r['default mean_abs']:.1f} % "
          f"(bias {100 * r['default bias']:+.1f} %), forrestal-S {100 * r['forrestal-S mean_abs']:.1f} %, "
          f"closed form {100 * r['closed form mean_abs']:.1f} %" + _covered(r) for r in table),
        f"written: {args.out}/depth.csv, depth.md, depth.png")
    return 0


def _covered(row: dict) -> str:
    """"; 10-90 % interval holds N of M" (the interval fitted without a set of the same name), or ""."""
    if "interval shots" not in row:
        return ""
    return f"; its 10-90 % interval holds {row['interval inside']} of {row['interval shots']}"

