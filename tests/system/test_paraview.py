"""The fields as a user meets them (issue 15; docs/results.md): ParaView's Xdmf3 and legacy XDMF readers
(pvpython), pyvista and meshio each open fields.xdmf of a finished run (serial and 2 ranks), a charged run,
and a run while it is running and after it was killed; every reader runs in a subprocess, so a crash is a
failure, not a dead test run. ParaView also renders the run's view.py to a PNG, and its tensor filter finds the
principal stresses of the six stress scalars in the one stress tensor of fields.xdmf and of the stress maps' .vtu
(issue 61).

ParaView comes from Debian (`apt-get install paraview xvfb`, done by tools/bootstrap.sh); where it is not
installed the ParaView tests are skipped and say so, the pyvista and meshio ones still run.
"""

import json
import os
import shutil
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT, Runs, run_fepen

#: one pytest-xdist worker runs this module (make test: -n 2 --dist loadgroup), so that its module-scoped
#: runs are made once, not once per worker
pytestmark = pytest.mark.xdist_group("test_paraview")

HERE = Path(__file__).resolve().parent
PVPYTHON = shutil.which("pvpython")
XVFB = shutil.which("xvfb-run")
needs_paraview = pytest.mark.skipif(PVPYTHON is None, reason="ParaView's pvpython is not installed "
                                                             "(apt-get install paraview xvfb; tools/bootstrap.sh)")
SMALL = ["--set", "mesh.size=0.006", "--set", "run.end_time=6e-5", "--set", "run.output_interval=2e-5"]
POINT_FIELDS = {"displacement_m", "velocity_m_s", "target_force_N", "target_normal_stress_Pa",
                "target_friction_traction_Pa"}
