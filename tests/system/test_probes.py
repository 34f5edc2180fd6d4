"""User-chosen point and cell histories ([[output.probes]], probes.csv) and the output times on the grid: a
coarse deformable C3 shot and the rigid one, each with probes (issue 32). The 1-against-2-ranks comparison of
probes.csv runs in the MPI lane only."""

import tempfile

import numpy as np
import pytest
from mpi4py import MPI

from fepen import scene
from fepen.errors import InputError
from fepen.io import results
from fepen.runs.deformable import DeformableRun
from fepen.runs.rigid import RigidRun

pytestmark = pytest.mark.xdist_group("probes")

LENGTH = 0.144
PROBES = [{"name": "tail", "point": [0.0, LENGTH, 0.0]},
          {"name": "wall", "point": [0.0, 0.07, 0.009], "kind": "cell"},
          {"name": "nose", "point": [0.0, 0.004, 0.0], "kind": "cell"},
          {"name": "side", "point": [0.0105, 0.1, 0.003]},
          {"name": "gauge", "point": [0.0, LENGTH, 0.0], "kind": "accelerometer"}]
SETS = ["mesh.size=0.005", "run.end_time=3.05e-5", "run.output_interval=1e-5", "run.checkpoint_interval=0",
        "run.fields=false", "run.figures=false"]


def deformable(comm, probes=PROBES, sets=SETS):
    out = comm.bcast(tempfile.mkdtemp(prefix="fepen-probes-") if comm.rank == 0 else None, root=0)
    run = DeformableRun(scene.Scene({"output": {"probes": probes}}, sets), out, comm)
    run.run()
    return run


def read(path):
    return np.genfromtxt(path, delimiter=",", names=True, deletechars="")


@pytest.fixture(scope="module")
def shot():
    run = deformable(MPI.COMM_SELF)
    return run, read(run.out / "history.csv"), read(run.out / "probes.csv")


def test_output_times_are_multiples_of_the_interval(shot):
    """Every history time but the last is k x the history interval (1 us here) to 1e-12; the last is the end."""
    run, h, p = shot
    t, interval = np.array([r[0] for r in run.rows]), run.shot.outputs.history_interval
    k = np.round(t[:-1] / interval)
    assert np.all(np.abs(t[:-1] - k * interval) <= 1e-12 * np.maximum(t[:-1], interval))
    assert np.array_equal(k, np.arange(len(t) - 1))  # none skipped, none twice
    assert t[-1] == 3.05e-5
    assert run.solver.clock.dt_min < interval / 2  # several steps per row: the landing shortened some


def test_probe_rows_are_the_history_rows(shot):
    run, h, p = shot
    assert len(p) == len(h) > 30
    assert np.array_equal(p["t_s"], [r[0] for r in run.rows])
    assert list(p.dtype.names[:4]) == ["t_s", "tail_ux_m", "tail_uy_m", "tail_uz_m"]
    assert "wall_von_mises_Pa" in p.dtype.names and "nose_temperature_K" in p.dtype.names


def test_an_accelerometer_is_its_nodes_acceleration_on_the_body_axes(shot):
    """The tail's accelerometer and the tail's node probe read the same node: its three raw channels are that
    acceleration turned onto the body's axes (the same length; the axial one along the history's tail-to-nose
    axis), in g; the filtered channels keep the record's time."""
    run, h, p = shot
    a = np.stack([p[f"tail_a{c}_m_s2"] for c in "xyz"], 1) / results.G0
    g = np.stack([p[f"gauge_{c}_g_raw"] for c in ("axial", "lateral", "out_of_plane")], 1)
    rows = np.array(run.rows)
    tip = np.stack([rows[:, 1], -rows[:, 2]], 1)  # the scene's frame, mm (z: the plane of fire holds it here)
    tail = np.stack([rows[:, 3], -rows[:, 4]], 1)
    axis = (tip - tail) / np.linalg.norm(tip - tail, axis=1)[:, None]
    peak = np.abs(a).max()
    assert peak > 1e3  # the tail rings at thousands of g in the first 30 µs
    assert np.allclose(np.linalg.norm(g, axis=1), np.linalg.norm(a, axis=1), rtol=0, atol=1e-9 * peak)
    assert np.allclose(g[:, 0], a[:, 0] * axis[:, 0] + a[:, 1] * axis[:, 1], rtol=0, atol=1e-4 * peak)
    assert all(f"gauge_{c}_g{raw}" in p.dtype.names for c in ("axial", "lateral", "out_of_plane")
               for raw in ("", "_raw"))


def test_tail_probe_is_the_history_tail(shot):
    """The node nearest (0, L, 0) is the tracked tail node: its position is the history's tail (mm, depth -y)."""
    run, h, p = shot
    rows = np.array(run.rows)
    assert np.allclose(1e3 * p["tail_ux_m"], rows[:, 3], rtol=0, atol=1e-9)
    assert np.allclose(-1e3 * (LENGTH + p["tail_uy_m"]), rows[:, 4], rtol=0, atol=1e-9)


