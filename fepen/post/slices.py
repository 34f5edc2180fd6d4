"""Plane cuts of a tetrahedral mesh and the charged projectile's pictures made from a run's files
(fields.h5, accelerations.csv, charge_sections.csv): stress maps of shell and charge in the x–y and y–z
planes, strain contours over the charge's cross-sections, the interface's gap and slip along the wall,
and the acceleration and section-stress histories.

Everything here reads the results directory on one process (rank 0 of a run, or a script afterwards) and
needs no dolfinx. Maps are cut from the deformed mesh (reference geometry + displacement) by planes through
the current axis: the plane of incidence (x–y: normal z) and the
plane at right angles to it containing the axis (y–z in the body frame). Cross-sections are material
sections: cut from the reference mesh at a reference axial position, coloured by the current state.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from fepen.geometry.frames import unit_axis

#: the tetrahedron's six edges
_EDGES = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))


def cut(points: np.ndarray, normal, offset: float, basis: np.ndarray):
    """The polygons in which the plane n·x = offset cuts tetrahedra.

    A vertex on the plane counts as on its positive side, so that a face lying in the plane is returned
    once (by the cell behind it).

    Args:
        points: (n, 4, 3) vertex coordinates.
        normal: (3,) unit normal of the plane; offset: its value of n·x.
        basis: (2, 3) orthonormal in-plane directions for the 2-D coordinates.

    Returns:
        (list of (k, 2) polygons, k = 3 or 4, in-plane coordinates, ordered around their centroid;
        int array of the cell each came from).
    """
    d = points @ np.asarray(normal, dtype=float) - offset
    neg = d < 0.0
    crossing = np.flatnonzero(neg.any(axis=1) & (~neg).any(axis=1))
    if not len(crossing):
        return [], np.zeros(0, dtype=np.int64)
    p, s, below = points[crossing], d[crossing], neg[crossing]
    i, j = np.array(_EDGES).T
    hit = below[:, i] != below[:, j]  # (k, 6): the edges the plane crosses (3 or 4 of each cell)
    si, sj = s[:, i], s[:, j]
    w = np.divide(si, si - sj, out=np.zeros_like(si), where=hit)
    q = (p[:, i] + w[..., None] * (p[:, j] - p[:, i])) @ basis.T  # (k, 6, 2)
    centre = (q * hit[..., None]).sum(axis=1) / hit.sum(axis=1)[:, None]
    angle = np.where(hit, np.arctan2(q[..., 1] - centre[:, 1:], q[..., 0] - centre[:, :1]), np.inf)
    order = np.argsort(angle, axis=1, kind="stable")  # the crossed edges first, around the centroid
    q = np.take_along_axis(q, order[..., None], axis=1)
    valid = np.take_along_axis(hit, order, axis=1)
    # duplicate points (a vertex on the plane is met by up to three edges): dropped after the first
    keep = valid.copy()
    keep[:, 1:] &= np.linalg.norm(np.diff(q, axis=1), axis=2) > 1e-15
    count = keep.sum(axis=1)
    polys = np.split(q[keep], np.cumsum(count)[:-1])
    good = np.flatnonzero(count >= 3)
    return [polys[k] for k in good], crossing[good].astype(np.int64)


def polygon_area(q: np.ndarray) -> float:
    """Area of a planar polygon given in order (shoelace)."""
    x, y = q[:, 0], q[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


# ---- reading a run -----------------------------------------------------------------------------------
def read_state(out: Path, time: float | None = None) -> dict:
    """The mesh and fields of fields.h5 at the output time nearest ``time`` (the last if None).

    Returns:
        dict: X (reference nodes), cells, t, and every field at that time (nodal (n, 3) or (n,), cell (n,)).
    """
    import h5py

    with h5py.File(Path(out) / "fields.h5", "r") as h5:
        X = h5["/Mesh/mesh/geometry"][()]
        cells = h5["/Mesh/mesh/topology"][()].astype(np.int64)
        names = list(h5["/Function"].keys())
        keys = list(h5[f"/Function/{names[0]}"].keys())
        times = np.array([float(k.replace("_", ".")) for k in keys])
        k = int(np.argmax(times)) if time is None else int(np.argmin(np.abs(times - time)))
        state = {"X": X, "cells": cells, "t": float(times[k])}
        for name in names:
            v = h5[f"/Function/{name}/{keys[k]}"][()]
            state[name] = v[:, 0] if v.ndim == 2 and v.shape[1] == 1 else v
    return state


def output_times(out: Path) -> np.ndarray:
    """The output times of fields.h5 (s), ascending."""
    import h5py

    with h5py.File(Path(out) / "fields.h5", "r") as h5:
        name = next(iter(h5["/Function"].keys()))
        return np.sort([float(k.replace("_", ".")) for k in h5[f"/Function/{name}"].keys()])


def _axis_frame(state: dict):
    """Current nose tip, unit axis (tail to nose) and the two map planes' (normal, basis)."""
    X, x = state["X"], state["X"] + state["displacement_m"]
    tip = x[np.argmin(np.linalg.norm(X, axis=1))]
    L = X[:, 1].max()
    tail = x[np.argmin(np.linalg.norm(X - [0.0, L, 0.0], axis=1))]
    axis = unit_axis(tip, tail)
    ez = np.array([0.0, 0.0, 1.0])
    lateral = np.cross(ez, axis)  # in the plane of incidence, across the axis
    lateral /= np.linalg.norm(lateral)
    back = -axis  # from the nose tip towards the tail
    planes = {"x-y (plane of incidence)": (ez, np.array([back, lateral])),
              "y-z (across it, through the axis)": (lateral, np.array([back, ez]))}
    return tip, axis, planes


