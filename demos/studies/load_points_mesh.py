"""The nose tip's plastic strain under the two samplings of the target's load (target.load_points), as the
mesh is refined: runs demos/studies/load_points_mesh.toml as a sweep and prints the table of
docs/validation.md ("How the load is sampled").

    .venv/bin/python demos/studies/load_points_mesh.py [--out results/load_points]   (mpirun -n N: N groups)

The tip's strain is the largest PEEQ of every cell within 2 mm of the original tip (hazard.csv's first bin);
the body's, the largest anywhere, with its distance from the tip (hazard.csv's bins); the depth and the final
axis from summary.json.
"""

import argparse
import json
from pathlib import Path

import numpy as np

import fepen

HERE = Path(__file__).resolve().parent


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="results/load_points")
    args = ap.parse_args(argv)
    table = fepen.sweep(HERE / "load_points_mesh.toml", out=args.out)
    print("| load points | mesh (mm) | cells | depth (mm) | final axis (deg) | tip PEEQ (0-2 mm) | largest PEEQ, "
          "where (mm from the tip) | first yield (us, mm from the tip) |")
    print("|---|---|---|---|---|---|---|---|")
    for _, row in table.sort_values(["target.load_points", "mesh.size"], ascending=[True, False]).iterrows():
        shot = Path(table.attrs["out"]) / "shots" / f"{int(row['shot']):05d}"
        haz = np.loadtxt(shot / "hazard.csv", delimiter=",", skiprows=1)
        s = json.loads((shot / "summary.json").read_text())
        k = int(np.argmax(haz[:, 3]))
        fy = s.get("first_yield")
        first = f"{fy['t_s'] * 1e6:.0f}, {fy['axial_from_nose_mm']:.1f}" if fy else "elastic"
        print(f"| {row['target.load_points']} | {row['mesh.size'] * 1e3:g} | {s['cells']} | {s['depth_mm']:.1f} | "
              f"{s['final_axis_angle_deg']:.1f} | {haz[0, 3]:.3f} | {haz[k, 3]:.3f} at {haz[k, 0]:.0f} | {first} |")


if __name__ == "__main__":
    main()
