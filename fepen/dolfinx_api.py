"""The one place fepen touches dolfinx's API (issue 34): dolfinx 0.5.2 (Debian bookworm) and the current release
(0.11), each call here in the form the running version takes, on public API where that version has it.

Imported lazily (``import fepen`` loads no dolfinx). ``SUPPORTED`` names the versions fepen runs on;
``check_version`` refuses any other in one line.
"""

from __future__ import annotations

import functools

import numpy as np

# MPI before dolfinx: PyPI's dolfinx 0.11 links libmpi.so.12 without a search path to the MPICH wheel that mpi4py
# loads; with mpi4py's MPI already loaded, dolfinx's import finds it (docs/install.md)
from mpi4py import MPI

__all__ = ["SUPPORTED", "TRY_UNSUPPORTED", "version", "modern", "check_version", "gmsh_io", "gmsh_topology",
           "model_to_mesh", "cell_perm", "tet_mesh", "entity_tags", "adjacency_int32", "vector_space",
           "tensor_dg0_space", "cell_dofs", "geometry_dofs", "new_vector", "scatter_reverse_add", "pack",
           "assemble_into", "quiet", "function", "internal_force_form", "exterior_facets", "write_mesh_xdmf",
           "versions", "stack"]

#: the dolfinx releases fepen is tested with (docs/install.md): (major, minor)
SUPPORTED = ((0, 5), (0, 11))


@functools.lru_cache(maxsize=1)
def version() -> tuple:
    """dolfinx's (major, minor, patch) as ints (a post-release suffix dropped)."""
    import dolfinx

    parts = dolfinx.__version__.split(".")[:3]
    return tuple(int("".join(ch for ch in p if ch.isdigit()) or 0) for p in parts)


def modern() -> bool:
    """True for the current release's API (0.10 and later), False for 0.5."""
    return version()[:2] >= (0, 10)


#: the environment variable that lets a run try an unsupported dolfinx (its value: "try")
TRY_UNSUPPORTED = "FEPEN_UNSUPPORTED_DOLFINX"


def check_version() -> None:
    """InputError (key "dolfinx") naming the supported releases when this dolfinx is not one of them, unless
    $FEPEN_UNSUPPORTED_DOLFINX is "try": then one warning (logger "fepen", rank 0) and the run goes on, in the
    0.5 form of each call below 0.10 and in the 0.11 form from 0.10 on (its numbers unchecked)."""
    import logging
    import os

    from fepen.errors import InputError

    if version()[:2] in SUPPORTED:
        return
    names = " and ".join(f"{a}.{b}" for a, b in SUPPORTED)
    this = ".".join(map(str, version()))
    if os.environ.get(TRY_UNSUPPORTED) == "try":
        if MPI.COMM_WORLD.rank == 0:
            logging.getLogger("fepen").warning(f"dolfinx {this} is not supported (fepen runs on dolfinx {names}): "
                                               f"tried as {TRY_UNSUPPORTED}=try asks; check its numbers")
        return
    raise InputError("dolfinx", f"version {this} is not supported: fepen runs on dolfinx {names} (docs/install.md; "
                                f"{TRY_UNSUPPORTED}=try runs it all the same)")


def gmsh_io():
    """dolfinx's gmsh module: ``dolfinx.io.gmshio`` (0.5), ``dolfinx.io.gmsh`` (0.10 on)."""
    if modern():
        from dolfinx.io import gmsh as g
    else:
        from dolfinx.io import gmshio as g
    return g


def gmsh_topology(model) -> dict:
    """{gmsh element type: {"topology", "cell_data"}} of the model's marked elements (0.11 returns the physical
    groups beside it)."""
    topo = gmsh_io().extract_topology_and_markers(model)
    return topo[0] if isinstance(topo, tuple) else topo


def model_to_mesh(model, comm, rank: int = 0):
    """dolfinx's own gmsh model to mesh (its default partitioner; for the tests' simple bodies): the mesh."""
    out = gmsh_io().model_to_mesh(model, comm, rank, gdim=3)
    return out.mesh if hasattr(out, "mesh") else out[0]


