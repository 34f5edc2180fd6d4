"""``fepen validate``: the eight Table 1 shots with one parameter set, compared with the experiments.

Writes to DIR: one results directory per shot (DIR/C1 ...), validation.csv, validation.md (Table 1 with the
simulated values and errors), validation.png (simulated against measured nose and tail positions, and
the trajectories) and paths.png (the nose and tail paths of the oblique shots against the straight line and
the test's final projectile, fepen.post.paths; ``python -m fepen.post.paths`` puts several DIRs on one figure).
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np
from mpi4py import MPI

from fepen import scene as fscene
from fepen.data import SHOTS
from fepen.io import files
from fepen.post import figures, paths
from fepen.runs import run_in_directory, setup

FIELDS = ["shot", "v0_m_s", "obliquity_deg", "attack_deg", "Hx_mm", "Hy_mm", "Tx_mm", "Ty_mm", "Hx_exp_mm",
          "Hy_exp_mm", "Tx_exp_mm", "Ty_exp_mm", "nose_error", "tail_error", "outcome", "wall_s"]


def validate(scene_path, sets, out, comm=MPI.COMM_WORLD) -> list[dict]:
    """Run all shots (same scene, same --set overrides, only impact.shot changes).

    Returns:
        One dict per shot with the FIELDS.
    """
    base = [s for s in sets if not s.startswith("impact.")]
    for s in sets:
        if s.startswith("impact."):
            from fepen.errors import InputError

            raise InputError(s.split("=")[0], "validate sets impact.* from Table 1; drop this --set")
    scenes = {name: fscene.load(scene_path, [*base, f'impact.shot="{name}"']) for name in SHOTS}
    for sc in scenes.values():
        setup.check_supported(sc)
    from fepen.io import rundir

    with rundir.study_directory(out, comm, False, "validate", VALIDATE_NAMES):
        return _validate(scene_path, base, scenes, Path(out), comm)


#: what fepen validate writes into its folder (fepen.io.rundir.study_directory): each shot's run folder too
VALIDATE_NAMES = (*SHOTS, "validation.csv", "validation.md", "validation.png", "paths.png", "hazard_maps.png")


def _validate(scene_path, base: list[str], scenes: dict, out: Path, comm) -> list[dict]:
    """validate's body, in its claimed folder."""
    out = files.prepare(out, comm)
    rows = []
    summaries = _side_by_side(scene_path, base, scenes, out) if _parallel(scenes, comm) else {}
    for name, sc in scenes.items():
        if name in summaries:
            s = summaries[name]
        else:  # the study owns its shots' folders: each run replaces exactly what the one before wrote there
            s = run_in_directory(sc, out / name, comm, "force")
        e = SHOTS[name]
        rows.append({"shot": name, "v0_m_s": e.v0, "obliquity_deg": e.obliquity_deg, "attack_deg": e.attack_deg,
                     "Hx_mm": s["Hx_mm"], "Hy_mm": s["Hy_mm"], "Tx_mm": s["Tx_mm"], "Ty_mm": s["Ty_mm"],
                     "Hx_exp_mm": e.Hx_mm, "Hy_exp_mm": e.Hy_mm, "Tx_exp_mm": e.Tx_mm, "Ty_exp_mm": e.Ty_mm,
                     "nose_error": s["experiment"]["nose_error"], "tail_error": s["experiment"]["tail_error"],
                     "outcome": s["outcome"], "wall_s": s["wall_s"]})
    if comm.rank == 0:
        buf = io.StringIO()
        w = csv.DictWriter(buf, FIELDS)
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
        files.write_text(out / "validation.csv", buf.getvalue(), comm)
        files.write_text(out / "validation.md", table(rows, scenes["C1"]), comm)
        figure(rows, out)
        paths.paths_figure({scenes["C1"].effects.fidelity: out}, out / "paths.png")
        if all((out / r["shot"] / "hazard.csv").is_file() for r in rows):
            hazard_figure(out)
    return rows


def _parallel(scenes, comm) -> bool:
    """Shots side by side: one rank, a deformable projectile (rigid shots take a second), several cores."""
    import os

    fid = next(iter(scenes.values())).effects.fidelity
    return comm.size == 1 and fid != "rigid" and (os.cpu_count() or 1) > 1


def _side_by_side(scene_path, base: list[str], scenes, out: Path) -> dict:
    """Run each shot as its own ``fepen run`` process (the user's scene file and --set options, and the shot),
    as many at once as there are cores; a failing shot's last line in the error."""
    import json
    import os
    import subprocess
    import sys
    import tempfile
    import time

    todo = list(scenes)
    running = []
    workers = min(os.cpu_count() or 1, len(todo))
    while todo or running:
        while todo and len(running) < workers:
            name = todo.pop(0)
            argv = [sys.executable, "-m", "fepen", "run", *([str(scene_path)] if scene_path is not None else []),
                    *(a for s in base for a in ("--set", s)), "--set", f'impact.shot="{name}"',
                    "--out", str(out / name), "--force"]
            log = tempfile.TemporaryFile("w+")  # the shot's console, read back only when it fails
            running.append((name, subprocess.Popen(argv, stdout=log, stderr=subprocess.STDOUT), log))
        time.sleep(0.5)
        for item in list(running):
            name, proc, log = item
            if proc.poll() is not None:
                running.remove(item)
                log.seek(0)
                last = [ln for ln in log.read().splitlines() if ln.strip()][-1:]
                log.close()
                if proc.returncode != 0:
                    raise RuntimeError(f"shot {name} failed (exit {proc.returncode}): {' '.join(last)}; see "
                                       f"{out / name / 'fepen.log'}")
    return {name: json.loads((out / name / "summary.json").read_text()) for name in scenes}


