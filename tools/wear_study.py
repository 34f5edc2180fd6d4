"""The studies of docs/wear.md: a striking-velocity sweep of a hard and a mild steel projectile, and Table 1
with wear and erosion on against the defaults. Prints the tables (markdown) and writes the figures.

    .venv/bin/python tools/wear_study.py sweep DIR [--run]
        DIR/{steel}-w{true,false}-{V}: scenes/mild-1300.toml with projectile.material.name, impact.velocity,
        effects.wear and 5 mm cells (erosion on); --run runs what is missing, one process at a time.
        Writes docs/img/wear-sweep.png and docs/img/wear-noses.png.
    .venv/bin/python tools/wear_study.py table1 WEAR_DIR BASE_DIR
        two `fepen validate` trees (wear and erosion on; the defaults). Writes docs/img/wear-trajectories.png.
"""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

STEELS = ("30crmnsini2a", "q235")
SPEEDS = (500, 700, 900, 1100, 1300)
ROOT = Path(__file__).resolve().parent.parent
IMG = ROOT / "docs" / "img"


def _summary(d: Path) -> dict | None:
    f = d / "summary.json"
    return json.loads(f.read_text()) if f.is_file() else None


def _run_sweep(out: Path) -> None:
    for steel in STEELS:
        for wear in ("true", "false"):
            for v in SPEEDS:
                d = out / f"{steel}-w{wear}-{v}"
                if _summary(d) is not None:
                    continue
                cmd = [sys.executable, "-m", "fepen", "run", str(ROOT / "scenes" / "mild-1300.toml"),
                       "--set", f'projectile.material.name="{steel}"', "--set", f"impact.velocity={v}",
                       "--set", f"effects.wear={wear}", "--set", "mesh.size=0.005", "--set", "run.fields=false",
                       "--out", str(d)]
                with open(f"{d}.log", "w") as log:
                    subprocess.run(cmd, stdout=log, stderr=subprocess.STDOUT, check=False)


def _fmt(s: dict | None, key: str, fmt: str) -> str:
    return format(s[key], fmt) if s is not None else "–"


def _profile(d: Path):
    rows = list(csv.DictReader(open(d / "nose_profile.csv")))
    out = {}
    for state in ("before", "after"):
        r = [x for x in rows if x["state"] == state]
        out[state] = (np.array([float(x["behind_tip_mm"]) for x in r]), np.array([float(x["radius_mm"]) for x in r]))
    return out


