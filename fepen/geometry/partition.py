"""The mesh distributed over the ranks in deterministic parts (docs/theory.md §3.4, §13): gmsh's model read
into dolfinx, bands along the projectile halved across the plane of the shot, and the cavity wall split for a
sliding charge (its nodes doubled, the two sides linked for the partitioner).
"""

from __future__ import annotations

import functools

import numpy as np

from fepen.geometry import tags

__all__ = ["split_wall", "model_to_mesh", "mirror_parts", "band_partitioner"]


def split_wall(n_nodes, cells, cell_values, facets, facet_values):
    """Double the nodes of the CAVITY wall: the charge's cells take new copies (numbered after the
    existing nodes) and the copied wall facets are tagged CHARGE_FACE.

    Args:
        n_nodes: number of nodes (gmsh may keep nodes that no cell uses: copies go after all of them).
        cells: (n_cells, 4) node indices; cell_values: SHELL / CHARGE per cell.
        facets: (n_facets, 3) node indices of the tagged facets; facet_values: their tags.

    Returns:
        (cells, facets, facet_values, wall nodes (the originals; their copies are n_nodes + i in that
        order), links: (k, 2) pairs of cells, a shell cell and a charge cell around the same wall node).
    """
    wall = np.unique(facets[facet_values == tags.CAVITY])
    twin = np.arange(n_nodes, dtype=np.int64)
    twin[wall] = n_nodes + np.arange(len(wall))
    cells = cells.copy()
    charge = cell_values == tags.CHARGE
    cells[charge] = twin[cells[charge]]
    new = twin[facets[facet_values == tags.CAVITY]]
    facets = np.vstack([facets, new])
    facet_values = np.concatenate([facet_values, np.full(len(new), tags.CHARGE_FACE, dtype=facet_values.dtype)])
    # cells around each wall node, on either side (the charge's through the copies)
    original = np.concatenate([np.arange(n_nodes), wall])  # node index -> original node
    on_wall = np.zeros(n_nodes, dtype=bool)
    on_wall[wall] = True
    c_idx = np.repeat(np.arange(len(cells)), 4)
    node = original[cells.ravel()]
    keep = on_wall[node]
    c_idx, node, side = c_idx[keep], node[keep], charge[c_idx[keep]]
    links = []
    order = np.argsort(node, kind="stable")
    c_idx, node, side = c_idx[order], node[order], side[order]
    cuts = np.flatnonzero(np.diff(node)) + 1
    for cs, sd in zip(np.split(c_idx, cuts), np.split(side, cuts)):
        sh, ch = np.unique(cs[~sd]), np.unique(cs[sd])
        links.append(np.stack(np.meshgrid(sh, ch, indexing="ij"), axis=-1).reshape(-1, 2))
    links = np.unique(np.concatenate(links), axis=0) if links else np.zeros((0, 2), dtype=np.int64)
    return cells, facets, facet_values, wall, links


def model_to_mesh(comm, split: bool):
    """dolfinx.io.gmshio.model_to_mesh for tetrahedra, distributed with band_partitioner, the wall split
    when asked (split_wall).

    Args:
        comm: the communicator; rank 0 holds the meshed model in gmsh. split: give the charge its own wall
            nodes.

    Returns:
        (mesh, cell tags, facet tags).
    """
    from fepen import dolfinx_api as dx

    gmshio = dx.gmsh_io()
    TET, TRI = 4, 2  # gmsh element types
    links = None  # rank 0, a split wall: extra links between cells for the partitioner
    if comm.rank == 0:
        import gmsh

        model = gmsh.model
        x = gmshio.extract_geometry(model)
        topo = dx.gmsh_topology(model)
        cells = np.asarray(topo[TET]["topology"], dtype=np.int64)
        cell_values = np.asarray(topo[TET]["cell_data"], dtype=np.int32)
        facets = np.asarray(topo[TRI]["topology"], dtype=np.int64)
        facet_values = np.asarray(topo[TRI]["cell_data"], dtype=np.int32)
        # number the nodes the cells use 0..n-1: a model just meshed keeps unused nodes, and dolfinx's
        # distribute_entity_data reads node indices as positions among the used ones (beyond: a crash)
        used = np.unique(cells)
        renumber = np.full(len(x), -1, dtype=np.int64)
        renumber[used] = np.arange(len(used))
        x, cells, facets = x[used], renumber[cells], renumber[facets]
        if split:
            cells, facets, facet_values, wall, links = split_wall(len(x), cells, cell_values, facets, facet_values)
            x = np.vstack([x, x[wall]])
            from scipy.sparse import coo_matrix

            n = len(cells)
            ones = np.ones(2 * len(links))
            links = coo_matrix((ones, (np.concatenate([links[:, 0], links[:, 1]]),
                                              np.concatenate([links[:, 1], links[:, 0]]))), shape=(n, n)).tocsr()
    else:
        x = np.zeros((0, 3))
        cells = np.zeros((0, 4), dtype=np.int64)
        cell_values = np.zeros(0, dtype=np.int32)
        facets = np.zeros((0, 3), dtype=np.int64)
        facet_values = np.zeros(0, dtype=np.int32)
    parts = mirror_parts(x, cells, comm.size) if comm.rank == 0 else None
    cells = cells[:, dx.cell_perm("tetrahedron", 4)]
    partitioner = functools.partial(band_partitioner, extra_links=links, parts=parts)
    mesh = dx.tet_mesh(comm, cells, x, partitioner)
    tdim = 3
    ct = dx.entity_tags(mesh, tdim, cells, cell_values)
    ct.name = "Cell tags"
    facets = facets[:, dx.cell_perm("triangle", 3)]
    mesh.topology.create_connectivity(tdim - 1, tdim)
    ft = dx.entity_tags(mesh, tdim - 1, facets, facet_values)
    ft.name = "Facet tags"
    return mesh, ct, ft


