"""The loaded surface: each OUTER facet one load point on the exact projectile surface, with its exact
normal turned with the facet and its curved patch's area stretched with it (docs/theory.md §10).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numba
import numpy as np
from mpi4py import MPI

from fepen import dolfinx_api as dx
from fepen.geometry import projection, tags
from fepen.geometry.cad import CadBody
from fepen.geometry.shape import Shape
from fepen.solver import ckernel

SUBDIVISION = 4  # facet patch areas: 4 x 4 sub-triangles projected on the exact surface


@numba.njit(cache=True, error_model="numpy")
def _facet_kinematics(x_all, v_all, tri, n_flat0, N0, area0, flat0, x, v, area, n):
    """Surface.kinematics in one compiled loop (the numpy version was a third of a penetration step):
    centroid, mean velocity, stretched exact area, and the exact normal N0 turned by the smallest rotation
    taking the flat reference normal a to the current one b (Rodrigues without angles):
    R v = (a·b) v + (a×b)×v + ((a×b)·v)(a×b)/(1 + a·b)."""
    for i in range(tri.shape[0]):
        i0, i1, i2 = tri[i, 0], tri[i, 1], tri[i, 2]
        ax, ay, az = x_all[i1, 0] - x_all[i0, 0], x_all[i1, 1] - x_all[i0, 1], x_all[i1, 2] - x_all[i0, 2]
        bx, by, bz = x_all[i2, 0] - x_all[i0, 0], x_all[i2, 1] - x_all[i0, 1], x_all[i2, 2] - x_all[i0, 2]
        cx, cy, cz = 0.5 * (ay * bz - az * by), 0.5 * (az * bx - ax * bz), 0.5 * (ax * by - ay * bx)
        a = math.sqrt(cx * cx + cy * cy + cz * cz)
        bx, by, bz = cx / a, cy / a, cz / a  # current unit normal of the flat facet
        px, py, pz = n_flat0[i, 0], n_flat0[i, 1], n_flat0[i, 2]
        c = px * bx + py * by + pz * bz
        kx, ky, kz = py * bz - pz * by, pz * bx - px * bz, px * by - py * bx
        vx, vy, vz = N0[i, 0], N0[i, 1], N0[i, 2]
        kv = (kx * vx + ky * vy + kz * vz) / max(1.0 + c, 1e-12)
        n[i, 0] = c * vx + (ky * vz - kz * vy) + kv * kx
        n[i, 1] = c * vy + (kz * vx - kx * vz) + kv * ky
        n[i, 2] = c * vz + (kx * vy - ky * vx) + kv * kz
        area[i] = area0[i] * (a / flat0[i])
        for k in range(3):
            x[i, k] = (x_all[i0, k] + x_all[i1, k] + x_all[i2, k]) / 3.0
            v[i, k] = (v_all[i0, k] + v_all[i1, k] + v_all[i2, k]) / 3.0


@numba.njit(cache=True)
def _to_nodes(tri, f, out):
    """out[tri[i, j]] += f[i] / 3 for each facet i and corner j, in facet order."""
    for j in range(3):
        for i in range(tri.shape[0]):
            for k in range(3):
                out[tri[i, j], k] += f[i, k] / 3.0


def area_vectors(x: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Area vectors ½ (x1 − x0) × (x2 − x0) of triangles (f, 3) of node indices into x."""
    p0 = x[tri[:, 0]]
    return 0.5 * np.cross(x[tri[:, 1]] - p0, x[tri[:, 2]] - p0)


def _patch_areas(shape, p: np.ndarray, patch: np.ndarray, m: int = SUBDIVISION) -> np.ndarray:
    """Areas of the exact-surface patches spanned by flat triangles p (f, 3, 3) on their meridian segments
    ``patch`` (f,)."""
    pts, tris = [], []
    index = {}
    for i in range(m + 1):
        for j in range(m + 1 - i):
            index[(i, j)] = len(pts)
            pts.append((i / m, j / m))
    for i in range(m):
        for j in range(m - i):
            tris.append((index[(i, j)], index[(i + 1, j)], index[(i, j + 1)]))
            if i + j < m - 1:
                tris.append((index[(i + 1, j)], index[(i + 1, j + 1)], index[(i, j + 1)]))
    lam = np.array([[1 - u - v, u, v] for u, v in pts])
    q = np.einsum("sk,fkd->fsd", lam, p)  # (f, s, 3)
    nf, ns = q.shape[:2]
    qp = projection.project(shape, q.reshape(-1, 3), np.repeat(patch, ns)).reshape(nf, ns, 3)
    t = np.array(tris)
    a = qp[:, t[:, 0]]
    return 0.5 * np.linalg.norm(np.cross(qp[:, t[:, 1]] - a, qp[:, t[:, 2]] - a), axis=2).sum(axis=1)


