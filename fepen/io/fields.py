"""Field output (fields.xdmf + fields.h5, gathered to rank 0) that a killed run never leaves half-written:
one HDF5 file per output time while the run goes on, one self-contained file at its end (docs/theory.md §12,
docs/results.md). fields.xdmf is one temporal collection with one grid per output time carrying the mesh
and every field of that time, all data items declared with their precision, so that ParaView (Xdmf3 and
legacy XDMF readers), pyvista and meshio's TimeSeriesReader read it as one dataset per time. The Cauchy stress,
when its six components are written, is also one tensor attribute (``stress_Pa``, a "Tensor": full_tensor).
"""

from __future__ import annotations

import shutil
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np
from mpi4py import MPI

from fepen.atomic import make_dir, replacing
from fepen.io import layout
from fepen.io.vtu import SYMMETRIC_TENSORS

#: what fields.xdmf says of its own frame and units (an Information element of its Domain)
#: what fepen writes in fields.d/ (fepen.io.layout)
_TIMES = layout.RUN.node("fields.d")
FRAME = ("fepen field output. Frame: the target's, in metres; the target face is the plane y = 0 and the target "
         "lies at y < 0 (depth = -y); the impact plane is x-y, z is normal to it; the geometry is the undeformed "
         "projectile (tip at the origin, axis +y towards the tail) placed at t = 0 by displacement_m, which is the "
         "total displacement from that geometry (warp by it for the deformed body). Units are in the names "
         "(Pa, K, m, m/s); peeq is dimensionless; cell_tag: 1 shell, 2 charge, 0 eroded.")


INT32, FLOAT64 = 'NumberType="Int" Precision="4"', 'NumberType="Float" Precision="8"'

# A tensor of fields.xdmf is an attribute of AttributeType "Tensor" (nine components: the 3 x 3 matrix row by row,
# xx, xy, xz, yx, yy, yz, zx, zy, zz), not "Tensor6" (docs/results.md, "The stress tensor"): a Tensor6 (XDMF's
# order xx, xy, xz, yy, yz, zz) is expanded to nine components by ParaView's legacy XDMF reader, but handed to VTK
# as its six values by the Xdmf3 reader (ParaView's and pyvista's), and VTK's tensor filters take six components
# in VTK's order xx, yy, zz, xy, yz, xz: two readers, two tensors, other principal stresses (seen in ParaView
# 5.11; VTK's current Xdmf3 reader has no conversion either). Nine components are one tensor to every reader.


def full_tensor(components: np.ndarray) -> np.ndarray:
    """The nine components of symmetric tensors, row by row (xx, xy, xz, yx, yy, yz, zx, zy, zz).

    Args:
        components: (n, 6) in fepen.io.vtu.VTK_SYMMETRIC_ORDER (xx, yy, zz, xy, yz, xz).

    Returns:
        (n, 9) float64.
    """
    return np.asarray(components, dtype=np.float64)[:, [0, 3, 5, 3, 1, 4, 5, 4, 2]]


def _time_name(t: float) -> str:
    """dolfinx's dataset name for an output time."""
    return repr(float(t)).replace(".", "_") if t != 0 else "0"


