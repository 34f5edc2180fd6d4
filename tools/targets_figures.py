"""The figures of docs/projectiles-and-targets.md: every nose family's mesh, the layered structure's
trajectory, and the rod into 6061-T6511 against Forrestal and Warren's closed form.

    python tools/targets_figures.py [--out docs/img] [--layered DIR] [--metal DIR]

--layered and --metal name results directories of demos/targets/layered_structure.py and metal_plate.py.
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402
from mpi4py import MPI  # noqa: E402

from fepen import scene  # noqa: E402
from fepen.runs import setup  # noqa: E402

FAMILIES = [("tangent ogive, CRH 3", []), ("secant ogive, CRH 4, 25 mm", ["projectile.nose='secant'",
                                                                          "projectile.crh=4.0",
                                                                          "projectile.nose_length=0.025"]),
            ("ogive with 8 mm meplat", ["projectile.meplat_diameter=0.008"]),
            ("cone, 30 mm", ["projectile.nose='cone'", "projectile.nose_length=0.03"]),
            ("hemisphere", ["projectile.nose='hemisphere'"]),
            ("ellipsoid, 30 mm", ["projectile.nose='ellipsoid'", "projectile.nose_length=0.03"]),
            ("flat", ["projectile.nose='flat'"]),
            ("ogive, boat-tail 20 mm to 18 mm", ["projectile.boattail_length=0.02",
                                                  "projectile.boattail_diameter=0.018"])]


def noses(out: Path) -> None:
    """Each family's default 2.5 mm mesh seen from the side: the outer facets of the near half."""
    fig, axes = plt.subplots(len(FAMILIES) // 2, 2, figsize=(11, 0.75 * len(FAMILIES)))
    axes = axes.T.ravel()
    for ax, (title, sets) in zip(axes, FAMILIES):
        pm = setup.mesh(scene.Scene(None, sets), MPI.COMM_SELF)
        x = pm.mesh.geometry.x
        facets = pm.facet_tags.find(11)
        pm.mesh.topology.create_connectivity(2, 0)
        f2v = pm.mesh.topology.connectivity(2, 0)
        tris = np.array([f2v.links(f) for f in facets])
        p = x[tris]
        near = p[:, :, 2].mean(axis=1) > 0
        ax.add_collection(PolyCollection(p[near][:, :, [1, 0]] * 1e3, facecolor="#c9d6e3", edgecolor="#34495e",
                                         linewidth=0.3))
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlim(-2, 146)
        ax.set_ylim(-13, 13)
        ax.set_title(f"{title}: {pm.mesh.topology.index_map(3).size_global} cells, cavity sized to 367 g",
                     fontsize=8, loc="left")
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(out / "nose-families.png", dpi=100)
    plt.close(fig)


def layered(out: Path, results: Path) -> None:
    """Nose depth and speed against time through the structure, the layers shaded."""
    s = __import__("json").loads((results / "summary.json").read_text())
    rows = list(csv.DictReader(open(results / "history.csv")))
    t = np.array([float(r["t_s"]) for r in rows]) * 1e3
    y = np.array([float(r["nose_y_mm"]) for r in rows]) / 1e3
    v = np.array([float(r["speed_m_s"]) for r in rows])
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.6))
    colours = {"concrete": "#bdc3c7", "soil": "#d7bf95"}
    for layer in s["layers"]:
        top = layer["top_m"]
        bottom = top + layer["thickness_m"] if layer["thickness_m"] else y.max() + 0.2
        a.axhspan(top, bottom, color=colours.get(layer["material"], "#ddd"), alpha=0.8)
        a.text(t.max() * 0.98, 0.5 * (top + min(bottom, top + 0.5)), layer["material"], ha="right", va="center",
               fontsize=8)
    a.plot(t, y, "k-")
    a.invert_yaxis()
    a.set_xlabel("t (ms)")
    a.set_ylabel("nose depth (m)")
    a.set_title("two 200 mm slabs, 1 m apart, over soil (800 m/s)", fontsize=9)
    b.plot(t, v, "k-")
    for layer in s["layers"]:
        for key, mark in (("entry", "v"), ("exit", "^")):
            if layer[f"{key}_time_s"] is not None:
                b.plot(layer[f"{key}_time_s"] * 1e3, layer[f"{key}_speed_m_s"], mark, color="C3")
    b.set_xlabel("t (ms)")
    b.set_ylabel("speed (m/s)")
    b.set_title("speed; entries (v) and exits (^) of the layers", fontsize=9)
    fig.tight_layout()
    fig.savefig(out / "layered-structure.png", dpi=130)
    plt.close(fig)


def metal(out: Path, rows: list[tuple[float, float, float]]) -> None:
    v, d, c = (np.array(x) for x in zip(*rows))
    fig, ax = plt.subplots(figsize=(5, 3.6))
    ax.plot(v, c, "k-", label="closed form (nose entry + Forrestal–Warren)")
    ax.plot(v, d, "o", color="C0", label="fepen, rigid, rings")
    ax.set_xlabel("striking speed (m/s)")
    ax.set_ylabel("depth (mm)")
    ax.set_title("CRH-3, 7.1 mm 4340 rod into 6061-T6511", fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "metal-plate.png", dpi=130)
    plt.close(fig)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--out", default="docs/img")
    p.add_argument("--layered", default=None)
    p.add_argument("--metal", default=None, help="'v,fepen_mm,closed_mm;...' rows printed by metal_plate.py")
    a = p.parse_args()
    out = Path(a.out)
    noses(out)
    if a.layered:
        layered(out, Path(a.layered))
    if a.metal:
        metal(out, [tuple(float(x) for x in row.split(",")) for row in a.metal.split(";")])


if __name__ == "__main__":
    main()
