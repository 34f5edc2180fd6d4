"""Path figures of the oblique Table 1 shots: where the nose and the tail went, against the test and a straight line.

One panel per shot in the x–depth plane (mm, depth downward, equal axes): the target face, the straight line
from the impact point at the impact angle α (dashed, "straight at α"), the test's final projectile (Table 1's
tail (Tx, Ty) to nose (Hx, Hy), thick black) and, for each labelled results directory, the nose and tail
paths of its history.csv and its final projectile. Table 1 gives only the final positions, so the test has no
path. By default the shots with an obliquity of 5° or more (C1, C3, C4, C5, C6, C7), on a 2 × 3 grid.

``fepen validate`` writes DIR/paths.png of its own run. To put two validation directories on one figure:

    python -m fepen.post.paths OUT.png rigid=DIR1 deformable=DIR2 [--shots C6,C7]

each DIR being a ``fepen validate --out DIR`` (DIR/C1/history.csv ...). A missing directory or shot is
skipped: its panel keeps the test and the straight line.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from fepen.data import SHOTS

#: shots at this obliquity (degrees) or more are drawn by default
OBLIQUE_DEG = 5.0
#: the history columns a path needs
PATH_COLUMNS = ("nose_x_mm", "nose_y_mm", "tail_x_mm", "tail_y_mm")
TEST_COLOUR = "black"


def oblique_shots(min_deg: float = OBLIQUE_DEG) -> list[str]:
    """The Table 1 shots at an obliquity of min_deg or more, in table order."""
    return [name for name, s in SHOTS.items() if s.obliquity_deg >= min_deg]


def read_path(run_dir: Path) -> dict[str, np.ndarray] | None:
    """The nose and tail paths (mm) of a results directory's history.csv; None when it has none to give."""
    path = Path(run_dir) / "history.csv"
    if not path.is_file():
        return None
    try:
        data = np.atleast_1d(np.genfromtxt(path, delimiter=",", names=True))
    except (OSError, ValueError):
        return None
    if data.dtype.names is None or data.size == 0 or not set(PATH_COLUMNS) <= set(data.dtype.names):
        return None
    return {k: np.asarray(data[k], dtype=float) for k in PATH_COLUMNS}


def title(name: str) -> str:
    """A panel's title: "C7: 820 m/s, 20°"."""
    s = SHOTS[name]
    return f"{name}: {s.v0:.0f} m/s, {s.obliquity_deg:.3g}°"


def offsets(final, alpha_deg: float) -> tuple[float, float]:
    """(nose beyond the straight line (mm), axis angle from the face normal (°)) of a final projectile.

    Args:
        final: (Tx, Ty, Hx, Hy) in mm. alpha_deg: the impact angle from the normal.

    The first is Hx - Hy tan α: positive when the nose ended further along the face than the straight line at
    its depth (the path turned toward the face), negative when it turned down.
    """
    tx, ty, hx, hy = final
    return hx - hy * math.tan(math.radians(alpha_deg)), math.degrees(math.atan2(hx - tx, hy - ty))


def _panel(ax, name: str, paths: Mapping[str, dict], colours: Mapping[str, str]) -> None:
    """One shot: face, straight line, the test's final projectile, each run's paths and final projectile."""
    s = SHOTS[name]
    xs, ys = [0.0, s.Hx_mm, s.Tx_mm], [s.Hy_mm]
    for p in paths.values():
        xs += [p["nose_x_mm"].max(), p["tail_x_mm"][-1]]
        ys += [p["nose_y_mm"].max()]
    depth = 1.08 * max(ys)
    alpha = math.radians(s.obliquity_deg)
    ax.axhline(0.0, color="saddlebrown", lw=1.5, label="target face", gid="face", zorder=1)
    ax.plot([0.0, depth * math.tan(alpha)], [0.0, depth], "--", color="grey", lw=1.0, label="straight at α",
            gid="straight", zorder=2)
    test = (s.Tx_mm, s.Ty_mm, s.Hx_mm, s.Hy_mm)
    _projectile(ax, test, TEST_COLOUR, "test: final projectile (Table 1)", "test:final", lw=4.0)
    notes = ["nose past the straight line; final axis angle",
             "test: {:+.0f} mm; {:.1f}°".format(*offsets(test, s.obliquity_deg))]
    for label, p in paths.items():
        c = colours[label]
        ax.plot(p["nose_x_mm"], p["nose_y_mm"], "-", color=c, lw=1.3, label=f"{label}: nose path",
                gid=f"{label}:nose", zorder=4)
        ax.plot(p["tail_x_mm"], p["tail_y_mm"], ":", color=c, lw=1.3, label=f"{label}: tail path",
                gid=f"{label}:tail", zorder=4)
        final = (p["tail_x_mm"][-1], p["tail_y_mm"][-1], p["nose_x_mm"][-1], p["nose_y_mm"][-1])
        _projectile(ax, final, c, f"{label}: final projectile", f"{label}:final")
        notes.append("{}: {:+.0f} mm; {:.1f}°".format(label, *offsets(final, s.obliquity_deg)))
    x0, x1 = min(xs), max(xs)
    pad = 0.06 * max(x1 - x0, depth)
    # the x range follows from the depth's at equal scales (adjustable="datalim" widens it about the paths):
    # setting it too would be dropped, with a warning from matplotlib 3.8 on
    ax.set_ylim(depth + pad, -0.12 * depth)  # depth downward; the flight above the face cut short
    ax.set_aspect("equal", adjustable="datalim")
    ax.text(0.03, 0.02, "\n".join(notes), transform=ax.transAxes, fontsize=7.5, va="bottom", ha="left",
            bbox={"boxstyle": "round", "fc": "white", "ec": "0.7", "alpha": 0.9})
    ax.set_title(title(name), fontsize=11)
    ax.set_xlabel("x along the face (mm)")
    ax.set_ylabel("depth (mm)")
    ax.grid(True, lw=0.4, alpha=0.5)


