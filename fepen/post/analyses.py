"""The paper's analyses of a deformable run (docs/paper.md §8), gathered on rank 0.

- Hazard map: the largest equivalent plastic strain of the surface cells (cells with a face on the outer
  surface) in axial bins along the projectile, from the nose (``hazard.csv``, ``hazard.png``).
- Strain gauges: four surface cells — top (+x), bottom (−x), two sides (±z) in the body frame, where x is
  the plane of incidence — at 1/3 L and 1/2 L from the nose; their axial logarithmic strain
  ln |F a0| (a0 the reference axis) over time (``strains.csv``). Bending shows as top/bottom ≫ sides.
- The deformed projectile, cut in the plane of incidence, coloured by PEEQ (``deformed.png``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from mpi4py import MPI

from fepen.geometry import tags
from fepen.geometry.cad import CadBody
from fepen.geometry.frames import unit_axis
from fepen.solver import probes

GAUGE_NAMES = ["top", "bottom", "side+", "side-"]
GAUGE_DIRECTIONS = np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]])


def surface_cells(pm, n_cells: int) -> np.ndarray:
    """Local indices of the owned cells having a face on the outer surface."""
    mesh = pm.mesh
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(tdim - 1, tdim)
    f2c = mesh.topology.connectivity(tdim - 1, tdim)
    cells = {int(f2c.links(f)[0]) for f in pm.facet_tags.find(tags.OUTER)}
    return np.array(sorted(c for c in cells if c < n_cells), dtype=np.int64)


def nearest_cell(centres: np.ndarray, candidates: np.ndarray, point: np.ndarray, comm) -> int:
    """The candidate cell whose centre is nearest to point, over all ranks (collective).

    Returns:
        Its local index on the one rank that owns it (ties: the lowest rank), -1 on the others.
    """
    if len(candidates):
        d = np.linalg.norm(centres[candidates] - point, axis=1)
        k = int(np.argmin(d))
        best = (float(d[k]), comm.rank)
    else:
        best, k = (np.inf, comm.rank), -1
    winner = comm.allreduce(best, op=MPI.MIN)
    return int(candidates[k]) if winner[1] == comm.rank else -1


class Gauges:
    """The eight strain-gauge cells and the surface cells of the hazard map of an ExplicitSolver.

    Args:
        solver: the ExplicitSolver. pm: its ProjectileMesh.
    """

    def __init__(self, solver, pm):
        self.solver, self.comm = solver, solver.comm
        L, a = pm.shape.length, pm.shape.radius
        self.surface = surface_cells(pm, solver.n_cells)
        centres = solver.X[solver.dofs].mean(axis=1)
        self.surface_y = centres[self.surface, 1]  # reference axial position from the nose
        self.targets = [(frac, name, np.array([0.0, frac * L, 0.0]) + a * d)
                        for frac in (1 / 3, 1 / 2) for name, d in zip(GAUGE_NAMES, GAUGE_DIRECTIONS)]
        self.cells = [nearest_cell(centres, self.surface, p, self.comm) for _, _, p in self.targets]
        self.columns = ["t_s"] + [f"{name}_{round(frac * 100)}pctL" for frac, name, _ in self.targets]
        self.rows = []

    def state(self) -> dict[str, np.ndarray]:
        """The rows so far (for checkpoints)."""
        return {"rows": np.array(self.rows, dtype=float)}

    def restore(self, state: dict) -> None:
        """Put back what state() returned."""
        self.rows = [list(r) for r in state["rows"]]

    def axial_strains(self) -> list[float]:
        """Axial logarithmic strain ln|F a0| of the gauge cells (a0 = reference axis), every rank."""
        s = self.solver
        x = s.positions()
        out = []
        for c in self.cells:
            val = 0.0
            if c >= 0:
                F = np.einsum("ai,aj->ij", x[s.dofs[c]], s.grad0[c])
                val = float(np.log(np.linalg.norm(F @ np.array([0.0, 1.0, 0.0]))))
            out.append(val)
        return list(self.comm.allreduce(np.array(out), op=MPI.SUM))

    def record(self) -> None:
        self.rows.append([self.solver.t, *self.axial_strains()])

    def hazard(self, bin_mm: float = 2.0):
        """(axial bin centres from the nose in mm, largest surface-cell PEEQ per bin) on rank 0, else None."""
        s = self.solver
        parts = self.comm.gather((self.surface_y, s.eps_p[self.surface]), root=0)
        if self.comm.rank:
            return None
        y = np.concatenate([p[0] for p in parts]) * 1e3
        e = np.concatenate([p[1] for p in parts])
        edges = np.arange(0.0, y.max() + bin_mm, bin_mm)
        idx = np.clip(np.digitize(y, edges) - 1, 0, len(edges) - 2)
        peak = np.zeros(len(edges) - 1)
        np.maximum.at(peak, idx, e)
        return 0.5 * (edges[1:] + edges[:-1]), peak

    def write(self, out: Path) -> None:
        """strains.csv, hazard.csv and hazard.png (rank 0)."""
        haz = self.hazard()
        if self.comm.rank:
            return
        out = Path(out)
        np.savetxt(out / "strains.csv", np.array(self.rows), delimiter=",", header=",".join(self.columns),
                   comments="", fmt="%.9g")
        np.savetxt(out / "hazard.csv", np.column_stack(haz), delimiter=",",
                   header="axial_from_nose_mm,max_surface_peeq", comments="", fmt="%.6g")
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(1, 2, figsize=(12, 3.8))
        ax[0].plot(*haz)
        ax[0].set(xlabel="distance from the nose (mm)", ylabel="max surface PEEQ", title="hazard map")
        d = np.array(self.rows)
        for k, name in enumerate(self.columns[1:]):
            ax[1].plot(d[:, 0] * 1e6, d[:, k + 1] * 1e3, label=name, ls="-" if "33" in name else "--")
        ax[1].set(xlabel="t (us)", ylabel="axial strain (1e-3)", title="surface cells at L/3 and L/2")
        ax[1].legend(fontsize=6, ncol=2)
        fig.tight_layout()
        fig.savefig(out / "hazard.png", dpi=110)
        plt.close(fig)


def deformed_picture(solver, path: Path, title: str = "") -> None:
    """Half of the deformed projectile (cells with z <= 0 in the body frame), coloured by PEEQ."""
    from fepen.post.figures import pyvista

    comm = solver.comm
    x = solver.positions()
    p = x[solver.dofs]
    centres0 = solver.X[solver.dofs].mean(axis=1)
    keep = (centres0[:, 2] <= 0.0) & (solver.mat >= 0)  # eroded cells are gone
    parts = comm.gather((p[keep], solver.eps_p[keep]), root=0)
    if comm.rank:
        return
    pts = np.concatenate([q[0] for q in parts])
    peeq = np.concatenate([q[1] for q in parts])
    pv = pyvista()
    n = len(pts)
    cells = np.hstack([np.full((n, 1), 4), np.arange(4 * n).reshape(n, 4)]).ravel()
    grid = pv.UnstructuredGrid(cells, np.full(n, pv.CellType.TETRA, dtype=np.uint8), pts.reshape(-1, 3) * 1e3)
    grid.cell_data["PEEQ"] = peeq
    plotter = pv.Plotter(off_screen=True, window_size=(1400, 700))
    plotter.set_background("white")
    # no scalar bar: VTK's bar formats its labels with std::regex, which crashes beside the libstdc++ that
    # dolfinx loads; the colour range is written as text instead
    hi = max(float(peeq.max()), 1e-12)
    plotter.add_mesh(grid, scalars="PEEQ", cmap="inferno", clim=(0.0, hi), show_edges=False,
                     show_scalar_bar=False)
    plotter.view_vector((0.0, 0.0, 1.0), viewup=(0.0, 1.0, 0.0))
    plotter.add_text(f"{title}\nPEEQ colour scale: black 0 ... yellow {hi:.3g}", font_size=10, color="black")
    plotter.screenshot(str(path))
    plotter.close()


#: axial bin of the nose profile (m)
PROFILE_BIN = 0.5e-3


def nose_profile(solver, shape, tip_node, tail_node, tri: np.ndarray, out: Path) -> dict | None:
    """nose_profile.csv and nose_profile.png: the nose's outer radius against the distance behind the
    original tip, before (the exact shape) and after (the largest radius of the final surface's nodes in
    each PROFILE_BIN, in the frame of the deformed axis: tail node to tip node), over the nose and one
    calibre behind it (collective; rank 0 writes).

    Args:
        solver: the ExplicitSolver. shape: the exact projectile (Shape; a CadBody, without an exact
            outside: the calibre over one calibre before).
        tip_node, tail_node: node handles of the nose tip and the tail centre (ExplicitSolver.node_at).
        tri: the surface's facets (node indices, fepen.solver.surface.Surface.tri). out: the results directory.

    Returns:
        {"tip_recession_mm", "max_radius_mm"} on every rank.
    """
    from fepen.io import files

    comm = solver.comm
    x = solver.positions()
    tip, tail = probes.node_value(solver, tip_node, x), probes.node_value(solver, tail_node, x)
    axis = unit_axis(tip, tail)  # tail to nose
    nodes = np.unique(tri)
    nodes = nodes[~solver.orphans[nodes]]
    rel = x[nodes] - tail
    along = rel @ axis
    behind = shape.length - along  # distance behind the original tip position
    radius = np.linalg.norm(rel - along[:, None] * axis, axis=1)
    parts = comm.gather((behind, radius), root=0)
    result = None
    if comm.rank == 0:
        behind = np.concatenate([p[0] for p in parts])
        radius = np.concatenate([p[1] for p in parts])
        cad = isinstance(shape, CadBody)
        reach = (0.0 if cad else shape.nose_length) + shape.diameter
        z0 = np.arange(0.0, reach + 1e-12, 0.25e-3)
        r0 = np.full(z0.shape, shape.radius) if cad else shape.outer_radius(z0)
        sel = behind <= reach
        k = np.floor(np.maximum(behind[sel], 0.0) / PROFILE_BIN).astype(int)
        r_after = np.zeros(k.max(initial=-1) + 1)
        np.maximum.at(r_after, k, radius[sel])
        z_after = (np.arange(len(r_after)) + 0.5) * PROFILE_BIN
        z_after, r_after = z_after[r_after > 0.0], r_after[r_after > 0.0]
        lines = ["state,behind_tip_mm,radius_mm"]
        lines += [f"before,{a * 1e3:.4f},{b * 1e3:.4f}" for a, b in zip(z0, r0)]
        lines += [f"after,{a * 1e3:.4f},{b * 1e3:.4f}" for a, b in zip(z_after, r_after)]
        files.write_text(Path(out) / "nose_profile.csv", "\n".join(lines) + "\n", MPI.COMM_SELF)
        result = {"tip_recession_mm": float(behind.min() * 1e3) if len(behind) else 0.0,
                  "max_radius_mm": float(radius[sel].max() * 1e3) if sel.any() else 0.0}
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(8, 3.2))
        for sign in (1, -1):
            ax.plot(z0 * 1e3, sign * r0 * 1e3, "k--", lw=1, label="before" if sign > 0 else None)
            ax.plot(z_after * 1e3, sign * r_after * 1e3, "C3", lw=1.5, label="after" if sign > 0 else None)
        ax.set(xlabel="distance behind the original tip (mm)", ylabel="radius (mm)", aspect="equal",
               title=f"nose profile: tip {result['tip_recession_mm']:.2f} mm behind, "
                     f"largest radius {result['max_radius_mm']:.2f} mm")
        ax.legend(loc="lower right", fontsize=8)
        fig.tight_layout()
        fig.savefig(Path(out) / "nose_profile.png", dpi=120)
        plt.close(fig)
    return comm.bcast(result, root=0)


class ChargeSections:
    """Axial and shear stress of the charge at points of three cross-sections and along the axis
    (docs/paper.md §7), recorded over time into ``charge_sections.csv``.

    Sections (reference axial position z from the nose tip): the charge's front face (its nose end, 0.5 mm
    inside), the nose/cylinder interface of the projectile (z = nose length; the charge's front when the
    cavity starts behind it), and half the charge length. On each, points at 0, 1/3, 2/3 and 0.9 of the
    local cavity radius in the plane of incidence (+x); along the axis, five points from front to rear.
    Each point is read from the charge cell whose reference centre is nearest. Axial stress σ_aa =
    a·σ·a with a the current axis (tail to nose); shear τ = a·σ·r with r the cell's current radial unit
    vector (Pa; compression negative).

    Args:
        solver: the ExplicitSolver. pm: its ProjectileMesh (with a charge). charge_material: its index.
    """

    def __init__(self, solver, pm, charge_material: int = 1):
        self.solver, self.comm = solver, solver.comm
        shape = pm.shape
        secs = shape.cavity_sections()
        z_front, z_rear = secs[0][0], secs[-1][1]

        def radius_at(z):
            return next((r for a, b, r in secs if a <= z <= b), secs[-1][2])

        self.points = []
        #: the three sections' reference distances behind the nose tip (m)
        self.sections = {"front": z_front + 5e-4, "nose_end": max(shape.nose_length, z_front + 5e-4),
                         "mid": 0.5 * (z_front + z_rear)}
        for label, z in self.sections.items():
            for frac in (0.0, 1 / 3, 2 / 3, 0.9):
                self.points.append((f"{label}_r{round(100 * frac)}", np.array([frac * radius_at(z), z, 0.0])))
        for k, z in enumerate(np.linspace(z_front + 5e-4, z_rear - 5e-4, 5)):
            self.points.append((f"axis{k}", np.array([0.0, z, 0.0])))
        centres = solver.X[solver.dofs].mean(axis=1)
        mine = np.flatnonzero(solver.mat == charge_material)
        self.cells = [nearest_cell(centres, mine, p, self.comm) for _, p in self.points]
        self.columns = ["t_s"] + [f"{n}_{q}_Pa" for n, _ in self.points for q in ("axial", "shear")]
        self.rows = []

    def state(self) -> dict[str, np.ndarray]:
        """The rows so far (for checkpoints)."""
        return {"rows": np.array(self.rows, dtype=float)}

    def restore(self, state: dict) -> None:
        """Put back what state() returned."""
        self.rows = [list(r) for r in state["rows"]]

    def record(self, tip: np.ndarray, tail: np.ndarray) -> None:
        """One row: the stresses at every point (collective); tip, tail: current nose tip and tail centre."""
        s = self.solver
        x = s.positions()
        axis = unit_axis(tip, tail)
        vals = np.zeros(2 * len(self.cells))
        for i, c in enumerate(self.cells):
            if c < 0:
                continue
            sd = s.s[c]
            pm = float(np.mean(s.nodal_p[s.dofs[c], s.mat[c]]))
            sig = np.array([[sd[0], sd[3], sd[5]], [sd[3], sd[1], sd[4]], [sd[5], sd[4], sd[2]]]) + pm * np.eye(3)
            centre = x[s.dofs[c]].mean(axis=0)
            r = (centre - tail) - ((centre - tail) @ axis) * axis  # from the axis line to the cell
            nr = np.linalg.norm(r)
            r = r / nr if nr > 1e-9 else np.cross(axis, [0.0, 0.0, 1.0])
            vals[2 * i] = axis @ sig @ axis
            vals[2 * i + 1] = axis @ sig @ r
        self.rows.append([s.t, *self.comm.allreduce(vals, op=MPI.SUM)])

    def write(self, out: Path) -> None:
        """charge_sections.csv (rank 0)."""
        if self.comm.rank == 0:
            np.savetxt(Path(out) / "charge_sections.csv", np.array(self.rows), delimiter=",",
                       header=",".join(self.columns), comments="", fmt="%.9g")
