"""Projectile bodies from CAD files (STEP or BREP), read and meshed with gmsh's OpenCASCADE kernel
(docs/projectiles-and-targets.md). The body is taken as drawn: axis along +y, nose toward −y; fepen moves it
so that its foremost point is at y = 0 and scales it to metres. No exact surface: the target loads the
mesh's own facets; mass properties come from the mesh. CadBody is such a body where a Shape (the exact
solid of revolution) would be.
"""

from __future__ import annotations

import hashlib
import math
import os
from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from fepen.errors import InputError


@dataclass(frozen=True)
class CadBody:
    """A projectile body read from a CAD file: no meridian, no exact surface or volume (those come from its
    mesh). Body frame as fepen.geometry.shape: foremost point at y = 0, axis along +y.

    Attributes:
        diameter, length: calibre (twice the largest distance from the y axis) and length along y (m), as
            probe measures them.
        file: the STEP or BREP file (absolute path). scale: metres per file unit.
        digest: digest(file), so that a changed file is meshed again (mesh-cache key).
        tip_point, tail_point: the mesh nodes tracked as nose tip and tail centre (end_nodes), set once the
            body is meshed; () before.
    """

    diameter: float
    length: float
    file: str
    scale: float = 1.0
    digest: str = ""
    tip_point: tuple = ()
    tail_point: tuple = ()

    #: a CAD body is meshed solid: fepen sizes no cavity in it
    has_cavity: ClassVar[bool] = False
    #: no cavity sized (mesh.json's cavity_length_m)
    cavity_length: ClassVar[float] = 0.0
    #: the nose's length is not known (taken as 0: the whole body is calibre)
    nose_length: ClassVar[float] = 0.0

    def __post_init__(self):
        for name in ("tip_point", "tail_point"):  # lists from JSON back to tuples
            object.__setattr__(self, name, tuple(float(v) for v in getattr(self, name)))

    @property
    def radius(self) -> float:
        """Half the calibre (m)."""
        return 0.5 * self.diameter

    @property
    def tip(self) -> tuple:
        """The tracked nose-tip point (a mesh node; the origin before meshing)."""
        return self.tip_point or (0.0, 0.0, 0.0)

    @property
    def tail(self) -> tuple:
        """The tracked tail-centre point (a mesh node; (0, length, 0) before meshing)."""
        return self.tail_point or (0.0, self.length, 0.0)

    def outer_radius(self, z):
        """The enclosing cylinder's radius at axial distances z from the tip (m): the calibre's half."""
        return np.full(np.shape(z), self.radius) if np.ndim(z) else self.radius

    def meshed_volume(self, charge: bool) -> float:
        """The volume gmsh fills, as known before meshing (m^3): the enclosing cylinder's."""
        return math.pi / 4.0 * self.diameter ** 2 * self.length

    def exact_volume(self, charge: bool) -> None:
        """The exact volume its mesh approximates: not known (no meridian), None.

        Args:
            charge: unused (a CAD body has no charge).

        Returns:
            None.
        """
        return None

    def exact_mass(self, shell_density: float, charge_density: float | None = None) -> None:
        """The mass known before any mesh: none, None (it comes from the mesh).

        Args:
            shell_density, charge_density: unused.

        Returns:
            None.
        """
        return None

    def needs_volume_mesh(self, fidelity: str) -> bool:
        """Whether a run of this fidelity meshes the body: always (the rigid body's load points and mass
        properties come from its mesh, fepen.runs.rigid.mesh_points).

        Args:
            fidelity: effects.fidelity (unused).

        Returns:
            True.
        """
        return True

    def crater_nose_factor(self) -> float:
        """N* the linear crater takes: 0, as fepen always took it (a CAD body has no meridian)."""
        return 0.0

    def after_meshing(self) -> CadBody:
        """The body with its tracked ends set to the mesh nodes gmsh just made (end_nodes)."""
        tip, tail = end_nodes()
        return replace(self, tip_point=tip, tail_point=tail)


def digest(path: str) -> str:
    """A short hash of the file's bytes (mesh-cache key): a changed file is meshed again. Read as probe checks
    it (a regular file, opened without blocking), in blocks."""
    h = hashlib.sha256()
    with _opened(path) as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()[:16]


