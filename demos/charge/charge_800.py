"""The paper's charged projectile at 800 m/s (Section 3.4), tied against frictional (run from the root).

    .venv/bin/python demos/charge/charge_800.py [--ranks 2] [--out results/charge] [--docs docs/img]
                                                [--quick] [--set KEY=VALUE ...]

Runs demos/charge/charge_800.toml twice with ``mpirun -n RANKS fepen run``: the charge bonded to the
shell (charge.contact = "tied") and in frictional contact with it ("frictional", μ = 0.1). Each run writes
its own pictures (stress_maps.png, cross_sections.png, charge_histories.png, and for the frictional one
interface.png; fields.xdmf for ParaView). Here: both side by side in tied_vs_frictional.png, and a table
of what the contact changes: peak accelerations of shell and charge (filtered as instrumented tests are,
and raw) with when and at which nose depth, the charge's largest equivalent stress and PEEQ and where,
the charge's axial stress at the front of its axis, friction dissipation, gap and slip.
--docs DIR copies the figures into DIR as charge-*.png (docs/charge.md shows them); --quick: a 4 mm mesh
and the first 200 us (for tests).
"""

import argparse
import json
import shutil
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
CONTACTS = ("tied", "frictional")


def run(contact: str, out: Path, ranks: int, sets: list[str]) -> dict:
    from fepen.studies.processes import run_fepen_process

    args = ["run", str(HERE / "charge_800.toml"), "--out", str(out), "--force", "--set", f'charge.contact="{contact}"']
    for s in sets:
        args += ["--set", s]
    code, wall, last = run_fepen_process(args, ranks)
    if code:
        print(f"{contact}: fepen run failed ({code}): {last}", file=sys.stderr)
        raise SystemExit(code)
    summary = json.loads((out / "summary.json").read_text())
    summary["demo_wall_s"] = wall
    return summary


def row(contact: str, s: dict, out: Path) -> dict:
    """The figures compared."""
    pk = s["peak_accelerations"]
    ch = s["charge"]["stress_maps"]["x-y (plane of incidence)"]["charge"]
    sh = s["charge"]["stress_maps"]["x-y (plane of incidence)"]["shell"]
    sec = np.genfromtxt(out / "charge_sections.csv", delimiter=",", names=True)
    hist = np.genfromtxt(out / "history.csv", delimiter=",", names=True)
    r = {"contact": contact, "depth_mm": s["Hy_mm"], "outcome": s["outcome"],
         "shell_peak_g": pk["shell_acc"]["filtered_g"], "shell_peak_t_us": pk["shell_acc"]["t_s"] * 1e6,
         "shell_peak_depth_mm": pk["shell_acc"]["nose_depth_mm"], "shell_raw_peak_g": pk["shell_acc"]["raw_peak_g"],
         "charge_peak_g": pk["charge_acc"]["filtered_g"], "charge_peak_t_us": pk["charge_acc"]["t_s"] * 1e6,
         "charge_peak_depth_mm": pk["charge_acc"]["nose_depth_mm"], "charge_raw_peak_g": pk["charge_acc"]["raw_peak_g"],
         "maps_t_us": s["charge"]["stress_maps"]["t_s"] * 1e6,
         "charge_vm_max_MPa": ch["von_mises_max_Pa"] * 1e-6, "charge_vm_at_mm": ch["von_mises_max_at_mm"],
         "charge_peeq_max": ch.get("peeq_max", 0.0), "charge_peeq_at_mm": ch.get("peeq_max_at_mm"),
         "shell_vm_max_MPa": sh["von_mises_max_Pa"] * 1e-6, "shell_vm_at_mm": sh["von_mises_max_at_mm"],
         "axis_front_min_MPa": float(sec["axis0_axial_Pa"].min()) * 1e-6,
         "axis_mid_min_MPa": float(sec["axis2_axial_Pa"].min()) * 1e-6,
         "energy_error": s["energy_error"], "wall_s": s["wall_s"]}
    cs = s.get("charge_safety") or {}  # the safety verdict (docs/charge.md, "Will the charge survive?")
    r.update(safety_governing=cs.get("governing"), safety_margin=cs.get("margin"),
             strength_margin=(cs.get("strength") or {}).get("margin"),
             tension_margin=(cs.get("tension") or {}).get("margin"))
    if "friction_J" in hist.dtype.names:
        r.update(friction_J=float(hist["friction_J"][-1]), slip_max_mm=float(hist["interface_slip_max_mm"].max()),
                 gap_max_mm=float(hist["interface_gap_max_mm"].max()),
                 penetration_max_mm=float(hist["interface_penetration_max_mm"].max()))
    return r