def _rim_segments(shape, p: np.ndarray, patch: np.ndarray) -> np.ndarray:
    """The circular segments between a forward-facing flat face's rim and the chords of its facets that span
    it (f,): the part of the exact disk (or annulus) the polygon leaves out, added at an outer rim and taken
    away at an inner one (a flat face's patches are otherwise only its flat triangles). Rear faces keep their
    polygon areas: they are loaded only when the body moves backward."""
    out = np.zeros(len(p))
    r = np.hypot(p[..., 0], p[..., 2])
    tol = 1e-6 * shape.length
    for i, seg in enumerate(shape.outer_path):
        if not (seg.kind == "line" and seg.p0[1] == seg.p1[1] and seg.p1[0] > seg.p0[0]):
            continue  # only faces that face forward (a flat nose, a meplat): a rear face is never loaded ahead
        on = np.flatnonzero(patch == i)
        lo, hi = sorted((seg.p0[0], seg.p1[0]))
        for R, sign in ((hi, 1.0), (lo, -1.0)):
            if R <= tol:
                continue
            for a, b in ((0, 1), (1, 2), (2, 0)):
                rim = (np.abs(r[on, a] - R) < tol) & (np.abs(r[on, b] - R) < tol)
                if not np.any(rim):
                    continue
                c = np.linalg.norm(p[on[rim], a] - p[on[rim], b], axis=1)
                theta = 2.0 * np.arcsin(np.minimum(c / (2.0 * R), 1.0))
                out[on[rim]] += sign * 0.5 * R * R * (theta - np.sin(theta))
    return out


