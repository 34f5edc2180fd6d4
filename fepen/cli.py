"""The ``fepen`` command (docs/scenes.md, docs/results.md).

    fepen run SCENE.toml [--out DIR] [--set KEY=VALUE ...]
    fepen run --resume DIR
    fepen mesh SCENE.toml [--out DIR] [--set KEY=VALUE ...]
    fepen validate [SCENE.toml] [--out DIR] [--set KEY=VALUE ...]
    fepen study accuracy-cost [--out DIR] [--ranks N] [--quick] [--fresh]
    fepen sweep SWEEP.toml [--out DIR] [--ranks-per-shot K] [--workers W] [--set KEY=VALUE ...] [--fresh]
    fepen keys
    fepen --version
    fepen --debug COMMAND ...    (a traceback with every error, for developers)

Exit codes (fepen.errors, docs/results.md): 0 success; 2 bad input (one line naming the key or argument and
what is allowed, before anything is written); 3 the simulation cannot go on (what, where, when); 4 a fault of
the machine (disk full, permission, a signal that stopped the run after a checkpoint); 1 a bug in fepen. Every
error is one line on stderr; --debug adds the traceback.
"""

from __future__ import annotations

import argparse
import sys

from fepen.errors import InputError, Interrupted, MachineFault, SimulationError, describe_os_error, stop_outcome


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2, as for every other bad input
        raise InputError("command line", message)


def _parser() -> argparse.ArgumentParser:
    ap = _Parser(prog="fepen", description="Projectile penetrating concrete, projectile-target separation.",
                 epilog="Exit codes: 0 success, 2 bad input, 3 the simulation cannot go on, 4 a fault of the "
                        "machine (disk full, permission, SIGTERM/SIGINT after a checkpoint), 1 a bug. "
                        "--debug (anywhere): tracebacks.")
    ap.add_argument("--version", action="store_true", help="print fepen's version and code revision and exit")
    sub = ap.add_subparsers(dest="command", parser_class=_Parser)

    def scene_args(p, out_default):
        p.add_argument("scene", nargs="?", help="scene file (TOML); absent: the default scene")
        p.add_argument("--out", default=out_default, help=f"results directory (default {out_default})")
        p.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE",
                       help="override a dotted scene key; VALUE in TOML syntax, bare words are strings")

    run = sub.add_parser("run", help="one simulation: summary.json, history.csv, fields.xdmf, figures")
    scene_args(run, "results/run")
    run.add_argument("--resume", metavar="DIR",
                     help="continue the killed or interrupted run in DIR from its last checkpoint (same scene, "
                          "same ranks)")
    run.add_argument("--force", action="store_true",
                     help="when --out holds another run's results, remove them first (only what fepen writes)")
    scene_args(sub.add_parser("validate", help="the Table 1 sweep: validation.csv, validation.md, figures"),
               "results/validation")
    scene_args(sub.add_parser("mesh", help="build the projectile mesh only: mesh.json, mesh.xdmf, mesh.png"),
               "results/mesh")
    vd = sub.add_parser("validate-depth", help="depth data sets by the rigid fidelity and Forrestal's closed "
                                               "form: depth.csv, depth.md, depth.png")
    vd.add_argument("--data", action="append", default=[], metavar="PATH",
                    help="a depth data set (CSV, docs/validation-depth.md) or a folder of them; repeatable")
    vd.add_argument("--only", action="store_true", help="run only the --data sets (not table1 and the shipped)")
    vd.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE",
                    help="override a scene key in every rigid run (e.g. target.strength_model=forrestal-S)")
    vd.add_argument("--out", default="results/validate-depth", help="results directory")
    vd.add_argument("--workers", type=int, default=1, help="processes at once (default 1)")
    st = sub.add_parser("study", help="accuracy-cost: what accuracy costs in time (study.md, pareto.png); "
                                      "ballistic-limit; ricochet (docs/studies.md)")
    st.add_argument("which", choices=["accuracy-cost", "ballistic-limit", "ricochet"])
    st.add_argument("scene", nargs="?", help="ballistic-limit, ricochet: the base scene (absent: the default)")
    st.add_argument("--out", default=None, help="results directory (default results/study, "
                                                "results/ballistic-limit or results/ricochet)")
    st.add_argument("--ranks", type=int, default=2, help="accuracy-cost: MPI ranks of each run (default 2)")
    st.add_argument("--quick", action="store_true", help="accuracy-cost: a small subset on coarse meshes")
    st.add_argument("--fresh", action="store_true", help="run again what DIR already holds")
    st.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE",
                    help="ballistic-limit, ricochet: override a key of the base scene")
    st.add_argument("--ranks-per-shot", type=int, default=1, metavar="K", help="ranks of each shot (default 1)")
    st.add_argument("--speeds", default=None, help="ballistic-limit: the bracket 'LOW,HIGH' (default 100,1500 "
                                                   "m/s); ricochet: the speeds (default 300,400,...,900 m/s)")
    st.add_argument("--tol", type=float, default=None,
                    help="the bisection's final width: m/s (ballistic-limit, default 2) or deg (ricochet, 0.5)")
    st.add_argument("--obliquity-max", type=float, default=85.0, help="ricochet: top of the bracket (deg)")
    sw = sub.add_parser("sweep", help="many shots of a base scene (grid, Monte Carlo or a table): sweep.csv, "
                                      "sweep.md, figures; resumable; MPI groups (docs/studies.md)")
    sw.add_argument("sweep", help="the sweep file (TOML)")
    sw.add_argument("--out", default="results/sweep", help="results directory (default results/sweep)")
    sw.add_argument("--ranks-per-shot", type=int, default=1, metavar="K",
                    help="ranks of each shot's MPI group (default 1; must divide the number of ranks)")
    sw.add_argument("--workers", type=int, default=None, metavar="W",
                    help="without mpirun: run under mpirun -n W (default: one per core; 1: in this process)")
    sw.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE",
                    help="override a key of the base scene")
    sw.add_argument("--fresh", action="store_true", help="discard the shots OUT holds and run them all again")
    sub.add_parser("keys", help="list every scene key with its default, unit and allowed values")
    vw = sub.add_parser("view", help="a run in ParaView (its view.py), or pyvista where ParaView is absent")
    vw.add_argument("dir", help="results directory of a run with fields (finished, running or killed)")
    vw.add_argument("--png", help="render one picture to this file, offscreen, and exit")
    vw.add_argument("--time", type=float, help="output time (s); default the last")
    vw.add_argument("--field", default="von_mises_Pa", help="the field to colour by (default von_mises_Pa)")
    return ap