def _strain_axial(X, x, cells) -> np.ndarray:
    """Axial logarithmic strain ln|F e_y| per cell (e_y the reference axis)."""
    P0, P = X[cells], x[cells]
    D0 = np.stack([P0[:, k] - P0[:, 0] for k in (1, 2, 3)], axis=2)
    D = np.stack([P[:, k] - P[:, 0] for k in (1, 2, 3)], axis=2)
    F = D @ np.linalg.inv(D0)
    return np.log(np.linalg.norm(F[:, :, 1], axis=1))


# ---- figures -----------------------------------------------------------------------------------------
def stress_maps(out: Path, path: Path, time: float | None = None, figures: bool = True) -> dict:
    """Equivalent stress and PEEQ of shell and charge in the x–y and y–z planes, one figure; and the same
    cuts as data, ``path`` with the suffix .vtu (write_cut_planes), for ParaView, pyvista and meshio.

    A body with no plastic strain anywhere at that time (PEEQ 0 in every cell: C3's shell at 2.5 mm stays
    elastic) has nothing to show in a PEEQ panel: its second panel shows the axial stress instead (MPa,
    tension red, compression blue: the load path and the bending across the axis), titled "no cell has
    yielded (PEEQ 0)". PEEQ panels share one colour scale, the body's largest PEEQ anywhere. The von
    Mises panels' titles give the largest value and its fraction of the body's initial yield stress (the
    shell steel's Johnson–Cook A, the charge's yield stress).

    figures: False: the .vtu and the returned figures only, no picture (run.figures).

    Returns:
        {"t_s", plane: {body: {"von_mises_max_Pa", "peeq_max", and where each is, "..._at_mm": [behind the
        nose tip along the axis, across it]}}}.
    """
    from fepen.post.figures import new_figure, run_info, run_title, save_figure

    st = read_state(out, time)
    x = st["X"] + st["displacement_m"]
    tip, _, planes = _axis_frame(st)
    body = st.get("cell_tag", np.ones(len(st["cells"])))
    info = run_info(out)
    bodies = [(1.0, "shell", info["yield_Pa"]), (2.0, "charge", info["charge_yield_Pa"])] if np.any(body == 2.0) \
        else [(1.0, "projectile", info["yield_Pa"])]
    # the second panel of each body: PEEQ where some cell yielded, else its axial stress
    second, peeq_top = {}, {}
    for value, bname, _ in bodies:
        mine = body == value
        peeq_top[bname] = float(st["peeq"][mine].max()) if "peeq" in st and mine.any() else 0.0
        second[bname] = "peeq" if peeq_top[bname] > 0.0 or "axial_stress_Pa" not in st else "axial_stress_Pa"
    ncol = 2 * len(bodies)
    fig = new_figure((2.7 * ncol + 1, 9.5)) if figures else None
    axes = fig.subplots(len(planes), ncol, squeeze=False) if figures else None
    report = {}
    write_cut_planes(st, x, tip, planes, Path(path).with_suffix(".vtu"))
    for r, (pname, (normal, basis)) in enumerate(planes.items()):
        polys, cells = cut(x[st["cells"]], normal, float(normal @ tip), basis)
        polys = [(q - tip @ basis.T) * 1e3 for q in polys]
        report[pname] = {}
        for value, bname, _ in bodies:
            mine = body[cells] == value
            mine_polys = [q for q, m in zip(polys, mine) if m]
            entry = report[pname].setdefault(bname, {}) if mine.any() else {}
            for name, scale, key in (("von_mises_Pa", 1e-6, "von_mises_max_Pa"), ("peeq", 1.0, "peeq_max")):
                if name in st and mine.any():
                    vals = st[name][cells[mine]] * scale
                    k = int(np.argmax(vals))
                    entry[key] = float(vals[k] / scale)
                    entry[key.replace("_Pa", "") + "_at_mm"] = [float(v) for v in mine_polys[k].mean(axis=0)]
        col = 0
        for quantity in ("von_mises_Pa", "second") if figures else ():
            for value, bname, yield_Pa in bodies:
                name = second[bname] if quantity == "second" else quantity
                _map_panel(fig, axes[r, col], polys, body[cells] == value, st[name][cells[body[cells] == value]],
                           name, bname, yield_Pa, peeq_top[bname])
                axes[r, col].set_ylabel((f"{pname}\n" if col == 0 else "") + "behind the nose tip, along the axis "
                                        "(mm)", fontsize=8 if col == 0 else 7)
                col += 1
    if not figures:
        return {"t_s": st["t"], **report}
    when = f"t = {st['t'] * 1e6:.0f} µs after impact"
    fig.suptitle(run_title(out, f"stress maps at {when}") + "\n(cuts through the deformed projectile's axis; "
                 "grey: the other body)", fontsize=10)
    fig.tight_layout()
    save_figure(fig, path)
    return {"t_s": st["t"], **report}