def _projectile(ax, final, colour, label, gid, lw=2.5) -> None:
    """A final projectile (Tx, Ty, Hx, Hy): a thick segment, the tail an open square, the nose a filled circle."""
    tx, ty, hx, hy = final
    ax.plot([tx, hx], [ty, hy], "-", color=colour, lw=lw, solid_capstyle="butt", label=label, gid=gid, zorder=5)
    ax.plot([hx], [hy], "o", color=colour, ms=6, gid=f"{gid}:nose", zorder=6)
    ax.plot([tx], [ty], "s", color=colour, mfc="white", ms=6, mew=1.5, gid=f"{gid}:tail", zorder=6)


def paths_figure(runs: Mapping[str, Path], out: Path, shots: Sequence[str] | None = None) -> Path:
    """The path figure of the shots (default: the oblique ones) for the labelled validation directories.

    Args:
        runs: label -> a ``fepen validate`` directory (DIR/C1/history.csv ...), e.g. {"rigid": d1,
            "deformable": d2}. A directory or shot it lacks is skipped.
        out: the PNG to write.
        shots: the shots to draw (names not in Table 1 are skipped); default oblique_shots().

    Returns:
        out.
    """
    from fepen.post.figures import new_figure, save_figure

    fig = new_figure(size(shots))
    draw(fig, runs, shots)
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    return save_figure(fig, out)


def _names(shots: Sequence[str] | None) -> list[str]:
    return [n for n in (oblique_shots() if shots is None else shots) if n in SHOTS]


def size(shots: Sequence[str] | None = None) -> tuple[float, float]:
    """The path figure's size (inches) for the shots (as paths_figure's)."""
    n = len(_names(shots))
    ncols = min(3, max(n, 1))
    return (4.4 * ncols, 6.0 * max(math.ceil(n / ncols), 1) + 0.8)


def draw(fig, runs: Mapping[str, Path], shots: Sequence[str] | None = None) -> None:
    """Draw the path figure (as paths_figure's) on ``fig``, a Figure of ``size(shots)``."""
    names = _names(shots)
    colours = {label: f"C{i}" for i, label in enumerate(runs)}
    ncols = min(3, max(len(names), 1))
    nrows = max(math.ceil(len(names) / ncols), 1)
    height = 6.0 * nrows + 0.8
    axes = np.atleast_1d(fig.subplots(nrows, ncols, squeeze=False).ravel())
    for ax, name in zip(axes, names):
        paths = {label: p for label, d in runs.items() if (p := read_path(Path(d) / name)) is not None}
        _panel(ax, name, paths, colours)
    for ax in axes[len(names):]:
        fig.delaxes(ax)
    handles = {}
    for ax in fig.axes:
        for h, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, h)
    if handles:
        fig.legend(list(handles.values()), list(handles), loc="lower center", ncol=min(len(handles), 5),
                   fontsize=9, frameon=False)
    drawn = [label for label in runs if any(f"{label}: nose path" in h for h in handles)]
    which = ", ".join(drawn) if drawn else "no runs"
    fig.suptitle(f"Nose and tail paths of the oblique shots ({which}) against Table 1's final positions",
                 fontsize=12)
    fig.tight_layout(rect=(0, 0.55 / height, 1, 1 - 0.45 / height))


def _labelled(text: str) -> tuple[str, Path]:
    label, sep, d = text.partition("=")
    if not sep or not label or not d:
        raise argparse.ArgumentTypeError(f"expected LABEL=DIR, got {text!r}")
    return label, Path(d)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m fepen.post.paths OUT.png LABEL=DIR [LABEL=DIR ...] [--shots C1,C7]``."""
    parser = argparse.ArgumentParser(prog="python -m fepen.post.paths",
                                     description="Path figure of the oblique Table 1 shots from validation dirs.")
    parser.add_argument("out", type=Path, help="the PNG to write")
    parser.add_argument("runs", nargs="+", type=_labelled, metavar="LABEL=DIR",
                        help="a fepen validate directory and its label, e.g. rigid=results/validation")
    parser.add_argument("--shots", default=None, help="comma-separated shots (default: obliquity >= 5°)")
    args = parser.parse_args(argv)
    shots = [s.strip() for s in args.shots.split(",") if s.strip()] if args.shots else None
    out = paths_figure(dict(args.runs), args.out, shots)
    print(f"written: {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