CELL_FIELDS = {"von_mises_Pa", "axial_stress_Pa", "peeq", "temperature_K", "cell_tag", "pressure_Pa", "triaxiality"}
#: the finished serial and 2-rank runs write the stress tensor: its six scalars and the one tensor made of them
TENSOR = ["--set", "run.stress_tensor_fields=true"]
STRESS_COMPONENTS = ("xx", "yy", "zz", "xy", "yz", "xz")
TENSOR_FIELDS = {f"stress_{c}_Pa" for c in STRESS_COMPONENTS} | {"stress_Pa"}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Finished runs: serial, 2 ranks, charged (serial), each made when first asked for (conftest.Runs: the
    2-rank run only in the system lane's two_ranks phase)."""
    base = tmp_path_factory.mktemp("pv")
    how = {"serial": (1, TENSOR), "ranks2": (2, TENSOR), "charged": (1, ["--set", "effects.charge=true"])}

    def make(name):
        ranks, extra = how[name]
        r = run_fepen("run", *SMALL, *extra, "--out", str(base / name), ranks=ranks)
        assert r.returncode == 0, r.stderr[-2000:]
        return base / name
    return Runs(make)


def xdmf_times(out: Path) -> list[float]:
    root = ET.parse(out / "fields.xdmf").getroot()
    return [float(t.get("Value")) for t in root.iter("Time")]


def mesh_counts(out: Path) -> tuple[int, int]:
    """Points and cells as the run's own mesh has them (the topology and geometry datasets)."""
    import h5py

    if (out / "fields.d" / "mesh.h5").is_file():
        with h5py.File(out / "fields.d" / "mesh.h5", "r") as h5:
            return h5["geometry"].shape[0], h5["topology"].shape[0]
    with h5py.File(out / "fields.h5", "r") as h5:
        return h5["/Mesh/mesh/geometry"].shape[0], h5["/Mesh/mesh/topology"].shape[0]


def run_reader(cmd: list[str], timeout: float = 300) -> dict:
    """A reader in its own process: its JSON line, or a failure with what it printed (a crash included)."""
    return run_readers([cmd], timeout)[0]


def run_readers(cmds: list[list[str]], timeout: float = 300) -> list[dict]:
    """Readers each in its own process, all at once (each mostly starts up: ParaView, VTK; the 2-rank phase
    runs one test at a time, so a second core would wait): their JSON lines, in order, or a failure with what
    the first failing one printed (a crash included)."""
    procs = [subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for cmd in cmds]
    found = []
    try:
        for cmd, p in zip(cmds, procs):
            stdout, stderr = p.communicate(timeout=timeout)
            assert p.returncode == 0, f"{cmd[:3]} exit {p.returncode}: {stderr[-1500:]}"
            found.append(json.loads([s for s in stdout.splitlines() if s.startswith("{")][-1]))
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
                p.communicate()
    return found


def paraview_cmd(out: Path, which: str) -> list[str]:
    return [PVPYTHON, str(HERE / "paraview_inspect.py"), str(out / "fields.xdmf"), which]


PYVISTA_MESHIO = """
import json, os, sys
os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkOSOpenGLRenderWindow")
import meshio, pyvista as pv
f = sys.argv[1]
r = pv.get_reader(f)
r.set_active_time_point(r.number_time_points - 1)
m = r.read()
out = {"pyvista": {"times": list(map(float, r.time_values)), "class": type(m).__name__, "points": m.n_points,
                   "cells": m.n_cells, "point_arrays": sorted(m.point_data.keys()),
                   "cell_arrays": sorted(m.cell_data.keys())}}
with meshio.xdmf.TimeSeriesReader(f) as ts:
    p, c = ts.read_points_cells()
    t, pd, cd = ts.read_data(ts.num_steps - 1)
    out["meshio"] = {"steps": ts.num_steps, "t": t, "points": len(p), "cells": sum(len(b.data) for b in c),
                     "point_arrays": sorted(pd), "cell_arrays": sorted(cd), "dtype": str(pd["displacement_m"].dtype)}
print(json.dumps(out))
"""


def pyvista_meshio_cmd(out: Path) -> list[str]:
    return [sys.executable, "-c", PYVISTA_MESHIO, str(out / "fields.xdmf")]


def same_times(found: list[float], times: list[float], running: bool) -> bool:
    """The reader's times are the file's (while the run goes on, the file may have grown since: the times
    read before are then the first ones the reader finds)."""
    if running:
        return len(found) >= len(times) and found[: len(times)] == pytest.approx(times, rel=1e-12, abs=0.0)
    return found == pytest.approx(times, rel=1e-12, abs=0.0)


def check_all_readers(out: Path, cell_fields=CELL_FIELDS, point_fields=POINT_FIELDS, running=False) -> dict:
    """Every reader finds one dataset per output time, the mesh's own counts, every field, the times."""
    n_points, n_cells = mesh_counts(out)
    times = xdmf_times(out)
    assert len(times) >= 2
    found = {}
    kinds = ("xdmf3", "legacy") if PVPYTHON is not None else ()
    *pvs, pm = run_readers([*(paraview_cmd(out, which) for which in kinds), pyvista_meshio_cmd(out)])
    for which, pv in zip(kinds, pvs):
        assert same_times(pv["times"], times, running), which
        for row in pv["rows"]:
            assert row["class"] == "vtkUnstructuredGrid", (which, row["class"])  # one dataset, not blocks
            assert (row["points"], row["cells"]) == (n_points, n_cells), which
            assert point_fields <= set(row["point_arrays"]) and cell_fields <= set(row["cell_arrays"]), which
            assert row["precision"] == "double"
        found[which] = pv
    p, m = pm["pyvista"], pm["meshio"]
    assert same_times(p["times"], times, running) and (p["points"], p["cells"]) == (n_points, n_cells)
    assert point_fields | cell_fields <= set(p["point_arrays"]) | set(p["cell_arrays"])
    assert m["steps"] >= len(times) if running else (m["steps"] == len(times) and m["t"] == times[-1])
    assert (m["points"], m["cells"]) == (n_points, n_cells) and m["dtype"] == "float64"
    assert point_fields <= set(m["point_arrays"]) and cell_fields <= set(m["cell_arrays"])
    return found


def last_history(out: Path) -> np.ndarray:
    return np.atleast_1d(np.genfromtxt(out / "history.csv", delimiter=",", names=True))[-1]


@pytest.mark.parametrize("name", ["serial", "ranks2"])
def test_every_reader_opens_a_finished_run_as_one_dataset_per_time(runs, name):
    """ParaView (both readers), pyvista and meshio; the von Mises range is the run's own, and the warped nose
    tip at the last time is where history.csv puts the nose (the fields' y is −depth)."""
    import h5py

    out = runs[name]
    found = check_all_readers(out, cell_fields=CELL_FIELDS | TENSOR_FIELDS)
    if not found:
        pytest.skip("ParaView's pvpython is not installed (the pyvista and meshio checks passed)")
    last = found["xdmf3"]["rows"][-1]
    with h5py.File(out / "fields.h5", "r") as h5:
        group = h5["/Function/von_mises_Pa"]
        key = min(group.keys(), key=lambda k: abs(float(k.replace("_", ".")) - last["t"]))
        vm = group[key][()]
    assert last["von_mises_range"] == pytest.approx([vm.min(), vm.max()], rel=1e-12)
    h = last_history(out)
    assert h["t_s"] == pytest.approx(last["t"], rel=1e-9)
    tip_mm = 1e3 * np.array(last["tip"])
    assert tip_mm[0] == pytest.approx(h["nose_x_mm"], abs=1e-6)
    assert -tip_mm[1] == pytest.approx(h["nose_y_mm"], abs=1e-6)


def principal_stresses(components: dict) -> np.ndarray:
    """Each cell's principal stresses (ascending, Pa) by numpy.linalg.eigvalsh of its six stress scalars."""
    m = np.zeros((len(components["xx"]), 3, 3))
    for c, v in components.items():
        i, j = "xyz".index(c[0]), "xyz".index(c[1])
        m[:, i, j] = m[:, j, i] = np.ravel(v)
    return np.linalg.eigvalsh(m)


def same_principal_stresses(found: list, components: dict) -> None:
    """ParaView's principal stresses are numpy's of the six scalars to float32's round-off (Tensor Glyph's
    eigenvalues are float32): 1e-6 of the largest; swapped components are off by a good part of it."""
    expected = principal_stresses(components)
    scale = np.abs(expected).max()
    assert scale > 1e8  # the nose is loaded
    got = np.array(found)
    assert got.shape == expected.shape
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-6 * scale)