def _map_panel(fig, ax, polys, mine, values, name: str, bname: str, yield_Pa, peeq_top: float) -> None:
    """One panel of stress_maps: a body's cut polygons coloured by one field (the other body grey).

    Args:
        fig, ax: the figure and its axes. polys: the cut polygons (mm, along the axis and across it).
        mine: which polygons are this body's. values: the field on them (SI). name: the field
        ("von_mises_Pa", "peeq" or "axial_stress_Pa"). bname: the body's name. yield_Pa: its initial yield
        stress (None: unknown). peeq_top: its largest PEEQ anywhere (the PEEQ colour scale).
    """
    from matplotlib.collections import PolyCollection

    others = [q for q, m in zip(polys, mine) if not m]
    ax.add_collection(PolyCollection([q[:, ::-1] for q in others], facecolors="0.85", edgecolors="none"))
    vals = np.asarray(values, float) * (1.0 if name == "peeq" else 1e-6)
    cmap = {"von_mises_Pa": "viridis", "peeq": "inferno", "axial_stress_Pa": "coolwarm"}[name]
    pc = PolyCollection([q[:, ::-1] for q, m in zip(polys, mine) if m], array=vals, cmap=cmap,
                        edgecolors="face", linewidths=0.2)
    top = float(np.abs(vals).max()) if len(vals) else 0.0
    if name == "peeq":  # one scale for both planes: the body's largest PEEQ anywhere
        pc.set_clim(0.0, max(peeq_top, 1e-9))
        label = "PEEQ (−)"
        title = f"{bname}: PEEQ, max {top:.3g} in this cut\n({peeq_top:.3g} anywhere)"
    elif name == "axial_stress_Pa":  # the scale of 99 % of the cells: one hot cell hides nothing
        lim = max(float(np.percentile(np.abs(vals), 99)) if len(vals) else 0.0, 1e-6)
        pc.set_clim(-lim, lim)
        label = "axial stress (MPa)"
        span = f" {round(vals.min()) + 0} to {round(vals.max()) + 0} MPa" if len(vals) else ""  # no "-0"
        title = f"{bname}: no cell has yielded (PEEQ 0):\naxial stress{span}, tension > 0"
    else:
        label = "von Mises stress (MPa)"
        title = f"{bname}: von Mises stress, max {top:.0f} MPa"
        if yield_Pa and len(vals):
            title += f"\n= {100 * top * 1e6 / yield_Pa:.0f} % of its yield stress {yield_Pa / 1e6:.0f} MPa"
    ax.add_collection(pc)
    extend = "both" if name == "axial_stress_Pa" and len(vals) and top > pc.get_clim()[1] else "neither"
    bar = fig.colorbar(pc, ax=ax, fraction=0.08, pad=0.02, format="%.3g", extend=extend)
    bar.set_label(label, fontsize=7)
    bar.ax.tick_params(labelsize=7)
    ax.set_title(title, fontsize=8)
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.invert_yaxis()
    ax.tick_params(labelsize=7)
    ax.set_xlabel("across the axis (mm)", fontsize=7)


