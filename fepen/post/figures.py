"""Figures (PNG, off-screen). Imports of matplotlib and pyvista stay inside the functions."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from mpi4py import MPI

from fepen.data import shot
from fepen.geometry import mesh as fmesh
from fepen.geometry import tags


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
    plotter.screenshot(str(path))
    plotter.close()


def history_figure(out: Path, experiment: str | None = None, comm=MPI.COMM_WORLD) -> None:
    """history.png: force, trajectory (with the experiment's end points when a shot is named), energies."""
    if comm.rank != 0:
        return
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    data = np.genfromtxt(Path(out) / "history.csv", delimiter=",", names=True)
    data = np.atleast_1d(data)
    fig, ax = plt.subplots(1, 3, figsize=(14, 3.8))
    t = data["t_s"] * 1e6
    ax[0].plot(t, data["decel_g"] / 1e3)
    ax[0].set(xlabel="t (us)", ylabel="deceleration (1000 g)")
    ax[1].plot(data["nose_x_mm"], data["nose_y_mm"], label="nose tip")
    ax[1].plot(data["tail_x_mm"], data["tail_y_mm"], label="tail centre")
    name = experiment
    if name:
        s = shot(name)
        ax[1].plot([s.Hx_mm], [s.Hy_mm], "o", color="C0", label=f"{name} nose, test")
        ax[1].plot([s.Tx_mm], [s.Ty_mm], "s", color="C1", label=f"{name} tail, test")
    ax[1].invert_yaxis()
    ax[1].set(xlabel="x along the face (mm)", ylabel="depth (mm)", aspect="equal")
    ax[1].legend(fontsize=7)
    for k in ("kinetic_J", "internal_work_J", "plastic_J", "external_work_J"):
        ax[2].plot(t, data[k], label=k)
    ax[2].set(xlabel="t (us)", ylabel="energy (J)")
    ax[2].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(Path(out) / "history.png", dpi=110)
    plt.close(fig)
