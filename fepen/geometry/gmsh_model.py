"""Gmsh (OpenCASCADE) model of the projectile: profile revolved about the axis, tagged, meshed in tets.

Runs on one process (rank 0 in MPI runs); :mod:`fepen.geometry.mesh` distributes the result with dolfinx.

Tags (physical groups) used by the rest of fepen:
    volumes  SHELL = 1, CHARGE = 2
    surfaces OUTER = 11 (the only surface the target may load), CAVITY = 12 (cavity wall; the
             shell-charge interface when the charge is meshed)
The nose tip (0, 0, 0) and the tail centre (0, L, 0) are mesh nodes (see :func:`build`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from fepen.geometry import cad, tetra
from fepen.geometry.shape import Shape

SHELL, CHARGE = 1, 2
OUTER, CAVITY = 11, 12
#: the charge's side of the cavity wall when it has nodes of its own (fepen.geometry.partition.split_wall)
CHARGE_FACE = 13


@dataclass(frozen=True)
class MeshOptions:
    """How to mesh.

    Attributes:
        size: nominal element size (m).
        nose_size: element size at the nose tip (m), growing to ``size`` over one nose length.
        optimize: "hxt" (gmsh's parallel Delaunay, HXT, with gmsh's own optimiser on every tetrahedron of
            quality below 0.5: the default), "netgen" (Delaunay, then Netgen's and gmsh's optimisers: the
            default before 0.5), "gmsh" (Delaunay and gmsh's optimiser) or "none".
    """

    size: float
    nose_size: float | None = None
    optimize: str = "hxt"


def _profile_loop(occ, pts: list[tuple[float, float]], curves: dict | None = None) -> int:
    """A closed plane loop through pts (x = radius, y = axial); edge i -> i+1 is a straight line unless
    ``curves`` maps i to a conic Segment (fepen.geometry.profile) from pts[i] to pts[i+1].

    Returns the gmsh surface tag."""
    curves = curves or {}
    tags = [occ.addPoint(x, y, 0.0) for x, y in pts]
    lines = []
    for i in range(len(tags)):
        j = (i + 1) % len(tags)
        seg = curves.get(i)
        if seg is None:
            lines.append(occ.addLine(tags[i], tags[j]))
            continue
        cr, cz = seg.centre
        centre = occ.addPoint(cr, cz, 0.0)
        if seg.is_circle:
            lines.append(occ.addCircleArc(tags[i], centre, tags[j]))
        else:  # OpenCASCADE wants a point on the major axis
            major = occ.addPoint(cr + seg.ar, cz, 0.0) if seg.ar >= seg.az else occ.addPoint(cr, cz + seg.az, 0.0)
            lines.append(occ.addEllipseArc(tags[i], centre, major, tags[j]))
    return occ.addPlaneSurface([occ.addCurveLoop(lines)])


def _loop(paths: list[list]) -> tuple[list[tuple[float, float]], dict]:
    """The vertices and conic edges of a closed loop through meridian paths in order (each a Segment list,
    joined end to start by straight lines; the last closes back to the first's start)."""
    pts, curves = [], {}
    for path in paths:
        for seg in path:
            p0 = (seg.p0[0], seg.p0[1])
            if not pts or abs(pts[-1][0] - p0[0]) + abs(pts[-1][1] - p0[1]) > 1e-12:
                pts.append(p0)
            if seg.kind == "conic":
                curves[len(pts) - 1] = seg
            pts.append((seg.p1[0], seg.p1[1]))
    if len(pts) > 1 and abs(pts[-1][0] - pts[0][0]) + abs(pts[-1][1] - pts[0][1]) <= 1e-12:
        pts.pop()
    return pts, curves


def _reversed(path: list) -> list:
    """A meridian path walked backwards (conic arcs with their angles swapped)."""
    from dataclasses import replace as _r

    return [_r(s, p0=s.p1, p1=s.p0, t0=s.t1, t1=s.t0) for s in reversed(path)]


#: the mesher retries with new random seeds until the shortest altitude reaches this fraction of the
#: nominal size (the stable explicit step is proportional to it); it keeps the best of MAX_SEEDS tries
ALTITUDE_GOAL = 0.27
MAX_SEEDS = 6


#: called with the name of each stage as it starts ("building", "meshing", "optimising"), or None: the mesh's
#: progress bar (fepen.geometry.mesh.progress)
stage_hook = None


def _stage(name: str) -> None:
    if stage_hook is not None:
        stage_hook(name)


def best_seed(opts: MeshOptions) -> float:
    """While the shortest altitude of the mesh in gmsh (built with seed 1) is below ALTITUDE_GOAL x size, mesh
    its volumes again with new seeds, up to MAX_SEEDS, and keep the best. The surface mesh is kept: the mesh's
    volume, hence its mass, is the same for every seed.

    Returns:
        The shortest altitude over the nominal size of the mesh left in gmsh.
    """
    best_seed = seed = 1
    best = ratio = float(tetra.shortest_altitudes(tet_points()).min()) / opts.size
    while ratio < ALTITUDE_GOAL and opts.optimize != "none" and seed < MAX_SEEDS:
        seed += 1
        _remesh_volumes(opts, seed)
        ratio = float(tetra.shortest_altitudes(tet_points()).min()) / opts.size
        if ratio > best:
            best_seed, best = seed, ratio
    if best_seed != seed:
        _remesh_volumes(opts, best_seed)
    return best


def _remesh_volumes(opts: MeshOptions, seed: int) -> None:
    """The volume mesh made again with another random seed, on the surface mesh as it is."""
    import gmsh

    _stage("building")
    gmsh.model.mesh.clear([(3, t) for _, t in gmsh.model.getEntities(3)])
    gmsh.option.setNumber("Mesh.RandomSeed", seed)
    _stage("meshing")
    gmsh.model.mesh.generate(3)
    _optimise(opts)


def build(shape: Shape | cad.CadBody, opts: MeshOptions, charge: bool, seed: int = 1) -> None:
    """Create and mesh the projectile in the current gmsh model (gmsh must be initialised).

    Args:
        shape: the exact projectile geometry, or a CadBody (meshed as its file draws it).
        opts: element sizes and optimiser.
        charge: mesh the cavity as a second volume (the explosive) when True; else it is a void.
        seed: gmsh's random seed (different seeds give different, equally valid meshes).
    """
    _stage("building")
    _build(shape, opts, charge, seed)


@functools.singledispatch
def _build(shape, opts: MeshOptions, charge: bool, seed: int) -> None:
    """The body in the current gmsh model, meshed, by the body's kind (build's arguments)."""
    raise TypeError(f"no gmsh model for a {type(shape).__name__}")


@_build.register(cad.CadBody)
def _build_cad(shape, opts: MeshOptions, charge: bool, seed: int) -> None:
    """A CadBody: imported as its file draws it, not revolved (no charge)."""
    cad.build(shape.file, shape.scale)
    _size_and_mesh(opts, 0.0, seed)


@_build.register(Shape)
def _build_exact(shape, opts: MeshOptions, charge: bool, seed: int) -> None:
    """The exact solid: its meridians revolved, tagged, the tip and tail centre made nodes."""
    import gmsh

    gmsh.model.add("projectile")
    _revolve(shape, charge)
    outer_s = _tag(shape, charge)
    # Make sure the tracked points are mesh nodes.
    _embed_axis_point(0.0, outer_s)
    _embed_axis_point(shape.length, outer_s)
    # Frontal-Delaunay (6) overlaps facets at the apex of a cone; Delaunay (5) meshes it
    apex = any(g.kind == "line" and g.p0[1] != g.p1[1] and 0.0 in (g.p0[0], g.p1[0]) for g in shape.outer_path)
    _size_and_mesh(opts, shape.nose_length, seed, 5 if apex else 6)


def _revolve(shape: Shape, charge: bool) -> None:
    """The shell (and the charge) as solids of revolution of their (r, z) profiles."""
    import gmsh

    occ = gmsh.model.occ
    # Outer profile from the tip, counter-clockwise in the (r, z) half plane, then back down the axis
    # through the cavity (if any).
    inner = shape.inner_path if shape.has_cavity else []
    pts, curves = _loop([shape.outer_path, _reversed(inner)])
    shell_face = _profile_loop(occ, pts, curves)
    faces = [(2, shell_face)]
    if inner and charge:
        fill, fill_curves = _loop([inner])
        faces.append((2, _profile_loop(occ, fill, fill_curves)))
    occ.synchronize()
    vols = []
    for face in faces:
        out = occ.revolve([face], 0, 0, 0, 0, 1, 0, 2 * math.pi)
        vols.append([t for d, t in out if d == 3])
    if len(vols) > 1:
        occ.fragment([(3, t) for t in vols[0]], [(3, t) for t in vols[1]])
    occ.removeAllDuplicates()
    occ.synchronize()


def _tag(shape: Shape, charge: bool) -> list[int]:
    """Physical groups SHELL, CHARGE, OUTER, CAVITY; returns the outer surfaces.

    Classified by bounding boxes (gmsh pads them by about 1e-7 m): the charge and the cavity wall lie
    inside the cavity's bounding cylinder; everything else is the shell and its outer surface."""
    import gmsh

    inner = shape.inner_path if shape.has_cavity else []
    tol = 1e-5 * shape.length
    if inner:
        zlo = min(s.z_range()[0] for s in inner)
        zhi = max(s.z_range()[1] for s in inner)
        rmax = max(s.r_range()[1] for s in inner)

    def in_cavity(dim: int, tag: int) -> bool:
        if not inner:
            return False
        xmin, ymin, zmin, xmax, ymax, zmax = gmsh.model.getBoundingBox(dim, tag)
        return ymin >= zlo - tol and ymax <= zhi + tol and max(-xmin, xmax, -zmin, zmax) <= rmax + tol

    all_vols = [t for d, t in gmsh.model.getEntities(3)]
    charge_v = [t for t in all_vols if charge and in_cavity(3, t)]
    shell_v = [t for t in all_vols if t not in charge_v]
    gmsh.model.addPhysicalGroup(3, shell_v, SHELL)
    if charge_v:
        gmsh.model.addPhysicalGroup(3, charge_v, CHARGE)
    shell_b = gmsh.model.getBoundary([(3, t) for t in shell_v], combined=False, oriented=False)
    surfaces = sorted({abs(t) for d, t in shell_b})
    cavity_s = [t for t in surfaces if in_cavity(2, t)]
    outer_s = [t for t in surfaces if t not in cavity_s]
    gmsh.model.addPhysicalGroup(2, outer_s, OUTER)
    if cavity_s:
        gmsh.model.addPhysicalGroup(2, cavity_s, CAVITY)
    return outer_s


def _size_and_mesh(opts: MeshOptions, nose_length: float, seed: int, algorithm: int = 6) -> None:
    """Element sizes (graded from the nose tip when opts.nose_size is smaller), mesh, optimise."""
    import gmsh

    h = opts.size
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    gmsh.option.setNumber("Mesh.MeshSizeMin", 0.2 * min(h, opts.nose_size or h))
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 1)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.Algorithm", algorithm)
    gmsh.option.setNumber("Mesh.Algorithm3D", 10 if opts.optimize == "hxt" else 1)
    gmsh.option.setNumber("Mesh.RandomSeed", seed)
    gmsh.option.setNumber("Mesh.OptimizeThreshold", 0.5)
    gmsh.option.setNumber("Mesh.Optimize", 1 if opts.optimize != "none" else 0)
    gmsh.option.setNumber("Mesh.OptimizeNetgen", 1 if opts.optimize == "netgen" else 0)
    if opts.nose_size is not None and opts.nose_size < h and nose_length > 0:
        f = gmsh.model.mesh.field
        dist = f.add("Distance")
        f.setNumbers(dist, "PointsList", [_tip_point()])
        thr = f.add("Threshold")
        f.setNumber(thr, "InField", dist)
        f.setNumber(thr, "SizeMin", opts.nose_size)
        f.setNumber(thr, "SizeMax", h)
        f.setNumber(thr, "DistMin", 0.0)
        f.setNumber(thr, "DistMax", nose_length)
        f.setAsBackgroundMesh(thr)
    _stage("meshing")
    gmsh.model.mesh.generate(3)
    _optimise(opts)


def _optimise(opts: MeshOptions) -> None:
    """The optimisers run after gmsh.model.mesh.generate (which ran gmsh's own, and Netgen's for "netgen")."""
    import gmsh

    if opts.optimize not in ("netgen", "gmsh"):
        return
    _stage("optimising")
    if opts.optimize == "netgen":
        gmsh.model.mesh.optimize("Netgen")
    gmsh.model.mesh.optimize("")


def _tip_point() -> int:
    import gmsh

    for _, t in gmsh.model.getEntities(0):
        x, y, z = gmsh.model.getValue(0, t, [])
        if abs(x) + abs(y) + abs(z) < 1e-12:
            return t
    raise RuntimeError("no geometric point at the nose tip")


def _embed_axis_point(y: float, surfaces: list[int]) -> None:
    """Ensure a mesh node at (0, y, 0) on the outer surface (the tip or the tail centre).

    On a revolved body the axis point of a flat end face is a pole of the revolution: OpenCASCADE keeps it
    as a model vertex that is not on the face's boundary, so it must be embedded to become a connected node.
    On an ogive the tip is the pole of the ogive face and already a node of it.
    """
    import gmsh

    vertex = None
    for _, t in gmsh.model.getEntities(0):
        px, py, pz = gmsh.model.getValue(0, t, [])
        if abs(px) + abs(py - y) + abs(pz) < 1e-12:
            vertex = t
    for s in surfaces:
        on_face = {abs(t) for d, t in gmsh.model.getBoundary([(2, s)], recursive=True) if d == 0}
        if vertex is not None and vertex in on_face:
            return
    for s in surfaces:
        xmin, ymin, zmin, xmax, ymax, zmax = gmsh.model.getBoundingBox(2, s)
        if abs(ymax - ymin) < 1e-6 and abs(0.5 * (ymin + ymax) - y) < 1e-6:
            if vertex is None:
                vertex = gmsh.model.occ.addPoint(0.0, y, 0.0)
                gmsh.model.occ.synchronize()
            gmsh.model.mesh.embed(0, [vertex], 2, s)
            return
    if vertex is None:
        raise RuntimeError(f"no mesh node can be placed at (0, {y}, 0)")


def tet_points(tag: int | None = None) -> np.ndarray:
    """Node coordinates of the tetrahedra of the current gmsh model, shape (n, 4, 3).

    Args:
        tag: a physical volume group (SHELL, CHARGE), or None for every tetrahedron.
    """
    import gmsh

    tags, coords, _ = gmsh.model.mesh.getNodes()
    index = np.zeros(int(tags.max()) + 1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(len(tags))
    x = coords.reshape(-1, 3)
    entities = (gmsh.model.getEntitiesForPhysicalGroup(3, tag) if tag is not None
                else [t for _, t in gmsh.model.getEntities(3)])
    blocks = []
    for ent in entities:
        types, _, nodes = gmsh.model.mesh.getElements(3, ent)
        for et, nd in zip(types, nodes):
            if et != 4:
                raise RuntimeError(f"unexpected element type {et}")
            blocks.append(x[index[nd.astype(np.int64)].reshape(-1, 4)])
    return np.concatenate(blocks) if blocks else np.zeros((0, 4, 3))


def tet_volumes(tag: int) -> np.ndarray:
    """Volumes of the tetrahedra of one physical volume group of the current gmsh model (m^3)."""
    return np.abs(tetra.signed_volumes(tet_points(tag)))
