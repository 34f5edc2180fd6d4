"""The hard cases at full size (run from the repository root).

    .venv/bin/python demos/hard_cases/run_all.py [--ranks 2] [--sizes 0.0025 0.004] [--out results/hard_cases]
                                                [--cases NAME ...] [--markdown FILE]

Runs every demos/hard_cases/*.toml with ``mpirun -n RANKS fepen run`` on each mesh size (the default mesh
first), without field output, and prints one row per run: outcome, energy error, steps, smallest step,
wall time, nose-tip and tail displacements, max PEEQ; the case beyond the method prints its one-line stop
message instead. With --markdown the table is also written as Markdown (docs/hard-cases.md quotes it).
"""

import argparse
import json
from pathlib import Path

from fepen.studies.processes import run_fepen_process

HERE = Path(__file__).resolve().parent


def run(case: Path, size: float, ranks: int, out: Path) -> dict:
    code, wall, message = run_fepen_process(["run", case, "--out", out, "--force", "--set", f"mesh.size={size}",
                                             "--set", "run.fields=false"], ranks)
    row = {"case": case.stem, "h_mm": size * 1e3, "exit": code, "process_s": wall}
    if code == 0:
        row.update(json.loads((out / "summary.json").read_text()))
    else:
        row["message"] = message
    return row


def table(rows, wall: bool = True) -> list[str]:
    """The cases' Markdown table, one row per run (with each run's wall time, unless ``wall`` is False: make
    docs' hard-case blocks leave the machine's figure out)."""
    cols = ["case", "h (mm)", "outcome", "energy error", "steps", "smallest step (ns)", *(["wall (s)"] * wall),
            "Hx (mm)", "Hy (mm)", "Tx (mm)", "Ty (mm)", "residual speed (m/s)", "max PEEQ"]
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for r in rows:
        if r["exit"] == 0:
            cells = [r["case"], f"{r['h_mm']:g}", r["outcome"], f"{r['energy_error']:.1e}", str(r["steps"]),
                     f"{r['dt_s'] * 1e9:.1f}", *((f"{r['wall_s']:.1f}",) if wall else ()),
                     *(f"{r[k]:.1f}" for k in ("Hx_mm", "Hy_mm", "Tx_mm", "Ty_mm", "residual_speed_m_s")),
                     f"{r['max_peeq']:.3f}"]
        else:
            cells = [r["case"], f"{r['h_mm']:g}", f"exit {r['exit']}: {r['message']}", *[""] * 3,
                     *((f"{r['process_s']:.1f}",) if wall else ()), *[""] * 6]
        lines.append("|" + "".join(f" {c} |" if c else " |" for c in cells))
    return lines


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--sizes", type=float, nargs="+", default=[0.0025, 0.004])
    ap.add_argument("--out", default="results/hard_cases")
    ap.add_argument("--cases", nargs="*")
    ap.add_argument("--markdown")
    args = ap.parse_args()
    cases = sorted(HERE.glob("*.toml"))
    if args.cases:
        cases = [c for c in cases if c.stem in args.cases]
    rows = []
    for case in cases:
        for size in args.sizes:
            if case.stem == "coarse_mesh" and size != args.sizes[0]:
                continue  # its mesh size is the point of the case: run it once, at 8 mm
            h = 0.008 if case.stem == "coarse_mesh" else size
            row = run(case, h, args.ranks, Path(args.out) / f"{case.stem}-{h * 1e3:g}mm")
            rows.append(row)
            print(table([row])[-1], flush=True)
    lines = table(rows)
    print("\n".join(lines))
    if args.markdown:
        Path(args.markdown).write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