@dataclass
class Surface:
    """Facet load points of the outer surface owned by this rank.

    Attributes:
        tri: facet node (block) indices (f, 3), ordered so that their area vector points outward.
        X: reference load points on the exact surface (f, 3).
        area0: exact patch areas (f,). flat0: flat reference facet areas (f,).
        N0: exact reference normals at the load points (f, 3). n_flat0: flat reference facet normals (f, 3).
        radius, R_meridian, sin_phi0: shape data for the law (f,).
        cell: the owned cell each facet bounds (f,).
    """

    tri: np.ndarray
    X: np.ndarray
    area0: np.ndarray
    flat0: np.ndarray
    N0: np.ndarray
    n_flat0: np.ndarray
    radius: np.ndarray
    R_meridian: np.ndarray
    sin_phi0: np.ndarray
    cell: np.ndarray

    FIELDS = ("tri", "X", "area0", "flat0", "N0", "n_flat0", "radius", "R_meridian", "sin_phi0", "cell")
    #: bumped whenever the facets change (keep, restore: collective, on every rank alike), so that their
    #: nodal sums (fepen.solver.assembly.NodalSum) are rebuilt
    version = 0

    def state(self) -> dict[str, np.ndarray]:
        """The load points (for checkpoints: wear and erosion change them)."""
        return {k: getattr(self, k) for k in self.FIELDS}

    def restore(self, state: dict) -> None:
        """Put back what state() returned."""
        for k in self.FIELDS:
            setattr(self, k, np.ascontiguousarray(state[k]))
        self.version += 1

    def keep(self, mask: np.ndarray) -> None:
        """Keep only the facets where mask is True (in place)."""
        for k in self.FIELDS:
            setattr(self, k, np.ascontiguousarray(getattr(self, k)[mask]))
        self.version += 1

    def append_flat(self, X_ref: np.ndarray, tri: np.ndarray, cell: np.ndarray) -> None:
        """Add facets exposed inside the body (by erosion): their own flat normals and areas, no exact
        surface (R_meridian = inf; sin_phi0 = |N_y|, the body axis being y).

        Args:
            X_ref: the reference node positions. tri: (k, 3) node indices ordered outward. cell: (k,).
        """
        av = area_vectors(X_ref, tri)
        flat = np.linalg.norm(av, axis=1)
        nf = av / np.maximum(flat, 1e-300)[:, None]
        c = X_ref[tri].mean(axis=1)
        new = dict(tri=tri, X=c, area0=flat, flat0=flat, N0=nf, n_flat0=nf, radius=np.hypot(c[:, 0], c[:, 2]),
                   R_meridian=np.full(len(tri), np.inf), sin_phi0=np.abs(nf[:, 1]), cell=cell)
        for k in self.FIELDS:
            old = getattr(self, k)
            setattr(self, k, np.ascontiguousarray(np.concatenate([old, new[k].astype(old.dtype)])))

    def follow_reference(self, X_old: np.ndarray, X_new: np.ndarray) -> None:
        """The reference facets moved from X_old to X_new (a receding surface, fepen.solver.recession):
        turn the exact normals as the flat ones turned, scale the exact areas as the flat ones, move the
        load points with the centroids, so that the load sees the worn shape."""
        f = len(self.tri)
        if not f:
            return
        c, n, area = np.empty((f, 3)), np.empty((f, 3)), np.empty(f)
        _facet_kinematics(X_new, np.zeros_like(X_new), self.tri, self.n_flat0, self.N0, self.area0, self.flat0,
                          c, np.empty((f, 3)), area, n)
        av = area_vectors(X_new, self.tri)
        flat = np.linalg.norm(av, axis=1)
        self.X = self.X + (c - X_old[self.tri].mean(axis=1))
        self.N0, self.area0, self.flat0 = n, area, flat
        self.n_flat0 = av / np.maximum(flat, 1e-300)[:, None]
        self.radius = np.hypot(self.X[:, 0], self.X[:, 2])

    def kinematics(self, x_all: np.ndarray, v_all: np.ndarray):
        """Current load-point positions, velocities, areas and unit normals.

        Args:
            x_all, v_all: current positions and velocities of all local nodes (ghosts included).

        Returns:
            (x (f, 3), v (f, 3), area (f,), n (f, 3)).
        """
        f = len(self.tri)
        x, v, n, area = np.empty((f, 3)), np.empty((f, 3)), np.empty((f, 3)), np.empty(f)
        lib = ckernel.library()
        arrays = (x_all, v_all, self.tri, self.n_flat0, self.N0, self.area0, self.flat0)
        if lib is not None and f and all(a.flags.c_contiguous for a in arrays) and self.tri.dtype == np.int64 \
                and x_all.dtype == v_all.dtype == np.float64:  # the C loop (cell_kernel.c), the same bits
            lib.facet_kinematics(f, *[a.ctypes.data for a in arrays], x.ctypes.data, v.ctypes.data,
                                 area.ctypes.data, n.ctypes.data)
        else:
            _facet_kinematics(*arrays, x, v, area, n)
        return x, v, area, n

    def to_nodes(self, f: np.ndarray, out: np.ndarray) -> None:
        """Add the load points' forces (f, 3) to their nodes, one third each, into out (n_nodes, 3)."""
        _to_nodes(self.tri, f, out)


#: facets whose normals differ by more than this meet at a feature edge (not smoothed across)
FEATURE_ANGLE_DEG = 30.0


