"""The literate demos as notebooks: jupytext reads demos/api_tour.py and demos/rigid_study.py, nbclient executes
them on an IPython kernel (the pins of fepen[kernel]: IPython 8 and matplotlib-inline 0.1.6 beside Debian's
matplotlib 3.6), as a user's Jupyter would. The serial run of the API tour is this one; test_api_runs runs the
same file as a script on two MPI ranks.

Each notebook checks inside the kernel that fepen left the notebook's matplotlib backend alone; the last cell
added here reports the backend and dir(fepen). The demos draw their own plots with pyplot, as a user does: those
must show inline (tests/unit/post/test_figures.py checks that fepen itself never imports pyplot).
"""

import json
import re
from pathlib import Path

import pytest
from conftest import ROOT
from mpi4py import MPI

from fepen import scene
from fepen.runs.rigid import RigidRun

nbclient = pytest.importorskip("nbclient", reason="the notebook tests need fepen[test] (nbclient, ipykernel)")
jupytext = pytest.importorskip("jupytext")
nbformat = pytest.importorskip("nbformat")

PROBE = ("import json, matplotlib, fepen\n"
         "print('PROBE', json.dumps({'backend': matplotlib.get_backend(), 'dir': dir(fepen), "
         "'all': sorted(fepen.__all__)}))")


def execute(path: Path, cwd: Path) -> tuple[str, list, dict]:
    """Execute a jupytext demo as a notebook in ``cwd``; (all text it printed, its outputs, the probe's dict)."""
    nb = jupytext.read(path)
    nb.cells.append(nbformat.v4.new_code_cell(PROBE))
    client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(cwd)}})
    client.execute()
    outputs = [o for cell in nb.cells if cell.cell_type == "code" for o in cell.get("outputs", [])]
    text = "".join(o.get("text", "") for o in outputs if o.get("output_type") == "stream")
    probe = json.loads(re.search(r"^PROBE (.*)$", text, re.M).group(1))
    return text, outputs, probe


def _check_probe(probe: dict) -> None:
    assert "inline" in probe["backend"], probe["backend"]  # the kernel's own backend, still in place
    assert probe["dir"] == probe["all"] and "run" in probe["dir"] and "sweep" in probe["dir"]


@pytest.mark.slow
def test_api_tour_as_a_notebook(tmp_path):
    text, outputs, probe = execute(ROOT / "demos" / "api_tour.py", tmp_path)
    _check_probe(probe)
    assert "refused: impact.velocity" in text
    root = Path(re.search(r"^written: (.*)/tour\.png$", text, re.M).group(1))
    rigid = json.loads((root / "rigid" / "summary.json").read_text())
    plastic = json.loads((root / "plastic" / "summary.json").read_text())
    assert plastic["ranks"] == 1 and plastic["outcome"] == "embedded"
    # the deformable C3 and the rigid one agree within a few percent (docs/validation.md), both near the test
    assert plastic["Hy_mm"] == pytest.approx(rigid["Hy_mm"], rel=0.05)
    assert abs(plastic["experiment"]["Hy_error"]) < 0.15
    assert any("image/png" in o.get("data", {}) for o in outputs)  # the trajectories, shown in the notebook
    record = json.loads((root / "plastic" / "run.json").read_text())
    assert record["command"][0].startswith("fepen.run(a Scene, out=") and "Jupyter kernel" in record["command"][1]


def test_rigid_study_as_a_notebook(tmp_path):
    text, outputs, probe = execute(ROOT / "demos" / "rigid_study.py", tmp_path)
    _check_probe(probe)
    assert "rising at every step: True" in text
    assert any("image/png" in o.get("data", {}) for o in outputs)  # the user's own plot, shown inline
    tables = [o for o in outputs if "text/html" in o.get("data", {})]
    assert tables and "Hy_mm" in tables[0]["data"]["text/html"]  # the DataFrame, shown as a table
    # Forrestal's law: depth grows as ln(1 + c v^2), so it rises more slowly than v^2 over 400-900 m/s
    ratio, v2 = map(float, re.search(r"depth ratio ([\d.]+) against a speed-squared ratio ([\d.]+)", text).groups())
    assert 1.5 < ratio < v2
    # what it states: normal incidence (every final axis within 1e-3 deg of the normal), and the tests C2 and C8
    # predicted as the rigid Table 1 shots predict them (the rigid validate's Hy errors, within 1.5 points:
    # the grid's interpolation and their 0.4 and 0.58 deg)
    assert float(re.search(r"the largest final axis angle ([-+\d.e]+) deg", text).group(1)) < 1e-3
    for name in ("C2", "C8"):
        said = float(re.search(rf"^{name}: .*\(([-+\d.]+)%\)$", text, re.M).group(1))
        direct = RigidRun(scene.load(None, ["effects.fidelity=rigid", f'impact.shot="{name}"']), None,
                          MPI.COMM_SELF).run()
        assert abs(said - 100.0 * direct["experiment"]["Hy_error"]) < 1.5, (name, said, direct["experiment"])