def write_cut_planes(st: dict, x: np.ndarray, tip: np.ndarray, planes: dict, path: Path) -> None:
    """The stress maps' two cuts through the deformed projectile as one unstructured grid of polygons in
    the target's frame (m): triangles and quads with every cell field of the state, ``cell_tag`` and
    ``plane`` (0 the x–y plane of incidence, 1 the y–z plane across it); VTK XML, which ParaView, pyvista
    and meshio open."""
    from fepen.io.vtu import write_vtu

    points, blocks, data = [], {3: [], 4: []}, {3: [], 4: []}
    names = [k for k, v in st.items() if isinstance(v, np.ndarray) and v.shape == (len(st["cells"]),)]
    n = 0
    for k, (normal, basis) in enumerate(planes.values()):
        off = float(normal @ tip)
        polys, cells = cut(x[st["cells"]], normal, off, basis)
        for q, c in zip(polys, cells):
            if len(q) not in blocks:
                continue
            points.append(q @ basis + off * np.asarray(normal))
            blocks[len(q)].append(np.arange(n, n + len(q)))
            data[len(q)].append([float(st[m][c]) for m in names] + [float(k)])
            n += len(q)
    kinds = [(3, "triangle"), (4, "quad")]
    cells_out = [(kind, np.array(blocks[m], dtype=np.int64).reshape(-1, m)) for m, kind in kinds]
    values = {m: np.array(data[m], dtype=float).reshape(-1, len(names) + 1) for m, _ in kinds}
    cell_data = {name: [values[m][:, i] for m, _ in kinds] for i, name in enumerate([*names, "plane"])}
    for key in ("cell_tag", "plane"):
        if key in cell_data:
            cell_data[key] = [v.astype(np.int32) for v in cell_data[key]]
    write_vtu(path, np.concatenate(points) if points else np.zeros((0, 3)), cells_out, cell_data)


def _one_path(polys: list):
    """The cut's polygons (the cells' sections: they tile the outline without overlapping) as one compound
    matplotlib Path: one filled shape, drawn without seams between its cells, and one path, not thousands, for
    the legend's search of an empty corner (matplotlib 3.11 tests every path of a collection)."""
    from matplotlib.path import Path as MplPath

    if not polys:
        return MplPath(np.zeros((0, 2)))
    verts = np.concatenate([np.vstack([q, q[:1]]) for q in polys])
    codes = np.concatenate([[MplPath.MOVETO] + [MplPath.LINETO] * (len(q) - 1) + [MplPath.CLOSEPOLY] for q in polys])
    return MplPath(verts, codes.astype(MplPath.code_type))


