"""Figures (PNG, off-screen). Imports of matplotlib and pyvista stay inside the functions.

Every matplotlib figure of fepen is drawn on its own ``matplotlib.figure.Figure`` with an explicit Agg canvas
(new_figure) and written by save_figure: fepen never imports matplotlib's state machine (plt) and never
changes the user's backend (a notebook's plots keep appearing after ``fepen.run``). Titles name the run by
its shot and fidelity (run_title: "C3 (584.3 m/s, 10.5°), plastic"), never by its results directory.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from mpi4py import MPI

from fepen.data import SHOTS, shot
from fepen.geometry import mesh as fmesh
from fepen.geometry import tags
from fepen.io import results


def pyvista():
    """pyvista set up for off-screen rendering with OSMesa (no X server needed)."""
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkOSOpenGLRenderWindow")
    import pyvista as pv

    pv.OFF_SCREEN = True
    return pv


def _gather_cells(pm: fmesh.ProjectileMesh):
    """All owned cells' node coordinates and volume tags, gathered on rank 0 (None elsewhere)."""
    comm = pm.mesh.comm
    p = fmesh.cell_points(pm.mesh)
    tag = np.full(len(p), tags.SHELL, dtype=np.int32)
    if pm.charge:
        tag[fmesh.owned_cells_tagged(pm, tags.CHARGE)] = tags.CHARGE
    parts = comm.gather((p, tag), root=0)
    if comm.rank != 0:
        return None
    return np.concatenate([q[0] for q in parts]), np.concatenate([q[1] for q in parts])


def mesh_picture(pm: fmesh.ProjectileMesh, path: Path, title: str = "") -> None:
    """Half-section of the projectile mesh (shell grey, charge orange), written on rank 0."""
    data = _gather_cells(pm)
    if pm.mesh.comm.rank != 0:
        return
    pv = pyvista()
    p, tag = data
    n = len(p)
    cells = np.hstack([np.full((n, 1), 4), np.arange(4 * n).reshape(n, 4)]).ravel()
    grid = pv.UnstructuredGrid(cells, np.full(n, pv.CellType.TETRA, dtype=np.uint8), p.reshape(-1, 3))
    grid.cell_data["body"] = tag
    centres = p.mean(axis=1)
    half = grid.extract_cells(np.flatnonzero(centres[:, 2] <= 0.0))
    plotter = pv.Plotter(off_screen=True, window_size=(1600, 500))
    plotter.set_background("white")
    colours = {tags.SHELL: "lightgrey", tags.CHARGE: "orange"}
    for t, colour in colours.items():
        part = half.extract_cells(np.flatnonzero(half.cell_data["body"] == t))
        if part.n_cells:
            plotter.add_mesh(part, color=colour, show_edges=True, edge_color="black", line_width=0.5)
    plotter.view_vector((0.0, 0.0, 1.0), viewup=(1.0, 0.0, 0.0))
    plotter.camera.zoom(1.6)
    if title:
        plotter.add_text(title, font_size=10, color="black")
    from fepen.atomic import replacing

    with replacing(path, ".png") as tmp:
        plotter.screenshot(str(tmp))
    plotter.close()


#: display names of the fidelities in titles
FIDELITY_NAMES = {"rigid": "rigid", "elastic": "elastic", "plastic": "plastic"}


