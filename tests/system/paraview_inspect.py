"""Run by ParaView's pvpython (not by pytest): read a run's fields.xdmf as a user would and print what was found
as one JSON line.

    pvpython paraview_inspect.py FIELDS_XDMF {xdmf3|legacy}

For every output time: the class of the reader's output (one dataset: vtkUnstructuredGrid, not a multiblock),
its point and cell counts, the names of its point and cell arrays and the range of von_mises_Pa; and the
position of the nose tip (the point of the undeformed geometry at the origin) after WarpByVector by
displacement_m.
"""

import json
import sys

from paraview import servermanager
from paraview.simple import WarpByVector, Xdmf3ReaderS, XDMFReader

path, which = sys.argv[1], sys.argv[2]
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
    rows.append(row)
print(json.dumps({"times": times, "rows": rows}))
