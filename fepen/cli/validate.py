"""``fepen validate [SCENE.toml] [--out DIR] [--set KEY=VALUE ...] [--workers W] [--fresh]``: the eight Table 1 shots
(fepen.studies.validate.Validate), one line per shot; its deformable shots side by side under ``mpirun -n W``
when started without mpirun (one rank each)."""

from __future__ import annotations

from fepen.cli.common import fresh_argument, say, scene_arguments, workers_argument

HELP = "the Table 1 sweep: validation.csv, validation.md, figures"


def add_arguments(parser) -> None:
    scene_arguments(parser, "results/validation")
    workers_argument(parser, "deformable shots at once, each on one rank under mpirun (default: one per core)")
    fresh_argument(parser)


def run(args) -> int:
    """The eight Table 1 shots."""
    import os
    import sys

    from mpi4py import MPI

    from fepen.cli.common import written_line
    from fepen.studies import processes, study, validate

    st = validate.Validate()
    plan = st.plan(args.scene, args.sets)  # bad input here, before anything is written
    workers = workers_count(args)
    deformable = next(iter(plan.scenes.values())).effects.fidelity != "rigid"
    if MPI.COMM_WORLD.size == 1 and deformable and workers > 1 and processes.launcher():
        os.environ.setdefault("FEPEN_PROGRESS", "1" if sys.stderr.isatty() else "0")
        argv = ["validate", *([args.scene] if args.scene else []), "--out", args.out,
                *[f"--set={s}" for s in args.sets], *(["--fresh"] if args.fresh else [])]
        return processes.relaunch(argv, min(workers, len(plan.scenes)))
    study.run(st, plan, args.out, MPI.COMM_WORLD, 1, args.fresh, say)
    say(written_line(args.out))
    return 0


def workers_count(args) -> int:
    """--workers, or one per core (InputError below 1)."""
    import os

    from fepen.errors import InputError

    if args.workers is not None and args.workers < 1:
        raise InputError("--workers", f"must be at least 1, got {args.workers}")
    return args.workers if args.workers is not None else (os.cpu_count() or 1)