class FieldWriter:
    """fields.xdmf + fields.h5 of a run.

    Args:
        out: results directory.
        solver: the ExplicitSolver (its mesh, index maps and reference positions).
        nodal: names of nodal vector fields, in writing order.
        cell: names of cell scalar fields, in writing order.
        nodal_scalar: names of nodal scalar fields, written after the cell fields.
        times: output times already written (when resuming a run; later step files are deleted).
        integer: the names (of any kind) whose values are integers (written as int32).

    A symmetric tensor whose six components are all among ``cell`` (fepen.io.vtu.SYMMETRIC_TENSORS) is written
    beside them as one more cell field of nine components (full_tensor), a "Tensor" attribute of fields.xdmf.
    """

    def __init__(self, out: Path, solver, nodal: list[str], cell: list[str], times: list[float] = (),
                 nodal_scalar: list[str] = (), integer: tuple[str, ...] = ()):
        self.out, self.comm = Path(out), solver.comm
        self.nodal, self.cell, self.nodal_scalar = list(nodal), list(cell), list(nodal_scalar)
        self.integer = set(integer)
        self.tensors = {name: parts for name, parts in SYMMETRIC_TENSORS.items() if set(parts) <= set(self.cell)}
        self.times = list(times)
        self.dir = self.out / "fields.d"
        imap = solver.V.dofmap.index_map
        self._n_owned = solver.n_owned
        self._n_cells = solver.n_cells
        counts_n = self.comm.gather(self._n_owned, root=0)
        counts_c = self.comm.gather(self._n_cells, root=0)
        self.n_nodes_global = imap.size_global
        self.n_cells_global = self.comm.allreduce(self._n_cells, op=MPI.SUM)
        # global topology: each rank's cells in global node numbering
        l2g = np.asarray(imap.local_to_global(np.arange(solver.n_nodes, dtype=np.int32)), dtype=np.int64)
        topo = self._gather(l2g[solver.dofs])
        geom = self._gather(solver.X0[: self._n_owned])  # the undeformed, unworn body
        if self.comm.rank == 0:
            assert sum(counts_n) == self.n_nodes_global and sum(counts_c) == self.n_cells_global
            make_dir(self.dir)  # fepen's or new, never a link
            mesh_file = self.dir / "mesh.h5"
            if not self.times or not mesh_file.exists():
                self._write_h5(mesh_file, {"geometry": geom, "topology": topo})
            keep = {mesh_file.name} | {self._step_file(k).name for k in range(len(self.times))}
            for f in self.dir.iterdir():  # output times after a checkpoint, and temporaries (a user's file stays)
                if f.name not in keep and (_TIMES.node(f.name) is layout.LEAF or _TIMES.temporary(f.name)):
                    f.unlink()
            self._write_index()

    @property
    def names(self) -> list[str]:
        """Every field name, in writing order."""
        return self.nodal + self.cell + self.nodal_scalar

    @property
    def datasets(self) -> list[str]:
        """Every field's dataset of an output time: the fields, then the tensors made of them."""
        return self.names + list(self.tensors)

    # ------------------------------------------------------------------------------------------------
    def _gather(self, local: np.ndarray):
        parts = self.comm.gather(np.ascontiguousarray(local), root=0)
        return np.concatenate(parts) if self.comm.rank == 0 else None

    def _step_file(self, k: int) -> Path:
        return self.dir / f"{k:06d}.h5"

    @staticmethod
    def _write_h5(path: Path, datasets: dict) -> None:
        """One HDF5 file, made in memory and written as plain bytes: a full disk is then an OSError of Python's
        write, never an error inside the HDF5 library (which leaves it unable to close its files)."""
        import io

        import h5py

        buf = io.BytesIO()
        with h5py.File(buf, "w") as h5:
            for name, data in datasets.items():
                h5.create_dataset(name, data=data)
        with replacing(path) as tmp:
            tmp.write_bytes(buf.getbuffer())

    def write(self, t: float, values: dict[str, np.ndarray]) -> None:
        """Write one output time (collective).

        Args:
            t: time (s).
            values: name -> nodal (n_owned, 3), cell (n_cells,) or nodal scalar (n_owned,) array (longer
                arrays are cut), for every name given.
        """
        from fepen.io import files

        data = {}
        for name in self.nodal + self.nodal_scalar:
            data[name] = self._gather(values[name][: self._n_owned])
        for name in self.cell:
            data[name] = self._gather(values[name][: self._n_cells])

        def write():  # the step file, then the index naming it: a failure leaves the index of the times before
            files.inject("fields")
            arrays = {k: (v.reshape(-1, 1) if v.ndim == 1 else v) for k, v in data.items()}
            arrays = {k: (np.rint(v).astype(np.int32) if k in self.integer else v) for k, v in arrays.items()}
            for name, parts in self.tensors.items():
                arrays[name] = full_tensor(np.column_stack([data[p] for p in parts]))
            self._write_h5(self._step_file(len(self.times)), arrays)
            self.times.append(float(t))
            try:
                self._write_index()
            except OSError:
                self.times.pop()
                raise

        files.agree(self.comm, f"{self.out / 'fields.xdmf'} at t = {t * 1e6:.3f} us", write)
        if self.comm.rank != 0:
            self.times.append(float(t))

    def _write_index(self) -> None:
        """fields.h5 of external links and fields.xdmf, each replaced atomically (rank 0)."""
        import io

        import h5py

        buf = io.BytesIO()
        with h5py.File(buf, "w") as h5:
            for name in ("geometry", "topology"):
                h5[f"/Mesh/mesh/{name}"] = h5py.ExternalLink("fields.d/mesh.h5", f"/{name}")
            for k, t in enumerate(self.times):
                for name in self.datasets:
                    h5[f"/Function/{name}/{_time_name(t)}"] = h5py.ExternalLink(
                        f"fields.d/{self._step_file(k).name}", f"/{name}")
        with replacing(self.out / "fields.h5") as tmp:
            tmp.write_bytes(buf.getbuffer())
        self._write_xdmf()

    def _write_xdmf(self, consolidated: bool = False) -> None:
        """fields.xdmf: one temporal collection of one grid per output time, each with the mesh and every
        field of that time (ParaView sees one dataset). While the run goes on, the data items name the
        per-time files of fields.d directly (no HDF5 external links, which not every reader follows); once
        consolidated, fields.h5."""
        nc, nn = self.n_cells_global, self.n_nodes_global
        if consolidated:
            mesh = {"geometry": "fields.h5:/Mesh/mesh/geometry", "topology": "fields.h5:/Mesh/mesh/topology"}
        else:
            mesh = {k: f"fields.d/mesh.h5:/{k}" for k in ("geometry", "topology")}
        lines = ['<?xml version="1.0"?>', '<!DOCTYPE Xdmf SYSTEM "Xdmf.dtd" []>', '<Xdmf Version="3.0">',
                 "  <Domain>", f"    <Information Name=\"fepen\" Value={quoteattr(FRAME)} />",
                 '    <Grid Name="fields" GridType="Collection" CollectionType="Temporal">']
        for k, t in enumerate(self.times):
            lines += [f'      <Grid Name="t{k:06d}" GridType="Uniform">', f'        <Time Value="{float(t)!r}" />',
                      f'        <Topology TopologyType="Tetrahedron" NumberOfElements="{nc}" NodesPerElement="4">',
                      f'          <DataItem Dimensions="{nc} 4" NumberType="Int" Precision="8" Format="HDF">'
                      f'{mesh["topology"]}</DataItem>', "        </Topology>", '        <Geometry GeometryType="XYZ">',
                      f'          <DataItem Dimensions="{nn} 3" NumberType="Float" Precision="8" Format="HDF">'
                      f'{mesh["geometry"]}</DataItem>', "        </Geometry>"]
            for name in self.datasets:
                if name in self.nodal:
                    dims, kind, centre = f"{nn} 3", "Vector", "Node"
                elif name in self.cell:
                    dims, kind, centre = f"{nc} 1", "Scalar", "Cell"
                elif name in self.tensors:
                    dims, kind, centre = f"{nc} 9", "Tensor", "Cell"  # not Tensor6: see full_tensor
                else:
                    dims, kind, centre = f"{nn} 1", "Scalar", "Node"
                number = INT32 if name in self.integer else FLOAT64
                where = (f"fields.h5:/Function/{name}/{_time_name(t)}" if consolidated
                         else f"fields.d/{self._step_file(k).name}:/{name}")
                lines += [f'        <Attribute Name={quoteattr(name)} AttributeType="{kind}" Center="{centre}">',
                          f'          <DataItem Dimensions="{dims}" {number} Format="HDF">{where}</DataItem>',
                          "        </Attribute>"]
            lines.append("      </Grid>")
        lines += ["    </Grid>", "  </Domain>", "</Xdmf>", ""]
        path = self.out / "fields.xdmf"
        with replacing(path) as tmp:
            tmp.write_text("\n".join(lines))

    def consolidate(self) -> None:
        """Copy every output time into a self-contained fields.h5 (atomic) and remove fields.d (rank 0;
        call on every rank)."""
        if self.comm.rank == 0 and self.dir.exists():
            import h5py

            need = sum(f.stat().st_size for f in self.dir.iterdir())
            free = shutil.disk_usage(self.out).free
            if free < 1.1 * need + (1 << 20):  # HDF5 must not meet a full disk: it cannot recover
                raise OSError(28, f"No space left on device: {need / 1e6:.1f} MB needed to consolidate the "
                                  f"fields, {free / 1e6:.1f} MB free (fields.d is kept, readable)",
                              str(self.out / "fields.h5"))
            path = self.out / "fields.h5"
            with replacing(path) as tmp, h5py.File(tmp, "w") as dst:
                with h5py.File(self.dir / "mesh.h5", "r") as src:
                    for name in ("geometry", "topology"):
                        dst.create_dataset(f"/Mesh/mesh/{name}", data=src[name][()])
                for k, t in enumerate(self.times):
                    with h5py.File(self._step_file(k), "r") as src:
                        for name in self.datasets:
                            dst.create_dataset(f"/Function/{name}/{_time_name(t)}", data=src[name][()])
            self._write_xdmf(consolidated=True)
            layout.remove_entry(self.dir, _TIMES)  # what fepen wrote there (a user's file stays, and the folder)
        self.comm.barrier()


