"""fepen's figures: drawn on their own Figure with an Agg canvas, never through matplotlib's state machine,
so that a user's backend (a notebook's inline one) is the same after fepen drew; and what a report needs in
them: titles naming the shot and fidelity (never the results directory), time in µs, every axis with its
quantity and unit, labelled legends, the Table 1 test's values marked, and panels that show something when
no cell yields.

Every figure function is fed small synthetic results (a box "projectile" of Kuhn tetrahedra with a charge
inside, analytic histories), so the file needs no solver run.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[3]
L, A = 0.144, 0.0118  # the box projectile's length and half-width (m)


# ---- synthetic results ------------------------------------------------------------------------------------
def box_mesh(n=(4, 12, 4)):
    """Nodes and Kuhn tetrahedra of the box [-A, A] x [0, L] x [-A, A] (nose tip at the origin, axis +y)."""
    nx, ny, nz = n
    xs, ys, zs = np.linspace(-A, A, nx + 1), np.linspace(0.0, L, ny + 1), np.linspace(-A, A, nz + 1)
    X = np.array([[x, y, z] for x in xs for y in ys for z in zs])

    def node(i, j, k):
        return (i * (ny + 1) + j) * (nz + 1) + k

    kuhn = [(0, 1, 3, 7), (0, 1, 5, 7), (0, 2, 3, 7), (0, 2, 6, 7), (0, 4, 5, 7), (0, 4, 6, 7)]
    cells = []
    for i in range(nx):
        for j in range(ny):
            for k in range(nz):
                corner = [node(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1)) for c in range(8)]
                cells += [[corner[a] for a in t] for t in kuhn]
    return X, np.array(cells, dtype=np.int64)


def write_scene(out: Path, shot="C3", fidelity="plastic", charge=False) -> None:
    """scene.toml as a run writes it (fepen.scene.to_toml: given keys as values, the rest as comments)."""
    from fepen import scene as fscene

    sets = [f"effects.fidelity={fidelity}", f"effects.charge={str(charge).lower()}"]
    sets += [f"impact.shot={shot}"] if shot else []
    (out / "scene.toml").write_text(fscene.to_toml(fscene.Scene(None, sets)))


def write_history(out: Path, n=200) -> None:
    """An analytic shot: the nose decelerates uniformly to the C3 test's depth, the tail 144 mm behind it."""
    t = np.linspace(0.0, 1.2e-3, n)
    tau = t / t[-1]
    depth = 349.6 * (2 * tau - tau**2)
    cols = {"t_s": t, "nose_x_mm": 0.233 * depth, "nose_y_mm": depth, "tail_x_mm": 0.233 * depth - 26.0,
            "tail_y_mm": depth - 141.5, "decel_g": 5.0e4 * (1 - np.exp(-t / 5e-5)),
            "kinetic_J": 62648.0 * (1 - tau) ** 2, "internal_work_J": 10.0 * tau, "external_work_J":
            -62648.0 * (1 - (1 - tau) ** 2), "elastic_J": 10.0 * tau, "plastic_J": np.zeros(n)}
    np.savetxt(out / "history.csv", np.column_stack(list(cols.values())), delimiter=",",
               header=",".join(cols), comments="", fmt="%.9g")


