"""``fepen study accuracy-cost | ballistic-limit | ricochet | uncertainty`` (docs/studies.md), four
sub-commands, each with only its own options:

    fepen study accuracy-cost [--out DIR] [--ranks N] [--quick] [--fresh]
    fepen study ballistic-limit [SCENE.toml] [--out DIR] [--speeds LOW,HIGH] [--tol M/S] [--ranks-per-shot K]
                                [--set KEY=VALUE ...] [--fresh]
    fepen study ricochet [SCENE.toml] [--out DIR] [--speeds V,...] [--tol DEG] [--obliquity-max DEG]
                         [--ranks-per-shot K] [--set KEY=VALUE ...] [--fresh]
    fepen study uncertainty [SCENE.toml] [--scatter SWEEP.toml] [--samples N] [--seed S] [--no-model-scatter]
                            [--set KEY=VALUE ...] [--out DIR] [--ranks-per-shot K] [--fresh]

accuracy-cost starts its own MPI jobs (fepen.studies.accuracy_cost); the limit studies
(fepen.studies.limits) and the uncertainty study (fepen.studies.uncertainty) run on the ranks they were
started on.
"""

from __future__ import annotations

import math

from fepen.cli.common import numbers, say, set_argument
from fepen.errors import InputError

HELP = ("accuracy-cost: what accuracy costs in time (study.md, pareto.png); ballistic-limit; ricochet; "
        "uncertainty (docs/studies.md)")
FRESH = "run again what DIR already holds"


def add_arguments(parser) -> None:
    sub = parser.add_subparsers(dest="which", required=True, parser_class=type(parser))
    ac = sub.add_parser("accuracy-cost", help="what accuracy costs in time: study.csv, study.md, pareto.png")
    ac.add_argument("--out", default="results/study", help="results directory (default results/study)")
    ac.add_argument("--ranks", type=int, default=2, help="MPI ranks of each run (default 2)")
    ac.add_argument("--quick", action="store_true", help="a small subset on coarse meshes")
    ac.add_argument("--fresh", action="store_true", help=FRESH)
    bl = sub.add_parser("ballistic-limit", help="the speed below which the target is not perforated, by "
                                                "bisection: ballistic_limit.json, ballistic_limit.png")
    _limit_arguments(bl, "results/ballistic-limit")
    bl.add_argument("--speeds", default="100,1500", help="the bracket 'LOW,HIGH' (default 100,1500 m/s)")
    bl.add_argument("--tol", type=float, default=2.0, help="the bisection's final width in m/s (default 2)")
    ri = sub.add_parser("ricochet", help="the outcome map over obliquity and speed, the critical obliquity at "
                                         "each speed: ricochet.json, ricochet.png")
    _limit_arguments(ri, "results/ricochet")
    ri.add_argument("--speeds", default="300,400,500,600,700,800,900", help="the speeds (default 300,400,...,900 "
                                                                            "m/s)")
    ri.add_argument("--tol", type=float, default=0.5, help="the bisection's final width in deg (default 0.5)")
    ri.add_argument("--obliquity-max", type=float, default=85.0, help="top of the bracket (deg)")
    un = sub.add_parser("uncertainty", help="the scatter of the inputs and fepen's own error together: the depth's "
                                            "distribution, P(perforation) with its intervals: uncertainty.json, "
                                            "uncertainty.md, uncertainty.png")
    _limit_arguments(un, "results/uncertainty")
    un.add_argument("--scatter", metavar="SWEEP.toml", help="a sweep file whose [monte_carlo] gives the inputs' "
                                                            "distributions (absent SCENE: its scene and [base] too)")
    un.add_argument("--samples", type=int, default=None, metavar="N", help="samples (default: the --scatter "
                                                                           "file's; without it 1000)")
    un.add_argument("--seed", type=int, default=None, metavar="S", help="the seed (default: the --scatter file's; "
                                                                        "without it 0)")
    un.add_argument("--no-model-scatter", dest="model_scatter", action="store_false",
                    help="the input scatter alone (fepen's own error not drawn)")