def mirror_parts(x: np.ndarray, cells: np.ndarray, nparts: int) -> np.ndarray:
    """The part of each cell (rank 0, before distribution): bands across the axis (y), each band cut in two
    halves of equal cell count across the plane of the shot (z = 0: the impact's plane, the body turns about z)
    when nparts is even.

    The target's load and the plastic flow gather at the nose, and a band partition left both to the rank
    holding the nose, the other ranks waiting for it at every step (docs/theory.md §3.4). Two halves mirrored
    across the plane of the shot carry mirrored loads: for a shot in that plane the two ranks of a band do the
    same work. The numbers do not depend on the partition (the sums are exact), only the time does.

    Args:
        x: (n_nodes, 3) node coordinates; cells: (n_cells, 4) node indices; nparts: the number of ranks.

    Returns:
        (n_cells,) int32 parts: band b's halves are parts 2b and 2b + 1 (b alone when nparts is odd).
    """
    n = len(cells)
    halves = 2 if nparts % 2 == 0 else 1
    bands = nparts // halves
    c = x[cells].mean(axis=1)
    part = np.zeros(n, dtype=np.int32)
    order = np.argsort(c[:, 1], kind="stable")  # along the axis
    band = np.empty(n, dtype=np.int64)
    band[order] = np.arange(n, dtype=np.int64) * bands // max(n, 1)
    for b in range(bands):
        mine = np.flatnonzero(band == b)
        side = np.empty(len(mine), dtype=np.int64)
        side[np.argsort(c[mine, 2], kind="stable")] = np.arange(len(mine), dtype=np.int64) * halves // max(len(mine), 1)
        part[mine] = (b * halves + side).astype(np.int32)
    return part


def band_partitioner(comm, nparts: int, graph, ghosting: bool, extra_links=None, parts=None):
    """A deterministic partition of the cells' dual graph into nparts bands along the projectile, or the
    parts given (mirror_parts).

    SCOTCH, dolfinx's default, gives a different partition from run to run on the same input, so that
    two runs on the same number of ranks differ in the last bits (and a checkpoint could not be matched
    cell for cell). Here, without parts: cells in breadth-first order from a pseudo-peripheral cell (the end of
    a breadth-first sweep from cell 0: the nose tip or the tail of a slender body), cut into nparts runs of
    equal length; each rank gets a band of the projectile, whose interfaces are cross-sections. With
    ghosting, a cell is also sent to the ranks owning its facet neighbours. A split wall (split_wall) adds
    its links to the graph: the parts cross both bodies, and a cell is also ghosted where its links are.

    Args:
        comm: communicator; graph: this rank's rows of the dual graph (global cell indices);
        nparts: number of parts; ghosting: return ghost destinations too.
        extra_links: rank 0, a split wall's cell links (scipy sparse, n x n), or None.
        parts: rank 0, the part of every cell in the global order (mirror_parts), or None: the bands.

    Returns:
        AdjacencyList_int32: per local row, the owner rank then the ghost ranks.
    """
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import breadth_first_order

    from fepen import dolfinx_api as dx

    offsets = np.asarray(graph.offsets, dtype=np.int64)
    array = np.asarray(graph.array, dtype=np.int64)
    rows = comm.gather((offsets, array), root=0)
    dest = None
    if comm.rank == 0:
        sizes = [len(o) - 1 for o, _ in rows]
        n = sum(sizes)
        indptr = np.concatenate([[0], np.cumsum(np.concatenate([np.diff(o) for o, _ in rows]))])
        indices = np.concatenate([a for _, a in rows]) if n else np.zeros(0, dtype=np.int64)
        part = np.zeros(n, dtype=np.int32)
        if n:
            g = csr_matrix((np.ones(len(indices)), indices, indptr), shape=(n, n))
            if extra_links is not None and extra_links.shape == (n, n):
                g = (g + extra_links).tocsr()
                g.sort_indices()
                indptr, indices = g.indptr.astype(np.int64), g.indices.astype(np.int64)
            if parts is not None and len(parts) == n:
                part[:] = parts
            else:
                start = int(breadth_first_order(g, 0, directed=False, return_predecessors=False)[-1])
                order = breadth_first_order(g, start, directed=False, return_predecessors=False)
                if len(order) < n:  # a disconnected mesh: the rest in index order
                    rest = np.setdiff1d(np.arange(n), order)
                    order = np.concatenate([order, rest])
                part[order] = (np.arange(n, dtype=np.int64) * nparts // n).astype(np.int32)
        dest = []
        lo = 0
        for size in sizes:
            data, offs = [], [0]
            for c in range(lo, lo + size):
                owner = int(part[c])
                ghosts = sorted({int(part[j]) for j in indices[indptr[c]:indptr[c + 1]]} - {owner}) if ghosting else []
                data += [owner, *ghosts]
                offs.append(len(data))
            dest.append((np.array(data, dtype=np.int32), np.array(offs, dtype=np.int32)))
            lo += size
    data, offs = comm.scatter(dest, root=0)
    return dx.adjacency_int32(data, offs)