def write_fields(out: Path, times=(2.0e-4, 6.0e-4, 1.2e-3), peeq=0.0) -> None:
    """fields.h5 as fepen's FieldWriter lays it out: the box moving down at an angle, a charge in its middle
    (cell_tag 2; the wall's nodes given twins), axial compression, PEEQ ``peeq`` in a few shell cells."""
    import h5py

    X, cells = box_mesh()
    centres = X[cells].mean(axis=1)
    charge = (np.abs(centres[:, 0]) < A / 2) & (np.abs(centres[:, 2]) < A / 2) & (centres[:, 1] > 0.04) \
        & (centres[:, 1] < 0.12)
    wall = np.flatnonzero((np.abs(X[:, 0]) == A / 2) & (X[:, 1] > 0.04) & (X[:, 1] < 0.12))
    Xall = np.vstack([X, X[wall]])  # the twins of the wall's nodes (fepen.mesh.split_wall)
    with h5py.File(out / "fields.h5", "w") as h5:
        h5["/Mesh/mesh/geometry"] = Xall
        h5["/Mesh/mesh/topology"] = cells
        for t in times:
            key = f"{t:.6g}".replace(".", "_")
            shift = np.array([0.06, -0.3, 0.0]) * t / times[-1]
            h5[f"/Function/displacement_m/{key}"] = np.tile(shift, (len(Xall), 1))
            h5[f"/Function/von_mises_Pa/{key}"] = (4e8 * (1 - centres[:, 1] / L) + 1e7)[:, None]
            h5[f"/Function/axial_stress_Pa/{key}"] = (-5e8 * (1 - centres[:, 1] / L) + 2e8 * centres[:, 0] / A)[:, None]
            p = np.zeros(len(cells))
            p[~charge & (centres[:, 1] > 0.06) & (centres[:, 1] < 0.08)] = peeq
            h5[f"/Function/peeq/{key}"] = p[:, None]
            h5[f"/Function/cell_tag/{key}"] = np.where(charge, 2.0, 1.0)[:, None]
            h5[f"/Function/interface_gap_m/{key}"] = (1e-5 * Xall[:, 1])[:, None]
            h5[f"/Function/interface_slip_m/{key}"] = (2e-5 * Xall[:, 1])[:, None]


def write_charge_csvs(out: Path, n=100) -> None:
    t = np.linspace(0.0, 1.2e-3, n)
    acc = {"t_s": t}
    for name in ("decel", "shell_acc", "charge_acc"):
        acc[f"{name}_g"] = 5e4 * np.sin(t / 1e-4) ** 2
        acc[f"{name}_filtered_g"] = 5e4 * np.sin(t / 1e-4) ** 2
    np.savetxt(out / "accelerations.csv", np.column_stack(list(acc.values())), delimiter=",",
               header=",".join(acc), comments="", fmt="%.9g")
    names = [f"{s}_r{r}" for s in ("front", "nose_end", "mid") for r in (0, 33, 67, 90)]
    names += [f"axis{k}" for k in range(5)]
    cols = ["t_s"] + [f"{n}_{q}_Pa" for n in names for q in ("axial", "shear")]
    data = np.column_stack([t] + [-1e7 * np.sin(t / 2e-4) * (1 + 0.1 * k) for k in range(len(cols) - 1)])
    np.savetxt(out / "charge_sections.csv", data, delimiter=",", header=",".join(cols), comments="", fmt="%.9g")


def make_runs(base: Path) -> dict:
    """Results directories of a rigid C3 run, a plastic C3 run with a charge (fields, no cell yielded) and a
    plastic run with no shot name whose shell yielded."""
    dirs = {"rigid": base / "run-rigid-dir", "charged": base / "run-charged-dir", "yielded": base / "run-yielded-dir"}
    for d in dirs.values():
        d.mkdir(parents=True)
        write_history(d)
    write_scene(dirs["rigid"], fidelity="rigid")
    write_scene(dirs["charged"], charge=True)
    write_fields(dirs["charged"])
    write_charge_csvs(dirs["charged"])
    write_scene(dirs["yielded"], shot=None)
    write_fields(dirs["yielded"], peeq=0.02)
    return dirs