def _say(*lines: str) -> None:
    from mpi4py import MPI

    from fepen.io import rundir

    if MPI.COMM_WORLD.rank == 0:
        print(*lines, sep="\n", flush=True)
        for line in lines:
            rundir.log_line(line)


def cmd_mesh(args) -> int:
    """Build the mesh of a scene, print and write its figures."""
    from dolfinx.io import XDMFFile
    from mpi4py import MPI

    from fepen import scene as fscene
    from fepen.io import files
    from fepen.post import figures
    from fepen.runs import setup

    comm = MPI.COMM_WORLD
    sc = fscene.load(args.scene, args.sets)
    setup.announce(sc, comm)  # geometry errors before anything is written
    pm = setup.mesh(sc, comm)
    info = setup.mesh_metrics(pm, sc)
    out = files.prepare(args.out, comm)
    info["versions"] = files.versions()
    files.write_json(out / "mesh.json", info, comm)
    files.write_text(out / "scene.toml", fscene.to_toml(sc), comm)
    with XDMFFile(comm, str(out / "mesh.xdmf"), "w") as xdmf:
        xdmf.write_mesh(pm.mesh)
        pm.mesh.topology.create_connectivity(2, 3)
        xdmf.write_meshtags(pm.cell_tags)
        xdmf.write_meshtags(pm.facet_tags)
    if comm.rank == 0:  # one dataset per file, as every reader wants it (fepen.io.fields.mesh_index)
        from fepen.io.fields import mesh_index

        mesh_index(out / "mesh.h5", out / "mesh.xdmf", out / "mesh_facets.xdmf")
    comm.barrier()
    figures.mesh_picture(pm, out / "mesh.png",
                         f"{info['cells']} tets, h = {1e3 * sc.mesh.size:g} mm, {1e3 * info['mass_kg']:.2f} g")
    keys = ("cells", "nodes", "mass_kg", "volume_m3", "min_quality", "shortest_altitude_m", "stable_dt_s")
    _say(*(f"{k} = {info[k]:.6g}" if isinstance(info[k], float) else f"{k} = {info[k]}" for k in keys),
         f"altitude_over_size = {info['altitude_over_size']:.4f}",
         f"written: {out}/mesh.json, mesh.xdmf, mesh_facets.xdmf (and .vtu), mesh.png")
    return 0