def trajectory_figure(out: Path, path: Path, experiment=None, outlines: int = 6, summary: dict | None = None) -> None:
    """The shot in the plane of incidence (the paper's Fig. 18): the target face and the target, the
    projectile's deformed outline (its cut by the plane z = 0) at a few output times, the nose and tail paths
    of history.csv and, for a Table 1 shot, the test's final nose and tail; the predicted depth interval as a
    band when summary.json reports one (fepen.post.figures.interval_band).

    Args:
        experiment: fepen.data.Shot (Hx_mm, Hy_mm, Tx_mm, Ty_mm) or None.
        outlines: how many output times to draw, evenly spread from the first to the last.
        summary: the run's summary, for its depth interval (None: summary.json, if any).
    """
    import matplotlib
    from matplotlib.patches import PathPatch

    from fepen.post.figures import depth_interval, interval_band, new_figure, run_title, save_figure

    out = Path(out)
    h = np.atleast_1d(np.genfromtxt(out / "history.csv", delimiter=",", names=True))
    fig = new_figure((7, 7.4))
    ax = fig.subplots()
    times = output_times(out)
    picks = sorted(set(np.linspace(0, len(times) - 1, min(outlines, len(times))).round().astype(int)))
    cmap = matplotlib.colormaps["viridis"]
    ez, basis = np.array([0.0, 0.0, 1.0]), np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])  # (x, depth)
    for i, k in enumerate(picks):
        st = read_state(out, float(times[k]))
        live = st["cell_tag"] > 0 if "cell_tag" in st else np.ones(len(st["cells"]), dtype=bool)
        x = st["X"] + st["displacement_m"]
        polys, _ = cut(x[st["cells"][live]], ez, 0.0, basis)
        colour = cmap(i / max(len(picks) - 1, 1))
        outline = _one_path([q * 1e3 for q in polys])
        ax.add_artist(PathPatch(outline, facecolor=colour, edgecolor="none", alpha=0.8,
                                label=f"projectile at t = {st['t'] * 1e6:.0f} µs"))
        if len(outline.vertices):  # the limits from the vertices at once (add_patch walks every segment)
            ax.update_datalim(outline.vertices)
    ax.plot(h["nose_x_mm"], h["nose_y_mm"], "-", color="C3", lw=1, label="nose path")
    ax.plot(h["tail_x_mm"], h["tail_y_mm"], "--", color="C0", lw=1, label="tail path")
    name = getattr(experiment, "name", None)
    if experiment is not None:
        ax.plot([experiment.Tx_mm, experiment.Hx_mm], [experiment.Ty_mm, experiment.Hy_mm], "k-", lw=2.5,
                label=f"{name or 'test'} test: final tail to nose (Table 1)")
        ax.plot([experiment.Hx_mm], [experiment.Hy_mm], "k^", ms=8)
    interval_band(ax, depth_interval(out, summary))  # before the limits: the band is in view
    ax.autoscale_view()
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    ax.axhspan(0.0, 10.0 * max(y1, 1.0), color="0.9", zorder=0)  # the target, past any limits drawn
    ax.set_ylim(y0, y1)
    ax.axhline(0.0, color="k", lw=1)
    ax.text(0.01, 0.0, "target face", va="bottom", fontsize=8, transform=ax.get_yaxis_transform())
    ax.set(xlabel="x along the target face (mm)", ylabel="depth below the target face (mm)")
    ax.set_title(run_title(out, "the shot in the plane of incidence", name), fontsize=10)
    ax.set_aspect("equal", adjustable="datalim")
    ax.invert_yaxis()
    ax.legend(fontsize=7, loc="best")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    save_figure(fig, path)


