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
