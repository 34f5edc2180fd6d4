# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: light
#       format_version: '1.5'
# ---

# # A tour of fepen's Python API
#
# This demo runs the paper's shot C3 twice, first with the rigid projectile and then with a coarse
# deformable one. It then loads a results directory back and plots both trajectories from the loaded
# results. Run it as a script (`python demos/api_tour.py [--out DIR]`), under MPI
# (`mpirun -n 2 python demos/api_tour.py`), or open it as a notebook with jupytext.
#
# The API has four calls and one scene type:
#
# - `fepen.Scene(source, sets=...)` builds a validated scene. The source can be a TOML file, TOML text
#   or a nested dict, and `sets` takes `--set`-style overrides.
# - `fepen.run(scene, out=None, comm=None)` runs it, exactly as `fepen run` does, and returns a `Result`.
# - `fepen.load(results_dir)` reads any finished run's directory back into a `Result`.
# - `fepen.sweep(spec, out=None)` runs many shots and returns their table as a pandas DataFrame
#   (demos/rigid_study.py).

# +
import argparse
import tempfile
from pathlib import Path

import matplotlib

import fepen

backend = matplotlib.get_backend()  # fepen draws on figures of its own: the notebook's backend stays

parser = argparse.ArgumentParser(description="A tour of fepen's Python API")
parser.add_argument("--out", default=None, help="where the runs go (default: a temporary directory)")
parser.add_argument("--size", type=float, default=0.004, help="element size of the deformable run (m)")
args, _ = parser.parse_known_args()  # (a notebook kernel adds arguments of its own)
# -

# ## A scene
#
# Every key is optional: the defaults are the paper's projectile, its 40 MPa concrete and shot C3.
# A nested dict reads like the TOML file it replaces. Bad input raises `fepen.InputError`, which
# names the key and what is allowed, before anything is meshed.

# +
from mpi4py import MPI  # noqa: E402 (a notebook imports where it first needs)

comm = MPI.COMM_WORLD
root = Path(args.out) if args.out else Path(comm.bcast(tempfile.mkdtemp(prefix="fepen-tour-") if comm.rank == 0
                                                      else None, root=0))
rigid = fepen.Scene({"impact": {"shot": "C3"}, "effects": {"fidelity": "rigid"}})
try:
    fepen.Scene({"impact": {"velocity": -5.0}})
except fepen.InputError as err:
    if comm.rank == 0:
        print("refused:", err)
# -

# ## A rigid shot
#
# `run` writes a results directory: `summary.json`, `history.csv` and the figures. The `Result` holds
# the summary as a dict and the history as a numpy structured array, one field per column of
# `history.csv`. The columns are in SI units or carry their unit in their name.

r1 = fepen.run(rigid, out=root / "rigid", comm=comm, force=True)  # force: a second tour replaces the first
assert matplotlib.get_backend() == backend, "fepen.run changed matplotlib's backend"
if comm.rank == 0:
    print(f"rigid: {r1.summary['outcome']}, Hy = {r1.summary['Hy_mm']:.1f} mm "
          f"(test {r1.summary['experiment']['Hy_mm']:g} mm), {len(r1.history)} history rows")

# ## A coarse deformable shot
#
# `with_sets` derives a new scene. The plastic projectile runs on every rank of `comm`. A 4 mm mesh
# keeps the tour short; the paper's resolution is about 1.2 mm.

plastic = rigid.with_sets(["effects.fidelity=plastic", f"mesh.size={args.size}", "run.output_interval=1e-4"])
r2 = fepen.run(plastic, out=root / "plastic", comm=comm, force=True)
if comm.rank == 0:
    print(f"plastic: {r2.summary['outcome']}, Hy = {r2.summary['Hy_mm']:.1f} mm, max PEEQ "
          f"{r2.summary['max_peeq']:.3g}, {r2.summary['cells']} cells on {r2.summary['ranks']} rank(s)")

# ## Loading a results directory back
#
# `load` needs only the directory, so it also reads results from the command line or from an
# earlier session. The nose depth in the last history row is the summary's `Hy_mm`.

# +
again = fepen.load(root / "plastic")
assert abs(again.history["nose_y_mm"][-1] - again.summary["Hy_mm"]) < 1e-6
if comm.rank == 0:
    print("loaded:", again)
    print("fields for ParaView:", again.fields)
    print("figures:", ", ".join(sorted(again.figures)))
# -

# ## A picture from the loaded results
#
# The trajectories of the nose tip, rigid against deformable, with the test's end point, drawn with pyplot as
# any of the notebook's own plots: fepen draws on figures of its own and leaves pyplot's backend alone, so this
# shows inline in a notebook (and is only saved, with Agg, when the tour runs as a script).

# +
import matplotlib.pyplot as plt  # noqa: E402

if comm.rank == 0:
    fig, ax = plt.subplots(figsize=(5, 4))
    for res, label in ((r1, "rigid"), (again, "plastic")):
        h = res.history
        ax.plot(h["nose_x_mm"], h["nose_y_mm"], label=label)
    e = again.summary["experiment"]
    ax.plot([e["Hx_mm"]], [e["Hy_mm"]], "ko", label="C3, test")
    ax.invert_yaxis()
    ax.set(xlabel="x along the face (mm)", ylabel="depth (mm)", title="shot C3, nose tip")
    ax.legend()
    fig.tight_layout()
    fig.savefig(root / "tour.png", dpi=100)
    print("written:", root / "tour.png")
    plt.show()
# -
