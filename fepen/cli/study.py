"""``fepen study NAME [--out DIR] [--fresh] [--ranks-per-shot K] ...`` (docs/studies.md): every study of the one
registry (fepen.studies.study.STUDIES) whose command is ``fepen study``, each sub-command with its own options
(the study's ``add_arguments``) and the common ones, all run by one handler: the study's plan (bad input in one
line before anything is written), then fepen.studies.study.run on the ranks it was started on.

    fepen study ballistic-limit [SCENE.toml] [--speeds LOW,HIGH] [--tol M/S] [--set KEY=VALUE ...]
    fepen study ricochet [SCENE.toml] [--speeds V,...] [--tol DEG] [--obliquity-max DEG] [--set KEY=VALUE ...]
    fepen study uncertainty [SCENE.toml] [--scatter SWEEP.toml] [--samples N] [--seed S] [--no-model-scatter]
                            [--workers W]
    fepen study charge-safety [SCENE.toml] [--speeds V,...] [--obliquities DEG,...] [--attacks DEG,...] [--set ...]
    fepen study accuracy-cost [--ranks N] [--quick]          (it starts its own MPI jobs: no mpirun)
    fepen study calibration | wear-calibration | prediction-errors   (fepen's own calibrations and tables)
"""

from __future__ import annotations

from fepen.cli.common import fresh_argument, say

HELP = "a study of many shots: " + "; ".join(("ballistic-limit", "ricochet", "uncertainty", "charge-safety",
                                               "accuracy-cost",
                                               "calibration, ...")) + " (docs/studies.md)"


def add_arguments(parser) -> None:
    from fepen.studies import study

    sub = parser.add_subparsers(dest="which", required=True, parser_class=type(parser))
    for name in study.study_names("study"):
        cls = study.get(name)
        sp = sub.add_parser(name, help=cls.help)
        cls.add_arguments(sp)
        sp.add_argument("--out", default=cls.out, help=f"results directory (default {cls.out})")
        fresh_argument(sp)
        sp.add_argument("--ranks-per-shot", type=int, default=1, metavar="K",
                        help="ranks of each shot's MPI group (default 1; must divide the number of ranks)")
        if hasattr(cls, "argv"):  # a study that can give its options back as words relaunches under mpirun
            sp.add_argument("--workers", type=int, default=1, metavar="W",
                            help="started without mpirun: the study under mpirun -n W, whose ranks share the "
                                 "shots (default 1: in this process), as fepen sweep's and fepen validate's")


def run(args) -> int:
    """The study named by the sub-command, on the ranks it was started on (or, with --workers W > 1 started
    without mpirun, under ``mpirun -n W``: fepen.studies.processes.relaunch)."""
    import math
    import os
    import sys

    from mpi4py import MPI

    from fepen.cli.common import written_line
    from fepen.errors import InputError
    from fepen.studies import engine, processes, study

    comm = MPI.COMM_WORLD
    engine.check_ranks_per_shot(args.ranks_per_shot, comm.size)
    if hasattr(args, "tol") and not (math.isfinite(args.tol) and args.tol > 0):
        raise InputError("--tol", f"a positive number (m/s or deg), got {args.tol!r}")
    cls = study.get(args.which)
    st = cls()
    workers = getattr(args, "workers", 1)
    if workers < 1:
        raise InputError("--workers", f"must be at least 1, got {workers}")
    plan = st.plan(**cls.options(args))  # bad input here, before anything is written
    if comm.size == 1 and workers > 1 and processes.launcher():
        engine.check_ranks_per_shot(args.ranks_per_shot, workers)
        os.environ.setdefault("FEPEN_PROGRESS", "1" if sys.stderr.isatty() else "0")
        return processes.relaunch(["study", args.which, *cls.argv(args), "--out", args.out, "--ranks-per-shot",
                                   str(args.ranks_per_shot), *(["--fresh"] if args.fresh else [])], workers)
    study.run(st, plan, args.out, comm, args.ranks_per_shot, args.fresh, say)
    say(written_line(args.out))
    return 0
