"""docs/theory.md's make docs blocks (tools/docs_theory.py): the logic its generators add to fepen's own."""

import importlib
import math
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT / "tools"))
import make_docs  # noqa: E402,F401  (tools/ is not a package; it imports docs_theory and registers its blocks)

docs_theory = importlib.import_module("docs_theory")


@pytest.mark.parametrize("angle", [0.0, 12.0, 25.0])
def test_the_loaded_projected_area_is_the_ogive_s_disc_inside_the_separation_angle(angle):
    """The end of the path's force (§8.7's table) takes σ_s over the projected area of the points a body moving
    along its axis loads: on a tangent ogive (CRH ψ, radius a, s = 2ψa) the surface angle is φ with
    sin φ = (l − z)/s, so the loaded part is the disc of radius r = a − s(1 − cos φ_min); the whole πa² at 0°.
    On rings of 0.5 mm panels the cut falls between two Gauss rings: within half a panel of r (the area within
    panel/(2r); forgetting the cut is 25 % off at 12°, counting the rear face 100 %)."""
    run, _ = docs_theory.rigid("mesh.rigid_panel=0.0005", f"target.separation_angle_deg={angle}",
                               "run.end_time=1e-6")
    a, s = run.shape.radius, run.shape.ogive_radius
    r = a - s * (1.0 - math.cos(math.radians(angle)))
    assert docs_theory.loaded_projected_area(run) == pytest.approx(math.pi * r * r, rel=0.5 * 0.0005 / r)


def test_a_range_prints_once_where_its_ends_print_alike():
    assert docs_theory._span([0.451, 0.588, 0.52], "{:.2f}") == "0.45–0.59"
    assert docs_theory._span([1.001, 1.004], "{:.2f}") == "1.00"
    assert docs_theory._span([-0.3, 0.2], "{:.1f}") == "−0.3–0.2"
