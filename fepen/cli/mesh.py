"""``fepen mesh [SCENE.toml] [--out DIR] [--set KEY=VALUE ...]``: the projectile's mesh only (fepen.api.mesh
writes mesh.json, mesh.xdmf, mesh_facets.xdmf, mesh.png and scene.toml), its metrics printed."""

from __future__ import annotations

from fepen.cli.common import say, scene_arguments

HELP = "build the projectile mesh only: mesh.json, mesh.xdmf, mesh.png"


def add_arguments(parser) -> None:
    scene_arguments(parser, "results/mesh")


def run(args) -> int:
    """Mesh the scene (fepen.api.mesh) and print its metrics."""
    from fepen import api
    from fepen import scene as fscene

    sc = fscene.load(args.scene, args.sets)
    # force: `fepen mesh` has always written its files among whatever --out holds (it has no --force option)
    from fepen.geometry import mesh as fmesh

    with fmesh.progress(True):  # gmsh's stages and the elapsed time, on a terminal
        info = api.mesh(sc, args.out, force=True)
    keys = ("cells", "nodes", "mass_kg", "volume_m3", "min_quality", "shortest_altitude_m", "stable_dt_s")
    say(*(f"{k} = {info[k]:.6g}" if isinstance(info[k], float) else f"{k} = {info[k]}" for k in keys),
        f"altitude_over_size = {info['altitude_over_size']:.4f}",
        f"written: {args.out}/mesh.json, mesh.xdmf, mesh_facets.xdmf (and .vtu), mesh.png")
    return 0