def sweep(out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    print("| steel | V (m/s) | Hy wear off (mm) | Hy wear on (mm) | mass loss (%) | length change (mm) | "
          "tip recession (mm) | max radius (mm) | eroded cells | max PEEQ | outcome |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    data = {}
    for steel in STEELS:
        for v in SPEEDS:
            on, off = _summary(out / f"{steel}-wtrue-{v}"), _summary(out / f"{steel}-wfalse-{v}")
            data[steel, v] = (on, off)
            if on is None and off is None:
                continue
            nose = on["nose_profile"] if on is not None else None
            print(f"| `{steel}` | {v} | {_fmt(off, 'Hy_mm', '.1f')} | {_fmt(on, 'Hy_mm', '.1f')} | "
                  f"{_fmt(on, 'mass_loss_percent', '.2f')} | {_fmt(on, 'length_change_mm', '.2f')} | "
                  f"{format(nose['tip_recession_mm'], '.2f') if nose else '–'} | "
                  f"{format(nose['max_radius_mm'], '.2f') if nose else '–'} | {_fmt(on, 'eroded_cells', 'd')} | "
                  f"{_fmt(on, 'max_peeq', '.3f')} | {on['outcome'] if on else '–'} |")
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    for steel, c in zip(STEELS, ("C0", "C3")):
        for wear, ls in (("on", "-"), ("off", "--")):
            pts = [(v, data[steel, v][0 if wear == "on" else 1]) for v in SPEEDS]
            pts = [(v, s) for v, s in pts if s is not None]
            if pts:
                ax[0].plot([p[0] for p in pts], [p[1]["Hy_mm"] for p in pts], ls, color=c, marker="o",
                           label=f"{steel}, wear {wear}")
            if wear == "on" and pts:
                ax[1].plot([p[0] for p in pts], [p[1]["mass_loss_percent"] for p in pts], ls, color=c, marker="o",
                           label=steel)
    ax[0].set(xlabel="striking velocity (m/s)", ylabel="depth Hy (mm)", title="depth, 35 MPa concrete, normal")
    ax[1].set(xlabel="striking velocity (m/s)", ylabel="mass loss (%)", title="mass loss, wear (η = 1) and erosion on")
    for a in ax:
        a.grid(alpha=0.3)
        a.legend(fontsize=8)
    fig.tight_layout()
    IMG.mkdir(exist_ok=True)
    fig.savefig(IMG / "wear-sweep.png", dpi=110)
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    for a, steel in zip(ax, STEELS):
        drawn = False
        for v, c in zip(SPEEDS, ("C0", "C1", "C2", "C3", "C4")):
            d = out / f"{steel}-wtrue-{v}"
            if not (d / "nose_profile.csv").is_file():
                continue
            p = _profile(d)
            if not drawn:
                a.plot(p["before"][0], p["before"][1], "k-", lw=2, label="before")
                drawn = True
            a.plot(p["after"][0], p["after"][1], "-", color=c, label=f"after, {v} m/s")
        a.set(xlabel="distance behind the original tip (mm)", title=f"{steel}: nose profile, wear and erosion on")
        a.set_xlim(-2, 60)
        a.grid(alpha=0.3)
        a.legend(fontsize=8)
    ax[0].set_ylabel("radius (mm)")
    fig.tight_layout()
    fig.savefig(IMG / "wear-noses.png", dpi=110)


def table1(wear_dir: Path, base_dir: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    print("| shot | Hy sim / test (mm) | mass loss (%) | length change (mm) | eroded cells | max PEEQ | "
          "nose error with wear (defaults) | tail error with wear (defaults) |")
    print("|---|---|---|---|---|---|---|---|")
    for shot in ("C1", "C2", "C3", "C4", "C5", "C6", "C7", "C8"):
        w, b = _summary(wear_dir / shot), _summary(base_dir / shot)
        if w is None or b is None:
            print(f"| {shot} | not run | | | | | | |")
            continue
        e, eb = w["experiment"], b["experiment"]
        print(f"| {shot} | {w['Hy_mm']:.1f} / {e['Hy_mm']:.1f} | {w['mass_loss_percent']:.2f} | "
              f"{w['length_change_mm']:.2f} | {w['eroded_cells']} | {w['max_peeq']:.3f} | "
              f"{100 * e['nose_error']:.1f} % ({100 * eb['nose_error']:.1f} %) | "
              f"{100 * e['tail_error']:.1f} % ({100 * eb['tail_error']:.1f} %) |")
    fig, ax = plt.subplots(1, 3, figsize=(12, 4.5))
    for a, shot in zip(ax, ("C5", "C7", "C8")):
        for d, ls, label in ((base_dir, "--", "defaults (wear off)"), (wear_dir, "-", "wear and erosion on")):
            f = d / shot / "history.csv"
            if not f.is_file() or _summary(d / shot) is None:
                continue
            h = np.genfromtxt(f, delimiter=",", names=True)
            a.plot(h["nose_x_mm"], h["nose_y_mm"], ls, label=f"nose, {label}")
            s = _summary(d / shot)
            a.plot([s["Tx_mm"], s["Hx_mm"]], [s["Ty_mm"], s["Hy_mm"]], ls, color="grey", lw=3, alpha=0.5)
        s = _summary(wear_dir / shot) or _summary(base_dir / shot)
        if s is not None:
            e = s["experiment"]
            a.plot([e["Tx_mm"], e["Hx_mm"]], [e["Ty_mm"], e["Hy_mm"]], "k-", lw=3, label="test: final tail–nose")
        a.set(xlabel="x (mm)", ylabel="depth y (mm)", title=shot)
        a.invert_yaxis()
        a.set_aspect("equal", adjustable="datalim")
        a.grid(alpha=0.3)
    ax[0].legend(fontsize=7)
    fig.tight_layout()
    IMG.mkdir(exist_ok=True)
    fig.savefig(IMG / "wear-trajectories.png", dpi=110)


def main(argv: list[str]) -> int:
    if len(argv) >= 2 and argv[0] == "sweep":
        out = Path(argv[1])
        if "--run" in argv:
            _run_sweep(out)
        sweep(out)
        return 0
    if len(argv) == 3 and argv[0] == "table1":
        table1(Path(argv[1]), Path(argv[2]))
        return 0
    print(__doc__)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