def cross_sections(out: Path, path: Path, sections: dict, time: float | None = None) -> dict:
    """Axial logarithmic strain over material cross-sections (reference planes y = const), one panel each.

    Args:
        sections: label -> reference axial position from the nose tip (m).

    Returns:
        {label: {"min": most compressive strain, "max": most tensile, "charge_mean": mean over the charge}}.
    """
    from matplotlib.collections import PolyCollection

    from fepen.post.figures import new_figure, run_title, save_figure

    st = read_state(out, time)
    X, cells = st["X"], st["cells"]
    strain = _strain_axial(X, X + st["displacement_m"], cells)
    body = st.get("cell_tag", np.ones(len(cells)))
    fig = new_figure((4.2 * len(sections), 4.3))
    axes = fig.subplots(1, len(sections), squeeze=False)
    basis = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    report = {}
    for ax, (label, y) in zip(axes[0], sections.items()):
        polys, c = cut(X[cells], [0.0, 1.0, 0.0], y, basis)
        vals = strain[c] * 1e3
        pc = PolyCollection([q * 1e3 for q in polys], array=vals, cmap="coolwarm", edgecolors="face", linewidths=0.2)
        lim = max(abs(vals).max(), 1e-9) if len(vals) else 1.0
        pc.set_clim(-lim, lim)
        ax.add_collection(pc)
        ch = body[c] == 2.0
        if np.any(ch):  # outline of the charge's cut
            for q in (q for q, m in zip(polys, ch) if m):
                ax.plot(*np.vstack([q, q[:1]]).T * 1e3, color="k", lw=0.1, alpha=0.3)
        fig.colorbar(pc, ax=ax, fraction=0.05, label="axial strain (1e-3, tension > 0)")
        ax.set(title=f"{label.replace('_', ' ')}: {y * 1e3:.1f} mm behind the nose tip",
               xlabel="x, in the plane of incidence (mm)", ylabel="z, across it (mm)")
        ax.title.set_fontsize(8)
        ax.set_aspect("equal")
        ax.autoscale_view()
        areas = np.array([polygon_area(q) for q in polys])
        report[label] = {"y_mm": y * 1e3, "min": float(vals.min()) * 1e-3, "max": float(vals.max()) * 1e-3,
                         "charge_mean": float(np.sum(areas[ch] * vals[ch]) / max(areas[ch].sum(), 1e-300)) * 1e-3
                         if np.any(ch) else None}
    fig.suptitle(run_title(out, f"axial logarithmic strain on material cross-sections, t = {st['t'] * 1e6:.0f} µs"),
                 fontsize=10)
    fig.tight_layout()
    save_figure(fig, path)
    return report


