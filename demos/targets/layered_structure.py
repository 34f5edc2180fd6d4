# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: light
#       format_version: '1.5'
# ---

# # A layered structure: two concrete slabs 1 m apart, over soil
#
# The paper's projectile (CRH 3, 367 g, D = 23.6 mm) strikes a structure at 800 m/s, normal incidence:
# a 200 mm slab of 40 MPa concrete, 1 m of air, a second 200 mm slab, 1 m of air, then soil
# (docs/projectiles-and-targets.md). Each slab perforated leaves a crater at its entry face and a free
# rear face; the projectile crosses the gaps unloaded and enters the next layer at the speed it left the last.
#
# Run it as a script (`python demos/targets/layered_structure.py [--out DIR] [--fidelity rigid|plastic]`) or
# under MPI (`mpirun -n 2 python demos/targets/layered_structure.py`). The default is the rigid fidelity,
# a few seconds; the deformable one crosses the 2.4 m of slabs and air in minutes.

# +
import argparse
import tempfile
from pathlib import Path

from mpi4py import MPI

import fepen

parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("--out", default=None, help="results directory (default: a temporary one)")
parser.add_argument("--fidelity", default="rigid", choices=["rigid", "elastic", "plastic"])
parser.add_argument("--set", action="append", default=[], help="extra KEY=VALUE scene overrides")
args = parser.parse_args()
comm = MPI.COMM_WORLD
out = Path(args.out or comm.bcast(tempfile.mkdtemp(prefix="fepen-layers-") if comm.rank == 0 else None))
# -

# The structure, as a scene file would give it: one `[[target.layers]]` table per layer, front to back.
# The last layer has no thickness: it is semi-infinite.

STRUCTURE = """
[impact]
velocity = 800.0
obliquity_deg = 0.0
attack_deg = 0.0

[[target.layers]]
material = "concrete"
thickness = 0.2
gap = 1.0

[[target.layers]]
material = "concrete"
thickness = 0.2
gap = 1.0

[[target.layers]]
material = "soil"
"""

scene = fepen.Scene(STRUCTURE, sets=[f"effects.fidelity={args.fidelity}", *args.set])
result = fepen.run(scene, out=out, comm=comm, force=True)

# Per layer: when and how fast the nose entered it, and when the whole projectile had left it.

if comm.rank == 0:
    s = result.summary
    print(f"outcome: {s['outcome']}, depth in the soil {s['depth_in_last_layer_mm']:.0f} mm, "
          f"total {s['depth_mm']:.0f} mm")
    print(f"{'layer':10s} {'top_m':>6s} {'entry_us':>9s} {'entry_m_s':>9s} {'exit_us':>9s} {'exit_m_s':>9s}")
    for row in s["layers"]:
        def cell(v, scale=1.0):
            return f"{v * scale:9.1f}" if v is not None else f"{'-':>9s}"
        print(f"{row['material']:10s} {row['top_m']:6.2f} {cell(row['entry_time_s'], 1e6)} "
              f"{cell(row['entry_speed_m_s'])} {cell(row['exit_time_s'], 1e6)} {cell(row['exit_speed_m_s'])}")
    print(f"results: {out}")