@pytest.mark.parametrize("name", ["tail", "side"])
def test_velocity_is_the_derivative_of_displacement(shot, name):
    """u(t_k+1) - u(t_k) against the trapezoid of the velocities, to the accuracy of the 1 us rows (O(h^3))."""
    run, h, p = shot
    t = p["t_s"]
    for c in "xyz":
        du = np.diff(p[f"{name}_u{c}_m"])
        v = p[f"{name}_v{c}_m_s"]
        dv = np.diff(v)
        trapezoid = 0.5 * (v[1:] + v[:-1]) * np.diff(t)
        scale = max(np.abs(np.diff(p[f"{name}_uy_m"])).max(), 1e-12)
        assert np.abs(du - trapezoid).max() <= 1e-4 * scale, c
        a = p[f"{name}_a{c}_m_s2"]
        assert np.abs(dv - 0.5 * (a[1:] + a[:-1]) * np.diff(t)).max() <= 0.2 * np.abs(dv).max() + 1e-6, c


def test_cell_probes_see_the_nose_compressed(shot):
    """At t = 0 the body is stress-free; 30 us into the target the nose cell is in compression along the axis."""
    run, h, p = shot
    for q in ("von_mises_Pa", "axial_stress_Pa", "pressure_Pa"):
        assert abs(p[f"nose_{q}"][0]) < 1.0 and abs(p[f"wall_{q}"][0]) < 1.0
    assert p["nose_pressure_Pa"][-1] > 1e8 and p["nose_axial_stress_Pa"][-1] < -1e8
    assert p["nose_von_mises_Pa"][-1] > 1e7
    assert np.all(p["nose_temperature_K"] >= 294.0 - 1e-9) and np.all(p["nose_peeq"] >= 0.0)


def test_a_point_off_the_mesh_is_refused_after_meshing():
    """A cell probe on the exact ogive is inside the exact body but outside the mesh's flat faces."""
    from fepen.runs import shot as shot_

    sh = shot_.resolve(scene.Scene({}, ["mesh.size=0.005"]))
    r = float(sh.built.shape.outer_radius(0.02))  # the ogive's radius 20 mm behind the tip
    with pytest.raises(InputError) as err:
        deformable(MPI.COMM_SELF, [{"name": "skin", "point": [r * np.sin(0.3), 0.02, r * np.cos(0.3)],
                                    "kind": "cell"}])
    assert err.value.key == "output.probes[0].point" and "no cell" in str(err.value)


def test_rigid_node_probes_are_the_rigid_motion(tmp_path):
    """The rigid fidelity's tip and tail probes are the history's nose and tail; their accelerations are the
    derivative of their velocities (central differences of the RK4 rows, away from the entry and the end)."""
    probes = [{"name": "tail", "point": [0.0, LENGTH, 0.0]}, {"name": "tip", "point": [0.0, 0.0, 0.0]}]
    run = RigidRun(scene.Scene({"output": {"probes": probes}}, ["effects.fidelity=rigid"]), tmp_path)
    run.run()
    rows, p = np.array(run.rows), read(tmp_path / "probes.csv")
    assert np.array_equal(p["t_s"], rows[:, 0]) and len(p) > 100
    assert np.allclose(1e3 * p["tip_ux_m"], rows[:, 1], rtol=0, atol=1e-9)
    assert np.allclose(-1e3 * p["tip_uy_m"], rows[:, 2], rtol=0, atol=1e-9)
    assert np.allclose(-1e3 * (LENGTH + p["tail_uy_m"]), rows[:, 4], rtol=0, atol=1e-9)
    t = p["t_s"]
    mid = slice(len(t) // 10, len(t) * 6 // 10)
    for name in ("tip", "tail"):
        v, a = p[f"{name}_vy_m_s"], p[f"{name}_ay_m_s2"]
        central = (v[2:] - v[:-2]) / (t[2:] - t[:-2])
        assert np.abs(central[mid] - a[1:-1][mid]).max() <= 0.03 * np.abs(a[mid]).max()  # the RK4 rows


@pytest.mark.mpi
def test_probes_are_the_same_bits_on_one_and_two_ranks():
    """probes.csv of the coarse shot on 1 rank and on 2, compared as text (every value written to the digits
    that give back its double)."""
    if MPI.COMM_WORLD.size < 2:
        pytest.skip("compares 1 and 2 ranks: the MPI lane")
    world = deformable(MPI.COMM_WORLD)
    alone = deformable(MPI.COMM_SELF)
    assert alone.probes.nodes != [] and alone.probes.cells != []
    a = (alone.out / "probes.csv").read_text()
    w = MPI.COMM_WORLD.bcast((world.out / "probes.csv").read_text() if MPI.COMM_WORLD.rank == 0 else None)
    assert a == w
