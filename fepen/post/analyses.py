"""The paper's analyses of a deformable run (docs/paper.md §8), gathered on rank 0.

- Hazard map: the largest equivalent plastic strain of the surface cells (cells with a face on the outer
  surface) in axial bins along the projectile, from the nose, and the largest von Mises stress those cells
  reached at any history row; the same over every cell of the bin, inside included (``hazard.csv``,
  ``hazard.png``): where a shot yields, and how close to yielding an elastic one came.
- First yield: the history row at which the first cell's plastic strain left zero, and where that cell is
  (summary.json ``first_yield``).
- Strain gauges: four surface cells — top (+x), bottom (−x), two sides (±z) in the body frame, where x is
  the plane of incidence — at 1/3 L and 1/2 L from the nose; their axial logarithmic strain
  ln |F a0| (a0 the reference axis) over time (``strains.csv``). Bending shows as top/bottom ≫ sides.
- The deformed projectile, cut in the plane of incidence, coloured by PEEQ (``deformed.png``).
"""

from __future__ import annotations

import math
from pathlib import Path

import numba
import numpy as np
from mpi4py import MPI

from fepen.geometry import tags
from fepen.geometry.frames import unit_axis
from fepen.io import columns, table
from fepen.solver import diagnostics, probes

#: hazard.csv's columns (declared in fepen.io.columns with their units and meanings)
HAZARD_COLUMNS = columns.HAZARD.columns
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
        #: the largest von Mises stress of each owned cell at the history rows so far (Pa)
        self.peak_von_mises = np.zeros(solver.n_cells)
        #: the history-row time at which each owned cell first had plastic strain (s; inf: not yet)
        self.first_yield_t = np.full(solver.n_cells, np.inf)
        self.centres = centres[: solver.n_cells]

    def state(self) -> dict[str, np.ndarray]:
        """The rows so far and the cells' peak von Mises stress (for checkpoints)."""
        return {"rows": np.array(self.rows, dtype=float), "peak_von_mises_Pa": self.peak_von_mises.copy(),
                "first_yield_s": self.first_yield_t.copy()}

    def restore(self, state: dict) -> None:
        """Put back what state() returned (a checkpoint without the peaks keeps zeros)."""
        self.rows = [list(r) for r in state["rows"]]
        peak = state.get("peak_von_mises_Pa")
        if peak is not None and len(peak) == len(self.peak_von_mises):
            self.peak_von_mises = np.array(peak, dtype=float)
        first = state.get("first_yield_s")
        if first is not None and len(first) == len(self.first_yield_t):
            self.first_yield_t = np.array(first, dtype=float)

    def axial_strains(self) -> list[float]:
        """Axial logarithmic strain ln|F a0| of the gauge cells (a0 = reference axis), every rank."""
        s = self.solver
        x = s.positions()
        out = []
        for c in self.cells:
            val = 0.0
            if c >= 0:
                F = np.einsum("ai,aj->ij", x[s.dofs[c]], s.cell.grad0[c])
                val = float(np.log(np.linalg.norm(F @ np.array([0.0, 1.0, 0.0]))))
            out.append(val)
        return list(self.comm.allreduce(np.array(out), op=MPI.SUM))

    def record(self) -> None:
        """One gauge row, and every cell's von Mises stress into its peak (collective)."""
        s = self.solver
        self.rows.append([s.t, *self.axial_strains()])
        _peaks(np.ascontiguousarray(s.s.T), s.mat, s.eps_p, s.t, self.peak_von_mises, self.first_yield_t)

    def first_yield(self) -> dict | None:
        """Where and when the projectile first yielded (collective, the same on every rank): the earliest
        history row at which a cell had plastic strain, and that cell (ties: the one nearest the nose, then
        the lowest rank). None if no cell yielded.

        Returns:
            {"t_s", "axial_from_nose_mm", "radius_mm", "angle_deg" (about the axis from +x, the plane of
            incidence's windward side, toward +z), "surface" (the cell has a face on the outer surface)}.
        """
        t = self.first_yield_t
        if len(t) and np.isfinite(t.min()):
            k = int(np.lexsort((self.centres[:, 1], t))[0])
            mine = (float(t[k]), float(self.centres[k, 1]), self.comm.rank)
        else:
            k, mine = -1, (np.inf, np.inf, self.comm.rank)
        best = self.comm.allreduce(mine, op=MPI.MIN)
        if not np.isfinite(best[0]):
            return None
        info = None
        if best[2] == self.comm.rank:
            c = self.centres[k]
            info = {"t_s": best[0], "axial_from_nose_mm": float(c[1]) * 1e3,
                    "radius_mm": float(np.hypot(c[0], c[2])) * 1e3,
                    "angle_deg": float(np.degrees(np.arctan2(c[2], c[0]))),
                    "surface": bool(np.isin(k, self.surface))}
        return self.comm.bcast(info, root=best[2])

    def hazard(self, bin_mm: float = 2.0):
        """(axial bin centres from the nose (mm), largest surface-cell PEEQ per bin, largest surface-cell von
        Mises stress per bin over the history rows (Pa), the same two over every cell of the bin) on rank 0,
        else None (collective)."""
        s = self.solver
        n = s.n_cells
        parts = self.comm.gather((self.surface_y, s.eps_p[self.surface], self.peak_von_mises[self.surface],
                                  self.centres[:, 1], s.eps_p[:n], self.peak_von_mises), root=0)
        if self.comm.rank:
            return None
        y_all = np.concatenate([p[3] for p in parts]) * 1e3
        edges = np.arange(0.0, y_all.max() + bin_mm, bin_mm)
        out = [0.5 * (edges[1:] + edges[:-1])]
        for y_k, vals in ((0, (1, 2)), (3, (4, 5))):
            y = np.concatenate([p[y_k] for p in parts]) * 1e3
            idx = np.clip(np.digitize(y, edges) - 1, 0, len(edges) - 2)
            for j in vals:
                peak = np.zeros(len(edges) - 1)
                np.maximum.at(peak, idx, np.concatenate([p[j] for p in parts]))
                out.append(peak)
        return tuple(out)

    def write(self, out: Path, figures: bool = True):
        """strains.csv and hazard.csv (collective; rank 0 writes). Returns hazard.png's drawing, a callable
        any rank can run (the map sent to every rank), or None when figures is False."""
        haz = self.hazard()
        out = Path(out)
        if self.comm.rank == 0:
            table.write(out / "strains.csv", self.columns, self.rows)
            table.write(out / "hazard.csv", HAZARD_COLUMNS, np.column_stack(haz).tolist(), digits=6)
        if not figures:
            return None
        haz = self.comm.bcast(haz[:3] if self.comm.rank == 0 else None, root=0)
        rows, columns = np.array(self.rows), list(self.columns)  # the same rows on every rank
        return lambda: hazard_figure(out, haz, rows, columns)