def draw_all(base: Path) -> list[Path]:
    """Every matplotlib figure function of fepen on synthetic data under base; returns the PNGs written."""
    from mpi4py import MPI

    from fepen.data import shot
    from fepen.post import analyses, figures, paths, slices
    from fepen.studies import limits, sweep

    dirs = make_runs(base)
    written = []
    for d in dirs.values():
        figures.history_figure(d, None, MPI.COMM_SELF)
        written.append(d / "history.png")
    c, y = dirs["charged"], dirs["yielded"]
    y_mm = np.arange(1.0, 144.0, 2.0)
    rows = np.column_stack([np.linspace(0, 1.2e-3, 50)] + [np.full(50, -1e-3 * k) for k in range(1, 9)])
    gauges = ["t_s"] + [f"{n}_{p}pctL" for p in (33, 50) for n in ("top", "bottom", "side+", "side-")]
    written.append(analyses.hazard_figure(c, (y_mm, np.zeros_like(y_mm), 6e8 * np.exp(-((y_mm - 60) / 30) ** 2)),
                                          rows, gauges))
    written.append(analyses.hazard_figure(y, (y_mm, 0.02 * (np.abs(y_mm - 70) < 5), np.full_like(y_mm, 9.6e8)),
                                          rows, gauges))
    z = np.linspace(0.0, 0.08, 50)
    written.append(analyses.nose_profile_figure(c, (z, np.minimum(z, A)), (z, 0.99 * np.minimum(z, A)),
                                                {"tip_recession_mm": 0.1, "max_radius_mm": 11.9}))
    for d in (c, y):
        slices.stress_maps(d, d / "stress_maps_peak.png", 2e-4)
        slices.trajectory_figure(d, d / "trajectory.png", shot("C3") if d == c else None)
        written += [d / "stress_maps_peak.png", d / "trajectory.png"]
    slices.charge_report(c, {"front": 0.045, "mid": 0.08}, 6e-4)
    written += [c / n for n in ("charge_histories.png", "cross_sections.png", "interface.png")]
    # the studies: each picture drawn on its own Figure (fepen.post.study_figures)
    from fepen.post import study_figures as sf
    from fepen.post.figures import new_figure, save_figure

    def draw(name, size, fn, *args):
        fig = new_figure(size)
        fn(fig, *args)
        written.append(save_figure(fig, base / name))

    res = {"v_bl_m_s": 400.0, "tol_m_s": 2.0, "a": 0.9, "p": 2.0,
           "curve": [{"v_m_s": v, "residual_speed_m_s": limits.recht_ipson(v, 400.0, 0.9, 2.0).item()}
                     for v in (420.0, 450.0, 500.0)],
           "bisection": [{"v_m_s": 300.0, "outcome": "embedded", "residual_speed_m_s": 0.0},
                         {"v_m_s": 600.0, "outcome": "perforated", "residual_speed_m_s": 400.0}]}
    from fepen import scene as fscene

    sc = fscene.Scene(None, ["effects.fidelity=rigid", "target.thickness=0.3"])
    x = np.linspace(400.0, 600.0, 50)
    draw("ballistic_limit.png", (6.4, 4.6), sf.limit, res, limits.scene_line(sc),
         (x, limits.recht_ipson(x, 400.0, 0.9, 2.0)))
    rico = {"speeds_m_s": [300.0, 600.0], "critical_obliquity_deg": [60.0, 70.0], "tol_deg": 0.5,
            "map": [{"v_m_s": v, "obliquity_deg": o, "outcome": "ricochet" if o > 65 else "embedded"}
                    for v in (300.0, 600.0) for o in (0.0, 40.0, 80.0)]}
    draw("ricochet.png", (6.4, 4.8), sf.ricochet, rico, limits.scene_line(sc))
    draw("depth.png", (6.6, 6.4), sf.depth, {"table1": [{"depth": 0.3, "default": 0.31},
                                                        {"depth": 0.5, "default": 0.47}]})
    draw("pareto.png", (12, 5), sf.pareto, [{"process_s": 10.0, "nose_error": 0.05, "H_vs_finest": 0.02,
                                             "group": "mesh", "shot": "C3", "name": "h 4 mm"}])
    grid = sweep.Sweep("grid", {"effects.fidelity": "rigid"}, ["impact.velocity", "target.compressive_strength"],
                       [{"impact.velocity": v, "target.compressive_strength": f} for v in (500.0, 600.0)
                        for f in (3.5e7, 4.5e7)])
    srows = [{**s, "status": "ok", "outcome": "embedded", "depth_mm": 300.0 + 0.2 * (s["impact.velocity"] - 500),
              "fidelity": "rigid"} for s in grid.shots]
    sw = base / "sweep"
    sw.mkdir()
    mc = sweep.Sweep("monte-carlo", {"effects.fidelity": "rigid"}, ["impact.velocity"],
                     [{"impact.velocity": 584.3 + k} for k in range(-20, 21)])
    mrows = [{**s, "status": "ok", "outcome": "embedded", "depth_mm": 300.0 + s["impact.velocity"] / 10,
              "Hx_mm": 80.0 + s["impact.velocity"] / 100, "fidelity": "rigid"} for s in mc.shots]
    shots = sweep.Sweep("grid", {"effects.fidelity": "rigid"}, ["impact.shot"],
                        [{"impact.shot": n} for n in ("C1", "C7")])
    trows = [{**s, "status": "ok", "outcome": "embedded", "depth_mm": 300.0,
              "experiment.Hy_mm": shot(s["impact.shot"]).Hy_mm, "fidelity": "rigid"} for s in shots.shots]
    for name, (s, r) in {"grid": (grid, srows), "mc": (mc, mrows), "shots": (shots, trows)}.items():
        (sw / name).mkdir()
        written += sweep.draw(s, list(r[0]), r, sw / name)
    val = base / "validate"
    (val / "C1").mkdir(parents=True)
    write_history(val / "C1")
    written.append(paths.paths_figure({"rigid": val}, base / "paths.png", ["C1", "C3"]))
    return written


