# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: light
#       format_version: '1.5'
# ---

# # An ogive rod into 6061-T6511 aluminium: fepen against Forrestal and Warren
#
# The separation method was first applied to metal targets (Warren and Tabbara's 6061-T6511 aluminium
# simulations). fepen's metal law is Forrestal and Warren's spherical cavity expansion of an incompressible,
# power-law strain-hardening metal (docs/theory.md §16): σ_n = A(E/Y, n) Y + (3/2) ρ (v·n)². This demo fires a
# CRH-3, 7.1 mm, 71 mm solid 4340 steel rod (the projectile of those experiments, 20 g) into a semi-infinite
# 6061-T6511 target at 500–1100 m/s with the rigid fidelity, and compares the depth with the closed form
# (the nose entering, then Forrestal and Warren's logarithm), under the closed form's assumptions (no free face,
# σ_s at once in angle and in speed, no tunnel's wall: at 800 m/s the rigid step's onset speed alone moves the
# depth 1.2 %, docs/theory.md §8.7). With `--deformable` it also runs one
# deformable shot into a 60 mm plate, which the rod perforates.
#
# Run: `python demos/targets/metal_plate.py [--out DIR] [--deformable]`, or under `mpirun -n 2`.

# +
import argparse
import tempfile
from pathlib import Path

from mpi4py import MPI

import fepen
from fepen.geometry import revolution
from fepen.runs import setup
from fepen.studies import closed_forms

parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("--out", default=None)
parser.add_argument("--speeds", default="500,800,1100")
parser.add_argument("--deformable", action="store_true", help="also a deformable shot through a 60 mm plate")
parser.add_argument("--set", action="append", default=[])
args = parser.parse_args()
comm = MPI.COMM_WORLD
out = Path(args.out or comm.bcast(tempfile.mkdtemp(prefix="fepen-metal-") if comm.rank == 0 else None))

ROD = ["target.material='6061-T6511'", "projectile.diameter=0.0071", "projectile.length=0.071",
       "projectile.cavity_diameter=0", "projectile.material.name='aisi-4340'", "impact.obliquity_deg=0",
       "impact.attack_deg=0"]
# -

# The closed form. While the nose enters (tip depth z < ℓ), the force is σ_s π r(z)² + B ρ V² K(z),
# K(z) = ∫_0^z 2π r r'³/(1 + r'²) dζ, a linear ODE in V²; beyond, Forrestal and Warren's
# P = ℓ + m/(2π a² ρ N* B) ln(1 + N* B ρ V1²/σ_s). The free-surface rule is off here, as in the closed form.


def closed_form(scene):
    shape, law = setup.projectile_shape(scene), setup.target_law(scene)
    m = revolution.mass_properties(shape, scene.projectile.material.density)[0]
    r, slope, ln = closed_forms.tangent_ogive(shape.radius, shape.crh)
    return closed_forms.depth_with_nose_entry(r, slope, ln, m, law.density, law.B, law.sigma_s, shape.nose_factor(),
                                              scene.impact.velocity)


rows = []
for v in (float(x) for x in args.speeds.split(",")):
    # the closed form's own assumptions: no free face, the sharp switches in angle and speed, no tunnel's wall
    scene = fepen.Scene(None, sets=[*ROD, "effects.fidelity=rigid", "effects.free_surface=false",
                                    "effects.tunnel=false",
                                    f"impact.velocity={v}", *args.set])
    depth = fepen.run(scene, out=out / f"rigid-{v:.0f}", comm=comm, force=True).summary["depth_mm"]
    rows.append((v, depth, 1e3 * closed_form(scene)))

if comm.rank == 0:
    law = setup.target_law(scene)
    mass_g = 1e3 * revolution.mass_properties(setup.projectile_shape(scene), scene.projectile.material.density)[0]
    print(f"sigma_s = {law.sigma_s / 1e6:.1f} MPa (A = {law.sigma_s / law.Y:.3f}), B = {law.B:g}, mass {mass_g:.2f} g")
    print(f"{'v0_m_s':>7s} {'fepen_mm':>9s} {'closed_mm':>9s} {'error':>8s}")
    for v, d, c in rows:
        print(f"{v:7.0f} {d:9.2f} {c:9.2f} {100 * (d / c - 1):+7.3f}%")

# A deformable rod through a 60 mm plate: the residual speed and the rod's plastic strain.

if args.deformable:
    scene = fepen.Scene("[target]\nthickness = 0.06\n", sets=[*ROD, "impact.velocity=800", "mesh.size=0.0015",
                                                               *args.set])
    s = fepen.run(scene, out=out / "deformable", comm=comm, force=True).summary
    if comm.rank == 0:
        print(f"deformable: {s['outcome']}, residual {s['residual_speed_m_s']:.0f} m/s, max PEEQ {s['max_peeq']:.3f}")