def _opened(path: str):
    """The CAD file open for reading: a regular file of at most CAD_MAX bytes, checked without blocking (a pipe
    or a device named projectile.cad is refused, not read for ever). InputError (projectile.cad) else."""
    from fepen.inputs import open_input, unreadable

    try:
        fh = open_input(path)
    except (OSError, ValueError) as err:
        raise unreadable(err, path, "projectile.cad", "a STEP or BREP body", missing=f"no such file: {path}") from None
    size = os.fstat(fh.fileno()).st_size
    if size > CAD_MAX:
        fh.close()
        raise InputError("projectile.cad", f"{path!r} is {size} bytes: a STEP or BREP body is at most "
                                           f"{CAD_MAX >> 20} MiB")
    return fh


def _import(path: str, scale: float) -> list:
    """Import the file into a new gmsh model, scaled to metres; its volumes (dim, tag)."""
    import gmsh

    if not gmsh.isInitialized():
        gmsh.initialize(interruptible=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("Geometry.OCCBoundsUseStl", 1)
    gmsh.model.add("cad")
    try:
        ents = gmsh.model.occ.importShapes(str(path))
    except Exception as err:  # gmsh raises a bare Exception with OpenCASCADE's message
        raise InputError("projectile.cad", f"gmsh cannot read {path!r} as STEP or BREP: {err}") from None
    vols = [(d, t) for d, t in ents if d == 3]
    if not vols:
        raise InputError("projectile.cad", f"{path!r} holds no solid (volume): fepen needs a closed body")
    if scale != 1.0:
        gmsh.model.occ.dilate(gmsh.model.occ.getEntities(), 0.0, 0.0, 0.0, scale, scale, scale)
    gmsh.model.occ.synchronize()
    return vols


#: the largest CAD file read (bytes)
CAD_MAX = 512 << 20


def probe(path: str, scale: float) -> tuple[float, float]:
    """The body's calibre (twice its largest distance from the y axis) and length along y (m).

    Raises:
        InputError (projectile.cad): no such file, unreadable, or no solid in it.
    """
    import gmsh

    _opened(path).close()  # gmsh opens it by name: checked here first
    _import(path, scale)
    xmin, ymin, zmin, xmax, ymax, zmax = gmsh.model.getBoundingBox(-1, -1)
    gmsh.model.remove()
    return 2.0 * max(-xmin, xmax, -zmin, zmax), ymax - ymin


def build(path: str, scale: float) -> None:
    """The CAD body in the current gmsh model, foremost point at y = 0, tagged: every volume SHELL, its
    boundary OUTER (fepen.geometry.tags); not yet meshed."""
    import gmsh

    from fepen.geometry import tags

    vols = _import(path, scale)
    _, ymin, _, _, _, _ = gmsh.model.getBoundingBox(-1, -1)
    gmsh.model.occ.translate(gmsh.model.occ.getEntities(), 0.0, -ymin, 0.0)
    if len(vols) > 1:
        gmsh.model.occ.fragment(vols[:1], vols[1:])
    gmsh.model.occ.removeAllDuplicates()
    gmsh.model.occ.synchronize()
    vols = [t for _, t in gmsh.model.getEntities(3)]
    gmsh.model.addPhysicalGroup(3, vols, tags.SHELL)
    bnd = gmsh.model.getBoundary([(3, t) for t in vols], combined=True, oriented=False)
    gmsh.model.addPhysicalGroup(2, sorted({abs(t) for _, t in bnd}), tags.OUTER)


def end_nodes() -> tuple[tuple, tuple]:
    """The mesh nodes fepen tracks as nose tip and tail centre: of the nodes within 1e-9 m of the foremost
    (rearmost) y, the one nearest the axis."""
    import gmsh

    _, coords, _ = gmsh.model.mesh.getNodes()
    x = coords.reshape(-1, 3)
    out = []
    for y in (x[:, 1].min(), x[:, 1].max()):
        near = np.flatnonzero(np.abs(x[:, 1] - y) < 1e-9)
        k = near[np.argmin(np.hypot(x[near, 0], x[near, 2]))]
        out.append(tuple(float(v) for v in x[k]))
    return out[0], out[1]