# ---- the user's matplotlib is left alone ---------------------------------------------------------------
def test_no_file_in_fepen_touches_the_global_matplotlib():
    """No matplotlib.use and no state machine (pyplot) anywhere in the package."""
    bad = [f"{p.relative_to(ROOT)}" for p in (ROOT / "fepen").rglob("*.py")
           if "matplotlib.use(" in p.read_text() or "pyplot" in p.read_text()]
    assert bad == []


def test_drawing_every_figure_keeps_the_backend_and_never_imports_pyplot(tmp_path):
    """In a fresh interpreter whose backend is svg (as a notebook's would be its inline one): after fepen drew
    every figure, the backend is still svg and matplotlib.pyplot was never imported; every PNG is a picture."""
    script = (
        "import sys, json; from pathlib import Path\n"
        f"sys.path.insert(0, {str(Path(__file__).parent)!r})\n"
        "import matplotlib\n"
        "before = matplotlib.get_backend()\n"
        "import test_figures\n"
        f"written = test_figures.draw_all(Path({str(tmp_path)!r}))\n"
        "pyplot = 'matplotlib.pyplot' in sys.modules\n"
        "print(json.dumps({'before': before, 'after': matplotlib.get_backend(), 'pyplot': pyplot,"
        " 'written': [str(p) for p in written]}))\n")
    env = {**os.environ, "MPLBACKEND": "svg", "PYTHONPATH": str(ROOT)}
    r = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    got = json.loads(r.stdout.strip().splitlines()[-1])
    assert got["before"] == got["after"] == "svg"
    assert got["pyplot"] is False
    assert len(got["written"]) >= 22
    for p in map(Path, got["written"]):
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and p.stat().st_size > 10_000, p


# ---- what the figures say ------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def drawn(tmp_path_factory):
    """Every figure drawn in this process, each Figure kept (save_figure wrapped) by its file name."""
    from fepen.post import figures

    base = tmp_path_factory.mktemp("figs")
    kept = {}
    save = figures.save_figure

    def keep(fig, path, dpi=110):
        kept[str(Path(path).relative_to(base))] = fig
        return save(fig, path, dpi)

    figures.save_figure = keep
    try:
        draw_all(base)
    finally:
        figures.save_figure = save
    return kept


def texts(fig) -> list[str]:
    """Every text of a figure: suptitle, titles, axis labels, legend entries and titles, free texts."""
    out = [fig._suptitle.get_text()] if fig._suptitle else []
    for ax in fig.axes:
        out += [ax.get_title(), ax.get_xlabel(), ax.get_ylabel(), *(t.get_text() for t in ax.texts)]
        leg = ax.get_legend()
        if leg is not None:
            out += [t.get_text() for t in leg.get_texts()] + [leg.get_title().get_text()]
    return [t for t in out if t]


def test_no_figure_names_the_results_directory_or_writes_us(drawn):
    for name, fig in drawn.items():
        for t in texts(fig):
            assert "-dir" not in t, (name, t)
            assert " us" not in t and "(us)" not in t, (name, t)


def test_every_data_axis_has_a_quantity_and_unit(drawn):
    """Each axes holding data has an x and a y label with a unit in parentheses (counts and names excepted);
    a twin axes shares the x label of its partner."""
    for name, fig in drawn.items():
        for ax in fig.axes:
            if ax.get_label() == "<colorbar>" or not (ax.lines or ax.collections or ax.patches):
                continue
            xl = ax.get_xlabel() or next((o.get_xlabel() for o in fig.axes if o is not ax and o.get_xlabel()
                                          and ax.get_shared_x_axes().joined(ax, o)), "")
            for label in (xl, ax.get_ylabel()):
                assert label, (name, ax.get_title())
                assert "(" in label or label in ("shots", "impact.shot"), (name, label)


