"""Runs: one scene into one results directory (set-up, time loops, stop rules, outputs, checkpoints)."""

from __future__ import annotations

from mpi4py import MPI

from fepen.runs import setup
from fepen.runs.rigid import RigidRun

__all__ = ["setup", "model", "deformable", "rigid", "events", "outputs", "checkpoint", "run_scene", "RigidRun"]


def run_scene(scene, out, comm=MPI.COMM_WORLD, progress: bool = False, resume: dict | None = None) -> dict:
    """Run one scene into a results directory, with the rigid or the deformable projectile.

    Args:
        scene: a resolved Scene.
        out: the results directory (None: write nothing; rigid runs only).
        comm: the communicator of the run.
        progress: a progress bar on rank 0 (deformable runs).
        resume: a checkpoint's state (fepen.runs.checkpoint.read_state) to continue from (deformable runs).

    Returns:
        The summary (the content of summary.json).
    """
    setup.check_supported(scene)
    if scene.effects.fidelity == "rigid":
        return RigidRun(scene, out, comm).run()
    from fepen.runs.deformable import DeformableRun  # dolfinx: only a deformable run pays for importing it

    return DeformableRun(scene, out, comm, progress, resume).run()


def run_in_directory(scene, out, comm=MPI.COMM_WORLD, mode: str = "new", progress: bool = False,
                     resume: dict | None = None) -> dict:
    """Run a scene into its results directory as ``fepen run`` does (fepen.api.run and resume, the studies'
    shots): claim OUT (fepen.io.rundir.RunDirectory: lock, run.json, fepen.log), write scene.toml unless
    resuming, run_scene, and draw history.png of whatever history.csv holds, even after a stop.

    Args:
        scene: a resolved Scene, checked by the caller (setup.check_supported, setup.announce) before OUT is
            claimed. out: the results directory. comm: the communicator of the run.
        mode: "new" (refuse a directory holding another run's results), "force" (clear them first) or "resume".
        progress, resume: as for run_scene.

    Returns:
        The summary (the content of summary.json).
    """
    from pathlib import Path

    from fepen import scene as fscene
    from fepen.io import files, rundir
    from fepen.post import figures

    out = Path(out)
    with rundir.RunDirectory(out, comm, mode):
        if mode != "resume":
            files.agree(comm, "scene.toml", lambda: files.write_text(out / "scene.toml", fscene.to_toml(scene), comm))
        try:
            return run_scene(scene, out, comm, progress=progress, resume=resume)
        finally:
            if (out / "history.csv").exists():  # a full disk leaves the last one
                try:
                    figures.history_figure(out, scene, comm)
                except OSError:
                    pass
            comm.barrier()
