"""Taylor impact against published experiments, on three meshes (run from the repository root).

    .venv/bin/python demos/verification/taylor.py [--sizes 1.2 0.8 0.6] [--out results/taylor]

Cases (Johnson & Cook 1983, Proc. 7th Int. Symp. Ballistics, pp. 541-547, as compiled by B. Banerjee):
4340 steel at 208 m/s (final length 0.885 L0) and OFHC copper at 146 m/s (0.736 L0), L0 = 25.4 mm,
D0 = 7.62 mm. Prints the final length per mesh, its error against the experiment, and the convergence.
"""

import argparse
import json
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
CASES = {"4340 steel, 208 m/s": ("taylor_4340.toml", 0.885 * 25.4),
         "OFHC copper, 146 m/s": ("taylor_copper.toml", 0.736 * 25.4)}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", type=float, nargs="+", default=[1.2, 0.8, 0.6], help="element sizes (mm)")
    ap.add_argument("--out", default="results/taylor")
    ap.add_argument("--cases", nargs="+", default=list(CASES))
    args = ap.parse_args()
    print(f"{'case':24s} {'h_mm':>5} {'cells':>7} {'L_final_mm':>10} {'L_exp_mm':>8} {'error_%':>7} "
          f"{'energy_err':>10} {'wall_s':>7}")
    for name in args.cases:
        toml, measured = CASES[name]
        for h in args.sizes:
            out = Path(args.out) / f"{toml[:-5]}_{h:g}mm"
            r = subprocess.run([sys.executable, "-m", "fepen", "run", str(HERE / toml), "--out", str(out), "--force",
                                "--set", f"mesh.size={h * 1e-3}", "--set", "run.fields=false"],
                               capture_output=True, text=True)
            if r.returncode:
                print(r.stderr, file=sys.stderr)
                raise SystemExit(r.returncode)
            s = json.loads((out / "summary.json").read_text())
            err = 100 * (s["length_mm"] / measured - 1)
            print(f"{name:24s} {h:5.2f} {s['cells']:7d} {s['length_mm']:10.3f} {measured:8.2f} {err:+7.2f} "
                  f"{s['energy_error']:10.1e} {s['wall_s']:7.1f}", flush=True)


if __name__ == "__main__":
    main()
