"""Runs: one scene into one results directory.

    shot         the scene resolved once (Shot): the only reader of the scene in fepen.runs
    budget       what a shot will cost, before it starts: mesh cells and memory, the rigid step
    setup        the builders of every law, shape and mesh from a scene (used by shot)
    targets      the target's kinds (one material, layered, rigid wall): each its law, checks, end, tunnel
    run          the Run skeleton both fidelities share: loop, stop, summary, history rows
    rigid        RigidRun: the rigid body (no mesh by default)
    batch        rigid shots in batches: one compiled call per projectile, bitwise RigidRun's summaries
    model        the deformable model: mesh, solver, target, contact, wear, erosion
    deformable   DeformableRun: the explicit solver's time loop, its outputs and checkpoints
    closing      the closing analyses of a completed deformable run
    charge_safety  the charge-safety criteria watched over a charged run, its verdict and margin fields
    events       the stop rules
    outputs      History, Fields, Checkpoint, Progress: due / write / close on one clock
    checkpoint   checkpoint files and --resume
    interrupts   SIGTERM / SIGINT during a run
    probes       the user's point and cell histories ([[output.probes]], probes.csv)
"""

from __future__ import annotations

from mpi4py import MPI

from fepen.runs import setup, shot
from fepen.runs.rigid import RigidRun
from fepen.runs.shot import Shot, resolve

__all__ = ["shot", "budget", "setup", "targets", "run", "rigid", "batch", "sensitivity", "model", "deformable",
           "closing", "charge_safety", "events", "outputs",
           "probes", "checkpoint", "interrupts", "run_scene", "run_in_directory", "expected_end", "resolve", "Shot",
           "RigidRun"]


def expected_end(scene, sh: Shot) -> float:
    """The time a deformable run is expected to end at, for the progress bar: run.end_time, else the end of
    the same shot with the rigid projectile (a fraction of a second to compute), else its hard end."""
    if sh.end_time is not None or not sh.target.takes_rigid():
        return sh.hard_end
    try:
        quick = RigidRun(shot.rigid_version(scene), None, MPI.COMM_SELF).run()
        return min(sh.hard_end, 1.05 * float(quick["end_time_s"]))
    except Exception:  # noqa: BLE001 - only the bar's length depends on it
        return sh.hard_end


def run_scene(scene, out, comm=MPI.COMM_WORLD, progress: bool = False, resume: dict | None = None,
              sh: Shot | None = None, blocks: dict | None = None) -> dict:
    """Run one scene into a results directory, with the rigid or the deformable projectile.

    Args:
        scene: a resolved Scene.
        out: the results directory (None: write nothing; rigid runs only).
        comm: the communicator of the run.
        progress: progress bars on rank 0, on a terminal (deformable runs: the mesh's stages, then the simulated
            time; rigid runs: the simulated time).
        resume: a checkpoint's state (fepen.runs.checkpoint.read_state) to continue from (deformable runs).
        sh: the scene's Shot when already resolved.
        blocks: further summary blocks, the same on every rank (fepen.api.run: attitude_sensitivity).

    Returns:
        The summary (the content of summary.json).
    """
    sh = sh or resolve(scene)
    if sh.rigid:
        run = RigidRun(sh, out, comm, progress=progress)
        run.summary_blocks = dict(blocks or {})
        return run.run()
    from fepen.geometry import mesh as fmesh
    from fepen.runs.deformable import DeformableRun  # dolfinx: only a deformable run pays for importing it

    end = expected_end(scene, sh) if progress and comm.rank == 0 else None
    with fmesh.progress(progress):  # gmsh's stages, when it meshes
        run = DeformableRun(sh, out, comm, end, resume)
    run.summary_blocks = dict(blocks or {})
    return run.run()


def run_in_directory(scene, out, comm=MPI.COMM_WORLD, mode: str = "new", progress: bool = False,
                     resume: dict | None = None, sh: Shot | None = None, blocks: dict | None = None) -> dict:
    """Run a scene into its results directory as ``fepen run`` does (fepen.api.run and resume, the studies'
    shots): claim OUT (fepen.io.rundir.RunDirectory: lock, run.json, fepen.log), write scene.toml unless
    resuming, run_scene, and draw history.png of whatever history.csv holds, even after a stop.

    Args:
        scene: a resolved Scene, resolved to its Shot by the caller (``sh``) before OUT is claimed, so that
            bad input writes nothing. out: the results directory. comm: the communicator of the run.
        mode: "new" (refuse a directory holding another run's results), "force" (clear them first) or "resume".
        progress, resume, sh, blocks: as for run_scene.

    Returns:
        The summary (the content of summary.json).
    """
    from pathlib import Path

    from fepen.io import files, rundir
    from fepen.post import figures

    out = Path(out)
    sh = sh or resolve(scene)
    with rundir.RunDirectory(out, comm, mode, inputs=sh.inputs):
        if mode != "resume":
            files.agree(comm, "scene.toml", lambda: files.write_text(out / "scene.toml", sh.scene_toml, comm))
        try:
            summary = run_scene(scene, out, comm, progress=progress, resume=resume, sh=sh, blocks=blocks)
        except BaseException:
            if comm.rank == 0 and sh.outputs.figures and (out / "history.csv").is_file():  # the history a stop left
                try:
                    figures.history_figure(out, sh.experiment, MPI.COMM_SELF)
                except Exception as err:  # noqa: BLE001 - the stop's own error is the one to report
                    rundir.log_line(f"fepen: while stopping, history.png not drawn: {err}")
            raise
        finally:
            comm.barrier()
    return summary
