"""The same numbers on both stacks (issue 34; docs/install.md): Table 1's eight shots, rigid and deformable at 6 mm,
and the default mesh, made by Debian's dolfinx 0.5.2 (.venv: numpy 1.24, Open MPI, Python 3.11) and by the
current dolfinx (.venv-current: 0.11 from PyPI, numpy 2, MPICH, Python 3.12). ``make test-current`` runs this
after the current stack's unit and MPI lanes; it needs both environments (make setup, make setup-current).

The two stacks do not run the same floating-point operations (numpy 2's SIMD exp and sin against libm's,
ffcx 0.11's generated kernel, another LLVM under numba), so their figures agree to round-off grown through a
run, not to the bit: the rigid shots' every summary figure within 1e-6 of itself (the 6 significant digits fepen
prints; the tip's recession, the residual speed and the energy error, differences of large figures, on their
scale: compare_stacks.SCALE) and every history column within 1e-6 of its own scale (on this machine 1e-11); the
deformable shots' depths to the printed digit, their other figures within TOLERANCE (the tunnel's wall makes a
nearly normal shot's small lateral figures carry a flipped contact: C2 4e-5, 2.8e-4)."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tools"))
import compare_stacks as cs  # noqa: E402

from fepen.studies import processes  # noqa: E402

MISSING = [str(p) for p in cs.STACKS.values() if not p.is_file()]
pytestmark = pytest.mark.skipif(bool(MISSING), reason=f"both stacks needed (make setup, make setup-current): "
                                                      f"missing {MISSING}")
#: the printed digits' resolution: fepen prints 6 significant digits
RTOL = 1e-6
#: the deformable shots since the tunnel's wall (issue 45), (summary, history): a point at the wall is loaded or
#: not, and the wall is pushed out to it, so round-off can flip one point's contact and the lateral figures of a
#: nearly normal shot, small themselves, carry it. Measured at 4 mm (tools/compare_stacks.py): C2 (0.58 deg)
#: final axis 4e-5 of itself, its instantaneous out-of-plane moment moment_x_N_m 1.6e-3 of the moments' scale,
#: C8 1.2e-5 and 2e-5; C3-C7 below 6e-6; the depths the same to the printed digit on every shot
#: The test runs the deformable shots at 6 mm, not the 4 mm of docs/install.md's table, for the suite's time (31 s
#: against 47 s per stack on 2 cores): the same code on a coarser mesh, compared at the same tolerances (at 6 mm on
#: this machine the largest summary difference was 4.5e-10, C2's Hx, and the largest history one 8.7e-9)
SIZE_MM = 6
TOLERANCE = {"rigid": (RTOL, RTOL), f"plastic-{SIZE_MM}mm": (1e-4, 5e-3)}


@pytest.fixture(scope="module")
def pairs(tmp_path_factory):
    """{case: (debian dir, current dir)}: Table 1 rigid and at SIZE_MM deformable, run by both stacks."""
    return {case: (a, b) for case, a, b in cs.run_both(tmp_path_factory.mktemp("stacks"), SIZE_MM)}


@pytest.mark.parametrize("case", ["rigid", f"plastic-{SIZE_MM}mm"])
def test_table1_gives_the_same_figures_on_both_stacks(pairs, case):
    rows = cs.compare(*pairs[case])
    assert [r["shot"] for r in rows] == [f"C{k}" for k in range(1, 9)]
    summary_tol, history_tol = TOLERANCE[case]
    for r in rows:
        assert r["outcome"][0] == r["outcome"][1] and not r["missing"], r
        assert cs.rel(r["depth_a"], r["depth_b"]) < RTOL, r
        assert r["summary_rel"] < summary_tol, \
            f"{r['shot']} {case}: {r['summary_key']} differs by {r['summary_rel']:.2g}"
        assert r["rows"][0] == r["rows"][1] and r["history_rel"] < history_tol, \
            f"{r['shot']} {case}: history.csv {r['history_col']} differs by {r['history_rel']:.2g}"


@pytest.mark.parametrize("case", ["rigid", f"plastic-{SIZE_MM}mm"])
def test_each_run_records_the_stack_it_ran_on(pairs, case):
    """summary.json (and a deformable run's run.json) name the MPI library, numpy and Python, and the dolfinx and
    PETSc of a deformable run (a rigid run imports neither)."""
    for stack, d in zip(cs.STACKS, pairs[case]):
        records = [json.loads((d / "C3" / "summary.json").read_text())["versions"]]
        if case != "rigid":
            records.append(json.loads((d / "C3" / "run.json").read_text())["versions"])
        for versions in records:
            assert versions["mpi"].startswith("Open MPI" if stack == "debian" else "MPICH"), versions
            assert versions["numpy"].startswith("1." if stack == "debian" else "2."), versions
            if case == "rigid":
                assert "dolfinx" not in versions
            else:
                assert versions["dolfinx"].startswith("0.5.2" if stack == "debian" else "0.11."), versions
                assert versions["petsc"].startswith("3.18." if stack == "debian" else "3."), versions


def test_the_mesh_is_the_same_on_both_stacks(tmp_path):
    """fepen mesh at 4 mm: the same metrics, and mesh.xdmf with its tags written by both dolfinx."""
    import h5py

    metrics = []
    for stack, py in cs.STACKS.items():
        out = tmp_path / stack
        subprocess.run([str(py), "-m", "fepen", "mesh", "--out", str(out), "--set", "mesh.size=4e-3"], cwd=ROOT,
                       check=True, stdout=subprocess.DEVNULL)
        metrics.append(json.loads((out / "mesh.json").read_text()))
        with h5py.File(out / "mesh.h5") as h5:
            groups = set(h5)
        assert {"Mesh", "MeshTags"} <= groups, (stack, groups)
    a, b = metrics
    for key in ("cells", "nodes"):
        assert a[key] == b[key]
    for key in ("mass_kg", "volume_m3", "min_quality", "shortest_altitude_m", "stable_dt_s"):
        assert a[key] == pytest.approx(b[key], rel=1e-12), key


def test_a_charged_shot_on_two_ranks_is_the_same_on_both_stacks(tmp_path):
    """The charged projectile (split wall, shell-charge contact) on 2 ranks, each stack under its own launcher
    (Open MPI's mpirun, MPICH's mpiexec): the same band partition with its ghosts, the same figures (the pairs'
    state counts apart: compare_stacks.is_state)."""
    dirs = []
    for stack, py in cs.STACKS.items():
        out = tmp_path / stack
        subprocess.run([processes.launcher(py), "-n", "2", str(py), "-m", "fepen", "run", "--out", str(out),
                        "--set", "effects.charge=true", "--set", "mesh.size=6e-3", "--set", "run.end_time=1e-4",
                        "--set", "run.fields=false"], cwd=ROOT, check=True, stdout=subprocess.DEVNULL,
                       env=processes.mpi_env())
        dirs.append(out)
    r = cs.compare_shot(*dirs)
    assert json.loads((dirs[1] / "summary.json").read_text())["ranks"] == 2
    assert not r["missing"] and r["summary_rel"] < RTOL, f"{r['summary_key']} differs by {r['summary_rel']:.2g}"
    assert r["rows"][0] == r["rows"][1] and r["history_rel"] < RTOL, f"{r['history_col']}: {r['history_rel']:.2g}"
    # the pairs' states (free, sticking, sliding) may differ only in the first rows, while the wall carries no load
    # and a pair's gap and slip are round-off (here: rows up to 15 of 101); from then on the same to the pair
    assert max(r["state_rows"], default=0) < 0.25 * r["rows"][0], r["state_rows"]