def compare(outs: dict, path: Path) -> None:
    """tied_vs_frictional.png."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 4, figsize=(19, 4))
    for contact, ls in zip(CONTACTS, ("--", "-")):
        out = outs[contact]
        acc = np.genfromtxt(out / "accelerations.csv", delimiter=",", names=True)
        sec = np.genfromtxt(out / "charge_sections.csv", delimiter=",", names=True)
        t, ts = acc["t_s"] * 1e6, sec["t_s"] * 1e6
        ax[0].plot(t, acc["shell_acc_filtered_g"] / 1e3, ls, color="C0", label=f"shell, {contact}")
        ax[0].plot(t, acc["charge_acc_filtered_g"] / 1e3, ls, color="C3", label=f"charge, {contact}")
        ax[1].plot(t, acc["charge_acc_g"] / 1e3, ls, color="C3" if contact == "frictional" else "k", lw=0.6,
                   label=f"charge raw, {contact}")
        for k, colour in ((0, "C0"), (2, "C2"), (4, "C4")):
            ax[2].plot(ts, sec[f"axis{k}_axial_Pa"] / 1e6, ls, color=colour, lw=0.8, label=f"axis {k}, {contact}")
        ax[3].plot(ts, sec["front_r90_shear_Pa"] / 1e6, ls, color="C1", lw=0.8, label=f"front r 90 %, {contact}")
        ax[3].plot(ts, sec["mid_r90_shear_Pa"] / 1e6, ls, color="C5", lw=0.8, label=f"mid r 90 %, {contact}")
    ax[0].set(xlabel="t (us)", ylabel="axial acceleration (1000 g)", title="filtered (10 kHz)")
    ax[1].set(xlabel="t (us)", ylabel="axial acceleration (1000 g)", title="charge, raw", xlim=(0, 400))
    ax[2].set(xlabel="t (us)", ylabel="axial stress (MPa)", title="charge axis: 0 front, 2 middle, 4 rear")
    ax[3].set(xlabel="t (us)", ylabel="shear stress (MPa)", title="charge near the wall (0.9 R)")
    for a in ax:
        a.legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--out", default="results/charge")
    ap.add_argument("--docs", default=None, help="copy the figures here as charge-*.png")
    ap.add_argument("--quick", action="store_true", help="4 mm mesh, first 200 us")
    ap.add_argument("--set", dest="sets", action="append", default=[])
    args = ap.parse_args()
    sets = list(args.sets) + (["mesh.size=0.004", "run.end_time=2e-4"] if args.quick else [])
    base = Path(args.out)
    outs, rows = {}, []
    for contact in CONTACTS:
        outs[contact] = base / contact
        rows.append(row(contact, run(contact, outs[contact], args.ranks, sets), outs[contact]))
    compare(outs, base / "tied_vs_frictional.png")
    (base / "comparison.json").write_text(json.dumps(rows, indent=1))
    keys = [k for k in rows[1] if k != "contact"]
    print("positions (..._at_mm): (behind the nose tip along the axis, across it in the plane), deformed, mm")
    print(f"{'':24s}" + "".join(f"{r['contact']:>22s}" for r in rows))
    for k in keys:
        cells = []
        for r in rows:
            v = r.get(k, "-")
            if isinstance(v, list):
                v = "(" + ", ".join(f"{c:.1f}" for c in v) + ")"
            cells.append(f"{v:>22.6g}" if isinstance(v, float) else f"{str(v):>22s}")
        print(f"{k:24s}" + "".join(cells))
    if args.docs:
        docs = Path(args.docs)
        docs.mkdir(parents=True, exist_ok=True)
        shutil.copy(base / "tied_vs_frictional.png", docs / "charge-tied-vs-frictional.png")
        for contact in CONTACTS:
            for name in ("stress_maps", "cross_sections", "charge_histories"):
                shutil.copy(outs[contact] / f"{name}.png", docs / f"charge-{contact}-{name.replace('_', '-')}.png")
        shutil.copy(outs["frictional"] / "interface.png", docs / "charge-frictional-interface.png")


if __name__ == "__main__":
    main()