def cell_perm(name: str, nodes: int) -> list:
    """The permutation from gmsh's node order to dolfinx's for a cell ("tetrahedron", "triangle")."""
    from dolfinx import mesh

    return gmsh_io().cell_perm_array(getattr(mesh.CellType, name), nodes)


def tet_mesh(comm, cells: np.ndarray, x: np.ndarray, partitioner):
    """A distributed mesh of linear tetrahedra from rank 0's cells (dolfinx order) and nodes.

    Args:
        comm: the communicator. cells, x: the cells (n, 4, int64) and node coordinates (m, 3) (empty on the
            other ranks). partitioner: a graph partitioner (comm, nparts, graph, ghosting) -> AdjacencyList_int32.
    """
    from dolfinx import cpp

    if modern():
        from dolfinx import mesh as dmesh

        domain = gmsh_io().ufl_mesh(4, 3, np.float64)
        # shared_facet: the partitioner is asked for ghosts (ghosting=True), as 0.5's create_mesh asks it; a split
        # wall's charge node then finds its shell twin on its own rank (fepen.solver.shell_charge)
        part = dmesh.create_cell_partitioner(partitioner, dmesh.GhostMode.shared_facet, 2)
        return dmesh.create_mesh(comm, cells, domain, x, partitioner=part)
    g = gmsh_io()
    return g.create_mesh(comm, cells, x, g.ufl_mesh(4, 3), partitioner=cpp.mesh.create_cell_partitioner(partitioner))


def entity_tags(mesh, dim: int, entities: np.ndarray, values: np.ndarray):
    """MeshTags of dimension ``dim`` from rank 0's entities (by input node index) and their values."""
    from dolfinx.mesh import meshtags_from_entities

    if modern():
        from dolfinx import graph, io

        local, vals = io.distribute_entity_data(mesh, dim, entities, values)
        mesh.topology.create_connectivity(dim, 0)
        return meshtags_from_entities(mesh, dim, graph.adjacencylist(local), vals.astype(np.int32))
    from dolfinx import cpp

    local, vals = cpp.io.distribute_entity_data(mesh._mesh, dim, entities, values)
    mesh.topology.create_connectivity(dim, 0)
    return meshtags_from_entities(mesh, dim, cpp.graph.AdjacencyList_int32(local), vals.astype(np.int32))


def adjacency_int32(data: np.ndarray, offsets: np.ndarray):
    """The C++ AdjacencyList_int32 a partitioner returns (dolfinx calls a Python partitioner from C++ and takes
    the C++ list back, on 0.11 as on 0.5: no public wrapper stands for it)."""
    from dolfinx import cpp

    return cpp.graph.AdjacencyList_int32(np.asarray(data, dtype=np.int32), np.asarray(offsets, dtype=np.int32))


def vector_space(mesh):
    """Continuous piecewise-linear vectors (3 components)."""
    from dolfinx import fem

    if modern():
        return fem.functionspace(mesh, ("Lagrange", 1, (3,)))
    return fem.VectorFunctionSpace(mesh, ("CG", 1))


def tensor_dg0_space(mesh):
    """Piecewise-constant 3x3 tensors."""
    from dolfinx import fem

    if modern():
        return fem.functionspace(mesh, ("DG", 0, (3, 3)))
    return fem.TensorFunctionSpace(mesh, ("DG", 0))


def cell_dofs(V) -> np.ndarray:
    """The cells' dofs (blocks), shape (cells, 4)."""
    if modern():
        return np.asarray(V.dofmaps(0).list if callable(getattr(V, "dofmaps", None)) else V.dofmap.list)
    return V.dofmap.list.array.reshape(-1, 4)


def geometry_dofs(mesh) -> np.ndarray:
    """The cells' geometry nodes, shape (cells, 4)."""
    if modern():
        return np.asarray(mesh.geometry.dofmap)
    return mesh.geometry.dofmap.array.reshape(-1, 4)