def cmd_run(args) -> int:
    """Run one scene."""
    from fepen import api

    if args.resume is not None:
        if args.scene is not None or args.sets or args.force:
            raise InputError("--resume", "takes the scene of the run it continues (DIR/scene.toml): give no "
                                         "scene file, no --set and no --force")
        result = api.resume(args.resume, progress=True)
    else:
        result = api.run(api.Scene(args.scene, sets=args.sets), out=args.out, progress=True, force=args.force)
    summary, out = result.summary, result.out
    keys = ("outcome", "Hx_mm", "Hy_mm", "Tx_mm", "Ty_mm", "length_mm", "residual_speed_m_s", "max_peeq",
            "energy_error", "steps", "dt_s", "wall_s")
    keys += tuple(k for k in ("mass_loss_kg", "mass_loss_percent") if k in summary)
    _say(*(f"{k} = {summary[k]:.6g}" if isinstance(summary[k], float) else f"{k} = {summary[k]}"
           for k in keys), f"written: {out}/summary.json, history.csv, history.png"
         + (", fields.xdmf" if result.fields is not None else ""))
    return 0


def cmd_validate(args) -> int:
    """The eight Table 1 shots."""
    from fepen.studies import validate

    rows = validate.validate(args.scene, args.sets, args.out)
    _say(*(f"{r['shot']}: Hx {r['Hx_mm']:.1f}/{r['Hx_exp_mm']:g} Hy {r['Hy_mm']:.1f}/{r['Hy_exp_mm']:g} "
           f"Tx {r['Tx_mm']:.1f}/{r['Tx_exp_mm']:g} Ty {r['Ty_mm']:.1f}/{r['Ty_exp_mm']:g} mm  nose error "
           f"{100 * r['nose_error']:.1f} %  tail error {100 * r['tail_error']:.1f} %  {r['outcome']}" for r in rows),
         f"written: {args.out}/validation.csv, validation.md, validation.png")
    return 0


def cmd_validate_depth(args) -> int:
    """Depth data sets: the table per set and the predicted-against-measured figure."""
    from fepen.studies import depth

    table = depth.validate_depth(args.data, args.sets, args.out, args.workers, shipped=not args.only)
    _say(*(f"{r['set']}: {r['count']} shots; mean |error| default {100 * r['default mean_abs']:.1f} % "
           f"(bias {100 * r['default bias']:+.1f} %), forrestal-S {100 * r['forrestal-S mean_abs']:.1f} %, "
           f"closed form {100 * r['closed form mean_abs']:.1f} %" for r in table),
         f"written: {args.out}/depth.csv, depth.md, depth.png")
    return 0


def cmd_study(args) -> int:
    """The accuracy-cost study (each run its own process, on --ranks MPI ranks)."""
    from mpi4py import MPI

    from fepen.studies import accuracy_cost

    if args.which != "accuracy-cost":
        return _limit_study(args)
    args.out = args.out or "results/study"
    if MPI.COMM_WORLD.size > 1:
        raise InputError("fepen study", "run it without mpirun: it starts its own MPI jobs (--ranks)")
    if args.ranks < 1:
        raise InputError("--ranks", f"must be at least 1, got {args.ranks}")
    accuracy_cost.study(args.out, ranks=args.ranks, quick=args.quick, fresh=args.fresh, say=_say)
    _say(f"written: {args.out}/study.csv, study.md, study.json, pareto.png")
    return 0


def _numbers(option: str, text: str) -> list[float]:
    import math

    try:
        values = [float(x) for x in text.split(",")]
    except ValueError:
        values = []
    if not values or not all(math.isfinite(v) and v > 0 for v in values):
        raise InputError(option, f"comma-separated positive numbers, got {text!r}")
    return values


