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


#: the FEniCSx packages whose API changes between releases: fepen reaches them through fepen.dolfinx_api alone
FENICSX = ("dolfinx", "ufl", "basix", "ffcx", "petsc4py")


def test_only_the_compatibility_layer_imports_dolfinx():
    """fepen.dolfinx_api is the one place fepen touches dolfinx (0.5.2 and the current release): no other module
    imports dolfinx, ufl, basix, ffcx or petsc4py, at the top or inside a function (docs/install.md)."""
    bad = {m: sorted(d for d in layout.all_imports(m) if d.split(".")[0] in FENICSX)
           for m in GRAPH if m != "fepen.dolfinx_api"}
    assert not {m: d for m, d in bad.items() if d} and layout.all_imports("fepen.dolfinx_api") & {"dolfinx"}


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


def test_no_class_over_300_lines():
    big = layout.large_classes(300)
    assert not big, "\n".join(f"{path}:{line} {name} ({n} lines)" for path, line, name, n in big)


def test_no_study_module_over_400_lines():
    """A study is one file (fepen.studies.study's skeleton does the rest): none grows past 400 lines."""
    big = [(p.name, n) for p in sorted((layout.PACKAGE / "studies").glob("*.py"))
           if (n := len(p.read_text().splitlines())) > 400]
    assert not big, big


def test_no_class_over_40_attributes():
    """Solver state and the like live in small named records (fepen.solver.state), not in one bag."""
    many = layout.many_attributes(40)
    assert not many, "\n".join(f"{path}:{line} {name} ({n} attributes)" for path, line, name, n in many)


def _lines_matching(pattern: str, homes: set, skip: tuple = ()) -> list[str]:
    """path:line of every line of fepen's modules matching ``pattern``, outside ``homes`` and the folders
    ``skip``."""
    import re

    return [f"{rel}:{i}" for p in sorted(layout.PACKAGE.rglob("*.py"))
            if (rel := str(p.relative_to(layout.PACKAGE))) not in homes and not rel.startswith(skip)
            for i, line in enumerate(p.read_text().splitlines(), 1) if re.search(pattern, line)]


def test_body_kinds_carry_their_own_behaviour():
    """No isinstance on a body kind (Shape, CadBody) and no ``.exact`` flag read outside the body kinds' own
    modules (issue 60, item 5): a caller asks the body (nose_length, outer_radius, meshed_volume, exact_volume,
    exact_mass, needs_volume_mesh, crater_nose_factor, after_meshing) or calls a function registered per kind
    (functools.singledispatch: gmsh_model._build, mesh_cache.record, mesh_cache._verify_extent, surface.facet_points,
    revolution.nose_zone, rigid.body_points, probes.outside_radially)."""
    homes = {"geometry/shape.py", "geometry/cad.py"}
    found = _lines_matching(r"isinstance\([^)]*\b(CadBody|Shape)\b|\.exact\b", homes)
    assert not found, found


#: modules allowed to branch on the target's kind besides its homes: none (issue 60, item 5)
TARGET_KIND_PENDING = ()


def test_target_kinds_carry_their_own_behaviour():
    """No branch on the target's kind outside the kinds themselves (fepen.runs.targets, fepen.laws.layers): no
    target.kind == or !=, no layered flag read, no isinstance on TargetLaw or Layered (issue 60, item 5); a
    caller asks the Shot's kind (law, check, plates, envelope_name, hard_end, tunnel, crossings, thickness,
    splits_load, crater, load, takes_rigid): the rigid wall too, with no law."""
    homes = {"runs/targets.py", "laws/layers.py"}
    pattern = (r"target\.kind\s*[!=]=|\.kind\s*[!=]=\s*\"(concrete|rigid-wall)\"|\.layered\b|"
               r"getattr\([^)]*\"layered\"|isinstance\([^)]*\b(TargetLaw|Layered)\b|"
               r"\.law is (not )?None")  # the rigid wall, the one kind without a law, answers for itself
    found = _lines_matching(pattern, homes, TARGET_KIND_PENDING)
    assert not found, found


def test_tests_mirror_the_package():
    """Every subpackage of fepen has its folder of unit tests, holding at least one test file."""
    unit = Path(__file__).resolve().parent
    missing = [p.parent.name for p in layout.PACKAGE.glob("*/__init__.py")
               if not any((unit / p.parent.name).glob("test_*.py"))]
    assert not missing, f"no tests/unit/<name>/test_*.py for {missing}"


def test_no_import_up_a_floor():
    """laws < geometry < solver < io < post, scene < runs < studies < api < cli (function-level imports too)."""
    assert layout.upward_imports(GRAPH) == []