def interface_profile(out: Path, path: Path, times=None) -> dict:
    """Gap and slip of the shell–charge wall against the reference axial position, at some output times.

    Returns:
        {time (s): {"gap_max_mm", "slip_max_mm", "gap_max_at_mm", "slip_max_at_mm"}}.
    """
    from fepen.post.figures import new_figure, run_title, save_figure

    all_t = output_times(out)
    times = all_t[[len(all_t) // 4, len(all_t) // 2, -1]] if times is None else times
    fig = new_figure((12, 4.2))
    ax = fig.subplots(1, 2)
    report = {}
    for t in times:
        st = read_state(out, t)
        if "interface_gap_m" not in st:
            raise ValueError(f"{out}: no interface fields (the charge is not in frictional contact)")
        X = st["X"]
        # the wall's nodes: those with a twin at the same reference place (fepen.mesh.split_wall)
        key = np.round(X / 1e-9).astype(np.int64)
        _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        wall = np.flatnonzero(cnt[inv] == 2)
        y = X[wall, 1] * 1e3
        g, s = st["interface_gap_m"][wall] * 1e3, st["interface_slip_m"][wall] * 1e3
        ax[0].plot(y, g, ".", ms=2, label=f"t = {st['t'] * 1e6:.0f} µs")
        ax[1].plot(y, s, ".", ms=2, label=f"t = {st['t'] * 1e6:.0f} µs")
        report[st["t"]] = {"gap_max_mm": float(g.max()), "gap_max_at_mm": float(y[np.argmax(g)]),
                           "slip_max_mm": float(s.max()), "slip_max_at_mm": float(y[np.argmax(s)])}
    ax[0].set(xlabel="wall node: reference distance behind the nose tip (mm)", ylabel="gap (mm, > 0 open)",
              title="shell–charge gap")
    ax[1].set(xlabel="wall node: reference distance behind the nose tip (mm)", ylabel="slip (mm)",
              title="shell–charge slip")
    for a in ax:
        a.legend(fontsize=7, markerscale=4)
        a.grid(alpha=0.3)
    fig.suptitle(run_title(out, "the shell–charge interface"), fontsize=10)
    fig.tight_layout()
    save_figure(fig, path)
    return report


def charge_histories(out: Path, path: Path) -> None:
    """Shell and charge accelerations (raw and filtered) and the charge's section stresses over time."""
    from fepen.post.figures import new_figure, run_title, save_figure

    acc = np.genfromtxt(Path(out) / "accelerations.csv", delimiter=",", names=True)
    sec = np.genfromtxt(Path(out) / "charge_sections.csv", delimiter=",", names=True)
    fig = new_figure((18, 4.4))
    ax = fig.subplots(1, 4)
    t = acc["t_s"] * 1e6
    tlabel = "time after impact (µs)"
    for name, colour in (("shell_acc", "C0"), ("charge_acc", "C3")):
        ax[0].plot(t, acc[f"{name}_g"] / 1e3, color=colour, lw=0.5, alpha=0.5)
        ax[0].plot(t, acc[f"{name}_filtered_g"] / 1e3, color=colour, lw=1.5, label=f"{name.split('_')[0]} (filtered)")
    ax[0].set(xlabel=tlabel, ylabel="axial acceleration (1000 g)", title="accelerations (thin: raw)")
    ts = sec["t_s"] * 1e6
    for k in range(5):
        ax[1].plot(ts, sec[f"axis{k}_axial_Pa"] / 1e6, label=f"axis point {k + 1} of 5 (front to rear)")
    ax[1].set(xlabel=tlabel, ylabel="axial stress (MPa, compression < 0)", title="along the charge's axis")
    for label, ls in (("front", "-"), ("nose_end", "--"), ("mid", ":")):
        for r, colour in zip((0, 33, 67, 90), ("C0", "C1", "C2", "C3")):
            ax[2].plot(ts, sec[f"{label}_r{r}_axial_Pa"] / 1e6, ls=ls, color=colour, lw=0.8,
                       label=f"{label.replace('_', ' ')}, r = {r} % of the cavity radius")
            ax[3].plot(ts, sec[f"{label}_r{r}_shear_Pa"] / 1e6, ls=ls, color=colour, lw=0.8)
    ax[2].set(xlabel=tlabel, ylabel="axial stress (MPa, compression < 0)",
              title="sections: — front, -- nose end, ··· mid")
    ax[3].set(xlabel=tlabel, ylabel="shear stress (MPa)", title="sections (colour: radius, as left)")
    for a in ax[:3]:
        a.legend(fontsize=6)
    for a in ax:
        a.grid(alpha=0.3)
        a.title.set_fontsize(9)
    fig.suptitle(run_title(out, "the charge's accelerations and section stresses"), fontsize=10)
    fig.tight_layout()
    save_figure(fig, path)


def charge_report(out: Path, sections: dict, time: float | None = None, figures: bool = True) -> dict:
    """Every picture of a charged run into its directory; returns what they show (for summary.json).

    Args:
        out: results directory (with fields.h5 when fields were written).
        sections: label -> reference axial position (m) of the charge's cross-sections.
        time: the time of the maps and cross-sections (the output time nearest it; None: the last).
        figures: False: no charge_histories.png (run.figures; the pictures made from the fields carry the
            report's numbers and are drawn regardless).
    """
    out = Path(out)
    report = {}
    if figures:
        charge_histories(out, out / "charge_histories.png")
    if (out / "fields.h5").exists():
        report["stress_maps"] = stress_maps(out, out / "stress_maps.png", time)
        report["cross_sections"] = cross_sections(out, out / "cross_sections.png", sections, time)
        import h5py

        with h5py.File(out / "fields.h5", "r") as h5:
            split = "interface_gap_m" in h5["/Function"]
        if split:  # a charge in frictional contact
            report["interface"] = {f"{t:.6g}": v for t, v in interface_profile(out, out / "interface.png").items()}
    return report
