"""The pictures and the report of a sweep (fepen.studies.sweep): depth and outcome against each varied key;
for a Monte Carlo sample, histograms and quantiles."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

__all__ = ["write", "report", "quantiles", "OUTCOME_COLOURS"]

OUTCOME_COLOURS = {"embedded": "tab:blue", "perforated": "tab:green", "ricochet": "tab:red", "ended": "tab:grey"}
#: the figures summarised by quantiles and histograms when present
FIGURES = ("depth_mm", "Hx_mm", "residual_speed_m_s", "charge_peak_acceleration_m_s2",
           "peak_acceleration_m_s2", "max_peeq", "mass_loss_percent")


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


def write(sweep, cols, rows, out: Path) -> list[Path]:
    """sweep.png (depth against each numeric varied key, coloured by outcome) and, for a Monte Carlo
    sample, histograms.png. Returns the files written."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    written = []
    keys = [k for k in sweep.keys if np.isfinite(_column(rows, k)).all()]
    depth = _column(rows, "depth_mm")
    outcome = [r.get("outcome", r["status"]) for r in rows]
    if keys and np.isfinite(depth).any() and len(depth) == len(rows):
        n = len(keys)
        ncol = min(n, 3)
        fig, axes = plt.subplots(math.ceil(n / ncol), ncol, figsize=(4.2 * ncol, 3.4 * math.ceil(n / ncol)),
                                 squeeze=False)
        small = len(rows) <= 200
        for ax, k in zip(axes.flat, keys):
            x = _column(rows, k)
            for name in sorted(set(outcome)):
                m = np.array([o == name for o in outcome])
                ax.plot(x[m], depth[m], "o" if small else ".", ms=5 if small else 2, alpha=0.8 if small else 0.4,
                        color=OUTCOME_COLOURS.get(name, "k"), label=f"{name} ({m.sum()})")
            ax.set_xlabel(k)
            ax.set_ylabel("depth (mm)")
            ax.grid(alpha=0.3)
        for ax in list(axes.flat)[n:]:
            ax.axis("off")
        axes.flat[0].legend(fontsize=8)
        fig.suptitle(f"{sweep.kind} sweep, {len(rows)} shots")
        fig.tight_layout()
        fig.savefig(out / "sweep.png", dpi=110)
        plt.close(fig)
        written.append(out / "sweep.png")
    if sweep.kind == "monte-carlo":
        names = _summarised(cols, rows)[:4]
        if names:
            fig, axes = plt.subplots(1, len(names), figsize=(4.2 * len(names), 3.4), squeeze=False)
            for ax, name in zip(axes.flat, names):
                v = _column(rows, name)
                v = v[np.isfinite(v)]
                q = quantiles(v)
                ax.hist(v, bins=min(60, max(10, int(np.sqrt(len(v))))), color="tab:blue", alpha=0.75)
                for p, style in (("P5", ":"), ("P50", "-"), ("P95", ":")):
                    ax.axvline(q[p], color="k", ls=style, lw=1)
                ax.set_xlabel(name + (" (perforated)" if name == "residual_speed_m_s" else ""))
                ax.set_ylabel("shots")
                ax.set_title(f"P5 {q['P5']:.4g}, P50 {q['P50']:.4g}, P95 {q['P95']:.4g}", fontsize=9)
            fig.suptitle(f"Monte Carlo, {len(rows)} shots")
            fig.tight_layout()
            fig.savefig(out / "histograms.png", dpi=110)
            plt.close(fig)
            written.append(out / "histograms.png")
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