def new_figure(figsize):
    """A matplotlib Figure on its own Agg canvas (no plt state machine, no global backend).

    Args:
        figsize: (width, height) in inches.

    Returns:
        The matplotlib.figure.Figure.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig, path, dpi: int = 110) -> Path:
    """Write fig as a PNG through a temporary file renamed over path (never a half-written picture).

    Args:
        fig: a Figure of new_figure. path: the PNG. dpi: its resolution.

    Returns:
        path.
    """
    from fepen.atomic import replacing
    from fepen.io.files import inject

    path = Path(path)
    with replacing(path, ".png") as tmp:
        fig.savefig(tmp, dpi=dpi, format="png")
        inject("figure")
    return path


def run_info(out) -> dict:
    """What a figure's title says of the run in a results directory, from its scene.toml (read_written_scene;
    else summary.json's scene); a value None when neither gives it.

    Args:
        out: the results directory.

    Returns:
        {"shot": impact.shot or None, "fidelity", "velocity_m_s", "obliquity_deg", "charge": bool,
        "yield_Pa": the shell's Johnson–Cook A (its static yield stress) or None, "steel": its name,
        "charge_yield_Pa": the charge's initial yield stress}.
    """
    flat = results.read(out).scene_keys()
    keys = {"shot": "impact.shot", "fidelity": "effects.fidelity", "velocity_m_s": "impact.velocity",
            "obliquity_deg": "impact.obliquity_deg", "charge": "effects.charge", "yield_Pa": "projectile.material.A",
            "steel": "projectile.material.name", "charge_yield_Pa": "charge.material.yield_stress"}
    info = {k: flat.get(v) for k, v in keys.items()}
    if info["shot"] in SHOTS and info["velocity_m_s"] is None:  # a scene.toml written by hand
        info["velocity_m_s"], info["obliquity_deg"] = SHOTS[info["shot"]].v0, SHOTS[info["shot"]].obliquity_deg
    return info


def run_title(out, what: str = "", shot: str | None = None) -> str:
    """A figure's title naming the run: "C3 (584.3 m/s, 10.5°), plastic: what", or "600 m/s at 10°, rigid:
    what" when no Table 1 shot is named; never the results directory.

    Args:
        out: the results directory (its scene.toml). what: the figure's subject. shot: the shot's name when
            the caller knows it (else the scene's impact.shot).

    Returns:
        The title.
    """
    info = run_info(out)
    shot = shot or info["shot"]
    v, ob = info["velocity_m_s"], info["obliquity_deg"]
    impact = f"{v:g} m/s, {ob:g}°" if v is not None and ob is not None else ""
    if shot:
        name = f"{shot} ({impact})" if impact else shot
    else:
        name = impact.replace(", ", " at ") if impact else "fepen run"
    fid = info["fidelity"]
    name += f", {FIDELITY_NAMES.get(fid, fid)}" if fid else ""
    name += ", charged" if info["charge"] else ""
    return f"{name}: {what}" if what else name


def depth_interval(out, summary: dict | None = None) -> dict | None:
    """The run's predicted depth interval, as its summary reports it (docs/uncertainty.md).

    Args:
        out: the results directory. summary: the run's summary when the caller has it (a run draws its figures
            before it writes summary.json); None: the directory's summary.json.

    Returns:
        {"low_mm", "high_mm", "levels": (the lower and upper probabilities)}, or None when the directory has no
        summary.json or the summary has no interval (a shot that did not stop, a target without public data).
    """
    summary = (summary if summary is not None else results.read(out).summary()) or {}
    bounds = summary.get("depth_interval_mm")
    if not bounds:
        return None
    levels = (summary.get("interval") or {}).get("levels") or (0.1, 0.9)
    return {"low_mm": float(bounds[0]), "high_mm": float(bounds[1]), "levels": tuple(levels)}


def interval_band(ax, interval: dict | None, label: bool = True):
    """The depth interval drawn across an axes whose y is the depth (mm): a shaded band from its low to its high
    end, with its probabilities in the legend's label.

    Args:
        ax: the axes. interval: depth_interval's dict, or None (nothing drawn). label: give the band a legend
            label.

    Returns:
        The band (matplotlib Polygon), or None.
    """
    if interval is None:
        return None
    lo, hi = interval["low_mm"], interval["high_mm"]
    p0, p1 = (round(100 * p) for p in interval["levels"])
    text = f"predicted depth, {p0}–{p1} %: {lo:.0f}–{hi:.0f} mm" if label else None
    return ax.axhspan(lo, hi, color="tab:purple", alpha=0.15, lw=0, zorder=0.5, label=text)


#: the attitude figure's history columns (fepen.io.columns.ATTITUDE): the axis in the plane of fire, the yaw
ATTITUDE_COLUMNS = ("axis_angle_deg", "yaw_deg")


def attitude_figure(out: Path, experiment: str | None = None, path: Path | None = None) -> Path | None:
    """attitude.png: the body's attitude over the time after impact (µs), from history.csv's attitude columns:
    the axis's angle from the target's normal in the plane of fire (``axis_angle_deg``, positive toward +x;
    the Table 1 test's final axis dashed) and the yaw, the angle between the axis and the velocity
    (``yaw_deg``). Drawn by whoever draws history.png (history_figure).

    Args:
        out: the results directory (history.csv, scene.toml). experiment: the Table 1 shot's name, or None
            (then the scene's impact.shot). path: where to write (default out/attitude.png).

    Returns:
        The PNG's path, or None when history.csv has no attitude columns (a run of an older fepen).
    """
    from fepen.io.columns import final_axis_deg

    out = Path(out)
    data = results.read(out).history()
    if not set(ATTITUDE_COLUMNS) <= set(data.dtype.names or ()):
        return None
    name = experiment or run_info(out)["shot"]
    s = shot(name) if name else None
    fig = new_figure((8.0, 6.4))
    axis, yaw = fig.subplots(2, 1, sharex=True)
    t = data["t_s"] * 1e6
    axis.plot(t, data["axis_angle_deg"], color="C0", label="simulated axis")
    if s is not None:
        final = float(final_axis_deg(s.Hx_mm, s.Hy_mm, s.Tx_mm, s.Ty_mm))
        axis.axhline(final, color="C0", ls="--", lw=1, label=f"{name} test: final axis {final:.1f}°")
    axis.set(ylabel="axis from the target's normal (°)", title="pitch: the axis in the plane of fire (+ toward +x)")
    axis.legend(fontsize=8, loc="best")
    yaw.plot(t, data["yaw_deg"], color="C3", label="yaw")
    yaw.set(xlabel="time after impact (µs)", ylabel="yaw (°)", title="yaw: the axis against the velocity (3-D)")
    for a in (axis, yaw):
        a.grid(alpha=0.3)
    line = f"final axis {data['axis_angle_deg'][-1]:.1f}°, final yaw {data['yaw_deg'][-1]:.1f}°"
    fig.suptitle(run_title(out, "attitude", name) + "\n" + line, fontsize=11)
    fig.tight_layout()
    return save_figure(fig, path or out / "attitude.png")


def _nonzero(values) -> bool:
    return bool(np.any(np.abs(np.nan_to_num(np.asarray(values, float))) > 0.0))


def _energies_panel(ax, data, t, tlabel: str) -> None:
    """history.png's energies: kinetic and given to the target (kJ), and on a right axis (J) the stored elastic
    energy and the plastic dissipation when not zero throughout (else named in the legend's title)."""
    ax.plot(t, data["kinetic_J"] / 1e3, label="kinetic")
    ax.plot(t, -data["external_work_J"] / 1e3, label="given to the target (−external work)")
    names = data.dtype.names
    zero, small = [], None
    for key, label, colour in (("elastic_J", "stored elastic", "C2"), ("plastic_J", "plastic dissipation", "C3")):
        if key in names and _nonzero(data[key]):
            small = small or ax.twinx()  # joules, beside the tens of kilojoules
            small.plot(t, data[key], "--", color=colour, lw=1, label=f"{label} (J, right axis)")
        elif key in names:
            zero.append(label)
    ax.set(xlabel=tlabel, ylabel="energy (kJ)", title="energies")
    handles, labels = ax.get_legend_handles_labels()
    if small is not None:
        small.set_ylabel("energy (J)")
        more = small.get_legend_handles_labels()
        handles, labels = handles + more[0], labels + more[1]
    (small or ax).legend(handles, labels, fontsize=7, loc="center right", framealpha=0.9,
                         title=("zero throughout: " + ", ".join(zero)) if zero else None, title_fontsize=7)


def history_figure(out: Path, experiment: str | None = None, comm=MPI.COMM_WORLD, summary: dict | None = None) -> None:
    """history.png (rank 0), four panels over the time after impact (µs): the nose and tail depths with the
    Table 1 test's final depths as horizontal lines; the target's deceleration; the path in the plane of
    incidence with the test's final nose and tail; the energies (kinetic, the energy given to the target,
    and the stored elastic energy and plastic dissipation when not zero throughout). The depth panels carry
    the predicted depth interval when summary.json reports one (interval_band). Then attitude.png
    (attitude_figure), so that every run that draws history.png draws its attitude too.

    Args:
        out: the results directory (history.csv, scene.toml). experiment: the Table 1 shot's name, or None
            (then the scene's impact.shot). comm: the run's communicator (only rank 0 draws). summary: the run's
            summary, for its depth interval, when the caller has it before summary.json is written (None: read
            summary.json, if any).
    """
    if comm.rank != 0:
        return
    out = Path(out)
    data = results.read(out).history()
    name = experiment or run_info(out)["shot"]
    s = shot(name) if name else None
    fig = new_figure((12.5, 8.0))
    ax = fig.subplots(2, 2).ravel()
    t = data["t_s"] * 1e6
    tlabel = "time after impact (µs)"
    # depths against time
    ax[0].plot(t, data["nose_y_mm"], color="C3", label="nose depth")
    ax[0].plot(t, data["tail_y_mm"], color="C0", label="tail depth")
    if s is not None:
        ax[0].axhline(s.Hy_mm, color="C3", ls="--", lw=1, label=f"{name} test: final nose depth {s.Hy_mm:g} mm")
        ax[0].axhline(s.Ty_mm, color="C0", ls="--", lw=1, label=f"{name} test: final tail depth {s.Ty_mm:g} mm")
    band = depth_interval(out, summary)
    interval_band(ax[0], band)
    ax[0].invert_yaxis()
    ax[0].set(xlabel=tlabel, ylabel="depth below the target face (mm)", title="depth")
    ax[0].legend(fontsize=7, loc="best")
    # deceleration
    ax[1].plot(t, data["decel_g"] / 1e3, color="k", lw=1, label="target deceleration along the axis")
    ax[1].set(xlabel=tlabel, ylabel="deceleration (1000 g)", title="deceleration (force / mass)")
    # path
    ax[2].plot(data["nose_x_mm"], data["nose_y_mm"], color="C3", label="nose tip")
    ax[2].plot(data["tail_x_mm"], data["tail_y_mm"], color="C0", label="tail centre")
    ax[2].plot([data["tail_x_mm"][-1], data["nose_x_mm"][-1]], [data["tail_y_mm"][-1], data["nose_y_mm"][-1]],
               "-", color="0.4", lw=3, alpha=0.6, label="final axis")
    if s is not None:
        ax[2].plot([s.Tx_mm, s.Hx_mm], [s.Ty_mm, s.Hy_mm], "k-", lw=1.5, label=f"{name} test: final axis")
        ax[2].plot([s.Hx_mm], [s.Hy_mm], "o", color="C3", mec="k", label=f"{name} test: nose")
        ax[2].plot([s.Tx_mm], [s.Ty_mm], "s", color="C0", mec="k", label=f"{name} test: tail")
    ax[2].axhline(0.0, color="saddlebrown", lw=1)
    interval_band(ax[2], band)
    ax[2].invert_yaxis()
    ax[2].set(xlabel="x along the target face (mm)", ylabel="depth below the target face (mm)",
              title="path in the plane of incidence (equal scales)")
    ax[2].set_aspect("equal", adjustable="datalim")
    ax[2].legend(fontsize=7, loc="best")
    _energies_panel(ax[3], data, t, tlabel)
    for a in ax:
        a.grid(alpha=0.3)
    depth = float(np.nanmax(data["nose_y_mm"]))
    line = f"final nose depth {data['nose_y_mm'][-1]:.1f} mm, deepest {depth:.1f} mm"
    if s is not None:
        line += f" (test {s.Hy_mm:g} mm: {100 * (data['nose_y_mm'][-1] / s.Hy_mm - 1):+.1f} %)"
    fig.suptitle(run_title(out, "history", name) + "\n" + line, fontsize=11)
    fig.tight_layout()
    save_figure(fig, out / "history.png")
    attitude_figure(out, name)
