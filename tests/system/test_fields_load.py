"""The fields a user opens to see the load the method applies and the stress it makes (issue 46, acceptance 1):
the target's surface load in fields.xdmf sums to the history's target force, and the stress fields are one
tensor (its trace the pressure, its deviator the von Mises stress, their ratio the triaxiality)."""

import h5py
import numpy as np
import pytest
from mpi4py import MPI

from fepen import scene
from fepen.runs.deformable import DeformableRun

SETS = ["mesh.size=0.005", "run.end_time=1e-4", "run.output_interval=2.5e-5", "run.checkpoint_interval=0",
        "run.stress_tensor_fields=true"]


@pytest.fixture(scope="module")
def shot(tmp_path_factory):
    out = tmp_path_factory.mktemp("fields-load")
    run = DeformableRun(scene.load(None, SETS), out, MPI.COMM_SELF)
    run.run()
    return run, out


def field(out, name):
    """{time: values} of one field of the finished run's fields.h5."""
    with h5py.File(out / "fields.h5", "r") as h5:
        g = h5[f"/Function/{name}"]
        return {float(k.replace("_", ".")): g[k][()] for k in g}


def test_the_surface_load_field_sums_to_the_historys_target_force(shot):
    run, out = shot
    rows = {r[0]: r for r in run.rows}
    col = [run.columns.index(f"force_{c}_N") for c in "xyz"]
    forces = field(out, "target_force_N")
    sigma = field(out, "target_normal_stress_Pa")
    checked = 0
    for t, f in forces.items():
        F = np.array([rows[t][c] for c in col]) * np.array([1.0, -1.0, 1.0])  # the history's y is depth
        total = f.sum(axis=0)
        if np.linalg.norm(F) == 0.0:
            assert np.all(f == 0.0) and np.all(sigma[t] == 0.0)
            continue
        assert np.linalg.norm(total - F) <= 1e-10 * np.linalg.norm(F), (t, total, F)
        # pressing in: the normal stress is positive where the nodes are loaded, of the law's size
        loaded = np.linalg.norm(f, axis=1) > 0.0
        assert np.all(sigma[t][loaded] >= 0.0) and 1e8 < sigma[t].max() < 3e9
        checked += 1
    assert checked >= 3


def test_the_stress_fields_are_one_tensor(shot):
    run, out = shot
    fields = {n: field(out, n) for n in ("stress_xx_Pa", "stress_yy_Pa", "stress_zz_Pa", "stress_xy_Pa",
                                         "stress_yz_Pa", "stress_xz_Pa", "pressure_Pa", "von_mises_Pa",
                                         "triaxiality")}
    t = max(fields["pressure_Pa"])
    s = {n: v[t].ravel() for n, v in fields.items()}
    mean = (s["stress_xx_Pa"] + s["stress_yy_Pa"] + s["stress_zz_Pa"]) / 3.0
    scale = np.abs(s["von_mises_Pa"]).max()
    assert scale > 1e8  # the nose yields
    np.testing.assert_allclose(-mean, s["pressure_Pa"], rtol=0, atol=1e-9 * scale)
    d = [s["stress_xx_Pa"] - mean, s["stress_yy_Pa"] - mean, s["stress_zz_Pa"] - mean]
    vm = np.sqrt(1.5 * (d[0] ** 2 + d[1] ** 2 + d[2] ** 2
                        + 2 * (s["stress_xy_Pa"] ** 2 + s["stress_yz_Pa"] ** 2 + s["stress_xz_Pa"] ** 2)))
    np.testing.assert_allclose(vm, s["von_mises_Pa"], rtol=0, atol=1e-6 * scale)
    live = s["von_mises_Pa"] > 1e-6 * scale
    np.testing.assert_allclose(s["triaxiality"][live], (mean / s["von_mises_Pa"])[live], rtol=1e-9, atol=1e-12)
