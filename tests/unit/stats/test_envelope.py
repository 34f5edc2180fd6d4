"""The validated envelope (fepen.stats.envelope, fepen.runs.setup.envelope_facts, fepen envelope): its ranges are
the public shots', a scene inside says so, a scene outside names each dimension and how far."""

import subprocess
import sys
from pathlib import Path

import pytest

from fepen import scene
from fepen.data import prediction_errors
from fepen.runs import setup
from fepen.stats import envelope

ROOT = Path(__file__).resolve().parents[3]


def _verdict(*sets):
    sc = scene.load(None, list(sets))
    return envelope.verdict(setup.envelope_facts(sc, setup.projectile(sc)))


def test_the_ranges_are_those_of_the_public_shots():
    rows = [r for r in prediction_errors.read() if r["quantity"] == "depth" and r["law"] == "scaled-S"]
    r = envelope.ranges("scaled-S")
    assert r["shots"] == len(rows) >= 171 and r["sets"] == len({x["set"] for x in rows})
    assert r["V_m_s"] == (min(x["V_m_s"] for x in rows), max(x["V_m_s"] for x in rows))
    assert r["obliquity_deg"] == (0.0, 20.0)  # Table 1's C6 and C7


def test_the_default_shot_is_inside():
    v = _verdict()
    assert v["inside"] and v["outside"] == []
    assert envelope.line(v).startswith("inside the validated envelope")


def test_a_fast_steep_shot_is_outside_by_how_much():
    hi = envelope.ranges("scaled-S")["V_m_s"][1]
    v = _verdict("impact.velocity=2000", "impact.obliquity_deg=30", "effects.fidelity=rigid")
    assert not v["inside"]
    by = {o["key"]: o["by"] for o in v["outside"]}
    assert by["impact.velocity"] == f"{100 * (2000 / hi - 1):.3g} % above"
    assert by["impact.obliquity_deg"] == "10 deg above"
    line = envelope.line(v)
    assert line.startswith("outside the validated envelope: striking speed 2000 m/s") and "\n" not in line


@pytest.mark.parametrize("sets, key", [
    (["target.material=granite"], "target.material"),
    (["projectile.nose=cone", "projectile.nose_length=0.03"], "projectile.nose"),
    (["target.thickness=0.15", "effects.fidelity=rigid"], "target.thickness"),
    (["projectile.material.name=aisi-4340"], "projectile.material.A"),
    (["target.strength_model=cavity-expansion"], "target.strength_model"),
    (["target.compressive_strength=2e8", "target.strength_basis=cylinder"], "target.compressive_strength"),
])
def test_each_condition_names_its_key(sets, key):
    v = _verdict(*sets)
    assert not v["inside"]
    assert key in [o["key"] for o in v["outside"]]


def test_a_rigid_run_of_another_steel_is_inside():
    """The steel matters only to a deformable projectile."""
    assert _verdict("projectile.material.name=aisi-4340", "effects.fidelity=rigid")["inside"]


def test_docs_show_the_tables_fepen_envelope_prints():
    """docs/uncertainty.md holds, in its make docs block envelope-tables, exactly what `fepen envelope` prints."""
    out = subprocess.run([sys.executable, "-m", "fepen", "envelope"], capture_output=True, text=True, check=True).stdout
    doc = (ROOT / "docs" / "uncertainty.md").read_text()
    begin, end = "<!-- make docs: envelope-tables -->\n", "<!-- /make docs: envelope-tables -->"
    assert begin in doc and end in doc
    body = doc.split(begin, 1)[1].split(end, 1)[0]
    assert body.startswith("<sub>Made by `fepen envelope` with fepen ")
    assert body.split("\n", 1)[1].strip() == out.strip()


def test_fepen_envelope_judges_a_scene_without_running_it():
    p = subprocess.run([sys.executable, "-m", "fepen", "envelope", "--set", "impact.velocity=2500"],
                       capture_output=True, text=True)
    assert p.returncode == 0
    assert "outside the validated envelope: striking speed 2500 m/s" in p.stdout
    assert "depth interval (10-90 %)" in p.stdout
    bad = subprocess.run([sys.executable, "-m", "fepen", "envelope", "--set", "impact.velocity=-1"],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "impact.velocity" in bad.stderr


#: the scene docs/uncertainty.md judges with `fepen envelope`: a 300 mm, 900 kg body, whose deformable mesh at the
#: default size would be past mesh.max_cells
BIG = ["--set", "projectile.diameter=0.3", "--set", "projectile.length=2.4", "--set", "projectile.mass=900", "--set",
       "impact.velocity=300"]


def test_fepen_envelope_judges_a_scene_too_big_to_mesh():
    """Issue 61: `fepen envelope` runs nothing, so the deformable mesh's budget is not its business. Before the fix
    the page's own command exited 2 ('mesh.size: 0.0025 m makes about 4.04e+07 cells')."""
    p = subprocess.run([sys.executable, "-m", "fepen", "envelope", *BIG], capture_output=True, text=True, cwd=ROOT)
    assert p.returncode == 0, p.stderr
    assert p.stdout.startswith("outside the validated envelope: calibre 300 mm is 47.8 % above")
    assert "projectile mass 900 kg is 320 % above" in p.stdout
    assert "depth interval (10-90 %): the predicted depth -28 % to +22 %" in p.stdout


def test_fepen_run_still_refuses_the_mesh_it_cannot_afford():
    """The same scene run deformable is refused before gmsh starts: one line naming mesh.size, exit 2."""
    p = subprocess.run([sys.executable, "-m", "fepen", "run", *BIG, "--out", "/nonexistent/never-written"],
                       capture_output=True, text=True, cwd=ROOT)
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and "mesh.size" in p.stderr and "cells" in p.stderr
