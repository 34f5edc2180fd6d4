"""Whole runs give the same history on 1 and on 2 ranks (issue 31): every sum that feeds the dynamics is
taken in an order that does not depend on the partition (fepen.solver.assembly), so the runs agree to
round-off in every history column, to the end, contact chatter included. Runs in the MPI lane only (on one
rank the two runs would be the same run)."""

import tempfile

import numpy as np
import pytest
from conftest import ROOT
from mpi4py import MPI

from fepen import scene
from fepen.io import results
from fepen.runs.deformable import DeformableRun

QUIET = ["run.fields=false", "run.checkpoint_interval=0", "run.figures=false"]
#: name -> (scene file or None for the default shot, settings)
CASES = {
    "C3_plastic_4mm": (ROOT / "scenes" / "default.toml", ["mesh.size=0.004"]),
    "charged_6mm": (ROOT / "demos" / "charge" / "charge_800.toml", ["mesh.size=0.006"]),
    "wear_erosion_5mm": (ROOT / "demos" / "hard_cases" / "soft_breaks.toml",
                         ["effects.wear=true", "effects.erosion=true", "projectile.failure_strain=100",
                          "mesh.size=0.005", "projectile.erosion.strain=0.02"]),
}


def whole_run(name, comm):
    path, sets = CASES[name]
    out = comm.bcast(tempfile.mkdtemp(prefix="fepen-ranks-") if comm.rank == 0 else None, root=0)
    sim = DeformableRun(scene.load(path, [*QUIET, *sets]), out, comm)
    summary = sim.run()
    return summary, np.array(sim.rows), sim


#: which rank makes each case's 1-rank run (alone): the two ranks make theirs at once, the longest on its own
ALONE_ON = {"C3_plastic_4mm": 0, "charged_6mm": 1, "wear_erosion_5mm": 1}


@pytest.fixture(scope="module")
def alone_runs():
    """{case: (summary, history rows)} of the 1-rank runs, made by the rank ALONE_ON names and sent to both
    (each rank used to make every one itself: the same run twice at once)."""
    world = MPI.COMM_WORLD
    if world.size < 2:
        return None
    mine = {name: whole_run(name, MPI.COMM_SELF)[:2] for name, rank in ALONE_ON.items() if rank == world.rank}
    out = {}
    for rank in sorted(set(ALONE_ON.values())):
        out.update(world.bcast(mine if world.rank == rank else None, root=rank))
    return out


@pytest.mark.mpi
@pytest.mark.parametrize("name", list(CASES))
def test_whole_run_is_the_same_on_one_and_two_ranks(name, alone_runs):
    """Every history column within 1e-10 of its largest value, from the first row to the last; the charged
    run's per-body kinetic energies and momenta and its contact resultant, the same bits."""
    if MPI.COMM_WORLD.size < 2:
        pytest.skip("compares 1 and 2 ranks: the MPI lane")
    sw, world, sim = whole_run(name, MPI.COMM_WORLD)
    sa, alone = alone_runs[name]
    assert sw["outcome"] == sa["outcome"]
    assert world.shape == alone.shape and len(alone) > 100
    scale = np.abs(alone).max(axis=0)
    diff = np.abs(world - alone).max(axis=0)
    worst = {c: float(d / s) if s > 0 else float(d) for c, d, s in zip(sim.columns, diff, scale)}
    assert max(worst.values()) <= 1e-10, {c: w for c, w in worst.items() if w > 1e-10}
    if name == "wear_erosion_5mm":
        assert sim.model.erosion.count > 0  # cells did erode
    if name == "charged_6mm":  # the bodies' kinetic energies and momenta and the contact resultant: exact sums
        exact = [c for c in results.BODY_COLUMNS + results.RESULTANT_COLUMNS if "internal" not in c]
        k = [sim.columns.index(c) for c in exact]
        assert np.array_equal(world[:, k], alone[:, k]), {c: worst[c] for c in exact}
