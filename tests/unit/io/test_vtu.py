"""fepen.io.vtu.write_vtu: the grid meshio and pyvista (VTK) read back is the one written, to the bit."""

import numpy as np
import pytest

from fepen.io.vtu import write_vtu


def test_a_mixed_grid_reads_back_the_same(tmp_path):
    meshio = pytest.importorskip("meshio")
    rng = np.random.default_rng(5)
    points = rng.standard_normal((40, 3))
    tri, quad = rng.integers(0, 40, (7, 3)), rng.integers(0, 40, (5, 4))
    stress = [rng.standard_normal(7), rng.standard_normal(5)]
    tag = [np.full(7, 1, dtype=np.int32), np.full(5, 2, dtype=np.int32)]
    path = tmp_path / "g.vtu"
    write_vtu(path, points, [("triangle", tri), ("quad", quad)], {"s": stress, "tag": tag})
    m = meshio.read(path)
    assert np.array_equal(m.points, points)
    assert [c.type for c in m.cells] == ["triangle", "quad"]
    assert np.array_equal(m.cells[0].data, tri) and np.array_equal(m.cells[1].data, quad)
    assert np.array_equal(np.concatenate(m.cell_data["s"]), np.concatenate(stress))
    got = np.concatenate(m.cell_data["tag"])
    assert got.dtype == np.int32 and np.array_equal(got, [1] * 7 + [2] * 5)
    pv = pytest.importorskip("pyvista")
    g = pv.read(path)
    assert g.n_cells == 12 and g.n_points == 40
    assert np.array_equal(np.asarray(g.cell_data["s"]), np.concatenate(stress))


def test_a_tetrahedral_mesh_and_an_empty_one(tmp_path):
    meshio = pytest.importorskip("meshio")
    points = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    write_vtu(tmp_path / "t.vtu", points, [("tetra", np.array([[0, 1, 2, 3]]))], {"cell_tag": [np.array([3])]})
    m = meshio.read(tmp_path / "t.vtu")
    assert m.cells[0].type == "tetra" and np.concatenate(m.cell_data["cell_tag"]).tolist() == [3]
    empty = [("triangle", np.zeros((0, 3), dtype=np.int64))]
    write_vtu(tmp_path / "e.vtu", np.zeros((0, 3)), empty, {"s": [np.zeros(0)]})  # meshio reads no empty grid
    pv = pytest.importorskip("pyvista")
    assert pv.read(tmp_path / "e.vtu").n_cells == 0


def test_cell_data_of_the_wrong_length_is_refused(tmp_path):
    with pytest.raises(ValueError, match="3 values for 2 cells"):
        write_vtu(tmp_path / "x.vtu", np.zeros((3, 3)), [("triangle", np.array([[0, 1, 2], [0, 2, 1]]))],
                  {"s": [np.zeros(3)]})


def test_the_six_stress_components_make_one_symmetric_tensor_array(tmp_path):
    """stress_xx_Pa ... stress_xz_Pa: also ``stress_Pa``, six components in VTK's order XX, YY, ZZ, XY, YZ, XZ,
    named so; meshio and pyvista read it back; a generic (k, c) array is written with its c components."""
    meshio = pytest.importorskip("meshio")
    rng = np.random.default_rng(61)
    points = rng.standard_normal((20, 3))
    tri, quad = rng.integers(0, 20, (4, 3)), rng.integers(0, 20, (3, 4))
    order = ("xx", "yy", "zz", "xy", "yz", "xz")
    comps = {f"stress_{c}_Pa": [rng.standard_normal(4), rng.standard_normal(3)] for c in order}
    vec = [rng.standard_normal((4, 3)), rng.standard_normal((3, 3))]
    path = tmp_path / "s.vtu"
    write_vtu(path, points, [("triangle", tri), ("quad", quad)], {**comps, "v": vec})
    expected = np.column_stack([np.concatenate(comps[f"stress_{c}_Pa"]) for c in order])
    m = meshio.read(path)
    assert np.array_equal(np.concatenate(m.cell_data["stress_Pa"]), expected)
    assert np.array_equal(np.concatenate(m.cell_data["v"]), np.concatenate(vec))
    assert np.array_equal(np.concatenate(m.cell_data["stress_xy_Pa"]), expected[:, 3])  # the scalars stay
    head = path.read_bytes().split(b"<AppendedData")[0].decode()
    assert ('Name="stress_Pa" NumberOfComponents="6" ComponentName0="XX" ComponentName1="YY" ComponentName2="ZZ" '
            'ComponentName3="XY" ComponentName4="YZ" ComponentName5="XZ"') in head
    pv = pytest.importorskip("pyvista")
    g = pv.read(path)
    assert np.array_equal(np.asarray(g.cell_data["stress_Pa"]), expected)
    write_vtu(tmp_path / "five.vtu", points, [("triangle", tri), ("quad", quad)],
              {k: v for k, v in comps.items() if k != "stress_xz_Pa"})
    assert "stress_Pa" not in meshio.read(tmp_path / "five.vtu").cell_data
