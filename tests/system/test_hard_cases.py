"""Hard cases stay numerically stable (demos/hard_cases/*.toml on coarse meshes; the full-size runs are
demos/hard_cases/run_all.py, figures in docs/hard-cases.md).

Each case: finishes without NaN with its expected outcome, closes the energy balance within 1 %, converges
under mesh refinement, and gives the same result on 1 and 2 ranks; the case beyond the method (a
projectile that would fracture) stops with a clear message, and inverted elements are detected, not hidden.
"""

import json
import tempfile

import numpy as np
import pytest
from conftest import ROOT, run_fepen
from mpi4py import MPI

from fepen import scene
from fepen.errors import SimulationError
from fepen.runs.deformable import DeformableRun

CASES = ROOT / "demos" / "hard_cases"
COARSE = ["mesh.size=0.006", "run.fields=false", "run.checkpoint_interval=0", "run.figures=false"]

#: case -> (extra settings for the suite, expected outcome)
SUITE = {
    "normal_1200": (["run.end_time=3e-4"], "ended"),
    "oblique_900_45": (["run.end_time=3e-4"], "ended"),
    "ricochet_250_75": ([], "ricochet"),
    "attack_900_5": (["run.end_time=3e-4"], "ended"),
    "coarse_mesh": ([], "embedded"),
    "slab_perforation": ([], "perforated"),
    "soft_bending": (["run.end_time=3e-4"], "ended"),
    "charged_oblique_900_45": (["run.end_time=3e-4"], "ended"),
}


def run_case(name, sets=(), comm=MPI.COMM_SELF, out=None):
    sc = scene.load(CASES / f"{name}.toml", [*COARSE, *SUITE.get(name, ([], None))[0], *sets])
    if out is None:
        out = comm.bcast(tempfile.mkdtemp(prefix="fepen-hard-") if comm.rank == 0 else None, root=0)
    sim = DeformableRun(sc, out, comm)
    summary = sim.run()
    return summary, np.array(sim.rows), sim


@pytest.mark.parametrize("name", list(SUITE))
def test_hard_case_is_stable(name, tmp_path):
    summary, rows, sim = run_case(name, out=tmp_path)
    assert summary["outcome"] == SUITE[name][1]
    assert np.all(np.isfinite(rows))
    assert summary["energy_error"] < 0.01
    assert np.max(rows[:, 18]) < 0.01  # energy_error column, at every recorded time
    if name == "ricochet_250_75":
        assert summary["residual_speed_m_s"] > 100.0 and rows[-1, 2] < 50.0  # leaves, shallow
    if name == "slab_perforation":
        assert summary["residual_speed_m_s"] > 300.0
    if name == "soft_bending":  # the soft body bends: top and bottom of mid-length strain oppositely
        g = np.genfromtxt(tmp_path / "strains.csv", delimiter=",", names=True)
        bending = np.max(np.abs(g["top_50pctL"] - g["bottom_50pctL"])) / 2
        # past four times the elastic limit of its 400 MPa steel: the 6 mm cells' gauges read 4.8-4.9 times it,
        # 4 mm cells 6.0-6.4 times (a cell average under-reads the surface strain of a bent beam)
        assert bending > 4 * 400e6 / 210e9
        assert g["bottom_50pctL"].max() > 0.002  # stretched side: tension of a bent beam
    if name == "charged_oblique_900_45":  # the wall slides and opens, never interpenetrates
        col = {k: rows[:, sim.columns.index(k)] for k in ("interface_slip_max_mm", "interface_penetration_max_mm")}
        assert col["interface_slip_max_mm"].max() > 0.01
        assert col["interface_penetration_max_mm"].max() < 0.01 * 6.0


def test_case_beyond_the_method_says_so(tmp_path):
    """A projectile that passes the failure strain the user asked to stop at: exit 3, one line saying beyond
    the method, where and when; the history up to then is kept, the summary says why and where, and reports
    no result."""
    r = run_fepen("run", CASES / "soft_breaks.toml", "--set", "mesh.size=0.005", "--set", "run.fields=false",
                  "--set", "projectile.failure_strain=0.5", "--out", tmp_path)
    assert r.returncode == 3
    line = r.stderr.strip().splitlines()[-1]
    assert "beyond the method" in line and "behind the nose tip" in line and " us" in line
    assert "Traceback" not in r.stderr
    assert (tmp_path / "history.csv").exists()
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["outcome"] == "stopped" and summary["stop_reason"] in line and "depth_mm" not in summary