def hazard_figure(out: Path, haz, rows: np.ndarray, columns: list[str]) -> Path:
    """hazard.png: where the projectile's surface yielded or came near it, and the strain gauges.

    Panels, along the projectile from the nose: the largest surface PEEQ (only when some cell yielded);
    the largest von Mises stress the surface cells reached at any history row (MPa), against the shell
    steel's static yield stress A (Johnson–Cook, a dashed line; right axis: σ_vm / A, the utilisation).
    Then the axial strain of the eight gauge cells over time (µs). A shot that stays elastic (C3) has no
    PEEQ to map: its first panel is the von Mises one, with the note "elastic throughout: max PEEQ 0" and
    the peak utilisation, which says how far from yielding the shell stayed and where it came closest.

    Args:
        out: the results directory (scene.toml for the title and A). haz: (bin centres (mm), largest PEEQ,
            largest von Mises stress (Pa)) per axial bin. rows: the gauge rows (t_s, then one strain per
            gauge). columns: their names ("t_s", "top_33pctL", ...).

    Returns:
        The PNG's path.
    """
    from fepen.post.figures import new_figure, run_info, run_title, save_figure

    y, peeq, vm = (np.asarray(a, float) for a in haz[:3])
    info = run_info(out)
    A = info["yield_Pa"]
    plastic = bool(np.any(peeq > 0.0))
    n = 3 if plastic else 2
    fig = new_figure((5.2 * n, 4.2))
    ax = list(fig.subplots(1, n))
    note = ""
    if plastic:
        a = ax.pop(0)
        a.plot(y, peeq, color="C3", label="largest PEEQ of the surface cells")
        a.set(xlabel="distance behind the nose tip (mm)", ylabel="equivalent plastic strain PEEQ (−)",
              title=f"plastic strain: max {peeq.max():.3g} at {y[np.argmax(peeq)]:.0f} mm")
        a.title.set_fontsize(9)
        a.grid(alpha=0.3)
    else:
        note = "elastic throughout: max PEEQ 0; "
    a = ax.pop(0)
    a.plot(y, vm / 1e6, color="C0", label="largest von Mises stress of the surface cells")
    k = int(np.argmax(vm)) if len(vm) else 0
    head = f"peak von Mises {vm.max() / 1e6:.0f} MPa at {y[k]:.0f} mm" if len(vm) else "no surface cells"
    if A:
        a.axhline(A / 1e6, color="k", ls="--", lw=1, label=f"static yield stress A = {A / 1e6:.0f} MPa"
                                                           f" ({info['steel'] or 'shell steel'})")
        sec = a.secondary_yaxis("right", functions=(lambda m, A=A: m * 1e6 / A, lambda u, A=A: u * A / 1e6))
        sec.set_ylabel("utilisation: von Mises / A (−)")
        if len(vm):
            head += f" = {100 * vm.max() / A:.0f} % of A"
        a.set_ylim(0.0, max(1.08 * A, 1.05 * vm.max(initial=0.0)) / 1e6)
    a.set(xlabel="distance behind the nose tip (mm)", ylabel="von Mises stress (MPa)", title=note + head)
    a.title.set_fontsize(9)
    a.legend(fontsize=7, loc="lower center")
    a.grid(alpha=0.3)
    a = ax.pop(0)
    if len(rows):
        for j, name in enumerate(columns[1:]):
            side, frac = name.rsplit("_", 1)
            a.plot(rows[:, 0] * 1e6, rows[:, j + 1] * 1e3, ls="-" if frac.startswith("33") else "--", lw=1,
                   label=f"{side}, {frac.replace('pctL', '')} % of L", color=f"C{j % 4}")
    a.set(xlabel="time after impact (µs)", ylabel="axial log strain (1e-3)",
          title="gauge cells on the surface at L/3 (—) and L/2 (--)")
    a.title.set_fontsize(9)
    a.legend(fontsize=6, ncol=2)
    a.grid(alpha=0.3)
    fig.suptitle(run_title(out, "hazard map along the projectile, and strain gauges"), fontsize=11)
    fig.tight_layout()
    return save_figure(fig, Path(out) / "hazard.png")