def test_run_figures_name_the_shot_and_fidelity(drawn):
    for name, fig in drawn.items():
        title = " ".join([fig._suptitle.get_text() if fig._suptitle else ""] + [a.get_title() for a in fig.axes])
        if name.startswith("run-rigid"):
            assert "C3 (584.3 m/s, 10.5°), rigid" in title, name
        elif name.startswith("run-charged"):
            assert "C3 (584.3 m/s, 10.5°), plastic, charged" in title, name
        elif name.startswith("run-yielded"):
            assert "584.3 m/s at 10.5°, plastic" in title and "C3" not in title.split(":")[0], name


def test_history_marks_the_tests_final_depths(drawn):
    """history.png: time in µs, nose and tail depths with the C3 test's final depths as horizontal lines."""
    fig = drawn["run-rigid-dir/history.png"]
    depth = fig.axes[0]
    assert "µs" in depth.get_xlabel()
    legend = [t.get_text() for t in depth.get_legend().get_texts()]
    assert legend[:2] == ["nose depth", "tail depth"]
    assert "C3 test: final nose depth 349.6 mm" in legend
    flat = [ln.get_ydata()[0] for ln in depth.lines if len(set(np.asarray(ln.get_ydata(), float))) == 1]
    assert 349.6 in flat and 212.0 in flat
    assert "test 349.6 mm" in fig._suptitle.get_text()


def test_a_shot_that_stays_elastic_still_has_a_hazard_map(drawn):
    """No PEEQ anywhere: the hazard map is the peak von Mises stress against A (950 MPa for 45 steel), with
    the note; its peak 600 MPa is 63 % of A. Where a cell yielded, the PEEQ panel comes first."""
    elastic = drawn["run-charged-dir/hazard.png"]
    assert len(elastic.axes) == 2
    title = elastic.axes[0].get_title()
    assert title.startswith("elastic throughout: max PEEQ 0") and "= 63 % of A" in title
    assert any(np.allclose(ln.get_ydata(), 950.0) for ln in elastic.axes[0].lines)
    plastic = drawn["run-yielded-dir/hazard.png"]
    assert len(plastic.axes) == 3 and plastic.axes[0].get_ylabel().startswith("equivalent plastic strain")


def test_stress_maps_show_axial_stress_where_nothing_yielded(drawn):
    elastic = [a.get_title() for a in drawn["run-charged-dir/stress_maps_peak.png"].axes]
    assert sum("no cell has yielded (PEEQ 0)" in t for t in elastic) == 4  # both bodies, both planes
    assert any("% of its yield stress 950 MPa" in t for t in elastic)
    plastic = [a.get_title() for a in drawn["run-yielded-dir/stress_maps_peak.png"].axes]
    assert sum("PEEQ, max" in t for t in plastic) == 2


def test_sweep_plots_mark_the_measured_depths(drawn):
    """The base scene is C3's impact: a star at C3's speed and 40 MPa; a grid of named shots: each test's depth;
    the Monte Carlo histograms: C3's depth and nose x as lines."""
    grid = drawn["sweep/grid/sweep.png"]
    assert [a.get_xlabel() for a in grid.axes[:2]] == ["impact.velocity (m/s)", "target.compressive_strength (MPa)"]
    stars = [(ln.get_xdata()[0], ln.get_ydata()[0]) for a in grid.axes for ln in a.lines if ln.get_marker() == "*"]
    assert stars == [(584.3, 349.6), (40.0, 349.6)]
    shots = drawn["sweep/shots/sweep.png"].axes[0]
    rings = next(ln for ln in shots.lines if ln.get_label() == "Table 1 test (measured)")
    assert list(rings.get_ydata()) == [281.8, 590.2]
    hist = drawn["sweep/mc/histograms.png"]
    assert {ln.get_label() for a in hist.axes for ln in a.lines} >= {"C3 test: 349.6 mm", "C3 test: 81.4 mm"}
