"""The projectile: exact solid of revolution, its checks, mass rule and surface projection, drawn profiles, CAD
bodies, gmsh model, distributed dolfinx mesh, tags, tetrahedra."""

__all__ = ["shape", "profile", "checks", "mass_rule", "projection", "revolution", "cad", "tags", "tetra", "frames",
           "gmsh_model", "mesh", "mesh_cache", "partition"]