def _declared_all(init: Path) -> set[str]:
    import ast

    for n in ast.parse(init.read_text()).body:
        if isinstance(n, ast.Assign) and any(getattr(t, "id", None) == "__all__" for t in n.targets):
            return {e.value for e in n.value.elts}
    return set()


PACKAGES = sorted(p.parent for p in layout.PACKAGE.rglob("__init__.py") if p.parent != layout.PACKAGE)


@pytest.mark.parametrize("package", PACKAGES, ids=lambda p: p.name)
def test_every_module_is_in_its_package_all(package):
    names = {p.stem for p in package.glob("*.py") if p.stem != "__init__"}
    names |= {p.name for p in package.iterdir() if (p / "__init__.py").is_file()}
    missing = names - _declared_all(package / "__init__.py")
    assert not missing, f"{package.name}/__init__.py's __all__ lacks {sorted(missing)}"


def _readme_layout() -> dict[str, str]:
    """The README's Layout block, by subpackage ("" for the top level)."""
    text = (layout.ROOT / "README.md").read_text()
    block = text.split("## Layout", 1)[1].split("```", 2)[1]
    parts, current = {"": ""}, ""
    for line in block.splitlines():
        stripped = line.strip()
        if line.startswith("  ") and not line.startswith("   ") and stripped.endswith("/") is False \
                and stripped.split()[0].endswith("/"):
            current = stripped.split()[0].rstrip("/")
            parts.setdefault(current, "")
        elif line.startswith("  ") and not line.startswith("   ") and stripped.split()[0].endswith(".py"):
            current = ""
        parts[current] = parts.get(current, "") + line + "\n"
    return parts


def test_every_module_is_in_the_readme_layout():
    parts = _readme_layout()
    missing = []
    for p in sorted(layout.PACKAGE.rglob("*")):
        if p.suffix not in (".py", ".c") or p.name in ("__init__.py", "__main__.py"):
            continue
        rel = p.relative_to(layout.PACKAGE)
        section = rel.parts[0] if len(rel.parts) > 1 else ""
        if p.name not in parts.get(section, ""):
            missing.append(str(rel))
    assert not missing, f"README's Layout does not name {missing}"


def test_no_study_module_draws_or_reaches_into_another_s_private_names():
    """Studies draw through fepen.post.study_figures and share through public names (issue 60): no study module
    imports matplotlib, and none imports or calls another study module's _private name."""
    import re

    studies = Path(__file__).resolve().parents[2] / "fepen" / "studies"
    mods = {p.stem for p in studies.glob("*.py")}
    bad = []
    for p in sorted(studies.glob("*.py")):
        text = p.read_text()
        if re.search(r"^\s*(import matplotlib|from matplotlib)", text, re.M):
            bad.append(f"{p.name}: imports matplotlib")
        for m in re.finditer(r"from fepen\.studies\.(\w+) import ([^\n]+)", text):
            if m.group(1) != p.stem and any(n.strip().startswith("_") for n in m.group(2).split(",")):
                bad.append(f"{p.name}: {m.group(0)}")
        for m in re.finditer(r"\b(\w+)\._[a-z]\w*\(", text):
            if m.group(1) in mods and m.group(1) != p.stem:
                bad.append(f"{p.name}: {m.group(0)}")
    assert not bad, bad


def test_one_csv_writer():
    """Every CSV fepen writes goes through fepen.io.table (issue 60): no other module makes a csv writer, calls
    numpy's savetxt, or joins a header line by hand for a .csv file."""
    import re

    package = Path(__file__).resolve().parents[2] / "fepen"
    bad = []
    for p in sorted(package.rglob("*.py")):
        if p == package / "io" / "table.py":
            continue
        text = p.read_text()
        for pattern in (r"csv\.writer\(", r"csv\.DictWriter\(", r"\.savetxt\(", r"lineterminator"):
            if re.search(pattern, text):
                bad.append(f"{p.relative_to(package)}: {pattern}")
    assert not bad, bad


def test_no_study_writes_its_own_files():
    """A study declares what it writes (document, tables, texts, pictures) and the skeleton's write() writes it
    (fepen.studies.products): no study class overrides write()."""
    import importlib

    from fepen.studies import study

    for name in study.STUDIES:
        cls = study.get(name)
        assert cls.write is study.Study.write, f"{name} ({cls.__name__}) overrides write()"
    for mod in {m for m, _ in study.STUDIES.values()}:
        importlib.import_module(mod)
    for cls in study.Study.__subclasses__():
        assert "write" not in vars(cls), cls.__name__