def smoothed_normals(P: np.ndarray, n: np.ndarray, area: np.ndarray, comm) -> np.ndarray:
    """Normals of a faceted surface without an exact one (a CAD body): at each corner of a facet the
    area-weighted mean of the unit normals of the facets around that node that lie within FEATURE_ANGLE_DEG
    of it, then the mean of its three corners, normalised. On a smooth surface this is the surface normal
    at the centroid to O(h²) where the flat normal is off by O(h); edges sharper than the feature angle
    stay sharp. Every rank sees every facet (allgather), so the result does not depend on the partition.

    Args:
        P: corners of this rank's facets (f, 3, 3). n: their flat unit normals (f, 3). area: their areas (f,).
        comm: the mesh's communicator.

    Returns:
        (f, 3) unit normals.
    """
    parts = comm.allgather((P, n, area))
    Pg = np.concatenate([p for p, _, _ in parts])
    ng = np.concatenate([q for _, q, _ in parts])
    ag = np.concatenate([a for _, _, a in parts])
    if not len(P):
        return np.zeros((0, 3))
    grid = 1e-9  # nodes are the same point to far better than a nanometre
    keys = np.round(np.concatenate([Pg.reshape(-1, 3), P.reshape(-1, 3)]) / grid).astype(np.int64)
    _, vid = np.unique(keys, axis=0, return_inverse=True)
    vid = vid.ravel()
    vg, vl = vid[: 3 * len(Pg)], vid[3 * len(Pg):].reshape(-1, 3)
    order = np.argsort(vg, kind="stable")
    starts = np.searchsorted(vg[order], np.arange(vid.max() + 2))
    facet_of = order // 3
    cos_min = math.cos(math.radians(FEATURE_ANGLE_DEG))
    out = np.zeros_like(n)
    for i in range(len(P)):
        total = np.zeros(3)
        for v in vl[i]:
            g = facet_of[starts[v]:starts[v + 1]]
            g = g[ng[g] @ n[i] > cos_min]
            m = (ag[g][:, None] * ng[g]).sum(axis=0)
            total += m / np.linalg.norm(m)
        out[i] = total / np.linalg.norm(total)
    return out


def node_positions(V) -> np.ndarray:
    """The mesh's own coordinates of V's nodes (owned and ghost) (n_nodes, 3): the solver's reference
    positions, bit for bit (tabulated dof coordinates are interpolated and may differ in the last bit, and
    differently on another partition)."""
    mesh = V.mesh
    imap = V.dofmap.index_map
    geometry_node = np.zeros(imap.size_local + imap.num_ghosts, dtype=np.int64)
    geometry_node[dx.cell_dofs(V).ravel()] = dx.geometry_dofs(mesh).ravel()
    return mesh.geometry.x[geometry_node, :3].copy()


def oriented_facets(V, facet_tags, tag: int, with_cells: bool = False):
    """The owned facets carrying ``tag``, as node triples (block indices of V) ordered so that their area
    vectors point out of the cell they bound, each starting at its node of the smallest input-mesh number.

    Args:
        V: the P1 vector function space of the solver (its block indices are the nodes).
        facet_tags: the mesh's facet MeshTags.
        tag: the facet tag.

    Returns:
        (n_facets, 3) int64 node indices; with_cells: also the cell each bounds (n_facets,).
    """
    mesh = V.mesh
    tdim = mesh.topology.dim
    for a, b in ((tdim - 1, tdim), (tdim - 1, 0), (tdim, 0)):
        mesh.topology.create_connectivity(a, b)
    f2c = mesh.topology.connectivity(tdim - 1, tdim)
    f2v = mesh.topology.connectivity(tdim - 1, 0)
    c2v = mesh.topology.connectivity(tdim, 0).array.reshape(-1, 4)
    cdofs = dx.cell_dofs(V)
    v2d = np.full(c2v.max() + 1, -1, dtype=np.int64)
    v2d[c2v.ravel()] = cdofs.ravel()
    imap = V.dofmap.index_map
    X = V.tabulate_dof_coordinates()[: imap.size_local + imap.num_ghosts]
    facets = facet_tags.find(tag)
    facets = facets[facets < mesh.topology.index_map(tdim - 1).size_local]
    tri = np.array([v2d[f2v.links(f)] for f in facets], dtype=np.int64).reshape(-1, 3)
    cells = np.zeros(len(facets), dtype=np.int64)
    for i, f in enumerate(facets):  # order each facet so that its area vector points outward
        cell = cells[i] = f2c.links(f)[0]
        opp = [d for d in cdofs[cell] if d not in tri[i]][0]
        p = X[tri[i]]
        if np.dot(np.cross(p[1] - p[0], p[2] - p[0]), p.mean(axis=0) - X[opp]) < 0:
            tri[i, [1, 2]] = tri[i, [2, 1]]
    # start each facet at its corner of the smallest input-mesh number (a turn: the orientation stays), so
    # that a facet's arithmetic (its centroid (x0 + x1 + x2) / 3, ...) is the same on any partition
    gdofs = dx.geometry_dofs(mesh)
    geometry_node = np.zeros(len(X), dtype=np.int64)
    geometry_node[cdofs.ravel()] = gdofs.ravel()
    first = np.argmin(np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)[geometry_node][tri], axis=1)
    tri = tri[np.arange(len(tri))[:, None], (first[:, None] + np.arange(3)) % 3]
    return (tri, cells) if with_cells else tri


