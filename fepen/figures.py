"""Figures (PNG, off-screen). Imports of matplotlib and pyvista stay inside the functions."""

from __future__ import annotations

from pathlib import Path

import os

import numpy as np

from fepen import geometry, mesh as fmesh


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
    tag = np.full(len(p), geometry.SHELL, dtype=np.int32)
    if pm.charge:
        tag[fmesh.owned_cells_tagged(pm, geometry.CHARGE)] = geometry.CHARGE
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
    colours = {geometry.SHELL: "lightgrey", geometry.CHARGE: "orange"}
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