def mesh_index(h5_path: Path, cells_xdmf: Path, facets_xdmf: Path) -> None:
    """Rewrite the XDMF index of a mesh written by dolfinx's XDMFFile (mesh, cell tags, facet tags in one
    file, three grids, which pyvista and meshio.read refuse) as two files of one grid each, on the same HDF5
    datasets: the tetrahedra with ``cell_tag`` (every cell is tagged: the cell tags' own topology is the
    mesh) and the tagged facets with ``facet_tag``; and each as .vtu beside it, for pyvista (rank 0)."""
    import h5py

    def item(ds, path):
        kind = "Float" if ds.dtype.kind == "f" else "Int"
        dims = " ".join(str(n) for n in ds.shape)
        return (f'<DataItem Dimensions="{dims}" NumberType="{kind}" Precision="{ds.dtype.itemsize}" '
                f'Format="HDF">{h5_path.name}:{path}</DataItem>')

    with h5py.File(h5_path, "r") as h5:
        geometry = item(h5["/Mesh/mesh/geometry"], "/Mesh/mesh/geometry")
        for target, group, shape, name in ((cells_xdmf, "Cell tags", "Tetrahedron", "cell_tag"),
                                           (facets_xdmf, "Facet tags", "Triangle", "facet_tag")):
            topo, values = h5[f"/MeshTags/{group}/topology"], h5[f"/MeshTags/{group}/Values"]
            lines = ['<?xml version="1.0"?>', '<Xdmf Version="3.0">', "  <Domain>",
                     f"    <!-- {FRAME.split(' Units')[0].replace('--', '-')} -->",  # meshio.read wants one child
                     '    <Grid Name="mesh" GridType="Uniform">',
                     f'      <Topology TopologyType="{shape}" NumberOfElements="{topo.shape[0]}">',
                     f"        {item(topo, f'/MeshTags/{group}/topology')}", "      </Topology>",
                     '      <Geometry GeometryType="XYZ">', f"        {geometry}", "      </Geometry>",
                     f'      <Attribute Name="{name}" AttributeType="Scalar" Center="Cell">',
                     f"        {item(values, f'/MeshTags/{group}/Values')}", "      </Attribute>",
                     "    </Grid>", "  </Domain>", "</Xdmf>", ""]
            with replacing(target) as tmp:
                tmp.write_text("\n".join(lines))
            _write_vtu(target.with_suffix(".vtu"), h5["/Mesh/mesh/geometry"][()], topo[()], name, values[()])


def _write_vtu(path: Path, points: np.ndarray, cells: np.ndarray, name: str, values: np.ndarray) -> None:
    """The same grid as VTK XML (.vtu): pyvista's XDMF reader cannot open an XDMF file without time values
    (pyvista 0.49), and a static XDMF file with them is one meshio.read cannot open."""
    from fepen.io.vtu import write_vtu

    kind = {4: "tetra", 3: "triangle"}[cells.shape[1]]
    write_vtu(path, points, [(kind, cells)], {name: [values.ravel()]})