def new_vector(index_map, bs: int):
    """A distributed vector over an index map, block size bs."""
    from dolfinx import la

    return la.vector(index_map, bs=bs)


def scatter_reverse_add(vec) -> None:
    """Ghost contributions added to their owners."""
    from dolfinx import la

    vec.scatter_reverse(la.InsertMode.add if modern() else la.ScatterMode.add)


def pack(form) -> tuple:
    """(constants, coefficients) of a compiled form, packed (the coefficients' arrays are rewritten in place):
    dolfinx.fem's pack_constants and pack_coefficients (0.11), their C++ functions (0.5 has no public ones)."""
    if modern():
        from dolfinx import fem

        return fem.pack_constants(form), fem.pack_coefficients(form)
    from dolfinx import cpp

    return cpp.fem.pack_constants(form), cpp.fem.pack_coefficients(form)


def assemble_into(out: np.ndarray, form, constants, coefficients) -> None:
    """The compiled vector form assembled into (added to) the flat array ``out``, with its packed constants and
    coefficients: dolfinx.fem.assemble_vector's array form (0.11); on 0.5 its C++ function, called directly as
    before (the step's hot path: bitwise and no dispatch)."""
    if modern():
        from dolfinx import fem

        fem.assemble_vector(out, form, constants, coefficients)
        return
    from dolfinx import cpp

    cpp.fem.assemble_vector(out, form, constants, coefficients)


def quiet() -> None:
    """dolfinx's own log at warnings and above (its C++ info lines would drown fepen's on every rank)."""
    from dolfinx import log

    log.set_log_level(log.LogLevel.WARNING)


def function(V, name: str | None = None):
    """A finite element function on the space V (zero), named for the output files when ``name`` is given."""
    from dolfinx import fem

    return fem.Function(V, name=name) if name else fem.Function(V)


def internal_force_form(P, V):
    """The compiled vector form of the internal force, the integral of P : grad(w) over the body, for the cell
    tensor function P and the test functions w of V."""
    import ufl
    from dolfinx import fem

    w = ufl.TestFunction(V)
    return fem.form(ufl.inner(P, ufl.grad(w)) * ufl.dx)


def exterior_facets(mesh) -> np.ndarray:
    """This rank's facets on the mesh's boundary (local indices; the facet-cell connectivity must exist)."""
    from dolfinx import mesh as dmesh

    return dmesh.exterior_facet_indices(mesh.topology)


def write_mesh_xdmf(comm, path, mesh, tags) -> None:
    """An XDMF file (with its .h5) holding the mesh and the MeshTags ``tags`` (cells, then facets)."""
    from dolfinx.io import XDMFFile

    with XDMFFile(comm, str(path), "w") as xdmf:
        xdmf.write_mesh(mesh)
        mesh.topology.create_connectivity(mesh.topology.dim - 1, mesh.topology.dim)
        for t in tags:
            if modern():
                xdmf.write_meshtags(t, mesh.geometry)
            else:
                xdmf.write_meshtags(t)


def versions() -> dict:
    """{"dolfinx", "petsc"} of this process when it has imported dolfinx (a rigid run does not), else {}."""
    import sys

    if "dolfinx" not in sys.modules:
        return {}
    import dolfinx
    from petsc4py import PETSc

    return {"dolfinx": dolfinx.__version__, "petsc": ".".join(str(v) for v in PETSc.Sys.getVersion())}


def stack() -> dict:
    """The software a deformable run would use (dolfinx imported here): Python, numpy, mpi4py, the MPI library, and
    dolfinx with PETSc and whether fepen supports it ("dolfinx" says why not when it does not import)."""
    import platform

    import mpi4py

    out = {"python": platform.python_version(), "numpy": np.__version__, "mpi4py": mpi4py.__version__,
           "mpi": " ".join(MPI.Get_library_version().splitlines()[0].split(",")[0].split())}
    try:
        import dolfinx  # noqa: F401
    except ImportError as err:
        out["dolfinx"] = f"not importable ({err})"
        return out
    out.update(versions())
    out["supported"] = version()[:2] in SUPPORTED
    return out
