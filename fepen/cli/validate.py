"""``fepen validate [SCENE.toml] [--out DIR] [--set KEY=VALUE ...] [--workers W] [--fresh] [--samples N [--seed S]]``:
the eight Table 1 shots (fepen.studies.validate.Validate), one line per shot; its deformable shots side by side
under ``mpirun -n W`` when started without mpirun (one rank each). With --samples, each shot as an ensemble of N
rigid members over its unmeasured inputs (fepen.studies.bands.Bands): bands.csv, bands.md, bands.png;
``--set effects.fidelity=plastic --shots C2,C7,C8``: deformable members of a subset, one per rank."""

from __future__ import annotations

from fepen.cli.common import fresh_argument, say, scene_arguments, workers_argument

HELP = "the Table 1 sweep: validation.csv, validation.md, figures"


def add_arguments(parser) -> None:
    scene_arguments(parser, "results/validation")
    workers_argument(parser, "deformable shots at once, each on one rank under mpirun (default: one per core)")
    fresh_argument(parser)
    parser.add_argument("--samples", type=int, default=None, metavar="N",
                        help="each shot as N rigid members drawn over its unmeasured inputs (docs/uncertainty.md): "
                             "bands.csv, bands.md, bands.png")
    parser.add_argument("--seed", type=int, default=0, help="the members' seed (with --samples; default 0)")
    parser.add_argument("--shots", default=None, metavar="C2,C7,...",
                        help="with --samples: these of Table 1's shots only (default: all eight)")


def run(args) -> int:
    """The eight Table 1 shots."""
    from mpi4py import MPI

    from fepen.cli.common import written_line
    from fepen.studies import processes, study, validate

    workers = workers_count(args)
    if args.samples is not None:
        from fepen.studies import bands

        st = bands.Bands()
        out = args.out if args.out != "results/validation" else st.out
        shots = [s.strip() for s in args.shots.split(",")] if args.shots else None
        plan = st.plan(args.scene, args.sets, args.samples, args.seed, shots=shots)  # bad input here
        if MPI.COMM_WORLD.size == 1 and workers > 1 and processes.launcher():
            argv = ["validate", *([args.scene] if args.scene else []), "--out", out,
                    *[f"--set={s}" for s in args.sets], *(["--fresh"] if args.fresh else []),
                    "--samples", str(args.samples), "--seed", str(args.seed),
                    *(["--shots", args.shots] if args.shots else [])]
            return processes.relaunch(argv, workers)
        study.run(st, plan, out, MPI.COMM_WORLD, 1, args.fresh, say)
        say(written_line(out))
        return 0
    if args.shots:
        from fepen.errors import InputError

        raise InputError("--shots", "chooses the shots of an ensemble: give it with --samples N")
    st = validate.Validate()
    plan = st.plan(args.scene, args.sets)  # bad input here, before anything is written
    deformable = next(iter(plan.scenes.values())).effects.fidelity != "rigid"
    if MPI.COMM_WORLD.size == 1 and deformable and workers > 1 and processes.launcher():
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
