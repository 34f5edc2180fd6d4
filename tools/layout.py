"""The package's structure from its own source (ast): imports between fepen's modules (function-level ones
included), import circles, the imports of the laws, and the longest functions.

    python tools/layout.py            prints the layers, what each subpackage imports, circles, long functions
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "fepen"


def modules() -> dict[str, Path]:
    """Dotted module name -> file, for every module of the package."""
    out = {}
    for p in sorted(PACKAGE.rglob("*.py")):
        parts = list(p.relative_to(ROOT).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = p
    return out


def all_imports(module: str) -> set[str]:
    """Every module a module imports, anywhere in it (``from a import b`` gives a.b when that is a module)."""
    mods = modules()
    tree = ast.parse(mods[module].read_text())
    out = set()
    for n in ast.walk(tree):
        if isinstance(n, ast.Import):
            out.update(a.name for a in n.names)
        elif isinstance(n, ast.ImportFrom) and n.module:
            base = n.module if n.level == 0 else _relative(module, n.module, n.level)
            out.add(base)
            out.update(f"{base}.{a.name}" for a in n.names if f"{base}.{a.name}" in mods)
    return out


def _relative(module: str, name: str, level: int) -> str:
    parts = module.split(".")
    return ".".join(parts[: len(parts) - level] + [name])


def import_graph() -> dict[str, set[str]]:
    """fepen module -> the fepen modules it imports (a package's __init__ is not counted as imported by its
    own submodules' ``from fepen.pkg import mod``)."""
    mods = modules()
    graph = {}
    for m in mods:
        deps = {d for d in all_imports(m) if d in mods and d != m}
        # "from fepen.runs import setup" names fepen.runs.setup; the bare package is an edge only when a
        # name other than a submodule is taken from it
        graph[m] = {d for d in deps if not (d in _packages(mods) and any(x.startswith(d + ".") for x in deps)
                                             and not _takes_names(m, d))}
    return graph


def _packages(mods) -> set[str]:
    return {m for m, p in mods.items() if p.name == "__init__.py"}


def _takes_names(module: str, package: str) -> bool:
    mods = modules()
    tree = ast.parse(mods[module].read_text())
    for n in ast.walk(tree):
        if isinstance(n, ast.ImportFrom) and n.module == package:
            if any(f"{package}.{a.name}" not in mods for a in n.names):
                return True
    return False


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def long_functions(limit: int = 80, roots=("fepen",)) -> list[tuple[str, int, str, int]]:
    """(path, line, name, length) of every function longer than ``limit`` lines, docstring included."""
    out = []
    for root in roots:
        for p in sorted((ROOT / root).rglob("*.py")):
            tree = ast.parse(p.read_text())
            for n in ast.walk(tree):
                if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    length = n.end_lineno - n.lineno + 1
                    if length > limit:
                        out.append((str(p.relative_to(ROOT)), n.lineno, n.name, length))
    return out


def large_classes(limit: int = 300, roots=("fepen",)) -> list[tuple[str, int, str, int]]:
    """(path, line, name, length) of every class longer than ``limit`` lines."""
    out = []
    for root in roots:
        for p in sorted((ROOT / root).rglob("*.py")):
            for n in ast.walk(ast.parse(p.read_text())):
                if isinstance(n, ast.ClassDef) and n.end_lineno - n.lineno + 1 > limit:
                    out.append((str(p.relative_to(ROOT)), n.lineno, n.name, n.end_lineno - n.lineno + 1))
    return out


def _assigned(node, name: str) -> set[str]:
    """The attributes ``name.X`` that assignments under node set (tuple targets and chains included)."""
    out = set()
    for n in ast.walk(node):
        targets = n.targets if isinstance(n, ast.Assign) else [n.target] if isinstance(
            n, (ast.AugAssign, ast.AnnAssign)) else []
        for t in targets:
            for e in (t.elts if isinstance(t, ast.Tuple) else [t]):
                if isinstance(e, ast.Attribute) and isinstance(e.value, ast.Name) and e.value.id == name:
                    out.add(e.attr)
    return out


def many_attributes(limit: int = 40, roots=("fepen",)) -> list[tuple[str, int, str, int]]:
    """(path, line, name, count) of every class whose instances get more than ``limit`` attributes: those its
    methods set on self, and those the module's functions set on a first parameter annotated with the class
    (the set-up functions of a class split into pieces count as its own)."""
    out = []
    for root in roots:
        for p in sorted((ROOT / root).rglob("*.py")):
            tree = ast.parse(p.read_text())
            functions = [n for n in tree.body if isinstance(n, ast.FunctionDef)]
            for c in (n for n in ast.walk(tree) if isinstance(n, ast.ClassDef)):
                names = set()
                for m in (n for n in c.body if isinstance(n, ast.FunctionDef) and n.args.args):
                    names |= _assigned(m, m.args.args[0].arg)
                for f in functions:
                    first = f.args.args[0] if f.args.args else None
                    ann = getattr(first, "annotation", None)
                    if ann is not None and c.name in (getattr(ann, "id", None), getattr(ann, "value", None)):
                        names |= _assigned(f, first.arg)
                if len(names) > limit:
                    out.append((str(p.relative_to(ROOT)), c.lineno, c.name, len(names)))
    return out


#: the floors of the package, bottom up (README "Layout"): a module may import only its own floor and below.
#: Top-level modules not named here sit on floor 0 (errors, atomic, version, native).
FLOORS = {"fepen.data": 0, "fepen.stats": 1, "fepen.laws": 1, "fepen.geometry": 2, "fepen.solver": 3, "fepen.io": 4,
          "fepen.post": 5, "fepen.scene": 5, "fepen.runs": 6, "fepen.studies": 7, "fepen.api": 8,
          "fepen.cli": 9, "fepen": 10, "fepen.__main__": 11}


def floor(module: str) -> int:
    """The floor of a module: that of its subpackage (or top-level module) in FLOORS, else 0."""
    parts = module.split(".")
    for k in (".".join(parts[:2]), module):
        if k in FLOORS:
            return FLOORS[k]
    return 0


def upward_imports(graph) -> list[tuple[str, str]]:
    """(importer, imported) pairs where a module imports one on a higher floor, function-level imports
    included."""
    return sorted((m, d) for m, deps in graph.items() for d in deps if floor(d) > floor(m))


def layers(graph) -> dict[str, set[str]]:
    """Subpackage -> the subpackages it imports."""
    def sub(m):
        parts = m.split(".")
        return parts[1] if len(parts) > 1 else "fepen"

    out: dict[str, set[str]] = {}
    for m, deps in graph.items():
        out.setdefault(sub(m), set()).update(sub(d) for d in deps if sub(d) != sub(m))
    return out


def main() -> int:
    graph = import_graph()
    print("subpackage -> what it imports of fepen")
    for s, deps in sorted(layers(graph).items()):
        print(f"  {s:10s} -> {', '.join(sorted(deps)) or '-'}")
    laws = {m: sorted(d for d in all_imports(m) if d.split(".")[0] in ("dolfinx", "mpi4py", "petsc4py", "ufl")
                      or d == "fepen.scene") for m in graph if m.startswith("fepen.laws")}
    print("laws importing dolfinx, mpi4py, petsc4py, ufl or the scene:", {m: v for m, v in laws.items() if v} or "none")
    print("scene readers:", ", ".join(sorted(m for m, d in graph.items() if "fepen.scene" in d)))
    print("import circles:", cycles(graph) or "none")
    longest = sorted(((n, f"{p}:{line} {name}") for p, line, name, n in long_functions(0)), reverse=True)[:8]
    print("longest functions:", "; ".join(f"{w} ({n} lines)" for n, w in longest))
    over = long_functions(80)
    print("over 80 lines:", "; ".join(f"{p}:{line} {name} ({n})" for p, line, name, n in over) or "none")
    big = large_classes(300)
    print("classes over 300 lines:", "; ".join(f"{p}:{line} {name} ({n})" for p, line, name, n in big) or "none")
    up = upward_imports(graph)
    print("imports up a floor:", "; ".join(f"{a} -> {b}" for a, b in up) or "none")
    return 1 if cycles(graph) or over or big or up else 0


if __name__ == "__main__":
    sys.exit(main())