def deformed_picture(solver, path: Path, title: str = "", peak_von_mises: np.ndarray | None = None) -> None:
    """Half of the deformed projectile (cells with z <= 0 in the body frame, seen from +z: the cut face in the
    plane of incidence), coloured by PEEQ; when no cell yielded (PEEQ 0 everywhere) and the peaks are
    given, coloured instead by each cell's peak von Mises stress over the shot divided by the shell steel's
    static yield stress A (the utilisation: how close to yielding each part came), with the note "elastic
    throughout: max PEEQ 0". Collective; rank 0 writes.

    Args:
        solver: the ExplicitSolver. path: the PNG (its folder's scene.toml gives the title's run and A).
        title: a line under the run's name (time, max PEEQ). peak_von_mises: each owned cell's largest von
            Mises stress so far (Pa; Gauges.peak_von_mises), or None.
    """
    from fepen.post.figures import pyvista, run_info, run_title

    comm = solver.comm
    x = solver.positions()
    p = x[solver.dofs]
    centres0 = solver.X[solver.dofs].mean(axis=1)
    keep = (centres0[:, 2] <= 0.0) & (solver.mat >= 0)  # eroded cells are gone
    peak = np.zeros(len(keep)) if peak_von_mises is None else np.asarray(peak_von_mises)
    given = comm.allreduce(peak_von_mises is not None, op=MPI.LAND)
    parts = comm.gather((p[keep], solver.eps_p[keep], peak[keep], solver.mat[keep]), root=0)
    if comm.rank:
        return
    pts = np.concatenate([q[0] for q in parts])
    peeq = np.concatenate([q[1] for q in parts])
    vm = np.concatenate([q[2] for q in parts])
    mat = np.concatenate([q[3] for q in parts])
    A = run_info(Path(path).parent)["yield_Pa"]
    pv = pyvista()
    n = len(pts)
    cells = np.hstack([np.full((n, 1), 4), np.arange(4 * n).reshape(n, 4)]).ravel()
    grid = pv.UnstructuredGrid(cells, np.full(n, pv.CellType.TETRA, dtype=np.uint8), pts.reshape(-1, 3) * 1e3)
    plotter = pv.Plotter(off_screen=True, window_size=(1400, 700))
    plotter.set_background("white")
    # no scalar bar: VTK's bar formats its labels with std::regex, which crashes beside the libstdc++ that
    # dolfinx loads; the colour range is written as text instead
    if float(peeq.max(initial=0.0)) > 0.0 or not given or not A:
        grid.cell_data["PEEQ"] = peeq
        hi = max(float(peeq.max(initial=0.0)), 1e-12)
        plotter.add_mesh(grid, scalars="PEEQ", cmap="inferno", clim=(0.0, hi), show_edges=False,
                         show_scalar_bar=False)
        scale = f"PEEQ colour scale: black 0 ... yellow {hi:.3g}"
    else:
        shell = mat == 0
        util = np.where(shell, vm / A, 0.0)
        grid.cell_data["utilisation"] = util
        plotter.add_mesh(grid, scalars="utilisation", cmap="viridis", clim=(0.0, 1.0), show_edges=False,
                         show_scalar_bar=False)
        scale = (f"elastic throughout: max PEEQ 0. Colour: the shell's peak von Mises stress over the shot / its "
                 f"yield stress A = {A / 1e6:.0f} MPa,\ndark blue 0 ... yellow 1 (yield); largest "
                 f"{util.max(initial=0.0):.2f}")
    plotter.view_vector((0.0, 0.0, 1.0), viewup=(0.0, 1.0, 0.0))
    head = run_title(Path(path).parent, "the deformed projectile, cut in the plane of incidence")
    plotter.add_text("\n".join(t for t in (head, title, scale) if t), font_size=10, color="black")
    from fepen.atomic import replacing

    with replacing(path, ".png") as tmp:
        plotter.screenshot(str(tmp))
    plotter.close()