def _limit_study(args) -> int:
    """fepen study ballistic-limit | ricochet, on the ranks it was started on."""
    import math

    from mpi4py import MPI

    from fepen.studies import limits

    fresh_dir(args)
    comm = MPI.COMM_WORLD
    if args.ranks_per_shot < 1 or comm.size % args.ranks_per_shot:
        raise InputError("--ranks-per-shot", f"must divide the number of ranks ({comm.size})")
    if args.tol is not None and not (math.isfinite(args.tol) and args.tol > 0):
        raise InputError("--tol", f"a positive number (m/s or deg), got {args.tol!r}")
    if not (math.isfinite(args.obliquity_max) and 0.0 < args.obliquity_max < 90.0):
        raise InputError("--obliquity-max", f"in (0, 90) deg, got {args.obliquity_max!r}")
    if args.which == "ballistic-limit":
        bracket = _numbers("--speeds", args.speeds) if args.speeds is not None else [100.0, 1500.0]
        if len(bracket) != 2:
            raise InputError("--speeds", f"two speeds LOW,HIGH (m/s), got {args.speeds!r}")
        lo, hi = bracket
        limits.ballistic_limit(args.scene, args.sets, args.out, comm, args.ranks_per_shot, lo, hi,
                               args.tol or 2.0, say=_say)
        _say(f"written: {args.out}/ballistic_limit.json, ballistic_limit.png")
    else:
        speeds = (_numbers("--speeds", args.speeds) if args.speeds is not None
                  else [300.0 + 100 * j for j in range(7)])
        limits.ricochet(args.scene, args.sets, args.out, comm, args.ranks_per_shot, speeds, args.obliquity_max,
                        args.tol or 0.5, say=_say)
        _say(f"written: {args.out}/ricochet.json, ricochet.png")
    return 0


def fresh_dir(args) -> None:
    """The default results directory of a limit study; --fresh clears its rounds (rank 0)."""
    import shutil
    from pathlib import Path

    from mpi4py import MPI

    args.out = args.out or f"results/{args.which}"
    if args.fresh and MPI.COMM_WORLD.rank == 0 and (Path(args.out) / "rounds").is_dir():
        shutil.rmtree(Path(args.out) / "rounds")
    MPI.COMM_WORLD.barrier()


def cmd_view(args) -> int:
    """ParaView on the run's view.py (pvpython offscreen under xvfb-run for --png; the GUI otherwise);
    pyvista where ParaView is not installed."""
    import shutil
    import subprocess
    from pathlib import Path

    from fepen.post import paraview

    out = Path(args.dir)
    if not (out / "fields.xdmf").is_file():
        raise InputError("dir", f"{out} holds no fields.xdmf (a run with run.fields = true writes it)")
    script = out / "view.py"
    if not script.is_file():  # a run from before view.py was written
        paraview.write_view_script(out)
    extra = [*(["--time", repr(args.time)] if args.time is not None else []), "--field", args.field]
    if args.png and shutil.which("pvpython"):
        cmd = ["pvpython", "--force-offscreen-rendering", str(script), "--png", str(Path(args.png).resolve()), *extra]
        if shutil.which("xvfb-run"):  # a virtual screen of 24-bit colour on a free display number
            cmd = ["xvfb-run", "-a", "-s", "-screen 0 1280x1024x24", *cmd]
        for _ in range(3):  # two xvfb-run started at once may race for one display: try again
            r = subprocess.run(cmd, capture_output=True, text=True)
            if r.returncode == 0 and Path(args.png).is_file():
                break
        if r.returncode != 0 or not Path(args.png).is_file():
            raise SimulationError(f"ParaView could not render {args.png}: {r.stderr.strip()[-400:]}")
    elif not args.png and shutil.which("paraview"):
        subprocess.run(["paraview", f"--script={script}"], check=False)
    else:
        paraview.plot(out, args.field, args.time, args.png)
    _say(f"written: {args.png}" if args.png else f"shown: {out}")
    return 0


def cmd_sweep(args) -> int:
    """A sweep, on the MPI ranks it was started on, or relaunched under mpirun -n --workers."""
    import os
    import shutil
    import subprocess

    from mpi4py import MPI

    from fepen.studies import processes, sweep

    world = MPI.COMM_WORLD
    if args.workers is not None and args.workers < 1:
        raise InputError("--workers", f"must be at least 1, got {args.workers}")
    if args.ranks_per_shot < 1:
        raise InputError("--ranks-per-shot", f"must be at least 1, got {args.ranks_per_shot}")
    workers = args.workers if args.workers is not None else (os.cpu_count() or 1)
    if world.size == 1 and workers > 1 and shutil.which("mpirun"):
        if workers % args.ranks_per_shot:
            raise InputError("--workers", f"must be a multiple of --ranks-per-shot {args.ranks_per_shot}, "
                                          f"got {workers}")
        sweep.read(args.sweep, args.sets)  # bad input here, in one line, before mpirun starts
        argv = ["sweep", args.sweep, "--out", args.out, "--ranks-per-shot", str(args.ranks_per_shot),
                "--workers", "1", *(["--fresh"] if args.fresh else []), *[f"--set={s}" for s in args.sets]]
        return subprocess.run(processes.command(argv, workers), env=processes.mpi_env()).returncode
    res = sweep.run(args.sweep, args.out, world, args.ranks_per_shot, args.sets, args.fresh, say=_say)
    _say(f"shots: {res['shots']} ({res['ran']} run now, {res['skipped']} recorded before); "
         + ", ".join(f"{k} {v}" for k, v in sorted(res["statuses"].items())) + f"; wall {res['wall_s']:.1f} s",
         f"written: {args.out}/sweep.csv, sweep.md, shots.jsonl, sweep.png")
    return 0


