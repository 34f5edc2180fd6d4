"""Run by ParaView's pvpython (not by pytest): read a run's fields.xdmf (or a .vtu) as a user would and print what
was found as one JSON line.

    pvpython paraview_inspect.py FIELDS_XDMF {xdmf3|legacy}
    pvpython paraview_inspect.py GRID_VTU vtu

For every output time: the class of the reader's output (one dataset: vtkUnstructuredGrid, not a multiblock),
its point and cell counts, the names of its point and cell arrays and the range of von_mises_Pa; and the
position of the nose tip (the point of the undeformed geometry at the origin) after WarpByVector by
displacement_m. At the last time, when the cells carry the stress tensor ``stress_Pa``: its number of components
and each cell's three principal stresses as ParaView's own tensor filter finds them (Cell Centers, then Tensor
Glyph extracting the eigenvalues, three glyphs a cell each coloured by its eigenvalue: no Calculator), ascending.
A .vtu: its cell count, cell arrays and the principal stresses.
"""

import json
import sys

from paraview import servermanager
from paraview.simple import CellCenters, TensorGlyph, WarpByVector, Xdmf3ReaderS, XDMFReader, XMLUnstructuredGridReader
from vtkmodules.util.numpy_support import vtk_to_numpy


def principal_stresses(source, t=None) -> list:
    """Each cell's principal values of its ``stress_Pa``, as Tensor Glyph finds them (ascending, Pa)."""
    centres = CellCenters(Input=source)
    centres.VertexCells = 1
    glyph = TensorGlyph(Input=centres, GlyphType="Box")
    glyph.Tensors = ["POINTS", "stress_Pa"]
    glyph.ScaleFactor = 1.0  # the glyphs' scalars are then the eigenvalues themselves
    glyph.LimitScalingByEigenvalues = 0
    glyph.ExtractEigenvalues = 1
    glyph.ThreeGlyphs = 1
    glyph.Symmetric = 0
    glyph.ColorGlyphs = 1
    glyph.Colorby = "eigenvalues"
    glyph.UpdatePipeline(t)
    n = servermanager.Fetch(centres).GetNumberOfPoints()
    values = vtk_to_numpy(servermanager.Fetch(glyph).GetPointData().GetArray("MaxEigenvalue"))
    per = values.reshape(n, 3, -1)  # each cell: three glyphs, each of the glyph source's points
    assert (per == per[:, :, :1]).all()
    return sorted_rows(per[:, :, 0])


def sorted_rows(values) -> list:
    return [sorted(float(v) for v in row) for row in values]


def inspect_vtu(path: str) -> dict:
    reader = XMLUnstructuredGridReader(FileName=[path])
    reader.UpdatePipeline()
    cd = servermanager.Fetch(reader).GetCellData()
    names = [cd.GetArrayName(i) for i in range(cd.GetNumberOfArrays())]
    found = {"cells": servermanager.Fetch(reader).GetNumberOfCells(), "cell_arrays": sorted(names)}
    if "stress_Pa" in names:
        a = cd.GetArray("stress_Pa")
        found["stress_components"] = [a.GetComponentName(i) for i in range(a.GetNumberOfComponents())]
        found["principal_stress_Pa"] = principal_stresses(reader)
    return found


def inspect_xdmf(path: str, which: str) -> dict:
    reader = Xdmf3ReaderS(FileName=[path]) if which == "xdmf3" else XDMFReader(FileNames=[path])
    reader.UpdatePipelineInformation()
    times = list(reader.TimestepValues)
    warp = WarpByVector(Input=reader)
    warp.Vectors = ["POINTS", "displacement_m"]
    rows = []
    for t in times:
        reader.UpdatePipeline(t)
        d = servermanager.Fetch(reader)
        row = {"t": t, "class": d.GetClassName()}
        if d.IsA("vtkDataSet"):
            pd, cd = d.GetPointData(), d.GetCellData()
            row.update(points=d.GetNumberOfPoints(), cells=d.GetNumberOfCells(),
                       point_arrays=sorted(pd.GetArrayName(i) for i in range(pd.GetNumberOfArrays())),
                       cell_arrays=sorted(cd.GetArrayName(i) for i in range(cd.GetNumberOfArrays())))
            vm = cd.GetArray("von_mises_Pa")
            row["von_mises_range"] = list(vm.GetRange()) if vm is not None else None
            row["precision"] = pd.GetArray("displacement_m").GetDataTypeAsString()
            best, tip = None, 0
            for i in range(d.GetNumberOfPoints()):
                p = d.GetPoint(i)
                r = p[0] ** 2 + p[1] ** 2 + p[2] ** 2
                if best is None or r < best:
                    best, tip = r, i
            warp.UpdatePipeline(t)
            w = servermanager.Fetch(warp)
            row["tip"] = list(w.GetPoint(tip))
            if t == times[-1] and cd.GetArray("stress_Pa") is not None:
                row["stress_components"] = cd.GetArray("stress_Pa").GetNumberOfComponents()
                row["principal_stress_Pa"] = principal_stresses(reader, t)
        rows.append(row)
    return {"times": times, "rows": rows}


path, which = sys.argv[1], sys.argv[2]
print(json.dumps(inspect_vtu(path) if which == "vtu" else inspect_xdmf(path, which)))