def outer_surface(V, facet_tags, shape, tag: int = tags.OUTER) -> Surface:
    """The facet load points of the owned facets carrying ``tag``.

    Args:
        V: the P1 vector function space of the solver (its block indices are the nodes).
        facet_tags: the mesh's facet MeshTags.
        shape: the exact fepen.geometry.shape.Shape the mesh was built from (body frame = reference frame),
            or its CadBody.
    """
    X = node_positions(V)
    tri, cells = oriented_facets(V, facet_tags, tag, with_cells=True)
    return facet_points(shape, X, tri, cells, V.mesh.comm)


@functools.singledispatch
def facet_points(shape, X, tri, cells, comm) -> Surface:
    """The load points of oriented outer facets, by the body's kind.

    Args:
        shape: the body the mesh was built from (a Shape or a CadBody). X: the node positions (n, 3) (m).
        tri: the facets' nodes (k, 3), oriented outward. cells: each facet's cell (k,). comm: the mesh's
            communicator.

    Returns:
        The Surface.
    """
    raise TypeError(f"no load points for a {type(shape).__name__}")


@facet_points.register(CadBody)
def _cad_facet_points(shape, X, tri, cells, comm) -> Surface:
    """A CadBody: no exact surface: the facets' own areas, their normals smoothed across smooth edges."""
    empty = np.zeros(0, dtype=np.int64)
    surf = Surface(np.zeros((0, 3), dtype=np.int64), np.zeros((0, 3)), np.zeros(0), np.zeros(0),
                   np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), np.zeros(0), np.zeros(0), empty)
    surf.append_flat(X, tri, cells)
    surf.N0 = smoothed_normals(X[tri], surf.n_flat0, surf.flat0, comm)
    surf.sin_phi0 = np.abs(surf.N0[:, 1])
    return surf


@facet_points.register(Shape)
def _exact_facet_points(shape, X, tri, cells, comm) -> Surface:
    """The exact solid: each facet's centroid projected on its meridian segment, the exact patch area."""
    av = area_vectors(X, tri)
    flat = np.linalg.norm(av, axis=1)
    nflat = av / np.maximum(flat, 1e-300)[:, None]
    centroid = X[tri].mean(axis=1)
    patch = projection.classify(shape, X[tri], nflat) if len(tri) else np.zeros(0, dtype=np.int64)  # meridian segments
    P = projection.project(shape, centroid, patch)
    N, radius, Rm, sphi = projection.surface_info(shape, P, patch)
    bad = np.isnan(N[:, 0])  # should not happen for centroids; fall back to the flat normal
    N[bad] = nflat[bad]
    area = _patch_areas(shape, X[tri], patch) if len(tri) else np.zeros(0)
    if len(tri):
        area += _rim_segments(shape, X[tri], patch)
    return Surface(tri, P, area, flat, N, nflat, radius, Rm, sphi, cells)


def gather_global(surface: Surface, comm: MPI.Comm) -> dict:
    """Every rank's load points in one deterministic order, on every rank (for the rigid body).

    Points are ordered by reference position (dolfinx's global numbering depends on the partition;
    positions do not), so every rank count gives bitwise the same arrays.

    Returns:
        dict of arrays X, area0, N, radius, R_meridian, sin_phi0.
    """
    local = dict(X=surface.X, area0=surface.area0, N=surface.N0, radius=surface.radius,
                 R_meridian=surface.R_meridian, sin_phi0=surface.sin_phi0)
    parts = comm.allgather(local)
    out = {k: np.concatenate([p[k] for p in parts]) for k in local}
    X = out["X"]
    order = np.lexsort((X[:, 2], X[:, 1], X[:, 0]))
    return {k: v[order] for k, v in out.items()}
