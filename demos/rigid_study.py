# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: light
#       format_version: '1.5'
# ---

# # A striking-velocity study in a notebook
#
# Eleven rigid shots of the paper's projectile into its 40 MPa concrete, from 400 to 900 m/s, become a pandas
# table and a plot beside the paper's two tests at normal incidence (C2 and C8). The whole study takes a few
# seconds: rigid shots run in batches in this process. Run it as a script (`python demos/rigid_study.py
# [--out DIR]`) or open it as a notebook with jupytext; `make notebook` installs Jupyter beside Debian's
# matplotlib.
#
# `fepen.sweep(spec, out=None)` runs a sweep as `fepen sweep SWEEP.toml` does and returns its table
# (`sweep.csv`) as a DataFrame: one row per shot, the varied keys, the status and every summary figure.
# `spec` is a sweep file or, as here, its content as a dict (docs/studies.md).

# +
import argparse

import matplotlib
import matplotlib.pyplot as plt
import numpy as np

import fepen

parser = argparse.ArgumentParser(description="a rigid striking-velocity study")
parser.add_argument("--out", default=None, help="the sweep's results directory (default: a temporary one)")
args, _ = parser.parse_known_args()  # (a notebook kernel adds arguments of its own)
backend = matplotlib.get_backend()  # fepen draws on its own figures: this stays the notebook's
# -

# ## The study
#
# The base scene is the default one (shot C3's projectile and concrete) with the rigid projectile, turned to
# normal incidence: the default is C3's 10.5° obliquity, so the base sets `impact.obliquity_deg` and
# `impact.attack_deg` to 0. The grid varies the striking velocity.

speeds = np.linspace(400.0, 900.0, 11)
base = {"effects.fidelity": "rigid", "impact.obliquity_deg": 0.0, "impact.attack_deg": 0.0}
table = fepen.sweep({"base": base, "grid": {"impact.velocity": speeds.tolist()}}, out=args.out)
assert matplotlib.get_backend() == backend, "fepen changed the notebook's matplotlib backend"
table[["impact.velocity", "status", "outcome", "Hy_mm", "final_axis_angle_deg"]]  # noqa: B018 (a table)

# ## Against the tests
#
# Table 1 of the paper ships with fepen (`fepen.data.experiments`); C2 and C8 were fired within 0.6° of
# normal incidence, so the study's depth at their speeds is a prediction of theirs (the same as the rigid
# `fepen validate` gives for them, to the interpolation's and the 0.6°'s few tenths of a per cent).
# Forrestal's law makes the depth grow as the logarithm of 1 + c v², so it rises at every step of the grid and
# more slowly than v².

# +
from fepen.data import experiments  # noqa: E402 (a notebook imports where it first needs)

tests = [e for e in experiments.SHOTS.values() if e.obliquity_deg < 1.0]
fig, ax = plt.subplots(figsize=(5.5, 4))  # the notebook's own plot, in its own backend
ax.plot(table["impact.velocity"], table["Hy_mm"], "o-", label="fepen, rigid projectile")
ax.plot([e.v0 for e in tests], [e.Hy_mm for e in tests], "ks", label="tests C2, C8 (Table 1)")
ax.set(xlabel="striking velocity (m/s)", ylabel="penetration depth (mm)",
       title="rigid projectile into 40 MPa concrete, normal incidence")
ax.legend()
fig.tight_layout()
if args.out:
    fig.savefig(f"{args.out}/study.png", dpi=100)
depth = table["Hy_mm"].to_numpy()
rise = bool((np.diff(depth) > 0).all())
print(f"depth from {depth[0]:.0f} to {depth[-1]:.0f} mm, rising at every step: {rise}; depth ratio "
      f"{depth[-1] / depth[0]:.2f} against a speed-squared ratio {(speeds[-1] / speeds[0]) ** 2:.2f}")
axis = float(np.abs(table["final_axis_angle_deg"]).max())
print(f"normal incidence: obliquity 0 deg, attack 0 deg; the largest final axis angle {axis:.2g} deg")
for e in tests:
    here = np.interp(e.v0, table["impact.velocity"], depth)
    print(f"{e.name}: {e.v0:g} m/s at {e.obliquity_deg:g} deg, test {e.Hy_mm:g} mm, fepen {here:.0f} mm "
          f"({here / e.Hy_mm - 1:+.1%})")
plt.show()
# -