@needs_paraview
@pytest.mark.parametrize("name", ["serial", "ranks2"])
def test_paraviews_tensor_filter_finds_the_principal_stresses_of_the_six_scalars(runs, name):
    """Issue 61: ParaView's own tensor filter (Cell Centers, then Tensor Glyph extracting the eigenvalues; no
    Calculator) on fields.xdmf's one stress attribute, stress_Pa, with both XDMF readers, at the last time, and on
    the stress maps' cut planes (stress_maps_end.vtu, six components XX YY ZZ XY YZ XZ): each cell's principal
    stresses are numpy.linalg.eigvalsh's of its six stress scalars."""
    import h5py
    import meshio

    out = runs[name]
    vtu = out / "stress_maps_end.vtu"
    *xdmf, cuts = run_readers([paraview_cmd(out, "xdmf3"), paraview_cmd(out, "legacy"),
                               [PVPYTHON, str(HERE / "paraview_inspect.py"), str(vtu), "vtu"]])
    for which, found in zip(("xdmf3", "legacy"), xdmf):
        row = found["rows"][-1]
        assert row["stress_components"] == 9, which  # the attribute is a Tensor of nine components
        with h5py.File(out / "fields.h5", "r") as h5:
            group = h5["/Function/stress_Pa"]
            key = min(group.keys(), key=lambda k: abs(float(k.replace("_", ".")) - row["t"]))
            components = {c: h5[f"/Function/stress_{c}_Pa/{key}"][()] for c in STRESS_COMPONENTS}
        same_principal_stresses(row["principal_stress_Pa"], components)
    assert cuts["stress_components"] == ["XX", "YY", "ZZ", "XY", "YZ", "XZ"]
    m = meshio.read(vtu)
    components = {c: np.concatenate(m.cell_data[f"stress_{c}_Pa"]) for c in STRESS_COMPONENTS}
    assert cuts["cells"] == len(components["xx"]) > 100
    same_principal_stresses(cuts["principal_stress_Pa"], components)