def hazard_figure(out: Path) -> None:
    """Hazard maps (max surface PEEQ along the axis) overlaid: C2/C3/C6 (angle) and C3/C4/C5 (speed)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(12, 3.8))
    ax = fig.subplots(1, 2)
    for a, (group, what) in zip(ax, ((("C2", "C3", "C6"), "obliquity"), (("C3", "C4", "C5"), "speed"))):
        for name in group:
            d = np.loadtxt(Path(out) / name / "hazard.csv", delimiter=",", skiprows=1)
            e = SHOTS[name]
            a.plot(d[:, 0], d[:, 1], label=f"{name}: {e.v0:g} m/s, {e.obliquity_deg:g}°")
        a.set(xlabel="distance from the nose (mm)", ylabel="max surface PEEQ", title=f"hazard map by {what}")
        a.legend(fontsize=8)
    fig.tight_layout()
    figures.save_figure(fig, Path(out) / "hazard_maps.png", dpi=110)


def table(rows, sc) -> str:
    """Markdown Table 1 with the simulated values and the errors."""
    lines = [f"Fidelity: {sc.effects.fidelity}; crater: {sc.effects.crater}; separation: {sc.effects.separation}"
             f" (phi_min {sc.target.separation_angle_deg:g} deg); free surface: {sc.effects.free_surface}; "
             f"friction: {sc.effects.friction}; mesh {sc.mesh.size * 1e3:g} mm.", "",
             "| shot | v0 (m/s) | α (°) | ϑ (°) | Hx sim / test (mm) | Hy sim / test (mm) | Tx sim / test (mm) | "
             "Ty sim / test (mm) | nose error | tail error | outcome |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(
            f"| {r['shot']} | {r['v0_m_s']:g} | {r['obliquity_deg']:g} | {r['attack_deg']:g} | "
            f"{r['Hx_mm']:.1f} / {r['Hx_exp_mm']:g} | {r['Hy_mm']:.1f} / {r['Hy_exp_mm']:g} | "
            f"{r['Tx_mm']:.1f} / {r['Tx_exp_mm']:g} | {r['Ty_mm']:.1f} / {r['Ty_exp_mm']:g} | "
            f"{100 * r['nose_error']:.1f} % | {100 * r['tail_error']:.1f} % | {r['outcome']} |")
    ne = np.array([r["nose_error"] for r in rows])
    te = np.array([r["tail_error"] for r in rows])
    lines += ["", f"Mean nose error {100 * ne.mean():.1f} %, largest {100 * ne.max():.1f} %; mean tail error "
                  f"{100 * te.mean():.1f} %, largest {100 * te.max():.1f} %. Errors: |H_sim − H_test| / |H_test| "
                  "with H = (Hx, Hy), likewise T.", ""]
    return "\n".join(lines)


def figure(rows, out: Path) -> None:
    """validation.png: simulated against measured (Hy, Ty), (Hx, Tx), and the nose trajectories."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(15, 4.6))
    ax = fig.subplots(1, 3)
    for k, (a, b) in enumerate((("Hy", "Ty"), ("Hx", "Tx"))):
        for key, mark in ((a, "o"), (b, "s")):
            x = [r[f"{key}_exp_mm"] for r in rows]
            y = [r[f"{key}_mm"] for r in rows]
            ax[k].plot(x, y, mark, label=f"{key}")
            for r, xi, yi in zip(rows, x, y):
                ax[k].annotate(r["shot"], (xi, yi), fontsize=7)
        lim = max(max(r[f"{a}_exp_mm"], r[f"{a}_mm"]) for r in rows) * 1.1
        ax[k].plot([0, lim], [0, lim], "k:", lw=0.8)
        ax[k].plot([0, lim], [0, 1.06 * lim], "k:", lw=0.5)
        ax[k].plot([0, lim], [0, 0.94 * lim], "k:", lw=0.5)
        ax[k].set(xlabel="test (mm)", ylabel="simulation (mm)", title=f"{a}, {b} (dotted: ±6 %)")
        ax[k].legend(fontsize=8)
    for i, r in enumerate(rows):
        d = np.genfromtxt(Path(out) / r["shot"] / "history.csv", delimiter=",", names=True)
        ax[2].plot(d["nose_x_mm"], d["nose_y_mm"], color=f"C{i}", label=r["shot"])
        ax[2].plot([r["Hx_exp_mm"]], [r["Hy_exp_mm"]], "o", color=f"C{i}")
        ax[2].plot([r["Tx_exp_mm"]], [r["Ty_exp_mm"]], "s", color=f"C{i}", mfc="none")
    ax[2].invert_yaxis()
    ax[2].set(xlabel="x (mm)", ylabel="depth (mm)", title="nose trajectories; tests: o nose, □ tail",
              aspect="equal")
    ax[2].legend(fontsize=7, ncol=2)
    fig.tight_layout()
    figures.save_figure(fig, Path(out) / "validation.png", dpi=110)
