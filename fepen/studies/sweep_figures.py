"""The pictures and the report of a sweep (fepen.studies.sweep): depth and outcome against each varied key;
for a Monte Carlo sample, histograms and quantiles."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

__all__ = ["write", "report", "quantiles", "key_axis", "measured_shot", "OUTCOME_COLOURS"]

OUTCOME_COLOURS = {"embedded": "tab:blue", "perforated": "tab:green", "ricochet": "tab:red", "ended": "tab:grey"}
#: the figures summarised by quantiles and histograms when present
FIGURES = ("depth_mm", "Hx_mm", "residual_speed_m_s", "charge_peak_acceleration_m_s2",
           "peak_acceleration_m_s2", "max_peeq", "mass_loss_percent")
#: axis labels of the summary figures, with their units
FIGURE_LABELS = {"depth_mm": "depth of penetration (mm)", "Hx_mm": "final nose x along the face (mm)",
                 "residual_speed_m_s": "residual speed (m/s)",
                 "charge_peak_acceleration_m_s2": "charge's peak acceleration (m/s²)",
                 "peak_acceleration_m_s2": "peak deceleration (m/s²)", "max_peeq": "largest PEEQ (−)",
                 "mass_loss_percent": "mass loss (%)"}
#: a scene unit: (the unit shown, the factor from the scene's value)
SHOWN_UNITS = {"Pa": ("MPa", 1e-6), "m": ("mm", 1e3), "kg": ("g", 1e3), "deg": ("°", 1.0)}
#: a varied key of names (impact.shot, target.material) is drawn when it has at most this many
MAX_CATEGORIES = 30
#: the Table 1 value of a summary figure (fepen.data.Shot attribute)
MEASURED = {"depth_mm": "Hy_mm", "Hx_mm": "Hx_mm"}


def _column(rows, name) -> np.ndarray:
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


def _summarised(cols, rows) -> list[str]:
    return [c for c in FIGURES if c in cols and np.isfinite(_column(rows, c)).any()]


def key_axis(key: str) -> tuple[str, float]:
    """(axis label with its unit, factor from the scene's SI value) of a varied scene key, e.g.
    ("target.compressive_strength (MPa)", 1e-6)."""
    from fepen.scene import SCHEMA

    unit = SCHEMA[key].unit if key in SCHEMA else ""
    shown, factor = SHOWN_UNITS.get(unit, (unit, 1.0))
    return (f"{key} ({shown})" if shown else f"{key} (−)"), factor


def measured_shot(sweep):
    """The Table 1 shot the sweep's base scene is (its striking speed, obliquity and attack angle those of a
    shot, and neither the projectile nor the target changed), or None: the sweep then varies keys around a
    measured test, whose values the figures mark."""
    from fepen import scene as fscene
    from fepen.data import SHOTS

    if any(k.startswith(("projectile.", "target.")) for k in sweep.base) or "impact.shot" in sweep.keys:
        return None
    try:
        sc = fscene.Scene(sweep.base)
    except Exception:  # noqa: BLE001 - a figure's mark, never an error
        return None
    if sc.get("impact.shot"):
        return SHOTS.get(sc.get("impact.shot"))
    v, ob, at = (sc.get(k) for k in ("impact.velocity", "impact.obliquity_deg", "impact.attack_deg"))
    for shot in SHOTS.values():
        if (shot.v0, shot.obliquity_deg, shot.attack_deg) == (v, ob, at):
            return shot
    return None


def _test_x(sweep, shot, key):
    """The test shot's value of a varied key (SI): its own impact values, else the base scene's."""
    from fepen import scene as fscene

    own = {"impact.velocity": shot.v0, "impact.obliquity_deg": shot.obliquity_deg,
           "impact.attack_deg": shot.attack_deg}
    if key in own:
        return own[key]
    value = fscene.Scene(sweep.base).get(key)
    return value if isinstance(value, (int, float)) and not isinstance(value, bool) else None


def _title(sweep, rows) -> str:
    fid = {r.get("fidelity") for r in rows} - {None, ""}
    if not fid:
        from fepen import scene as fscene

        try:
            fid = {fscene.Scene(sweep.base).get("effects.fidelity")}
        except Exception:  # noqa: BLE001
            fid = set()
    return f"{sweep.kind} sweep, {len(rows)} shots" + (f", {', '.join(sorted(fid))} fidelity" if fid else "")


def write(sweep, cols, rows, out: Path) -> list[Path]:
    """sweep.png (depth against each varied key, coloured by outcome, in the keys' units; a key of names
    one tick per name) and, for
    a Monte Carlo sample, histograms.png. The measured values are marked: a row's Table 1 depth when its
    shot is named (black rings), and the test the base scene is (measured_shot: a star at its own values, or
    a line on the histograms). Returns the files written."""
    from fepen.post.figures import new_figure, save_figure

    written = []
    keys = [k for k in sweep.keys if np.isfinite(_column(rows, k)).all()
            or len({str(r.get(k)) for r in rows}) <= MAX_CATEGORIES]  # numbers, or a few names (impact.shot)
    depth = _column(rows, "depth_mm")
    measured = _column(rows, "experiment.Hy_mm")
    outcome = [r.get("outcome", r["status"]) for r in rows]
    shot = measured_shot(sweep)
    title = _title(sweep, rows)
    if keys and np.isfinite(depth).any() and len(depth) == len(rows):
        n = len(keys)
        ncol = min(n, 3)
        fig = new_figure((4.4 * ncol, 3.6 * math.ceil(n / ncol) + 0.6))
        axes = fig.subplots(math.ceil(n / ncol), ncol, squeeze=False)
        small = len(rows) <= 200
        for ax, k in zip(axes.flat, keys):
            label, factor = key_axis(k)
            x = _column(rows, k) * factor
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
            elif shot is not None and (xt := _test_x(sweep, shot, k)) is not None:
                ax.plot([xt * factor], [shot.Hy_mm], "*", ms=14, color="gold", mec="k", zorder=5,
                        label=f"{shot.name} test: {shot.Hy_mm:g} mm")
            ax.set_xlabel(label)
            ax.set_ylabel(FIGURE_LABELS["depth_mm"])
            ax.grid(alpha=0.3)
        for ax in list(axes.flat)[n:]:
            ax.axis("off")
        axes.flat[0].legend(fontsize=7)
        fig.suptitle(title)
        fig.tight_layout()
        written.append(save_figure(fig, out / "sweep.png"))
    if sweep.kind == "monte-carlo":
        names = [c for c in _summarised(cols, rows) if np.nanmax(_column(rows, c)) > np.nanmin(_column(rows, c))][:4]
        if names:
            fig = new_figure((4.4 * len(names), 3.8))
            axes = fig.subplots(1, len(names), squeeze=False)
            for ax, name in zip(axes.flat, names):
                label = FIGURE_LABELS.get(name, name)
                v = _column(rows, name)
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
            written.append(save_figure(fig, out / "histograms.png"))
    return written


def report(sweep, rows, wall_s: float, ran: int, ranks: int, ranks_per_shot: int) -> str:
    """sweep.md: what ran, the outcomes, quantiles of the main figures."""
    statuses, outcomes = {}, {}
    for r in rows:
        statuses[r["status"]] = statuses.get(r["status"], 0) + 1
        if r["status"] == "ok":
            outcomes[r.get("outcome")] = outcomes.get(r.get("outcome"), 0) + 1
    lines = [f"# Sweep ({sweep.kind}, {len(sweep.shots)} shots)", "",
             f"Varied: {', '.join(f'`{k}`' for k in sweep.keys)}. Ran {ran} shots now "
             f"({len(sweep.shots) - ran} recorded before) on {ranks} rank(s), {ranks_per_shot} per shot, in "
             f"{wall_s:.1f} s.", "",
             "Status: " + ", ".join(f"{k} {v}" for k, v in sorted(statuses.items())) + ". Outcomes: "
             + ", ".join(f"{k} {v}" for k, v in sorted(outcomes.items(), key=lambda kv: str(kv[0]))) + ".", ""]
    cols = list(rows[0]) if rows else []
    names = [*[k for k in sweep.keys if np.isfinite(_column(rows, k)).all()], *_summarised(cols, rows)]
    if names:
        lines += ["| figure | count | mean | std | min | P5 | P50 | P95 | max |",
                  "|---|---|---|---|---|---|---|---|---|"]
        for name in names:
            q = quantiles(_column(rows, name))
            if q["count"]:
                label = f"`{name}`" + (" (perforated)" if name == "residual_speed_m_s" else "")
                lines.append(f"| {label} | {q['count']} | " + " | ".join(
                    f"{q[p]:.5g}" for p in ("mean", "std", "min", "P5", "P50", "P95", "max")) + " |")
    lines += ["", "Files: sweep.csv (one row per shot), costs.csv (wall time per shot), shots.jsonl (the records, "
              "full precision), sweep.json, sweep.png" + (", histograms.png" if sweep.kind == "monte-carlo" else "")
              + ".", ""]
    return "\n".join(lines)