def test_a_charged_run_carries_both_cell_tags_and_the_interface_fields(runs):
    """Shell and charge in one dataset: cell_tag takes 1 and 2; the gap and slip of the interface on the
    points."""
    out = runs["charged"]
    check_all_readers(out, point_fields=POINT_FIELDS | {"interface_gap_m", "interface_slip_m"})
    code = ("import meshio, sys, numpy as np\n"
            "with meshio.xdmf.TimeSeriesReader(sys.argv[1]) as ts:\n"
            "    ts.read_points_cells(); t, pd, cd = ts.read_data(ts.num_steps - 1)\n"
            "print(sorted(set(np.concatenate(cd['cell_tag']).ravel().tolist())))")
    r = subprocess.run([sys.executable, "-c", code, str(out / "fields.xdmf")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-1000:]
    assert r.stdout.strip().splitlines()[-1] == "[1, 2]"
    # the cut planes of the stress maps open the same way: both planes, both bodies, the fields on them
    code = ("import json, sys, meshio, numpy as np, pyvista as pv\n"
            "g = pv.read(sys.argv[1]); m = meshio.read(sys.argv[1])\n"
            "tags = sorted(set(np.concatenate(m.cell_data['cell_tag']).tolist()))\n"
            "planes = sorted(set(np.asarray(g.cell_data['plane']).tolist()))\n"
            "n = sum(len(c.data) for c in m.cells)\n"
            "print(json.dumps({'r': [g.n_cells, n, tags, planes, sorted(g.array_names)]}))")
    for name in ("stress_maps_peak.vtu", "stress_maps_end.vtu", "stress_maps.vtu"):
        n_pv, n_meshio, tags, planes, arrays = run_reader([sys.executable, "-c", code, str(out / name)])["r"]
        assert n_pv == n_meshio > 100 and tags == [1, 2] and planes == [0, 1]
        assert {"von_mises_Pa", "peeq", "cell_tag"} <= set(arrays)


def test_every_reader_opens_a_running_and_then_a_killed_run(tmp_path):
    """While the run goes on, and after SIGKILL: every reader opens fields.xdmf up to its last complete
    output time (per-time files, no HDF5 external links in the readers' way)."""
    out = tmp_path / "run"
    cmd = [sys.executable, "-m", "fepen", "run", "--set", "mesh.size=0.006", "--set", "run.end_time=3e-3",
           "--set", "run.output_interval=1e-5", "--out", str(out)]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=ROOT)
    try:
        deadline = time.time() + 300
        while time.time() < deadline and proc.poll() is None:
            if (out / "fields.xdmf").is_file() and len(xdmf_times(out)) >= 3:
                break
            time.sleep(0.5)
        assert proc.poll() is None, "the run ended before it could be read while running"
        check_all_readers(out, running=True)
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    assert (out / "fields.d").is_dir() and not (out / "summary.json").exists()
    check_all_readers(out)  # killed


@needs_paraview
@pytest.mark.skipif(XVFB is None, reason="xvfb-run is not installed (apt-get install xvfb)")
def test_paraview_renders_the_run_warped_and_coloured(runs, tmp_path):
    """`fepen view DIR --png`: ParaView runs the run's view.py offscreen; the picture has the projectile in
    colour (many distinct colours, not one flat one)."""
    import matplotlib.image as mpimg

    png = tmp_path / "view.png"
    r = run_fepen("view", str(runs["serial"]), "--png", str(png))
    assert r.returncode == 0, r.stderr[-2000:]
    img = mpimg.imread(png)[..., :3]
    assert img.shape[0] >= 600 and img.shape[1] >= 900
    colours = np.unique((img.reshape(-1, 3) * 255).astype(np.uint8), axis=0)
    assert len(colours) > 200
    saturated = np.ptp(img, axis=2) > 0.4  # red, yellow, cyan, blue of the colour map, not the grey background
    assert saturated.mean() > 0.002


