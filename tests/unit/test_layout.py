"""The package's layering, checked from the code's own imports (ast): the laws on plain arrays, one door from
the scene, no import circle, no function over 80 lines. The same checks by hand: ``python tools/layout.py``."""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tools"))
import layout  # noqa: E402

GRAPH = layout.import_graph()


@pytest.mark.parametrize("module", sorted(m for m in GRAPH if m.startswith("fepen.laws")))
def test_laws_import_no_dolfinx_mpi_petsc_or_scene(module):
    bad = {m for m in layout.all_imports(module) if m.split(".")[0] in ("dolfinx", "mpi4py", "petsc4py", "ufl")
           or m == "fepen.scene"}
    assert not bad, f"{module} imports {sorted(bad)}"


def test_only_runs_and_above_read_the_scene():
    """The scene reaches the physics through fepen.runs.setup alone."""
    readers = {m for m, deps in GRAPH.items() if "fepen.scene" in deps}
    below = {m for m in readers if m.split(".")[1] in ("laws", "geometry", "solver", "io", "post")}
    assert not below, f"modules below fepen.runs import the scene: {sorted(below)}"


def test_no_import_circle():
    assert layout.cycles(GRAPH) == []


def test_no_function_over_80_lines():
    long = [f for f in layout.long_functions(80)]
    assert not long, "\n".join(f"{path}:{line} {name} ({n} lines)" for path, line, name, n in long)