#: axial bin of the nose profile (m)
PROFILE_BIN = 0.5e-3


def nose_profile(solver, shape, tip_node, tail_node, tri: np.ndarray, out: Path, figures: bool = True) -> dict | None:
    """nose_profile.csv and nose_profile.png: the nose's outer radius against the distance behind the
    original tip, before (the exact shape) and after (the largest radius of the final surface's nodes in
    each PROFILE_BIN, in the frame of the deformed axis: tail node to tip node), over the nose and one
    calibre behind it (collective; rank 0 writes).

    Args:
        solver: the ExplicitSolver. shape: the exact projectile (Shape; a CadBody, without an exact
            outside: the calibre over one calibre before).
        tip_node, tail_node: node handles of the nose tip and the tail centre (ExplicitSolver.node_at).
        tri: the surface's facets (node indices, fepen.solver.surface.Surface.tri). out: the results directory.
        figures: False: nose_profile.csv alone (run.figures).

    Returns:
        {"tip_recession_mm", "max_radius_mm"} on every rank.
    """

    comm = solver.comm
    x = solver.positions()
    tip, tail = probes.node_value(solver, tip_node, x), probes.node_value(solver, tail_node, x)
    axis = unit_axis(tip, tail)  # tail to nose
    nodes = np.unique(tri)
    nodes = nodes[~solver.node.orphans[nodes]]
    rel = x[nodes] - tail
    along = rel @ axis
    behind = shape.length - along  # distance behind the original tip position
    radius = np.linalg.norm(rel - along[:, None] * axis, axis=1)
    parts = comm.gather((behind, radius), root=0)
    result = None
    if comm.rank == 0:
        behind = np.concatenate([p[0] for p in parts])
        radius = np.concatenate([p[1] for p in parts])
        reach = shape.nose_length + shape.diameter
        z0 = np.arange(0.0, reach + 1e-12, 0.25e-3)
        r0 = shape.outer_radius(z0)
        sel = behind <= reach
        k = np.floor(np.maximum(behind[sel], 0.0) / PROFILE_BIN).astype(int)
        r_after = np.zeros(k.max(initial=-1) + 1)
        np.maximum.at(r_after, k, radius[sel])
        z_after = (np.arange(len(r_after)) + 0.5) * PROFILE_BIN
        z_after, r_after = z_after[r_after > 0.0], r_after[r_after > 0.0]
        rows = [["before", a * 1e3, b * 1e3] for a, b in zip(z0, r0)]
        rows += [["after", a * 1e3, b * 1e3] for a, b in zip(z_after, r_after)]
        table.write(Path(out) / "nose_profile.csv", ["state", "behind_tip_mm", "radius_mm"], rows)
        result = {"tip_recession_mm": float(behind.min() * 1e3) if len(behind) else 0.0,
                  "max_radius_mm": float(radius[sel].max() * 1e3) if sel.any() else 0.0}
        if figures:
            nose_profile_figure(out, (z0, r0), (z_after, r_after), result)
    return comm.bcast(result, root=0)