def cmd_keys(args) -> int:
    """Print the scene-key table (Markdown)."""
    from fepen import scene as fscene

    _say(fscene.describe())
    return 0


COMMANDS = {"run": cmd_run, "mesh": cmd_mesh, "validate": cmd_validate, "validate-depth": cmd_validate_depth,
            "study": cmd_study, "sweep": cmd_sweep, "keys": cmd_keys, "view": cmd_view}


def version_line() -> str:
    """``fepen 0.1.0 (revision abc123…)``: the version and the code revision of this source tree."""
    from fepen.io.rundir import revision
    from fepen.version import __version__

    rev = revision()
    return f"fepen {__version__}" + (f" (revision {rev})" if rev else "")


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``fepen`` console script. Returns the exit code (fepen.errors): every error is one
    line on stderr, with its traceback only under --debug."""
    from fepen.io import rundir

    argv = list(sys.argv[1:] if argv is None else argv)
    rundir.command_line = ["fepen", *map(str, argv)]
    rundir.forget()
    debug = "--debug" in argv
    argv = [a for a in argv if a != "--debug"]
    try:
        args = _parser().parse_args(argv)
        if args.version:
            _say(version_line())
            return 0
        if args.command is None:
            raise InputError("command line", "name a command: " + ", ".join(COMMANDS) + " (fepen --help)")
        _quiet()
        return COMMANDS[args.command](args)
    except BaseException as err:  # noqa: B036 - every way out is one line and a documented code
        if isinstance(err, SystemExit):
            return err.code if isinstance(err.code, int) else 0  # --help
        code, line = _verdict(err)
        if debug:
            import traceback

            traceback.print_exc()
        _error(line)
        return code


def _verdict(err: BaseException) -> tuple[int, str]:
    """The exit code and the one line of an error (whitespace, newlines in a path included, collapsed)."""
    code, line = _verdict_line(err)
    return code, " ".join(line.split())


def _verdict_line(err: BaseException) -> tuple[int, str]:
    """The exit code (fepen.errors.stop_outcome, the one classification) and the line before its whitespace is
    collapsed."""
    code = stop_outcome(err).exit_code
    if isinstance(err, ValueError) and "null byte" in str(err):  # a path holding NUL, from a script
        return code, "fepen: bad input: a file name holds a NUL byte"
    if isinstance(err, InputError):
        return code, f"fepen: bad input: {err}"
    if isinstance(err, SimulationError):
        return code, f"fepen: simulation stopped: {err}"
    if isinstance(err, Interrupted):
        return code, f"fepen: interrupted: {err}"
    if isinstance(err, MachineFault):
        return code, f"fepen: stopped by a fault of the machine: {err}"
    if isinstance(err, OSError):
        return code, f"fepen: stopped by a fault of the machine: {describe_os_error(err)}"
    if isinstance(err, KeyboardInterrupt):
        return code, "fepen: interrupted (SIGINT) before the run had anything to keep"
    if isinstance(err, MemoryError):
        return code, "fepen: stopped by a fault of the machine: out of memory"
    text = " ".join(str(err).split())[:300]
    return code, (f"fepen: internal error (a bug in fepen; run again with --debug for the traceback and report "
                  f"it): {type(err).__name__}: {text}")


def _quiet() -> None:
    import logging

    logging.getLogger("dolfinx").setLevel(logging.WARNING)
    logging.basicConfig(format="fepen: %(message)s", level=logging.INFO)


def _error(line: str) -> None:
    from mpi4py import MPI

    from fepen.io import rundir

    if MPI.COMM_WORLD.rank == 0:
        print(line, file=sys.stderr, flush=True)
        rundir.log_line(line)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