def test_inverted_elements_are_detected(tmp_path):
    """Without erosion and with the failure strain lifted, the soft nose collapses: the run stops on the first
    inverted (or flattened) element with where and when, instead of carrying on with NaN."""
    with pytest.raises(SimulationError, match=r"inverted|nearly flat") as err:
        run_case("soft_breaks", ["mesh.size=0.005", "projectile.failure_strain=100"], out=tmp_path)
    assert "behind the nose" in str(err.value) and " us" in str(err.value)
    hist = np.genfromtxt(tmp_path / "history.csv", delimiter=",", names=True)
    assert np.all(np.isfinite(hist["nose_y_mm"]))  # what was written before the stop is sound


@pytest.mark.parametrize("name", ["oblique_900_45", "attack_900_5"])
def test_hard_case_converges_under_refinement(name):
    """Nose position and speed after 150 us on 8, 6 and 4 mm meshes agree with the 4 mm result within
    0.5 % of the distance travelled and 1 % of the speed. (Each size is a new unstructured mesh, so the
    results scatter by ~0.2 % rather than converge monotonically; on 8, 6, 5, 4 and 3 mm meshes the nose
    positions of these two cases stay within 0.3 mm of each other, see docs/hard-cases.md.)"""
    q = []
    for h in (0.008, 0.006, 0.004):
        # phi_min 0: at the calibrated 12 deg the loaded region's edge jumps from facet to facet and the 8 mm
        # mesh is 0.9 % of the travel off (issue 29's note; to be smoothed with issue 31)
        s, rows, _ = run_case(name, [f"mesh.size={h}", "run.end_time=1.5e-4", "target.separation_angle_deg=0"])
        q.append(rows[-1, [1, 2, 5]])  # nose x, nose y (mm), speed (m/s)
    q = np.array(q)
    travelled = np.hypot(q[2, 0], q[2, 1])
    e8, e6 = (np.hypot(*(q[k, :2] - q[2, :2])) for k in (0, 1))
    assert max(e8, e6) < 0.005 * travelled
    assert np.all(np.abs(q[:2, 2] - q[2, 2]) < 0.01 * q[2, 2])


@pytest.mark.mpi
@pytest.mark.parametrize("name", ["oblique_900_45", "ricochet_250_75", "slab_perforation", "charged_oblique_900_45"])
def test_hard_case_is_the_same_on_any_rank_count(name):
    """1 and 2 ranks: the same history within 1e-10 relative."""
    sets = ["run.end_time=1.2e-4"] if name != "ricochet_250_75" else ["run.end_time=2e-4"]
    _, world, _ = run_case(name, sets, comm=MPI.COMM_WORLD)
    _, alone, _ = run_case(name, sets, comm=MPI.COMM_SELF)
    assert world.shape == alone.shape
    cols = [1, 2, 3, 4, 5]
    assert np.max(np.abs(world[:, cols] - alone[:, cols])) <= 1e-10 * np.abs(alone[:, cols]).max()


@pytest.mark.mpi
def test_a_heterogeneous_concrete_is_the_same_on_any_rank_count():
    """The concrete's random field (cv 0.3, docs/theory.md §8.8) is a function of the target point alone: 1 and
    2 ranks give the same history within 1e-10 relative, and it is not the plain concrete's."""
    sets = ["run.end_time=1.2e-4", "target.heterogeneity_cv=0.3", "target.heterogeneity_seed=3"]
    _, world, _ = run_case("oblique_900_45", sets, comm=MPI.COMM_WORLD)
    _, alone, _ = run_case("oblique_900_45", sets, comm=MPI.COMM_SELF)
    _, plain, _ = run_case("oblique_900_45", sets[:1], comm=MPI.COMM_SELF)
    cols = [1, 2, 3, 4, 5]
    assert world.shape == alone.shape
    assert np.max(np.abs(world[:, cols] - alone[:, cols])) <= 1e-10 * np.abs(alone[:, cols]).max()
    assert np.max(np.abs(plain[-1, cols] - alone[-1, cols])) > 1e-4 * np.abs(alone[:, cols]).max()
