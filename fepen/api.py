"""fepen's Python API: a scene in, a Result out, the same run as ``fepen run`` (docs/api.md).

    scene = fepen.Scene("scenes/default.toml", sets=["effects.fidelity=rigid"])
    result = fepen.run(scene, out="results/C3-rigid")
    result.summary["Hy_mm"], result.history["nose_y_mm"][-1]
    again = fepen.load("results/C3-rigid")
    table = fepen.sweep({"base": {"effects.fidelity": "rigid"}, "grid": {"impact.velocity": [500.0, 700.0]}})
    info = fepen.mesh(scene, "results/C3-mesh")      # the mesh only, as ``fepen mesh``: info["cells"]
    limit = fepen.study("ballistic-limit", sets=["effects.fidelity=rigid", "target.thickness=0.15"])
    limit["v_bl_m_s"]                                # any study the command line runs, by its name

Under ``mpirun -n N python script.py`` every rank calls ``fepen.run`` with the same arguments (or a
communicator), as the command does.
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fepen.errors import InputError
from fepen.scene import Scene

__all__ = ["Scene", "Result", "run", "load", "resume", "mesh", "sweep", "study"]


@dataclass
class Result:
    """A results directory as Python objects.

    Attributes:
        out: the results directory.
        summary: the content of summary.json (SI units or the unit in each key's name).
        scene: the resolved Scene of the run.
        fields: fields.xdmf when the run wrote fields, else None.
        figures: the pictures the run wrote, by name ("history", "hazard", "deformed", ...).

    The run's tables, read on first use: ``history`` (numpy structured array), and as pandas DataFrames
    ``history_frame``, ``probes``, ``accelerations`` and ``strains``, their columns named as in the files (units in
    the names; docs/results.md). A table the run did not write raises FileNotFoundError saying why.
    """

    out: Path
    summary: dict
    scene: Scene
    fields: Path | None = None
    figures: dict = field(default_factory=dict)
    _history: np.ndarray | None = field(default=None, repr=False)
    _tables: dict = field(default_factory=dict, repr=False)

    @property
    def history(self) -> np.ndarray:
        """history.csv as a numpy structured array: ``history["nose_y_mm"]`` (columns: docs/results.md)."""
        if self._history is None:
            from fepen.io import results

            self._history = results.read(self.out).history()
        return self._history

    @property
    def history_frame(self):
        """history.csv as a pandas DataFrame (the same numbers as ``history``)."""
        from fepen.io.results import pandas

        return pandas("Result.history_frame").DataFrame(self.history)

    @property
    def probes(self):
        """probes.csv as a pandas DataFrame: ``t_s`` and the ``[[output.probes]]``' columns (``tip_uy_m``,
        ``tail_vy_m_s``, ...; docs/results.md). Raises FileNotFoundError, saying why, for a run without probes."""
        return self._table("probes.csv")

    @property
    def accelerations(self):
        """accelerations.csv as a pandas DataFrame: ``t_s``, ``decel_g``, ``decel_filtered_g`` (and the shell's
        and charge's with a charge). Raises FileNotFoundError, saying why, for a rigid run (it writes none)."""
        return self._table("accelerations.csv")

    @property
    def strains(self):
        """strains.csv as a pandas DataFrame: ``t_s`` and the eight gauges' axial log strains (``top_33pctL``,
        ...). Raises FileNotFoundError, saying why, for a rigid run (it writes none)."""
        return self._table("strains.csv")

    def _table(self, name: str):
        """One of the run's CSV tables as a DataFrame, read on first use (fepen.io.results.RunFiles.table)."""
        if name not in self._tables:
            from fepen.io import results

            self._tables[name] = results.read(self.out).table(name)
        return self._tables[name]

    def plot(self, field: str = "von_mises_Pa", time: float | None = None, png=None):
        """The projectile at an output time (the last by default) warped by its displacement, coloured by
        ``field``, with the target face (pyvista; ``png``: write the picture offscreen instead of showing it).
        Returns the pyvista Plotter. ParaView: ``fepen view DIR`` or ``paraview --script=DIR/view.py``."""
        from fepen.post import paraview

        if self.fields is None:
            raise InputError("run.fields", paraview.missing_fields(self.out))

        return paraview.plot(self.out, field, time, png)

    def __repr__(self) -> str:
        s = self.summary
        if "Hx_mm" not in s:  # a run that stopped before its end
            return (f"fepen.Result({str(self.out)!r}, outcome={s.get('outcome')!r}, "
                    f"stop_reason={s.get('stop_reason')!r})")
        extra = ""
        if s.get("depth_interval_mm") is not None:
            lo, hi = s["depth_interval_mm"]
            extra += f", depth_mm={s['depth_mm']:.6g} (10-90 %: {lo:.4g} to {hi:.4g})"
        if s.get("envelope") is not None:
            extra += f", inside_envelope={s['envelope']['inside']}"
        return (f"fepen.Result({str(self.out)!r}, outcome={s.get('outcome')!r}, Hx_mm={s.get('Hx_mm'):.6g}, "
                f"Hy_mm={s.get('Hy_mm'):.6g}{extra})")


def load(results_dir) -> Result:
    """The Result of a finished run's directory (summary.json, scene.toml, history.csv).

    Raises:
        InputError: when the directory holds no finished run.
    """
    from fepen.io import results

    files = results.read(results_dir)
    out, summary = files.out, files.summary()
    if summary is None:
        raise InputError("results_dir", f"{out} holds no finished run (no readable summary.json)")
    scene = Scene(out / "scene.toml") if (out / "scene.toml").is_file() else Scene(summary.get("scene"))
    return Result(out, summary, scene, files.fields(), files.figures())


def _comm(comm):
    from mpi4py import MPI

    return MPI.COMM_WORLD if comm is None else comm


def _caller() -> str:
    """Who called: "a Jupyter kernel", "an interactive session", or the script's path."""
    import sys

    if "ipykernel" in sys.modules:
        return "a Jupyter kernel"
    main = getattr(sys.modules.get("__main__"), "__file__", None)
    return str(Path(main).resolve()) if main else "an interactive session"


def _source(scene) -> str:
    """How a scene was given, for run.json: a file's path, or its kind."""
    if isinstance(scene, Scene):
        return "a Scene"
    if isinstance(scene, Path) or (isinstance(scene, str) and "\n" not in scene and "=" not in scene):
        return repr(str(Path(scene).resolve()))
    return "a dict" if isinstance(scene, dict) else "TOML text" if isinstance(scene, str) else type(scene).__name__


def _record_call(name: str, scene, **kwargs) -> None:
    """run.json's "command" for an API call: the call and who made it, not the interpreter's argv (a notebook
    kernel's would say nothing); the scene itself is the results directory's scene.toml."""
    from fepen.io import rundir

    args = ", ".join([_source(scene)] + [f"{k}={v!r}" for k, v in kwargs.items()])
    rundir.api_call([f"fepen.{name}({args})", f"# from {_caller()}"])


def run(scene, out=None, comm=None, progress: bool = False, force: bool = False, sensitivity: bool = True) -> Result:
    """Run one scene, as ``fepen run`` does, and return its Result.

    Args:
        scene: a Scene, or anything Scene() takes (a TOML file, TOML text, a dict).
        out: the results directory; None: a new temporary directory (Result.out names it).
        comm: the MPI communicator of the run; None: COMM_WORLD.
        progress: a progress bar on rank 0.
        force: when ``out`` holds another run's results, remove them first (else InputError).
        sensitivity: also run two rigid shots at the in-plane attack ± the declared unmeasured yaw and keep the
            final axis's gain in summary.json's ``attitude_sensitivity`` (fepen.runs.sensitivity).

    Returns:
        The Result.

    Raises:
        InputError: bad input, before anything is meshed or written; ``out`` holding another run's results
            (without force) or in use by a running one.
        SimulationError: the simulation could not go on (what, where, when); what it wrote is kept.
        MachineFault: disk full, permission, a signal (fepen.errors); what it wrote is kept and resumable.
    """
    from fepen.runs import resolve, run_in_directory, setup

    comm = _comm(comm)
    _record_call("run", scene, out=None if out is None else str(out), **({"force": True} if force else {}),
                 **({"sensitivity": False} if not sensitivity else {}))
    sc = scene if isinstance(scene, Scene) else Scene(scene)
    sh = resolve(sc)  # bad input before anything is written; the projectile built once
    setup.announce(sc, comm, sh.built)
    blocks = {}
    if sensitivity:
        from fepen.runs import sensitivity as fsens

        blocks["attitude_sensitivity"] = comm.bcast(fsens.attitude(sc, built=sh.built) if comm.rank == 0 else None,
                                                    root=0)
    if out is None:
        out = comm.bcast(tempfile.mkdtemp(prefix="fepen-") if comm.rank == 0 else None, root=0)
    out = Path(out)
    run_in_directory(sc, out, comm, "force" if force else "new", progress=progress, sh=sh, blocks=blocks)
    return load(out)


def resume(results_dir, comm=None, progress: bool = False) -> Result:
    """Continue a killed or interrupted deformable run from its last checkpoint (same number of ranks), or run
    a stopped rigid run again; its Result."""
    from fepen.io import rundir
    from fepen.runs import checkpoint, resolve, run_in_directory, shot

    comm = _comm(comm)
    _record_call("resume", results_dir)
    out = Path(results_dir)
    if not (out / "scene.toml").exists():
        raise InputError("--resume", f"{out} is not a results directory (no scene.toml)")
    record, foreign = rundir.read_record(out) if comm.rank == 0 else (None, None)
    record, foreign = comm.bcast((record, foreign), root=0) if comm.size > 1 else (record, foreign)
    if record is None:
        raise InputError("--resume", f"{out} holds no fepen run to resume (run.json is {foreign or 'absent'})")
    sc = Scene(out / "scene.toml")
    sh = resolve(sc)
    changed = shot.inputs_changed(record.get("inputs"), sh.inputs)
    rigid = sc.effects.fidelity == "rigid"  # seconds to run: a stopped rigid run runs again from the start
    state = None if rigid else checkpoint.read_state(out, comm)
    if changed is None and state is not None and state.get("inputs_sha256") not in (None, sh.inputs["sha256"]):
        changed = "the checkpoint's inputs digest differs from the scene's"
    if changed:
        raise InputError("--resume", f"{out} was run with other inputs: {changed}; a resume continues the same "
                                     "shot: run the new one into another --out (or --force)")
    run_in_directory(sc, out, comm, "resume", progress=progress, resume=state, sh=sh)
    return load(out)


def sweep(spec, out=None, comm=None, sets=(), fresh: bool = False, ranks_per_shot: int = 1, progress: bool = True):
    """Run a sweep, as ``fepen sweep`` does on the ranks of ``comm``, and return its table (sweep.csv).

    Args:
        spec: a SWEEP.toml, or its content as a dict (docs/studies.md), e.g. ``{"base": {"effects.fidelity":
            "rigid"}, "grid": {"impact.velocity": [500.0, 600.0, 700.0]}}``; a relative ``scene`` file is then
            taken from the working directory.
        out: the results directory (sweep.csv, sweep.md, figures; resumable); None: a new temporary directory.
        comm: the communicator (None: COMM_WORLD); ranks_per_shot: ranks of each shot's group.
        sets: ``KEY=VALUE`` overrides of the base scene. fresh: run every shot again.
        progress: a progress bar of the shots on rank 0.

    Returns:
        A pandas DataFrame, one row per shot: ``shot``, the varied keys, ``status``, ``message`` and every
        summary figure (docs/results.md), on every rank; ``DataFrame.attrs["out"]`` names the directory.

    Raises:
        InputError: bad input (naming the sweep or scene key), before any shot runs.
    """
    import logging

    from fepen.io.results import pandas
    from fepen.studies import engine
    from fepen.studies import sweep as fsweep

    pd = pandas("fepen.sweep")

    comm = _comm(comm)
    _record_call("sweep", spec, out=None if out is None else str(out))
    engine.check_ranks_per_shot(ranks_per_shot, comm.size)
    if out is None:
        out = comm.bcast(tempfile.mkdtemp(prefix="fepen-sweep-") if comm.rank == 0 else None, root=0)
    out = Path(out)
    log = logging.getLogger("fepen")  # its lines go to the fepen logger (INFO), not into a notebook's cell
    say = (lambda *lines: log.info("\n".join(lines))) if comm.rank == 0 else (lambda *lines: None)
    fsweep.run(spec, out, comm, ranks_per_shot, sets, fresh, say=say, progress=progress)
    comm.barrier()
    table = pd.read_csv(out / "sweep.csv", keep_default_na=False, na_values=[""])
    table.attrs["out"] = out
    return table


def mesh(scene, out, comm=None, force: bool = False) -> dict:
    """Mesh a scene's projectile without running it, as ``fepen mesh`` does; the mesh's metrics.

    Writes into ``out``: mesh.json (the metrics and the versions), scene.toml, mesh.xdmf with mesh.h5 (the
    mesh, its cell tags and facet tags), mesh_facets.xdmf (fepen.io.fields.mesh_index: one dataset per file,
    as every reader wants it) and mesh.png (a half-section).

    Args:
        scene: a Scene, or anything Scene() takes.
        out: the results directory (created).
        comm: the MPI communicator; None: COMM_WORLD.
        force: write into a directory that holds a run's results, removing exactly the files that run wrote
            (its manifest); without it, InputError before anything is meshed or written. An earlier mesh's files
            in ``out`` are replaced without it; a user's own files are never touched.

    Returns:
        The content of mesh.json: cells, nodes, mass_kg, volume_m3, min_quality, shortest_altitude_m,
        stable_dt_s, altitude_over_size, ..., versions.
    """
    from fepen import scene as fscene
    from fepen.io import files, rundir
    from fepen.post import figures
    from fepen.runs import setup

    comm = _comm(comm)
    _record_call("mesh", scene, out=str(out), **({"force": True} if force else {}))
    sc = scene if isinstance(scene, Scene) else Scene(scene)
    out = Path(out)
    from fepen import dolfinx_api

    dolfinx_api.check_version()  # before anything is written
    setup.announce(sc, comm)  # geometry errors before anything is written
    setup.check_mesh_cost(sc, comm)  # a mesh past the machine's memory, before gmsh starts
    with rundir.RunDirectory(out, comm, "force" if force else "new", kind="mesh"):
        pm = setup.mesh(sc, comm)
        info = setup.mesh_metrics(pm, sc)
        info["versions"] = files.versions()
        files.write_json(out / "mesh.json", info, comm)
        files.write_text(out / "scene.toml", fscene.to_toml(sc), comm)
        _write_mesh(pm, out, comm)
        figures.mesh_picture(pm, out / "mesh.png",
                             f"{info['cells']} tets, h = {1e3 * sc.mesh.size:g} mm, {1e3 * info['mass_kg']:.2f} g")
    return info


def _write_mesh(pm, out: Path, comm) -> None:
    """mesh.xdmf (with mesh.h5): the mesh, its cell tags and facet tags; mesh_facets.xdmf beside it."""
    from fepen import dolfinx_api
    from fepen.atomic import guard
    from fepen.io.fields import mesh_index

    for name in ("mesh.xdmf", "mesh.h5"):  # dolfinx writes them by name: fepen's or new, never through a link
        guard(out / name)
    dolfinx_api.write_mesh_xdmf(comm, out / "mesh.xdmf", pm.mesh, (pm.cell_tags, pm.facet_tags))
    if comm.rank == 0:  # one dataset per file, as every reader wants it
        mesh_index(out / "mesh.h5", out / "mesh.xdmf", out / "mesh_facets.xdmf")
    comm.barrier()


def study(name: str, out=None, comm=None, ranks_per_shot: int = 1, fresh: bool = False, progress: bool = False,
          say=None, **options) -> dict:
    """Run a study by its name, as the command line does (``fepen study NAME``, ``fepen sweep``, ``fepen
    validate``, ``fepen validate-depth``; the registry: fepen.studies.study.STUDIES), and return its result.

    Args:
        name: "ballistic-limit", "ricochet", "uncertainty", "charge-safety", "accuracy-cost", "sweep", "validate",
            "validate-depth", "calibration", "wear-calibration" or "prediction-errors".
        out: its folder (None: a new temporary one). comm: the communicator (None: COMM_WORLD).
        ranks_per_shot: ranks of each shot's group. fresh: remove what the study wrote in ``out`` first.
        progress: the shots' bar on rank 0. say: prints its lines (None: silent).
        options: the study's own (its plan's keywords), e.g. ``scene_path``, ``sets``, ``v_low``, ``v_high``,
            ``tol`` for the ballistic limit; ``spec`` for a sweep.

    Returns:
        The study's result (the content of its NAME.json where it writes one), with "wall_s" and "ran".

    Raises:
        InputError: an unknown study or bad options, before anything is written.
    """
    from fepen.studies import study as fstudy

    comm = _comm(comm)
    from fepen.io import rundir

    args = ", ".join([repr(name)] + [f"{k}={v!r}" for k, v in {"out": out, **options}.items()])
    rundir.api_call([f"fepen.study({args})", f"# from {_caller()}"])
    cls = fstudy.get(name)
    st = cls()
    plan = st.plan(**options)
    if out is None:
        out = comm.bcast(tempfile.mkdtemp(prefix=f"fepen-{name}-") if comm.rank == 0 else None, root=0)
    return fstudy.run(st, plan, out, comm, ranks_per_shot, fresh, say or (lambda *lines: None), progress)