def test_the_pyvista_picture_of_the_api(runs, tmp_path):
    """Result.plot(png=...) (pyvista, offscreen) draws the warped, coloured projectile."""
    code = ("import sys, fepen\n"
            "fepen.load(sys.argv[1]).plot(png=sys.argv[2])")
    png = tmp_path / "pyvista.png"
    env = dict(os.environ, VTK_DEFAULT_OPENGL_WINDOW="vtkOSOpenGLRenderWindow")
    r = subprocess.run([sys.executable, "-c", code, str(runs["serial"]), str(png)], capture_output=True, text=True,
                       env=env)
    assert r.returncode == 0, r.stderr[-1500:]
    import matplotlib.image as mpimg

    img = mpimg.imread(png)[..., :3]
    assert (np.ptp(img, axis=2) > 0.4).mean() > 0.002


def test_the_mesh_files_open_in_every_reader(tmp_path):
    """`fepen mesh`: mesh.xdmf (the tetrahedra, cell_tag) and mesh_facets.xdmf (the tagged facets, facet_tag),
    one dataset each, for ParaView's two readers and meshio.read; their .vtu twins for pyvista; the counts
    those of mesh.json."""
    r = run_fepen("mesh", "--set", "mesh.size=0.005", "--out", str(tmp_path))
    assert r.returncode == 0, r.stderr[-1500:]
    info = json.loads((tmp_path / "mesh.json").read_text())
    code = ("import json, sys, meshio, pyvista as pv\n"
            "out = {}\n"
            "for f, name in (('mesh', 'cell_tag'), ('mesh_facets', 'facet_tag')):\n"
            "    m = meshio.read(sys.argv[1] + '/' + f + '.xdmf')\n"
            "    g = pv.read(sys.argv[1] + '/' + f + '.vtu')\n"
            "    tags = sorted(set(m.cell_data[name][0].ravel().tolist()))\n"
            "    out[f] = [len(m.points), sum(len(c.data) for c in m.cells), tags, g.n_points, g.n_cells]\n"
            "print(json.dumps(out))")
    pv_cmds, expected = [], []
    if PVPYTHON is not None:  # ParaView's two readers on both files, beside meshio and pyvista: all at once
        for f in ("mesh.xdmf", "mesh_facets.xdmf"):
            for reader in ("Xdmf3ReaderS(FileName=[f])", "XDMFReader(FileNames=[f])"):
                script = ("import json, sys\nfrom paraview import servermanager\nfrom paraview.simple import *\n"
                          f"f = sys.argv[1]\nr = {reader}\nr.UpdatePipeline()\nd = servermanager.Fetch(r)\n"
                          "print(json.dumps({'r': [d.GetClassName(), d.GetNumberOfPoints(), d.GetNumberOfCells()]}))")
                pv_cmds.append([PVPYTHON, "-c", script, str(tmp_path / f)])
                expected.append((f, reader))
    found, *pvs = run_readers([[sys.executable, "-c", code, str(tmp_path)], *pv_cmds])
    n, c = info["nodes"], info["cells"]
    assert found["mesh"] == [n, c, [1], n, c]
    assert found["mesh_facets"][0] == n and found["mesh_facets"][2] == [11, 12]
    assert found["mesh_facets"][1] == found["mesh_facets"][4] > 0
    cells = {"mesh.xdmf": c, "mesh_facets.xdmf": found["mesh_facets"][1]}
    for (f, reader), pv in zip(expected, pvs):
        assert pv["r"] == ["vtkUnstructuredGrid", n, cells[f]], (f, reader)
