"""VTK XML unstructured grids (.vtu) for ParaView, pyvista and meshio: one piece, its arrays appended raw after
the XML (each an 8-byte little-endian byte count, then the values), as VTK's own writer lays them out.

fepen writes its stress maps' cut planes and its meshes' .vtu twins with it (it used meshio's writer, whose
import, with every format meshio knows, took 0.13 s of a run's closing figures on each rank).

A symmetric tensor whose six component arrays are all written (SYMMETRIC_TENSORS: the Cauchy stress's
stress_xx_Pa ... stress_xz_Pa) is also written as one 6-component array (``stress_Pa``) in VTK's own order of a
symmetric tensor, XX, YY, ZZ, XY, YZ, XZ (each component named), which ParaView's tensor filters (Tensor Glyph)
take as it is.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["write_vtu", "CELL_TYPES", "SYMMETRIC_TENSORS", "VTK_SYMMETRIC_ORDER"]

#: VTK's cell type numbers of the cells fepen writes
CELL_TYPES = {"triangle": 5, "quad": 9, "tetra": 10}

#: VTK's order of a symmetric tensor's six components (vtkMath::TensorFromSymmetricTensor, ParaView's names)
VTK_SYMMETRIC_ORDER = ("XX", "YY", "ZZ", "XY", "YZ", "XZ")

#: symmetric tensors written as one array wherever their six component fields are all written (here, and in
#: fields.xdmf, fepen.io.fields): name -> its components' field names in VTK_SYMMETRIC_ORDER (the solver's
#: stress columns, fepen.runs.shot.STRESS_TENSOR_FIELDS)
SYMMETRIC_TENSORS = {"stress_Pa": tuple(f"stress_{c.lower()}_Pa" for c in VTK_SYMMETRIC_ORDER)}

_TYPES = {np.dtype(np.float64): "Float64", np.dtype(np.float32): "Float32", np.dtype(np.int64): "Int64",
          np.dtype(np.int32): "Int32", np.dtype(np.uint8): "UInt8"}


def write_vtu(path: Path, points: np.ndarray, blocks: list[tuple[str, np.ndarray]],
              cell_data: dict[str, list[np.ndarray]] | None = None) -> None:
    """Write an unstructured grid to ``path`` (replaced whole, fepen.atomic).

    Args:
        path: the .vtu file.
        points: (n, 3) coordinates (m).
        blocks: (kind, connectivity (k, m) point indices) per cell kind, kind a key of CELL_TYPES; the cells
            are numbered block after block.
        cell_data: name -> one array per block (its cells' values: float64, float32, int64 or int32), (k,) or
            (k, c) for c components; the six components of a SYMMETRIC_TENSORS entry also make its tensor.
    """
    from fepen.atomic import replacing

    points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    conn = [np.atleast_2d(np.asarray(c, dtype=np.int64)) for _, c in blocks]
    n_cells = sum(len(c) for c in conn)
    connectivity = np.concatenate([c.ravel() for c in conn]) if conn else np.zeros(0, dtype=np.int64)
    offsets = np.cumsum(np.concatenate([np.full(len(c), c.shape[1], dtype=np.int64) for c in conn])
                        if conn else np.zeros(0, dtype=np.int64))
    types = np.concatenate([np.full(len(c), CELL_TYPES[kind], dtype=np.uint8) for (kind, _), c in zip(blocks, conn)]
                           ) if conn else np.zeros(0, dtype=np.uint8)
    arrays: list[tuple[str, np.ndarray, int]] = []  # (the XML attributes, the values, components)
    arrays.append(('NumberOfComponents="3"', points, 3))
    cells_xml = [('Name="connectivity"', connectivity, 1), ('Name="offsets"', offsets, 1), ('Name="types"', types, 1)]
    data_xml = []
    for name, values in _cell_arrays(cell_data or {}).items():
        if len(values) != n_cells:
            raise ValueError(f"cell data {name!r} has {len(values)} values for {n_cells} cells")
        c = values.shape[1] if values.ndim == 2 else 1
        attrs = f'Name="{name}"' + (f' NumberOfComponents="{c}"' if c > 1 else "")
        if c == 6 and name in SYMMETRIC_TENSORS:
            attrs += "".join(f' ComponentName{i}="{n}"' for i, n in enumerate(VTK_SYMMETRIC_ORDER))
        data_xml.append((attrs, values, c))
    offset, payload, lines = 0, [], []

    def array(attrs: str, values: np.ndarray) -> str:
        nonlocal offset
        raw = np.ascontiguousarray(values).astype(values.dtype.newbyteorder("<"), copy=False).tobytes()
        payload.append(np.array([len(raw)], dtype="<u8").tobytes() + raw)
        line = f'<DataArray type="{_TYPES[values.dtype]}" {attrs} format="appended" offset="{offset}"/>'
        offset += 8 + len(raw)
        return line

    lines += ['<?xml version="1.0"?>',
              '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">',
              "  <UnstructuredGrid>", f'    <Piece NumberOfPoints="{len(points)}" NumberOfCells="{n_cells}">',
              "      <Points>", "        " + array(arrays[0][0], points), "      </Points>", "      <Cells>"]
    lines += ["        " + array(a, v) for a, v, _ in cells_xml]
    lines += ["      </Cells>", "      <CellData>"]
    lines += ["        " + array(a, v) for a, v, _ in data_xml]
    lines += ["      </CellData>", "    </Piece>", "  </UnstructuredGrid>", '  <AppendedData encoding="raw">']
    head = ("\n".join(lines) + "\n   _").encode()
    tail = b"\n  </AppendedData>\n</VTKFile>\n"
    with replacing(Path(path), ".vtu") as tmp:
        tmp.write_bytes(head + b"".join(payload) + tail)


def _cell_arrays(cell_data: dict) -> dict[str, np.ndarray]:
    """Each cell array over all blocks ((n,) or (n, c), of a type VTK XML names), and the SYMMETRIC_TENSORS
    whose six components are among them ((n, 6), VTK_SYMMETRIC_ORDER) after them."""
    arrays = {}
    for name, parts in cell_data.items():
        parts = [np.asarray(p) for p in parts]
        values = np.concatenate([p if p.ndim == 2 else p.ravel() for p in parts]) if parts else np.zeros(0)
        arrays[name] = values if values.dtype in _TYPES else values.astype(np.float64)
    for name, parts in SYMMETRIC_TENSORS.items():
        if name not in arrays and all(p in arrays and arrays[p].ndim == 1 for p in parts):
            arrays[name] = np.column_stack([arrays[p].astype(np.float64) for p in parts])
    return arrays