def _limit_arguments(parser, out_default: str) -> None:
    """The options ballistic-limit and ricochet share."""
    parser.add_argument("scene", nargs="?", help="the base scene (absent: the default)")
    parser.add_argument("--out", default=out_default, help=f"results directory (default {out_default})")
    parser.add_argument("--fresh", action="store_true", help=FRESH)
    set_argument(parser, "override a key of the base scene")
    parser.add_argument("--ranks-per-shot", type=int, default=1, metavar="K", help="ranks of each shot (default 1)")


def run(args) -> int:
    """The study named by the sub-command."""
    return {"accuracy-cost": _accuracy_cost, "ballistic-limit": _ballistic_limit, "ricochet": _ricochet,
            "uncertainty": _uncertainty}[args.which](args)


def _accuracy_cost(args) -> int:
    """The accuracy-cost study (each run its own process, on --ranks MPI ranks)."""
    from mpi4py import MPI

    from fepen.studies import accuracy_cost

    if MPI.COMM_WORLD.size > 1:
        raise InputError("fepen study", "run it without mpirun: it starts its own MPI jobs (--ranks)")
    if args.ranks < 1:
        raise InputError("--ranks", f"must be at least 1, got {args.ranks}")
    accuracy_cost.study(args.out, ranks=args.ranks, quick=args.quick, fresh=args.fresh, say=say)
    say(f"written: {args.out}/study.csv, study.md, study.json, pareto.png")
    return 0


def _ballistic_limit(args) -> int:
    """fepen study ballistic-limit, on the ranks it was started on."""
    from mpi4py import MPI

    from fepen.io import rundir
    from fepen.studies import limits

    comm = MPI.COMM_WORLD
    _check_limit_options(args, comm)
    bracket = numbers("--speeds", args.speeds)
    if len(bracket) != 2:
        raise InputError("--speeds", f"two speeds LOW,HIGH (m/s), got {args.speeds!r}")
    lo, hi = bracket
    limits.check_ballistic_limit(args.scene, args.sets, lo, hi, args.tol)  # bad input before anything is written
    with rundir.study_directory(args.out, comm, args.fresh, "ballistic-limit", limits.BALLISTIC_NAMES):
        limits.ballistic_limit(args.scene, args.sets, args.out, comm, args.ranks_per_shot, lo, hi, args.tol, say=say)
    say(f"written: {args.out}/ballistic_limit.json, ballistic_limit.png")
    return 0


def _ricochet(args) -> int:
    """fepen study ricochet, on the ranks it was started on."""
    from mpi4py import MPI

    from fepen.io import rundir
    from fepen.studies import limits

    comm = MPI.COMM_WORLD
    _check_limit_options(args, comm)
    if not (math.isfinite(args.obliquity_max) and 0.0 < args.obliquity_max < 90.0):
        raise InputError("--obliquity-max", f"in (0, 90) deg, got {args.obliquity_max!r}")
    speeds = numbers("--speeds", args.speeds)
    limits.check_ricochet(args.scene, args.sets, speeds, args.obliquity_max, args.tol)  # before anything is written
    with rundir.study_directory(args.out, comm, args.fresh, "ricochet", limits.RICOCHET_NAMES):
        limits.ricochet(args.scene, args.sets, args.out, comm, args.ranks_per_shot, speeds, args.obliquity_max,
                        args.tol, say=say)
    say(f"written: {args.out}/ricochet.json, ricochet.png")
    return 0


def _uncertainty(args) -> int:
    """fepen study uncertainty, on the ranks it was started on: bad input in one line before any shot."""
    from mpi4py import MPI

    from fepen.studies import engine, uncertainty

    comm = MPI.COMM_WORLD
    engine.check_ranks_per_shot(args.ranks_per_shot, comm.size)
    p = uncertainty.plan(args.scene, args.scatter, args.sets, args.samples, args.seed, args.model_scatter)
    uncertainty.study(p, args.out, comm, args.ranks_per_shot, args.fresh, say=say)
    return 0


def _check_limit_options(args, comm) -> None:
    """--ranks-per-shot (fepen.studies.engine.check_ranks_per_shot) and --tol, before anything is written."""
    from fepen.studies import engine

    engine.check_ranks_per_shot(args.ranks_per_shot, comm.size)
    if not (math.isfinite(args.tol) and args.tol > 0):
        raise InputError("--tol", f"a positive number (m/s or deg), got {args.tol!r}")


