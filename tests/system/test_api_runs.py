"""The Python API in whole processes: fepen.run of a bare dict, fepen.load of a results directory, and the
literate API tour (demos/api_tour.py) on two MPI ranks (its serial run is test_notebooks': as a notebook)."""

import json

import pytest
from conftest import ROOT, run_python

ONE_LINER = ("import fepen; r = fepen.run({'effects': {'fidelity': 'rigid'}}, out=%r); "
             "h = fepen.load(%r).history; print(r.summary['Hy_mm'], h['nose_y_mm'][-1])")


def test_run_a_dict_and_load_it_back(tmp_path):
    out = str(tmp_path / "rigid")
    r = run_python("-c", ONE_LINER % (out, out))
    assert r.returncode == 0, r.stderr[-2000:]
    hy, last = map(float, r.stdout.split()[-2:])
    summary = json.loads((tmp_path / "rigid" / "summary.json").read_text())
    assert hy == summary["Hy_mm"]
    assert last == pytest.approx(hy, rel=1e-8)  # history.csv keeps 9 significant digits
    assert summary["outcome"] == "embedded" and 300.0 < hy < 1000.0


@pytest.mark.slow
@pytest.mark.parametrize("ranks", [2])
def test_api_tour(tmp_path, ranks):
    # a 6 mm deformable shot (12 s on 2 ranks; the tour's 4 mm default took 66 s): the agreement checked below
    # holds on it (plastic 352.6 mm against rigid 351.5 mm)
    r = run_python(ROOT / "demos" / "api_tour.py", "--out", tmp_path, "--size", "0.006", ranks=ranks)
    assert r.returncode == 0, r.stderr[-3000:]
    assert "refused: impact.velocity" in r.stdout
    rigid = json.loads((tmp_path / "rigid" / "summary.json").read_text())
    plastic = json.loads((tmp_path / "plastic" / "summary.json").read_text())
    assert plastic["ranks"] == ranks and plastic["outcome"] == "embedded"
    # the deformable C3 and the rigid one agree within a few percent (docs/validation.md), both near the test
    assert plastic["Hy_mm"] == pytest.approx(rigid["Hy_mm"], rel=0.05)
    assert abs(plastic["experiment"]["Hy_error"]) < 0.15
    assert (tmp_path / "tour.png").stat().st_size > 10_000