def nose_profile_figure(out: Path, before, after, result: dict) -> Path:
    """nose_profile.png: the nose's outline before and after (both sides of the axis, equal scales).

    Args:
        out: the results directory. before, after: (distance behind the original tip (m), radius (m)) arrays
            of the drawn shape and of the final surface. result: {"tip_recession_mm", "max_radius_mm"}.

    Returns:
        The PNG's path.
    """
    from fepen.post.figures import new_figure, run_title, save_figure

    (z0, r0), (z_after, r_after) = before, after
    fig = new_figure((8, 3.6))
    ax = fig.subplots()
    for sign in (1, -1):
        ax.plot(np.asarray(z0) * 1e3, sign * np.asarray(r0) * 1e3, "k--", lw=1,
                label="before (the drawn shape)" if sign > 0 else None)
        ax.plot(np.asarray(z_after) * 1e3, sign * np.asarray(r_after) * 1e3, "C3", lw=1.5,
                label="after (largest radius of the final surface)" if sign > 0 else None)
    ax.set(xlabel="distance behind the original nose tip (mm)", ylabel="radius from the axis (mm)", aspect="equal")
    ax.set_title(f"nose tip {result['tip_recession_mm']:.2f} mm behind where it was, largest radius "
                 f"{result['max_radius_mm']:.2f} mm", fontsize=9)
    fig.suptitle(run_title(out, "nose profile"), fontsize=10)
    ax.legend(loc="lower right", fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return save_figure(fig, Path(out) / "nose_profile.png", dpi=120)


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
            table.write(Path(out) / "charge_sections.csv", self.columns, self.rows)


@numba.njit(cache=True)
def _peaks(sT, mat, eps_p, t, peak, first):
    """Each owned cell's von Mises stress (diagnostics.von_mises: the same products, in the same order) into its
    peak (NaN kept, as numpy.maximum keeps it; an eroded cell's stress is gone, its peak kept), and the time t
    into first where the cell has plastic strain for the first time."""
    for e in range(len(peak)):
        vm = 0.0
        if mat[e] >= 0:
            vm = math.sqrt(1.5 * diagnostics.deviator_square(sT, e))
        p = peak[e]
        if p != p or vm != vm:
            peak[e] = np.nan
        elif vm > p:
            peak[e] = vm
        if eps_p[e] > 0.0 and math.isinf(first[e]):
            first[e] = t
