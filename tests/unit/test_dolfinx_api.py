"""The dolfinx compatibility layer (fepen/dolfinx_api.py): this dolfinx is a supported one, an unsupported one is
refused in one line naming the supported releases before anything is written, and the calls give what the
solver needs (2-D dofmaps of tetrahedra, vectors whose ghosts add to their owners)."""

import numpy as np
import pytest
from mpi4py import MPI

from fepen import cli
from fepen import dolfinx_api as dx


def test_this_dolfinx_is_supported():
    assert dx.version()[:2] in dx.SUPPORTED
    dx.check_version()


@pytest.mark.parametrize("v", [(0, 8, 0), (0, 4, 1), (1, 0, 0)])
def test_an_unsupported_dolfinx_is_refused_in_one_line(monkeypatch, capsys, tmp_path, bad_input_line, v):
    monkeypatch.setattr(dx, "version", lambda: v)
    out = tmp_path / "run"
    code = cli.main(["run", "--out", str(out), "--set", "mesh.size=0.008"])
    bad_input_line(code, capsys.readouterr().err, "dolfinx", r"is not supported: fepen runs on dolfinx 0\.5 and 0\.11")
    assert not out.exists()


def test_an_unsupported_dolfinx_can_be_tried_when_asked(monkeypatch, caplog):
    """FEPEN_UNSUPPORTED_DOLFINX=try: one warning naming the version and the supported ones, and no refusal."""
    monkeypatch.setattr(dx, "version", lambda: (0, 12, 0))
    monkeypatch.setenv(dx.TRY_UNSUPPORTED, "try")
    with caplog.at_level("WARNING", logger="fepen"):
        dx.check_version()
    assert [r.getMessage() for r in caplog.records] == [
        "dolfinx 0.12.0 is not supported (fepen runs on dolfinx 0.5 and 0.11): tried as FEPEN_UNSUPPORTED_DOLFINX=try "
        "asks; check its numbers"]
    monkeypatch.setenv(dx.TRY_UNSUPPORTED, "yes")  # only "try" lets it through
    with pytest.raises(Exception, match="is not supported"):
        dx.check_version()


def test_a_rigid_run_needs_no_supported_dolfinx(monkeypatch, tmp_path):
    """The rigid fidelity makes no mesh: it runs whatever dolfinx is installed."""
    monkeypatch.setattr(dx, "version", lambda: (0, 8, 0))
    assert cli.main(["run", "--out", str(tmp_path / "r"), "--set", "effects.fidelity=rigid"]) == 0


def test_spaces_dofmaps_and_vectors():
    from dolfinx import mesh

    m = mesh.create_unit_cube(MPI.COMM_SELF, 2, 2, 2)
    V = dx.vector_space(m)
    dofs, geo = dx.cell_dofs(V), dx.geometry_dofs(m)
    assert dofs.shape == geo.shape == (48, 4)
    assert V.dofmap.bs == 3 and dx.tensor_dg0_space(m).dofmap.bs == 9
    vec = dx.new_vector(V.dofmap.index_map, 3)
    vec.array[:] = 1.0
    dx.scatter_reverse_add(vec)  # one rank: no ghosts, nothing added
    assert np.all(vec.array == 1.0)
