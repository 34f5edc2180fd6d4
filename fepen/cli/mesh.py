"""``fepen mesh [SCENE.toml] [--out DIR] [--set KEY=VALUE ...]``: the projectile's mesh only (fepen.api.mesh
writes mesh.json, mesh.xdmf, mesh_facets.xdmf, mesh.png and scene.toml), its metrics printed."""

from __future__ import annotations

from fepen.cli.common import say, scene_arguments, written_line

HELP = "build the projectile mesh only: mesh.json, mesh.xdmf, mesh.png"


def add_arguments(parser) -> None:
    scene_arguments(parser, "results/mesh")
    parser.add_argument("--force", action="store_true",
                        help="when --out holds a run's results, remove them first (exactly the files that run wrote); "
                             "an earlier mesh's files are replaced without it")


def run(args) -> int:
    """Mesh the scene (fepen.api.mesh) and print its metrics."""
    from fepen import api
    from fepen import scene as fscene

    sc = fscene.load(args.scene, args.sets)
    from fepen.geometry import mesh as fmesh

    with fmesh.progress(True):  # gmsh's stages and the elapsed time, on a terminal
        info = api.mesh(sc, args.out, force=args.force)
    keys = ("cells", "nodes", "mass_kg", "volume_m3", "min_quality", "shortest_altitude_m", "stable_dt_s")
    say(*(f"{k} = {info[k]:.6g}" if isinstance(info[k], float) else f"{k} = {info[k]}" for k in keys),
        f"altitude_over_size = {info['altitude_over_size']:.4f}",
        written_line(args.out))
    return 0
