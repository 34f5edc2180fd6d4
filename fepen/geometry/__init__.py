"""The projectile: exact solid of revolution, gmsh model, distributed dolfinx mesh, tags, tetrahedra."""

__all__ = ["shape", "tags", "tetra", "frames", "gmsh_model", "mesh"]
