"""The pictures of the studies (fepen.studies): each draws on the matplotlib Figure it is given (ASE's plot(ax)),
from the study's result and what the study hands over of its scene (fepen.post reads no scene): a sweep's depth
against each varied key and its histograms, the ballistic limit and the ricochet boundary, the uncertainty
study's depths and probabilities, the depth sets, the accuracy-cost Pareto front, the Table 1 validation and
its hazard maps."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

__all__ = ["OUTCOME_COLOURS", "SHOWN_UNITS", "column", "quantiles", "summarised", "sweep_size", "sweep_figure",
           "histogram_names", "histograms", "charge_safety", "limit", "ricochet", "uncertainty", "depth", "pareto",
           "validation", "VALIDATION_SIZE", "place_labels", "hazard_maps"]

OUTCOME_COLOURS = {"embedded": "tab:blue", "perforated": "tab:green", "ricochet": "tab:red", "ended": "tab:grey"}
#: the figures summarised by quantiles and histograms when present
FIGURES = ("depth_mm", "Hx_mm", "final_axis_angle_deg", "residual_speed_m_s", "charge_peak_acceleration_m_s2",
           "peak_acceleration_m_s2", "max_peeq", "mass_loss_percent", "nose_offset_mm")
#: axis labels of the summary figures, with their units
FIGURE_LABELS = {"depth_mm": "depth of penetration (mm)", "Hx_mm": "final nose x along the face (mm)",
                 "residual_speed_m_s": "residual speed (m/s)",
                 "charge_peak_acceleration_m_s2": "charge's peak acceleration (m/s²)",
                 "peak_acceleration_m_s2": "peak deceleration (m/s²)", "max_peeq": "largest PEEQ (−)",
                 "mass_loss_percent": "mass loss (%)", "final_axis_angle_deg": "final axis from the normal (°)",
                 "nose_offset_mm": "nose's offset from the line of fire (mm)"}
#: a scene unit: (the unit shown, the factor from the scene's value)
SHOWN_UNITS = {"Pa": ("MPa", 1e-6), "m": ("mm", 1e3), "kg": ("g", 1e3), "deg": ("°", 1.0)}
#: a varied key of names (impact.shot, target.material) is drawn when it has at most this many
MAX_CATEGORIES = 30
#: the Table 1 value of a summary figure (fepen.data.Shot attribute)
MEASURED = {"depth_mm": "Hy_mm", "Hx_mm": "Hx_mm"}


def column(rows, name) -> np.ndarray:
    """A numeric column (NaN where absent); the residual speed only of the perforated shots (an embedded
    shot's is the sideways drift left when it stops advancing)."""
    if name == "residual_speed_m_s":
        rows = [r for r in rows if r.get("outcome") == "perforated"]
    return np.array([r[name] if isinstance(r.get(name), (int, float)) and not isinstance(r.get(name), bool)
                     else np.nan for r in rows], float)


def quantiles(values: np.ndarray) -> dict:
    """count, mean, std, min, P5, P50, P95, max of the finite values."""
    v = values[np.isfinite(values)]
    if not len(v):
        return {"count": 0}
    p5, p50, p95 = np.percentile(v, [5, 50, 95])
    return {"count": len(v), "mean": float(v.mean()), "std": float(v.std(ddof=1)) if len(v) > 1 else 0.0,
            "min": float(v.min()), "P5": float(p5), "P50": float(p50), "P95": float(p95), "max": float(v.max())}


def summarised(cols, rows) -> list[str]:
    """The summary figures (FIGURES) the rows hold numbers of."""
    return [c for c in FIGURES if c in cols and np.isfinite(column(rows, c)).any()]


def _plotted(axes, rows) -> list:
    """The varied keys a sweep's figure draws: numbers, or a few names (impact.shot)."""
    return [a for a in axes if np.isfinite(column(rows, a[0])).all()
            or len({str(r.get(a[0])) for r in rows}) <= MAX_CATEGORIES]


def sweep_size(axes, rows) -> tuple[float, float] | None:
    """The size of sweep.png for these varied keys, or None when there is nothing to draw.

    Args:
        axes: one (key, axis label, unit factor, the test shot's value or None) per varied key.
        rows: the table's rows.
    """
    depth = column(rows, "depth_mm")
    n = len(_plotted(axes, rows))
    if not (n and np.isfinite(depth).any() and len(depth) == len(rows)):
        return None
    ncol = min(n, 3)
    return (4.4 * ncol, 3.6 * math.ceil(n / ncol) + 0.6)


def sweep_figure(fig, axes, rows, shot, title: str) -> None:
    """sweep.png: depth against each varied key, coloured by outcome, in the keys' units; a key of names one
    tick per name. The measured values are marked: a row's Table 1 depth when its shot is named (black rings),
    and the test the base scene is (a star at its own values).

    Args:
        fig: the Figure (sweep_size). axes: one (key, label, factor, test value or None) per varied key.
        rows: the table's rows. shot: the Table 1 shot the base scene is, or None. title: the figure's title.
    """
    keys = _plotted(axes, rows)
    depth = column(rows, "depth_mm")
    measured = column(rows, "experiment.Hy_mm")
    outcome = [r.get("outcome", r["status"]) for r in rows]
    n = len(keys)
    ncol = min(n, 3)
    grid = fig.subplots(math.ceil(n / ncol), ncol, squeeze=False)
    small = len(rows) <= 200
    for ax, (k, label, factor, test) in zip(grid.flat, keys):
        x = column(rows, k) * factor
        names = None
        if not np.isfinite(x).all():  # a key of names: one tick each, in the order met
            names = list(dict.fromkeys(str(r.get(k)) for r in rows))
            x = np.array([names.index(str(r.get(k))) for r in rows], float)
            label = k
        for name in sorted(set(outcome)):
            m = np.array([o == name for o in outcome])
            ax.plot(x[m], depth[m], "o" if small else ".", ms=5 if small else 2, alpha=0.8 if small else 0.4,
                    color=OUTCOME_COLOURS.get(name, "k"), label=f"fepen: {name} ({m.sum()})")
        if np.isfinite(measured).any():
            ax.plot(x, measured, "o", ms=9, mfc="none", mec="k", mew=1.2, label="Table 1 test (measured)")
        if names is not None:
            ax.set_xticks(range(len(names)), names, rotation=30 if len(names) > 6 else 0)
            ax.set_xlim(-0.5, len(names) - 0.5)
        elif shot is not None and test is not None:
            ax.plot([test * factor], [shot.Hy_mm], "*", ms=14, color="gold", mec="k", zorder=5,
                    label=f"{shot.name} test: {shot.Hy_mm:g} mm")
        ax.set_xlabel(label)
        ax.set_ylabel(FIGURE_LABELS["depth_mm"])
        ax.grid(alpha=0.3)
    for ax in list(grid.flat)[n:]:
        ax.axis("off")
    grid.flat[0].legend(fontsize=7)
    fig.suptitle(title)
    fig.tight_layout()


def histogram_names(cols, rows) -> list[str]:
    """The summary figures a Monte Carlo sample's histograms show (at most four that vary)."""
    return [c for c in summarised(cols, rows) if np.nanmax(column(rows, c)) > np.nanmin(column(rows, c))][:4]


def histograms(fig, names, rows, shot, title: str) -> None:
    """histograms.png: each figure's histogram with P5, P50 and P95, and the test's value (a line)."""
    axes = fig.subplots(1, len(names), squeeze=False)
    for ax, name in zip(axes.flat, names):
        label = FIGURE_LABELS.get(name, name)
        v = column(rows, name)
        v = v[np.isfinite(v)]
        q = quantiles(v)
        ax.hist(v, bins=min(60, max(10, int(np.sqrt(len(v))))), color="tab:blue", alpha=0.75,
                label="fepen shots")
        for p, style in (("P5", ":"), ("P50", "-"), ("P95", ":")):
            ax.axvline(q[p], color="k", ls=style, lw=1, label="P50; P5, P95 (dotted)" if p == "P50" else None)
        if shot is not None and name in MEASURED:
            value = getattr(shot, MEASURED[name])
            ax.axvline(value, color="tab:red", lw=2, label=f"{shot.name} test: {value:g} mm")
        ax.set_xlabel(label + (" (perforated)" if name == "residual_speed_m_s" else ""))
        ax.set_ylabel("shots")
        unit = label[label.rfind("(") + 1:-1] if label.endswith(")") else ""
        unit = "" if unit in ("−", "") else f" {unit}"
        ax.set_title(f"P5 {q['P5']:.4g}, P50 {q['P50']:.4g}, P95 {q['P95']:.4g}{unit}", fontsize=9)
        ax.legend(fontsize=7)
    fig.suptitle(title)
    fig.tight_layout()


# ------------------------------------------------------------------------------------------------- limit studies
def limit(fig, res: dict, line: str | None, fit=None) -> None:
    """ballistic_limit.png: residual against striking speed, the shots that did not perforate on the axis, the
    Recht–Ipson fit and the limit (dotted). line: what the base scene is (the title's second line), or None.
    fit: (speeds, residual speeds) of the fitted curve, or None."""
    ax = fig.subplots()
    pts = res["curve"] + [{"v_m_s": b["v_m_s"], "residual_speed_m_s": b["residual_speed_m_s"]}
                          for b in res["bisection"] if b["outcome"] == "perforated"]
    v = np.array([p["v_m_s"] for p in pts])
    vr = np.array([p["residual_speed_m_s"] for p in pts])
    ax.plot(v, vr, "o", label="fepen shots (perforated)")
    stuck = [b["v_m_s"] for b in res["bisection"] if b["outcome"] != "perforated"]
    ax.plot(stuck, np.zeros(len(stuck)), "x", color="tab:red", label="fepen shots (not perforated)")
    if fit is not None and "a" in res:
        ax.plot(*fit, "-", color="k", label=f"Recht–Ipson fit: a = {res['a']:.3f}, p = {res['p']:.2f}")
    ax.axvline(res["v_bl_m_s"], ls=":", color="k", label=f"ballistic limit {res['v_bl_m_s']:.1f} m/s")
    ax.set_xlabel("striking speed (m/s)")
    ax.set_ylabel("residual speed (m/s)")
    title = f"ballistic limit {res['v_bl_m_s']:.1f} m/s (± {res['tol_m_s'] / 2:g} m/s)"
    ax.set_title(title + (f"\n{line}" if line else ""), fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()


def ricochet(fig, res: dict, line: str | None) -> None:
    """ricochet.png: the outcome of every shot over striking speed and obliquity, and the bisected ricochet
    boundary. line: what the base scene is (the title's second line), or None."""
    ax = fig.subplots()
    for name in sorted({c["outcome"] for c in res["map"]}):
        c = [m for m in res["map"] if m["outcome"] == name]
        ax.plot([m["v_m_s"] for m in c], [m["obliquity_deg"] for m in c], "s", ms=5,
                color=OUTCOME_COLOURS.get(name, "k"), label=f"fepen shots: {name}", alpha=0.8)
    ax.plot(res["speeds_m_s"], res["critical_obliquity_deg"], "-k", lw=1.5,
            label=f"ricochet boundary (± {res['tol_deg'] / 2:g}°)")
    ax.set_xlabel("striking speed (m/s)")
    ax.set_ylabel("obliquity from the face normal (°)")
    ax.set_title("critical obliquity of ricochet" + (f"\n{line}" if line else ""), fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()


# ------------------------------------------------------------------------------------------------- uncertainty
def _probabilities(res: dict) -> list:
    """(sample, what, entry) of every probability uncertainty.json holds."""
    probs = []
    for name in ("combined", "inputs"):
        e = res["samples"].get(name)
        if e is None:
            continue
        if "perforation" in e and e["perforation"].get("shots"):
            probs.append((name, "target", e["perforation"]))
        for lay in e.get("layers", []):
            if lay.get("shots"):
                probs.append((name, f"layer {lay['layer']}", lay))
        if e.get("ricochet", {}).get("shots"):
            probs.append((name, "ricochet", e["ricochet"]))
        if e.get("axis_beyond", {}).get("shots"):
            probs.append((name, f"|axis| > {e['axis_beyond']['angle_deg']:g}°", e["axis_beyond"]))
    return probs


def _fans_panel(ax3, res: dict, fans: dict, colours: dict, names: dict) -> None:
    """uncertainty.png's fan of final bodies, nose to tail, in the plane of fire and across it."""
    for name, f in (fans or {}).items():
        f = np.asarray(f, float).reshape(-1, 6)
        for cols, colour, plane in (((0, 1, 2, 3), colours[name], "in the plane of fire (x)"),
                                    ((4, 1, 5, 3), {"combined": "tab:purple", "inputs": "tab:brown"}[name],
                                     "across it (z)")):
            hx, hy, tx, ty = f[:, cols].T
            ax3.plot(np.array([tx, hx]), np.array([ty, hy]), color=colour, alpha=0.08, lw=1)
            ax3.plot([], [], color=colour, label=f"{names[name]}, {plane}")
    t = res["scene"]["test"]
    if t and "Hx_mm" in t:
        ax3.plot([t["Tx_mm"], t["Hx_mm"]], [t["Ty_mm"], t["Hy_mm"]], "k-", lw=2, label=f"test {t['shot']} (x)")
    ax3.set_xlabel("x or z (mm)")
    ax3.set_ylabel("depth (mm)")
    ax3.invert_yaxis()
    ax3.set_title("final bodies, nose to tail")
    if fans:
        ax3.legend(fontsize=7)


def uncertainty(fig, res: dict, depths: dict, fans: dict | None = None) -> None:
    """uncertainty.png: the depth histograms of both samples with their P10 and P90, the slab and the test; the
    probabilities a designer asks (perforation of a finite target and of its layers, ricochet, the final axis
    beyond an angle) with their intervals, or the depth's CDF without them; and the fan of final bodies in the
    plane of fire and across it (fig: 17 x 4.8 in). depths: the depth (mm) arrays by sample name ("combined",
    "inputs"), +inf for a shot through the target; fans: (Hx, Hy, Tx, Ty, Hz, Tz) rows by sample name."""
    ax, ax2, ax3 = fig.subplots(1, 3)
    colours = {"combined": "tab:blue", "inputs": "tab:orange"}
    names = {"combined": "inputs and model", "inputs": "inputs alone"}
    finite = [d[np.isfinite(d)] for d in depths.values()]
    allv = np.concatenate(finite) if finite else np.array([])
    bins = np.linspace(allv.min(), allv.max(), 41) if len(allv) and allv.max() > allv.min() else 20
    for name, d in depths.items():
        d = d[np.isfinite(d)]
        if not len(d):
            continue
        q = res["samples"][name]["depth"]
        through = q["shots"] - q["stopped"]
        ax.hist(d, bins=bins, alpha=0.45, color=colours[name], label=f"{names[name]} ({len(d)} stopped"
                + (f", {through} through)" if through else ")"))
        for p in ("P10_mm", "P90_mm"):
            if q[p] is not None:
                ax.axvline(q[p], color=colours[name], ls="--", lw=1.2)
    th = res["target"]["thickness_m"]
    if th is not None:
        ax.axvline(1e3 * th, color="k", lw=2, label=f"slab {1e3 * th:.4g} mm")
    if res["scene"]["test"]:
        t = res["scene"]["test"]
        ax.axvline(t["depth_mm"], color="tab:red", lw=2, label=f"test {t['shot']} {t['depth_mm']:.1f} mm")
    ax.set_xlabel("depth of penetration (mm)")
    ax.set_ylabel("samples")
    ax.set_title("depth; dashed: P10 and P90")
    ax.legend(fontsize=8)
    probs = _probabilities(res)
    if probs:
        for j, (name, what, e) in enumerate(probs):
            lo, hi = e["wilson95"]
            ax2.errorbar([j], [e["probability"]], yerr=[[max(e["probability"] - lo, 0.0)],
                                                       [max(hi - e["probability"], 0.0)]],
                         fmt="o", color=colours[name], capsize=6, label=f"{names[name]}: Wilson 95 %"
                         if (name, what) == next((n, w) for n, w, _ in probs if n == name) else None)
            if "systematic" in e:
                a, b = e["systematic"]["probability"]
                ax2.fill_between([j - 0.25, j + 0.25], [a, a], [b, b], color=colours[name], alpha=0.2,
                                 label="systematic band (b at 10 %, 90 %)" if j == next(
                                     i for i, q in enumerate(probs) if "systematic" in q[2]) else None)
        ax2.set_xticks(range(len(probs)), [f"{what}\n{names[name]}" for name, what, _ in probs], fontsize=8)
        ax2.set_xlim(-0.6, len(probs) - 0.4)
        ax2.set_ylim(-0.02, 1.02)
        ax2.set_ylabel("probability (−)")
        ax2.set_title("perforation, ricochet, final axis beyond")
        ax2.legend(fontsize=8)
    else:
        for name, d in depths.items():
            d = np.sort(d[np.isfinite(d)])
            if len(d):
                ax2.plot(d, (np.arange(len(d)) + 1) / len(d), color=colours[name], label=names[name])
        if res["scene"]["test"]:
            ax2.axvline(res["scene"]["test"]["depth_mm"], color="tab:red", lw=2, label="test")
        ms = res["model_scatter"]
        if "response" in ms:
            ax2.axvline(ms["response"]["depth_at_1_mm"], color="k", ls=":", label="fepen at the nominal inputs")
        ax2.set_xlabel("depth of penetration (mm)")
        ax2.set_ylabel("cumulative probability (−)")
        ax2.set_title("depth's distribution")
        ax2.grid(alpha=0.3)
        ax2.legend(fontsize=8)
    _fans_panel(ax3, res, fans or {}, colours, names)
    sc = res["scene"]
    fig.suptitle(f"Uncertainty: {sc['label']}, {sc['fidelity']} fidelity, {res['scatter']['samples']} samples")
    fig.tight_layout()


# ------------------------------------------------------------------------------------------------- validations
def depth(fig, results: dict[str, list[dict]], method: str = "default") -> None:
    """depth.png: predicted against measured depth, one marker per set, with the ±10 % and ±20 % bands (log
    scales, mm; fig: 6.6 x 6.4 in). results: the shots' {"depth", method} (m) by set."""
    ax = fig.subplots()
    hi = max(max(max(s["depth"], s[method]) for s in shots) for shots in results.values()) * 1.1e3
    lo = min(min(min(s["depth"], s[method]) for s in shots) for shots in results.values()) / 1.1 * 1e3
    line = np.geomspace(lo, hi, 50)
    ax.plot(line, line, "k-", lw=1, label="predicted = measured")
    for f, style in ((0.1, "--"), (0.2, ":")):
        ax.plot(line, line * (1 + f), "k" + style, lw=0.8, label=f"±{f:.0%}")
        ax.plot(line, line * (1 - f), "k" + style, lw=0.8)
    markers = "osD^v<>pXh*P"
    count = 0
    for i, (name, shots) in enumerate(results.items()):
        count += len(shots)
        ax.plot([s["depth"] * 1e3 for s in shots], [s[method] * 1e3 for s in shots], markers[i % len(markers)],
                ms=5, mfc="none", label=f"{name} ({len(shots)} tests)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(lo, hi)
    ax.set_ylim(lo, hi)
    ax.set_xlabel("measured depth of penetration (mm)")
    ax.set_ylabel(f"predicted depth (mm): rigid fidelity, {method} law")
    ax.set_title(f"rigid fidelity against {count} measured depths ({len(results)} data sets)", fontsize=10)
    ax.legend(fontsize=7, loc="upper left")
    ax.grid(True, which="both", lw=0.3)
    fig.tight_layout()


#: validation.png's size (inches): the scatter panels square enough for eight shots' names each
VALIDATION_SIZE = (17.0, 6.4)
#: the offsets a point's name is tried at (points), nearest first, each in eight directions
LABEL_RINGS = (5.0, 12.0, 22.0, 34.0, 48.0, 64.0)


def _boxes_overlap(a, b) -> bool:
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


def _free(box, taken, marks, frame) -> bool:
    """The box is inside the frame, clear of the boxes taken and of every marker's centre."""
    inside = frame.x0 <= box.x0 and box.x1 <= frame.x1 and frame.y0 <= box.y0 and box.y1 <= frame.y1
    if not inside or any(_boxes_overlap(box, t) for t in taken):
        return False
    return not np.any((marks[:, 0] > box.x0) & (marks[:, 0] < box.x1) & (marks[:, 1] > box.y0)
                      & (marks[:, 1] < box.y1))


def place_labels(ax, xy, names, taken=(), fontsize: float = 7.5, colours=None) -> list:
    """Name points without a collision: each name is put at the nearest offset (LABEL_RINGS, eight directions)
    where its box overlaps no name put before, none of the boxes ``taken`` (a legend) and no marker of the axes,
    inside the axes; beyond the first ring a thin leader line joins it to its point. Call it after the figure's
    layout is final (the boxes are measured on its canvas).

    Args:
        ax: the axes, its points and legends drawn. xy: the points (data coordinates). names: their names.
        taken: display-coordinate boxes to keep clear (matplotlib Bbox). fontsize: the names' size (points).
        colours: each name's colour (its marker's, so that a name beside two markers says whose it is).

    Returns:
        The annotations (matplotlib Annotation), one per point.
    """
    fig = ax.figure
    renderer = fig.canvas.get_renderer()
    frame = ax.get_window_extent(renderer)
    marks = [ax.transData.transform(line.get_xydata()) for line in ax.lines
             if line.get_marker() not in (None, "None", "", " ") and len(line.get_xydata())]
    marks = np.vstack(marks) if marks else np.zeros((0, 2))
    taken = list(taken)
    directions = [(math.cos(a), math.sin(a)) for a in np.radians([45, 135, -45, -135, 0, 90, 180, -90])]
    placed = []
    for i, ((x, y), name) in enumerate(zip(xy, names)):
        probe = ax.annotate(name, (x, y), xytext=(0, 0), textcoords="offset points", fontsize=fontsize)
        found = None
        for r in LABEL_RINGS:
            for dx, dy in directions:
                where = {"xytext": (r * dx, r * dy), "ha": "left" if dx > 0.1 else "right" if dx < -0.1 else "center",
                         "va": "bottom" if dy > 0.1 else "top" if dy < -0.1 else "center"}
                probe.xyann = where["xytext"]
                probe.set(ha=where["ha"], va=where["va"])
                if _free(probe.get_window_extent(renderer), taken, marks, frame):
                    found = (r, where)
                    break
            if found is not None:
                break
        probe.remove()
        r, where = found or (LABEL_RINGS[0], {"xytext": (LABEL_RINGS[0],) * 2, "ha": "left", "va": "bottom"})
        colour = "k" if colours is None else colours[i]
        leader = {"arrowprops": {"arrowstyle": "-", "lw": 0.6, "color": colour, "shrinkA": 1, "shrinkB": 3}} \
            if r > LABEL_RINGS[0] else {}
        label = ax.annotate(name, (x, y), textcoords="offset points", fontsize=fontsize, color=colour, **where,
                            **leader)
        taken.append(label.get_window_extent(renderer))
        placed.append(label)
    return placed


def validation(fig, rows, out) -> None:
    """validation.png: simulated against measured (Hy, Ty), (Hx, Tx), each point named by its shot without a
    collision (place_labels), and the nose trajectories (read from each shot's history.csv in OUT); fig:
    VALIDATION_SIZE."""
    ax = fig.subplots(1, 3, gridspec_kw={"width_ratios": [1.0, 1.0, 0.8]})
    named = []
    for k, (a, b) in enumerate((("Hy", "Ty"), ("Hx", "Tx"))):
        for key, mark, what in ((a, "o", "nose"), (b, "s", "tail")):
            x = [r[f"{key}_exp_mm"] for r in rows]
            y = [r[f"{key}_mm"] for r in rows]
            line, = ax[k].plot(x, y, mark, ms=5, label=f"{key} ({what})")
            named += [(k, (xi, yi), r["shot"], line.get_color()) for r, xi, yi in zip(rows, x, y)]
        lim = max(max(r[f"{c}_exp_mm"], r[f"{c}_mm"]) for r in rows for c in (a, b)) * 1.1
        ax[k].plot([0, lim], [0, lim], "k:", lw=0.8)
        ax[k].plot([0, lim], [0, 1.06 * lim], "k:", lw=0.5)
        ax[k].plot([0, lim], [0, 0.94 * lim], "k:", lw=0.5)
        ax[k].set(xlabel="test (mm)", ylabel="simulation (mm)", title=f"{a}, {b} (dotted: equal and ±6 %)",
                  xlim=(-0.04 * lim, lim), ylim=(-0.04 * lim, lim))
        ax[k].legend(fontsize=8, loc="upper left")
        ax[k].grid(alpha=0.25)
    for i, r in enumerate(rows):
        d = np.genfromtxt(Path(out) / r["shot"] / "history.csv", delimiter=",", names=True)
        ax[2].plot(d["nose_x_mm"], d["nose_y_mm"], color=f"C{i}", label=r["shot"])
        ax[2].plot([r["Hx_exp_mm"]], [r["Hy_exp_mm"]], "o", color=f"C{i}")
        ax[2].plot([r["Tx_exp_mm"]], [r["Ty_exp_mm"]], "s", color=f"C{i}", mfc="none")
    ax[2].invert_yaxis()
    ax[2].set(xlabel="x (mm)", ylabel="depth (mm)", title="nose trajectories; tests: o nose, □ tail",
              aspect="equal")
    ax[2].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0), title="shot", title_fontsize=8)
    fig.tight_layout()
    fig.canvas.draw()  # the layout final: the names are placed on it
    for k in (0, 1):
        legend = ax[k].get_legend().get_window_extent(fig.canvas.get_renderer())
        mine = [n for n in named if n[0] == k]
        place_labels(ax[k], [n[1] for n in mine], [n[2] for n in mine], [legend], colours=[n[3] for n in mine])


def hazard_maps(fig, out) -> None:
    """hazard_maps.png: the hazard maps (max surface PEEQ along the axis) of a validation overlaid, C2/C3/C6
    (angle) and C3/C4/C5 (speed), read from each shot's hazard.csv in OUT (fig: 12 x 3.8 in)."""
    from fepen.data import SHOTS

    ax = fig.subplots(1, 2)
    for a, (group, what) in zip(ax, ((("C2", "C3", "C6"), "obliquity"), (("C3", "C4", "C5"), "speed"))):
        for name in group:
            d = np.loadtxt(Path(out) / name / "hazard.csv", delimiter=",", skiprows=1)
            e = SHOTS[name]
            a.plot(d[:, 0], d[:, 1], label=f"{name}: {e.v0:g} m/s, {e.obliquity_deg:g}°")
        a.set(xlabel="distance from the nose (mm)", ylabel="max surface PEEQ", title=f"hazard map by {what}")
        a.legend(fontsize=8)
    fig.tight_layout()


# ------------------------------------------------------------------------------------------------- accuracy-cost
def pareto(fig, rows) -> None:
    """pareto.png: error against Table 1 (nose) and against the finest run, against wall time, log-log (fig: 12
    x 5 in)."""
    from matplotlib.lines import Line2D

    axes = fig.subplots(1, 2)
    marks = {"mesh": "o", "fidelity": "s", "cheaper": "^", "costlier": "v", "ranks": "D"}
    colours = {"C3": "tab:blue", "C7": "tab:red"}
    for ax, key, label in ((axes[0], "nose_error", "nose error against Table 1's test"),
                           (axes[1], "H_vs_finest", "nose position against the finest run")):
        for r in rows:
            if "failed" in r or not np.isfinite(r.get(key, np.nan)) or r.get(key, 0) <= 0:
                continue
            ax.loglog(r["process_s"], 100 * r[key], marks[r["group"]], color=colours.get(r["shot"], "k"),
                      alpha=0.8)
            ax.annotate(r["name"], (r["process_s"], 100 * r[key]), fontsize=6, alpha=0.7,
                        xytext=(3, 2), textcoords="offset points")
        ax.set(xlabel="wall time of the run (s)", ylabel=f"{label} (%)")
        ax.grid(True, which="both", alpha=0.3)
    handles = [Line2D([], [], marker=m, ls="", color="gray", label=f"varied: {g}") for g, m in marks.items()]
    handles += [Line2D([], [], marker="o", ls="", color=c, label=f"shot {s}") for s, c in colours.items()]
    axes[0].legend(handles=handles, fontsize=8)
    fig.suptitle("fepen: accuracy against time (shots C3 and C7)")
    fig.tight_layout()


def fans(fig, fans: dict, tests: dict) -> None:
    """bands.png: each shot's ensemble of final bodies (nose to tail, one faint line per member:
    fepen.studies.bands), in the plane of fire (x, blue) and across it (z, orange) against the depth, with the
    test's final body in the plane of fire in black (its z was not measured) (fig: 15 x 6.5 in)."""
    names = list(fans)
    axes = np.atleast_1d(fig.subplots(2, (len(names) + 1) // 2) if len(names) > 3 else fig.subplots(1, len(names)))
    axes = axes.ravel()
    for ax, name in zip(axes, names):
        f = np.asarray(fans[name], dtype=float)
        for (hx, hy, tx, ty), colour in ((f[:, :4].T, "tab:blue"), (f[:, [4, 1, 5, 3]].T, "tab:orange")):
            ax.plot(np.array([tx, hx]), np.array([ty, hy]), color=colour, alpha=0.08, lw=1)
            ax.plot(hx, hy, ".", color=colour, ms=2)
        ax.plot([], [], "-", color="tab:blue", label="in the plane of fire (x)")
        ax.plot([], [], "-", color="tab:orange", label="across it (z)")
        t = tests[name]
        ax.plot([t["Tx_mm"], t["Hx_mm"]], [t["Ty_mm"], t["Hy_mm"]], "k-", lw=2, label="test (x)")
        ax.plot([t["Hx_mm"]], [t["Hy_mm"]], "ko", ms=4)
        ax.set_title(name)
        ax.set_xlabel("x or z (mm)")
        ax.set_ylabel("depth (mm)")
        ax.invert_yaxis()
        ax.set_aspect("equal", adjustable="datalim")
    for ax in axes[len(names):]:
        ax.set_visible(False)
    axes[0].legend(loc="lower left", fontsize=8)
    fig.tight_layout()


def charge_safety(fig, result: dict) -> None:
    """charge_safety.png (fepen study charge-safety): the governing margin over speed and obliquity (first angle
    of attack), its margin-1 line, each point's value; hollow markers outside the validated envelope."""
    rows = [r for r in result["rows"] if r["attack_deg"] == min(x["attack_deg"] for x in result["rows"])]
    speeds = sorted({r["velocity_m_s"] for r in rows})
    obl = sorted({r["obliquity_deg"] for r in rows})
    M = np.full((len(obl), len(speeds)), np.nan)
    for r in rows:
        if r["margin"] is not None:
            M[obl.index(r["obliquity_deg"]), speeds.index(r["velocity_m_s"])] = r["margin"]
    ax = fig.add_subplot(111)
    if len(speeds) > 1 and len(obl) > 1 and np.isfinite(M).all():
        from matplotlib.colors import TwoSlopeNorm

        lo, hi = min(float(M.min()), 0.95), max(float(M.max()), 1.05)  # red below 1 (past the threshold), green above
        levels = np.unique(np.concatenate([np.linspace(lo, 1.0, 7), np.linspace(1.0, hi, 7)]))
        cs = ax.contourf(speeds, obl, M, levels=levels, cmap="RdYlGn", norm=TwoSlopeNorm(1.0, lo, hi))
        fig.colorbar(cs, ax=ax, label="governing margin (below 1: past the threshold)")
        if M.min() < 1.0 < M.max():
            ax.contour(speeds, obl, M, levels=[1.0], colors="k", linewidths=2.0)
    pad_v = 0.04 * (max(speeds) - min(speeds) or 100.0)
    pad_o = 0.06 * (max(obl) - min(obl) or 10.0)
    ax.set_xlim(min(speeds) - pad_v, max(speeds) + 2 * pad_v)
    ax.set_ylim(min(obl) - pad_o, max(obl) + 2 * pad_o)
    for r in rows:
        inside = r["inside_envelope"]
        ax.plot(r["velocity_m_s"], r["obliquity_deg"], "o", mfc="k" if inside else "none", mec="k")
        if r["margin"] is not None:
            ax.annotate(f"{r['margin']:.3g}", (r["velocity_m_s"], r["obliquity_deg"]), textcoords="offset points",
                        xytext=(4, 4), fontsize=8)
    for b in result["boundary"]:
        if b["boundary_speed_m_s"] is not None and b["attack_deg"] == rows[0]["attack_deg"]:
            ax.plot(b["boundary_speed_m_s"], b["obliquity_deg"], "kx", ms=9)
    ax.set_xlabel("striking speed (m/s)")
    ax.set_ylabel("obliquity (deg)")
    ax.set_title(f"charge safety ({result['explosive']}): the governing margin\n(line and x: margin 1; hollow "
                 "markers: outside the validated envelope)", fontsize=9)
