"""The stress as one tensor attribute of fields.xdmf (issue 61): FieldWriter writes ``stress_Pa`` beside the six
stress scalars, a cell attribute of nine components (the 3 x 3 matrix row by row) whose values are the scalars',
named by the XDMF as fields.d's per-time files while the run goes on and as fields.h5 once consolidated; meshio
reads it. The writer is given a small box of tetrahedra in place of a solver."""

import xml.etree.ElementTree as ET
from types import SimpleNamespace

import h5py
import numpy as np
import pytest
from mpi4py import MPI

from fepen.io.fields import FieldWriter, full_tensor
from fepen.io.vtu import SYMMETRIC_TENSORS, VTK_SYMMETRIC_ORDER

COMPONENTS = SYMMETRIC_TENSORS["stress_Pa"]


class _IndexMap:
    def __init__(self, n):
        self.size_global = n

    @staticmethod
    def local_to_global(local):
        return np.asarray(local)


def _solver(n=2):
    """A serial solver's view of an n x n x n box of 6 n^3 tetrahedra (what FieldWriter reads of it)."""
    g = np.linspace(0.0, 1.0, n + 1)
    X = np.array([[x, y, z] for x in g for y in g for z in g])

    def node(i, j, k):
        return (i * (n + 1) + j) * (n + 1) + k

    kuhn = [(0, 1, 3, 7), (0, 1, 5, 7), (0, 2, 3, 7), (0, 2, 6, 7), (0, 4, 5, 7), (0, 4, 6, 7)]
    cells = []
    for i in range(n):
        for j in range(n):
            for k in range(n):
                corner = [node(i + (c >> 2 & 1), j + (c >> 1 & 1), k + (c & 1)) for c in range(8)]
                cells += [[corner[a] for a in t] for t in kuhn]
    cells = np.array(cells, dtype=np.int32)
    return SimpleNamespace(comm=MPI.COMM_SELF, V=SimpleNamespace(dofmap=SimpleNamespace(index_map=_IndexMap(len(X)))),
                           n_owned=len(X), n_nodes=len(X), n_cells=len(cells), dofs=cells, X0=X)


def _values(solver, rng, names):
    v = {"displacement_m": rng.standard_normal((solver.n_owned, 3)) * 1e-3}
    v.update({name: rng.standard_normal(solver.n_cells) * 3e8 for name in names})
    return v


def _attributes(xdmf):
    """{grid name: {attribute name: (AttributeType, Center, Dimensions, data path)}} of fields.xdmf."""
    root = ET.parse(xdmf).getroot()
    found = {}
    for grid in root.iter("Grid"):
        if grid.get("GridType") != "Uniform":
            continue
        found[grid.get("Name")] = {a.get("Name"): (a.get("AttributeType"), a.get("Center"),
                                                   a.find("DataItem").get("Dimensions"), a.find("DataItem").text)
                                   for a in grid.iter("Attribute")}
    return found


def _read(out, where):
    path, name = where.split(":")
    with h5py.File(out / path, "r") as h5:
        return h5[name][()]


def _check_tensor(out, n_cells, n_times):
    """Every grid's stress_Pa is a cell Tensor of nine components, symmetric, its components the scalars'."""
    grids = _attributes(out / "fields.xdmf")
    assert len(grids) == n_times
    for attrs in grids.values():
        kind, centre, dims, where = attrs["stress_Pa"]
        assert (kind, centre, dims) == ("Tensor", "Cell", f"{n_cells} 9")
        tensor = _read(out, where).reshape(-1, 3, 3)
        scalars = np.column_stack([_read(out, attrs[c][3]).ravel() for c in COMPONENTS])
        assert tensor.dtype == np.float64 and np.array_equal(tensor, np.transpose(tensor, (0, 2, 1)))
        row_col = {"X": 0, "Y": 1, "Z": 2}
        for k, comp in enumerate(VTK_SYMMETRIC_ORDER):  # xx, yy, zz, xy, yz, xz
            assert np.array_equal(tensor[:, row_col[comp[0]], row_col[comp[1]]], scalars[:, k]), comp
        # the principal stresses of the attribute are those of the six scalars
        matrices = np.zeros((len(scalars), 3, 3))
        for k, comp in enumerate(VTK_SYMMETRIC_ORDER):
            i, j = row_col[comp[0]], row_col[comp[1]]
            matrices[:, i, j] = matrices[:, j, i] = scalars[:, k]
        np.testing.assert_allclose(np.linalg.eigvalsh(tensor), np.linalg.eigvalsh(matrices), rtol=0, atol=1e-6)
    return grids


def _meshio_tensor(out):
    meshio = pytest.importorskip("meshio")
    with meshio.xdmf.TimeSeriesReader(str(out / "fields.xdmf")) as ts:
        ts.read_points_cells()
        steps = [ts.read_data(k) for k in range(ts.num_steps)]
    return [(t, np.concatenate(cd["stress_Pa"]), np.concatenate(cd["stress_xy_Pa"]).ravel()) for t, _, cd in steps]


def test_the_stress_tensor_attribute_is_the_six_scalars(tmp_path):
    solver, rng = _solver(), np.random.default_rng(61)
    w = FieldWriter(tmp_path, solver, ["displacement_m"], ["von_mises_Pa", *COMPONENTS])
    assert list(w.tensors) == ["stress_Pa"]
    for t in (1e-5, 2e-5):
        w.write(t, _values(solver, rng, ["von_mises_Pa", *COMPONENTS]))
    grids = _check_tensor(tmp_path, solver.n_cells, 2)  # while running: fields.d's files
    assert all(a["stress_Pa"][3].startswith("fields.d/") for a in grids.values())
    running = _meshio_tensor(tmp_path)
    w.consolidate()
    grids = _check_tensor(tmp_path, solver.n_cells, 2)
    assert all(a["stress_Pa"][3].startswith("fields.h5:/Function/stress_Pa/") for a in grids.values())
    # the scalars stay, as they were
    assert all(a[c][:3] == ("Scalar", "Cell", f"{solver.n_cells} 1") for a in grids.values() for c in COMPONENTS)
    done = _meshio_tensor(tmp_path)
    for (t0, s0, _), (t1, s1, xy1) in zip(running, done):
        assert t0 == t1 and s0.shape == (solver.n_cells, 9)
        assert np.array_equal(s0, s1) and np.array_equal(s1[:, 1], xy1) and np.array_equal(s1[:, 3], xy1)


def test_no_tensor_without_all_six_components(tmp_path):
    solver, rng = _solver(1), np.random.default_rng(1)
    names = ["von_mises_Pa", *COMPONENTS[:5]]
    w = FieldWriter(tmp_path, solver, ["displacement_m"], names)
    w.write(1e-5, _values(solver, rng, names))
    w.consolidate()
    assert w.tensors == {} and "stress_Pa" not in next(iter(_attributes(tmp_path / "fields.xdmf").values()))
    with h5py.File(tmp_path / "fields.h5", "r") as h5:
        assert "stress_Pa" not in h5["/Function"]


def test_full_tensor_is_the_matrix_row_by_row():
    xx, yy, zz, xy, yz, xz = 1.0, 2.0, 3.0, 4.0, 5.0, 6.0
    assert full_tensor(np.array([[xx, yy, zz, xy, yz, xz]])).tolist() == [[xx, xy, xz, xy, yy, yz, xz, yz, zz]]


def test_the_run_writes_the_components_the_tensor_is_made_of():
    """The run's six stress fields (fepen.runs.shot) are the tensor's components, in the solver's column order."""
    from fepen.runs import shot

    assert shot.STRESS_TENSOR_FIELDS == COMPONENTS
