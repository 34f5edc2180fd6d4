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
    polys, cells = [], []
    for c in crossing:
        p, s = points[c], d[c]
        pts = []
        for i, j in _EDGES:
            if (s[i] < 0.0) != (s[j] < 0.0):
                w = s[i] / (s[i] - s[j])
                pts.append(p[i] + w * (p[j] - p[i]))
        q = np.array(pts) @ basis.T
        centre = q.mean(axis=0)
        order = np.argsort(np.arctan2(q[:, 1] - centre[1], q[:, 0] - centre[0]))
        q = q[order]
        # duplicate points (a vertex on the plane is met by up to three edges)
        keep = np.ones(len(q), dtype=bool)
        keep[1:] = np.linalg.norm(np.diff(q, axis=0), axis=1) > 1e-15
        q = q[keep]
        if len(q) >= 3:
            polys.append(q)
            cells.append(c)
    return polys, np.array(cells, dtype=np.int64)


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
def stress_maps(out: Path, path: Path, time: float | None = None) -> dict:
    """Equivalent stress and PEEQ of shell and charge in the x–y and y–z planes, one figure; and the same
    cuts as data, ``path`` with the suffix .vtu (write_cut_planes), for ParaView, pyvista and meshio.

    Returns:
        {plane: {body: {"von_mises_max_Pa", "peeq_max", and where each is, "..._at_mm": [behind the nose tip
        along the axis, across it]}}}.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    st = read_state(out, time)
    x = st["X"] + st["displacement_m"]
    tip, _, planes = _axis_frame(st)
    body = st.get("cell_tag", np.ones(len(st["cells"])))
    quantities = [("von_mises_Pa", "equivalent stress (MPa)", 1e-6, "viridis")]
    if "peeq" in st:
        quantities.append(("peeq", "PEEQ", 1.0, "inferno"))
    bodies = [(1.0, "shell"), (2.0, "charge")] if np.any(body == 2.0) else [(1.0, "projectile")]
    ncol = len(quantities) * len(bodies)
    fig, axes = plt.subplots(len(planes), ncol, figsize=(2.6 * ncol + 1, 9.5), squeeze=False)
    report = {}
    write_cut_planes(st, x, tip, planes, Path(path).with_suffix(".vtu"))
    for r, (pname, (normal, basis)) in enumerate(planes.items()):
        polys, cells = cut(x[st["cells"]], normal, float(normal @ tip), basis)
        polys = [(q - tip @ basis.T) * 1e3 for q in polys]
        report[pname] = {}
        col = 0
        for name, label, scale, cmap in quantities:
            for value, bname in bodies:
                ax = axes[r, col]
                col += 1
                mine = body[cells] == value
                others = [p for p, m in zip(polys, mine) if not m]
                ax.add_collection(PolyCollection([p[:, ::-1] for p in others], facecolors="0.85", edgecolors="none"))
                vals = st[name][cells[mine]] * scale
                pc = PolyCollection([p[:, ::-1] for p, m in zip(polys, mine) if m], array=vals, cmap=cmap,
                                    edgecolors="face", linewidths=0.2)
                if name == "peeq" and len(vals):
                    pc.set_clim(0.0, max(float(vals.max()), 1e-6))
                ax.add_collection(pc)
                fig.colorbar(pc, ax=ax, fraction=0.08, pad=0.02)
                none = name == "peeq" and (not len(vals) or float(vals.max()) == 0.0)
                ax.set_title(f"{bname}: {label}" + (" = 0 everywhere" if none else ""), fontsize=8)
                ax.set_aspect("equal")
                ax.autoscale_view()
                ax.invert_yaxis()
                ax.tick_params(labelsize=7)
                if col == 1:
                    ax.set_ylabel(f"{pname}\nalong the axis from the nose tip (mm)", fontsize=8)
                if len(vals):
                    k = int(np.argmax(vals))
                    at = [p for p, m in zip(polys, mine) if m][k].mean(axis=0)
                    entry = report[pname].setdefault(bname, {})
                    key = "peeq_max" if name == "peeq" else "von_mises_max_Pa"
                    entry[key] = float(vals[k] / scale)
                    entry[key.replace("_Pa", "") + "_at_mm"] = [float(at[0]), float(at[1])]
    fig.suptitle(f"{Path(out).name}: t = {st['t'] * 1e6:.0f} us (deformed; grey: the other body)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return {"t_s": st["t"], **report}


def write_cut_planes(st: dict, x: np.ndarray, tip: np.ndarray, planes: dict, path: Path) -> None:
    """The stress maps' two cuts through the deformed projectile as one unstructured grid of polygons in
    the target's frame (m): triangles and quads with every cell field of the state, ``cell_tag`` and
    ``plane`` (0 the x–y plane of incidence, 1 the y–z plane across it); VTK XML, which ParaView, pyvista
    and meshio open."""
    import meshio

    from fepen.atomic import replacing

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
    mesh = meshio.Mesh(np.concatenate(points) if points else np.zeros((0, 3)), cells_out, cell_data=cell_data)
    with replacing(path, ".vtu") as tmp:
        meshio.write(tmp, mesh, file_format="vtu")


def trajectory_figure(out: Path, path: Path, experiment=None, outlines: int = 6) -> None:
    """The shot in the plane of incidence (the paper's Fig. 18): the target face and the target, the
    projectile's deformed outline (its cut by the plane z = 0) at a few output times, the nose and tail paths
    of history.csv and, for a Table 1 shot, the test's final nose and tail.

    Args:
        experiment: fepen.data.Shot (Hx_mm, Hy_mm, Tx_mm, Ty_mm) or None.
        outlines: how many output times to draw, evenly spread from the first to the last.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    out = Path(out)
    h = np.atleast_1d(np.genfromtxt(out / "history.csv", delimiter=",", names=True))
    fig, ax = plt.subplots(figsize=(7, 7))
    times = output_times(out)
    picks = sorted(set(np.linspace(0, len(times) - 1, min(outlines, len(times))).round().astype(int)))
    cmap = plt.get_cmap("viridis")
    ez, basis = np.array([0.0, 0.0, 1.0]), np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])  # (x, depth)
    for i, k in enumerate(picks):
        st = read_state(out, float(times[k]))
        live = st["cell_tag"] > 0 if "cell_tag" in st else np.ones(len(st["cells"]), dtype=bool)
        x = st["X"] + st["displacement_m"]
        polys, _ = cut(x[st["cells"][live]], ez, 0.0, basis)
        colour = cmap(i / max(len(picks) - 1, 1))
        ax.add_collection(PolyCollection([q * 1e3 for q in polys], facecolors=colour, edgecolors="none", alpha=0.8,
                                         label=f"t = {st['t'] * 1e6:.0f} us"))
    ax.plot(h["nose_x_mm"], h["nose_y_mm"], "-", color="C3", lw=1, label="nose path")
    ax.plot(h["tail_x_mm"], h["tail_y_mm"], "--", color="C0", lw=1, label="tail path")
    if experiment is not None:
        ax.plot([experiment.Tx_mm, experiment.Hx_mm], [experiment.Ty_mm, experiment.Hy_mm], "k-", lw=2.5,
                label="test: final tail to nose")
        ax.plot([experiment.Hx_mm], [experiment.Hy_mm], "k^", ms=8)
    ax.autoscale_view()
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    ax.axhspan(0.0, max(y1, 1.0), color="0.9", zorder=0)
    ax.axhline(0.0, color="k", lw=1)
    ax.text(x0, 0.0, " target face", va="bottom", fontsize=8)
    ax.set(xlabel="x (mm)", ylabel="depth, -y (mm)", title=f"{out.name}: the shot in the plane of incidence")
    ax.set_aspect("equal", adjustable="datalim")
    ax.invert_yaxis()
    ax.legend(fontsize=7, loc="best")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def cross_sections(out: Path, path: Path, sections: dict, time: float | None = None) -> dict:
    """Axial logarithmic strain over material cross-sections (reference planes y = const), one panel each.

    Args:
        sections: label -> reference axial position from the nose tip (m).

    Returns:
        {label: {"min": most compressive strain, "max": most tensile, "charge_mean": mean over the charge}}.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    st = read_state(out, time)
    X, cells = st["X"], st["cells"]
    strain = _strain_axial(X, X + st["displacement_m"], cells)
    body = st.get("cell_tag", np.ones(len(cells)))
    fig, axes = plt.subplots(1, len(sections), figsize=(4.2 * len(sections), 4.0), squeeze=False)
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
        fig.colorbar(pc, ax=ax, fraction=0.05, label="axial strain (1e-3)")
        ax.set(title=f"{label}: {y * 1e3:.1f} mm behind the nose tip", xlabel="x (mm)", ylabel="z (mm)")
        ax.title.set_fontsize(8)
        ax.set_aspect("equal")
        ax.autoscale_view()
        areas = np.array([polygon_area(q) for q in polys])
        report[label] = {"y_mm": y * 1e3, "min": float(vals.min()) * 1e-3, "max": float(vals.max()) * 1e-3,
                         "charge_mean": float(np.sum(areas[ch] * vals[ch]) / max(areas[ch].sum(), 1e-300)) * 1e-3
                         if np.any(ch) else None}
    fig.suptitle(f"{Path(out).name}: axial logarithmic strain on material cross-sections, t = {st['t'] * 1e6:.0f} us",
                 fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return report


def interface_profile(out: Path, path: Path, times=None) -> dict:
    """Gap and slip of the shell–charge wall against the reference axial position, at some output times.

    Returns:
        {time (s): {"gap_max_mm", "slip_max_mm", "gap_max_at_mm", "slip_max_at_mm"}}.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    all_t = output_times(out)
    times = all_t[[len(all_t) // 4, len(all_t) // 2, -1]] if times is None else times
    fig, ax = plt.subplots(1, 2, figsize=(12, 3.8))
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
        ax[0].plot(y, g, ".", ms=2, label=f"t = {st['t'] * 1e6:.0f} us")
        ax[1].plot(y, s, ".", ms=2, label=f"t = {st['t'] * 1e6:.0f} us")
        report[st["t"]] = {"gap_max_mm": float(g.max()), "gap_max_at_mm": float(y[np.argmax(g)]),
                           "slip_max_mm": float(s.max()), "slip_max_at_mm": float(y[np.argmax(s)])}
    ax[0].set(xlabel="wall node: reference distance behind the nose tip (mm)", ylabel="gap (mm, > 0 open)")
    ax[1].set(xlabel="wall node: reference distance behind the nose tip (mm)", ylabel="slip (mm)")
    for a in ax:
        a.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return report


def charge_histories(out: Path, path: Path) -> None:
    """Shell and charge accelerations (raw and filtered) and the charge's section stresses over time."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    acc = np.genfromtxt(Path(out) / "accelerations.csv", delimiter=",", names=True)
    sec = np.genfromtxt(Path(out) / "charge_sections.csv", delimiter=",", names=True)
    fig, ax = plt.subplots(1, 4, figsize=(18, 3.8))
    t = acc["t_s"] * 1e6
    for name, colour in (("shell_acc", "C0"), ("charge_acc", "C3")):
        ax[0].plot(t, acc[f"{name}_g"] / 1e3, color=colour, lw=0.5, alpha=0.5)
        ax[0].plot(t, acc[f"{name}_filtered_g"] / 1e3, color=colour, lw=1.5, label=f"{name.split('_')[0]} (filtered)")
    ax[0].set(xlabel="t (us)", ylabel="axial acceleration (1000 g)", title="thin: raw")
    ts = sec["t_s"] * 1e6
    for k in range(5):
        ax[1].plot(ts, sec[f"axis{k}_axial_Pa"] / 1e6, label=f"axis point {k} (front to rear)")
    ax[1].set(xlabel="t (us)", ylabel="axial stress (MPa)", title="along the charge's axis")
    for label, ls in (("front", "-"), ("nose_end", "--"), ("mid", ":")):
        for r, colour in zip((0, 33, 67, 90), ("C0", "C1", "C2", "C3")):
            ax[2].plot(ts, sec[f"{label}_r{r}_axial_Pa"] / 1e6, ls=ls, color=colour, lw=0.8,
                       label=f"{label}, r = {r} %")
            ax[3].plot(ts, sec[f"{label}_r{r}_shear_Pa"] / 1e6, ls=ls, color=colour, lw=0.8)
    ax[2].set(xlabel="t (us)", ylabel="axial stress (MPa)", title="sections: - front, -- nose end, : mid")
    ax[3].set(xlabel="t (us)", ylabel="shear stress (MPa)", title="sections (colour: radius)")
    for a in ax[:3]:
        a.legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def charge_report(out: Path, sections: dict, time: float | None = None) -> dict:
    """Every picture of a charged run into its directory; returns what they show (for summary.json).

    Args:
        out: results directory (with fields.h5 when fields were written).
        sections: label -> reference axial position (m) of the charge's cross-sections.
        time: the time of the maps and cross-sections (the output time nearest it; None: the last).
    """
    out = Path(out)
    report = {}
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
