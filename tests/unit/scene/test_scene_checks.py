"""The checks across scene keys and their list: every refusal in fepen.scene (resolve, checks, reading) is a
registered check with its one-line description, every registered check runs, and the list ``fepen keys`` prints
is the one docs/scenes.md shows."""

import ast
import inspect
from pathlib import Path

from fepen import scene
from fepen.scene import checks, reading, resolve

MODULES = (resolve, checks, reading)

ROOT = Path(__file__).resolve().parents[3]
HEADER = "Checks across keys, before anything is meshed (bad input, exit 2, naming the key):"

#: the functions that refuse what the user gave before any key is known: not checks across keys
PARSING = {"flatten", "unknown_key", "parse_set", "check_sets", "read_toml", "read_capped", "given_from", "resolve"}


def _functions() -> dict[str, ast.FunctionDef]:
    out = {}
    for m in MODULES:
        tree = ast.parse(Path(inspect.getfile(m)).read_text())
        out.update({n.name: n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef)})
    return out


def _raises_input_error(fn: ast.FunctionDef) -> bool:
    return any(isinstance(n, ast.Raise) and isinstance(n.exc, ast.Call) and getattr(n.exc.func, "id", "") ==
               "InputError" for n in ast.walk(fn))


def test_docs_list_the_generated_checks():
    """docs/scenes.md's list of checks is the one built from the checks' descriptions (regenerate the file
    with ``(printf '# Scene keys\\n\\n'; fepen keys) > docs/scenes.md``)."""
    doc = (ROOT / "docs" / "scenes.md").read_text().splitlines()
    listed = doc[doc.index(HEADER) + 1:]
    assert [line for line in listed if line] == [f"- {c}" for c in scene.CROSS_CHECKS]
    generated = scene.describe().splitlines()
    assert listed == generated[generated.index(HEADER) + 1:]


def test_every_refusal_is_a_registered_check():
    registered = {f.__name__ for _, f in scene.registered_checks()}
    refusing = {name for name, fn in _functions().items() if _raises_input_error(fn)}
    assert refusing - PARSING <= registered, f"checks without a description: {sorted(refusing - PARSING - registered)}"


def test_every_registered_check_runs():
    """Each registered function is called (or passed on to be called) somewhere besides its definition."""
    used = set()
    for m in MODULES:
        tree = ast.parse(Path(inspect.getfile(m)).read_text())
        used |= {n.id for n in ast.walk(tree) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)}
    missing = [f.__name__ for _, f in scene.registered_checks() if f.__name__ not in used]
    assert not missing, f"registered but never run: {missing}"


def test_descriptions_are_single_distinct_lines():
    descriptions = [d for d, _ in scene.registered_checks()] + list(scene.CHECKS_AFTER_RESOLUTION)
    assert all(d.strip() and "\n" not in d for d in descriptions)
    assert len(set(descriptions)) == len(descriptions)
    assert scene.CROSS_CHECKS == tuple(descriptions)


def test_the_checks_that_had_no_line_are_listed():
    """The refusals CROSS_CHECKS used to leave out: erosion with the rigid fidelity, [[target.layers]]."""
    text = "\n".join(scene.CROSS_CHECKS)
    assert "effects.erosion with effects.fidelity" in text
    assert "[[target.layers]]: target.material and target.thickness per layer" in text
