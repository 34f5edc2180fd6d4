"""A property-based fuzz of the scene schema and of the command line's argument paths (issue 18, item 3).

The strategies are generated from fepen.scene.SCHEMA itself: every key with its type and range (lo, hi,
choices), values just outside the range, wrong types, NaN and inf, integers no float holds, unknown keys and
sections, as dicts, TOML text (also mangled) and --set items. The property: a scene either resolves, with
every value within the schema's range and a TOML text that resolves to the same scene, or is refused with
InputError naming a key the user gave (or SCENE, --set) in one line; never another exception. The command line
gets argument lists that are always wrong somewhere (unknown options and commands, bad --set, missing files,
bad numbers) and must answer exit 2 with exactly one line on stderr, "fepen: bad input: ...", writing nothing.
Validation only: nothing is meshed or run. On a failure hypothesis prints the falsifying example and the blob
to reproduce it (print_blob).
"""

import contextlib
import io
import math
import os
import re
import tomllib

import pytest
from hypothesis import HealthCheck, assume, event, given, settings
from hypothesis import strategies as st

from fepen import cli
from fepen.data import CONSTANTS, TARGETS
from fepen.errors import InputError
from fepen.runs import setup
from fepen.scene import LAYER_KEYS, SCHEMA, SECTIONS, Scene, parse_set, to_toml
from fepen.scene import display_name as _name

FUZZ = dict(deadline=None, database=None, derandomize=False, print_blob=True,
            suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much, HealthCheck.data_too_large,
                                   HealthCheck.function_scoped_fixture])
NAMES = sorted(SCHEMA)
LEAVES = sorted({n.rsplit(".", 1)[1] for n in NAMES})
#: text without surrogates (TOML cannot hold them)
TEXT = st.text(st.characters(blacklist_categories=("Cs",)), max_size=12)
HUGE = 10**400  # a TOML integer no float holds


# ------------------------------------------------------------------------------------------- values by key
def _outside(key) -> list:
    """Numbers just outside the key's range (and its open ends)."""
    out = []
    if key.lo is not None:
        out += [math.nextafter(key.lo, -math.inf), key.lo - 1.0] + ([key.lo] if key.lo_open else [])
    if key.hi is not None:
        out += [math.nextafter(key.hi, math.inf), key.hi * 2.0 + 1.0] + ([key.hi] if key.hi_open else [])
    return out


def _number(key, bad: bool) -> st.SearchStrategy:
    """In the range (floats, the ends, integers); with bad: also just outside, NaN, inf, integers no float
    holds and wrong types."""
    inside = st.floats(min_value=key.lo, max_value=key.hi, exclude_min=key.lo_open and key.lo is not None,
                       exclude_max=key.hi_open and key.hi is not None, allow_nan=False, allow_infinity=False)
    ends = [v for v in (key.lo, key.hi, key.default) if isinstance(v, float)]
    ends = [v for v in ends if not ((v == key.lo and key.lo_open) or (v == key.hi and key.hi_open))]
    a, b = math.ceil(key.lo if key.lo is not None else -1e6), math.floor(min(key.hi or 1e6, 1e6))
    good = st.one_of(inside, inside, st.sampled_from(ends) if ends else inside,
                     st.integers(a, b) if a <= b else inside)  # TOML integers where the range holds some
    if not bad:
        return good
    return st.one_of(good, st.sampled_from(_outside(key) + [math.nan, math.inf, -math.inf, HUGE, -HUGE]), _wrong())


def _wrong() -> st.SearchStrategy:
    """Values of the wrong type."""
    return st.one_of(TEXT, st.booleans(), st.lists(st.integers(-3, 3), max_size=3), st.just({"x": 1}))


def _string(key, bad: bool) -> st.SearchStrategy:
    if key.choices:
        good = st.sampled_from(key.choices)
        near = st.sampled_from(key.choices).map(lambda c: c.upper() if c != c.upper() else c + "x")
        return st.one_of(good, near, _wrong(), st.floats(allow_nan=True)) if bad else good
    good = st.text(st.characters(blacklist_categories=("Cs",)), min_size=1, max_size=12).filter(
        lambda t: t.strip() and "\x00" not in t)
    odd = st.one_of(st.sampled_from(["", " ", "a\x00b"]), st.integers(), st.booleans())
    return st.one_of(good, odd) if bad else good


def _sections(bad: bool) -> st.SearchStrategy:
    pair = st.lists(st.floats(1e-4, 0.2), min_size=2, max_size=2)
    good = st.lists(pair, min_size=1, max_size=3)
    if not bad:
        return good
    bad_pair = st.one_of(st.lists(st.floats(allow_nan=True), max_size=3), st.just([0.01, HUGE]),
                         st.just(["a", 0.01]), st.just([0.0, 0.01]), st.just([True, 0.01]))
    return st.one_of(good, st.lists(st.one_of(pair, bad_pair), max_size=3), _wrong())


def _layer(bad: bool) -> st.SearchStrategy:
    constants = st.dictionaries(st.sampled_from(CONSTANTS), st.none(), max_size=2).flatmap(
        lambda d: st.fixed_dictionaries({k: value(f"target.{k}", bad) for k in d}))
    optional = {"material": st.sampled_from(sorted(TARGETS)), "thickness": value("target.thickness", bad),
                "gap": st.floats(0.0, 1.0), "crater": st.sampled_from(["none", "energy"])}
    if bad:
        optional.update(material=st.one_of(st.sampled_from(sorted(TARGETS)), TEXT),
                        gap=st.one_of(st.floats(0.0, 1.0), st.just(-1.0), TEXT),
                        crater=st.sampled_from(["none", "energy", "linear"]),
                        family=st.sampled_from(["concrete", "rock", "metal", "soil", "glass"]),
                        thickens=st.just(1.0))  # an unknown key, close to one
    return st.builds(lambda a, b: {**a, **b}, st.fixed_dictionaries({}, optional=optional), constants)


def _layers(bad: bool) -> st.SearchStrategy:
    good = st.lists(_layer(bad), min_size=1, max_size=3)
    return st.one_of(good, st.just([]), st.just([1, 2]), _wrong()) if bad else good


def value(name: str, bad: bool = True) -> st.SearchStrategy:
    """A value for the scene key ``name`` from its SCHEMA entry: within its type and range, or (bad) also
    outside them."""
    key = SCHEMA[name]
    if key.kind is float or key.kind is int:
        return _number(key, bad)
    if key.kind is bool:
        return st.one_of(st.booleans(), st.sampled_from([0, 1, "true", "yes", 1.0])) if bad else st.booleans()
    if key.kind is str:
        return _string(key, bad)
    if name == "output.probes":
        return _probes(bad)
    return _sections(bad) if name == "projectile.cavity_sections" else _layers(bad)


def _probes(bad: bool) -> st.SearchStrategy:
    """[[output.probes]] tables: names (repeated ones refused), points, kinds; bad ones with any text, short points,
    unknown kinds and keys."""
    point = st.lists(st.floats(-0.01, 0.2), min_size=3, max_size=3)
    probe = {"name": st.sampled_from(["tail", "nose", "mid_1"]), "point": point}
    optional = {"kind": st.sampled_from(["node", "cell"])}
    if bad:
        probe.update(name=st.one_of(st.sampled_from(["tail", "a b", ""]), TEXT),
                     point=st.one_of(point, st.lists(st.floats(allow_nan=True), max_size=4), TEXT))
        optional.update(kind=st.one_of(st.sampled_from(["node", "cell", "nodes"]), TEXT), where=st.just(1.0))
    good = st.lists(st.fixed_dictionaries(probe, optional=optional), min_size=1, max_size=3)
    return st.one_of(good, st.just([]), st.just([1, 2]), _wrong()) if bad else good


def _unknown_key() -> st.SearchStrategy:
    """A key the schema does not have: a leaf in the wrong section, a misspelling, an unknown section."""
    misplaced = st.builds(lambda s, leaf: f"{s}.{leaf}", st.sampled_from(SECTIONS), st.sampled_from(LEAVES))
    typo = st.builds(lambda n, i: n[:i] + n[i + 1:], st.sampled_from(NAMES), st.integers(0, 30))
    other = st.builds(lambda a, b: f"{a}.{b}", TEXT, TEXT)
    return st.one_of(misplaced, typo, other).filter(lambda k: k not in SCHEMA)


def scenes(max_keys: int = 6) -> st.SearchStrategy:
    """A flat {dotted key: value} scene: known keys with values from their schema, half the time all within
    their ranges, else any; sometimes an unknown key."""
    known = st.tuples(st.lists(st.sampled_from(NAMES), max_size=max_keys, unique=True), st.booleans()).flatmap(
        lambda nb: st.fixed_dictionaries({n: value(n, nb[1]) for n in nb[0]}))
    unknown = st.dictionaries(_unknown_key(), st.one_of(st.floats(0.0, 1.0), TEXT), max_size=1)
    return st.builds(lambda a, b: {**a, **b}, known, st.one_of(st.just({}), st.just({}), st.just({}), unknown))


# ---------------------------------------------------------------------------------------------- TOML text
BARE = re.compile(r"^[A-Za-z0-9_-]+$")


def toml_string(text: str) -> str:
    return '"' + "".join(f"\\{c}" if c in '"\\' else f"\\u{ord(c):04x}" if ord(c) < 0x20 or ord(c) == 0x7F
                         else c for c in text) + '"'


def toml_key(dotted: str) -> str:
    return ".".join(p if BARE.match(p) else toml_string(p) for p in dotted.split("."))


def toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf") if math.isinf(v) else repr(v)
    if isinstance(v, str):
        return toml_string(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{toml_key(k)} = {toml_value(x)}" for k, x in v.items()) + "}"
    return str(v)


def toml_text(flat: dict, tables: bool) -> str:
    """The scene as dotted keys at the top, or (tables) under [section] headers."""
    if not tables:
        return "\n".join(f"{toml_key(k)} = {toml_value(v)}" for k, v in flat.items()) + "\n"
    lines, by_section = [], {}
    for k, v in flat.items():
        head, _, rest = k.partition(".")
        by_section.setdefault(head, []).append((rest or head, v))
    for head, items in by_section.items():
        lines.append(f"[{toml_key(head)}]")
        lines.extend(f"{toml_key(k)} = {toml_value(v)}" for k, v in items)
    return "\n".join(lines) + "\n"


# ----------------------------------------------------------------------------------------------- property
LISTED = re.compile(r"^(target\.layers|projectile\.cavity_sections|output\.probes)\[\d+\](\..*)?$")


def _allowed_keys(given_keys) -> set:
    """Keys an InputError may name: a schema key, the scene text, --set, or a key (or table) the user gave."""
    out = set(SCHEMA) | {"SCENE", "--set"}
    for k in _flatten_keys(given_keys) if isinstance(given_keys, dict) else given_keys:
        parts = str(k).split(".")
        out |= {_name(".".join(parts[:i])) for i in range(1, len(parts) + 1)}
    return out


def _in_range(sc) -> None:
    """Every resolved value passes its key's check again (type and range)."""
    for name, key in SCHEMA.items():
        v = sc.get(name)
        if v is None:
            continue
        if name == "target.layers":
            for layer in v:
                for k, x in layer.items():
                    if k in CONSTANTS:
                        SCHEMA[f"target.{k}"].check(k, x)
                    elif k == "thickness":
                        SCHEMA["target.thickness"].check(k, x)
                assert set(layer) <= set(LAYER_KEYS) | set(CONSTANTS)
        else:
            key.check(name, v)


def resolves_or_refuses(make, given_keys):
    """Call make(); a Scene it returns is in range and round-trips through TOML; an InputError it raises names
    an allowed key in one line. Any other exception fails the test."""
    try:
        sc = make()
    except InputError as err:
        assert "\n" not in str(err) and "\n" not in err.message and err.message, repr(err)
        assert err.key in _allowed_keys(given_keys) or LISTED.match(err.key), f"unexpected key {err.key!r}: {err}"
        event("refused")
        return None
    event("resolved")
    _in_range(sc)
    again = Scene(to_toml(sc))
    assert again.as_dict() == sc.as_dict() and again.explicit == sc.explicit
    return sc


# ------------------------------------------------------------------------------------------- scene fuzzing
@settings(max_examples=400, **FUZZ)
@given(scenes())
def test_fuzz_scene_from_a_dict(flat):
    resolves_or_refuses(lambda: Scene(flat), flat)


@settings(max_examples=300, **FUZZ)
@given(scenes(), st.booleans(), st.data())
def test_fuzz_scene_from_toml_text(flat, tables, data):
    text = toml_text(flat, tables)
    if data.draw(st.integers(0, 3)) == 0:  # mangled: a character in, a slice out, or cut short
        at = data.draw(st.integers(0, len(text)))
        how = data.draw(st.sampled_from(["insert", "delete", "cut"]))
        if how == "insert":
            text = text[:at] + data.draw(st.sampled_from(list("[]{}=\"'#.,\n\\ ") + ["[[", "]]", "= ="])) + text[at:]
        elif how == "delete":
            text = text[:at] + text[at + data.draw(st.integers(1, 8)):]
        else:
            text = text[:at]
        text += "\n"  # TOML text, not a file name
    try:
        keys = list(_flatten_keys(tomllib.loads(text)))
    except ValueError:
        keys = []
    resolves_or_refuses(lambda: Scene(text), keys)


def _flatten_keys(tree, prefix=""):
    for k, v in tree.items():
        if isinstance(v, dict) and v:
            yield from _flatten_keys(v, f"{prefix}{k}.")
        else:
            yield f"{prefix}{k}"


@settings(max_examples=200, **FUZZ)
@given(scenes(4), st.lists(st.sampled_from(["noequals", "=1", " = ", "impact.velocity==5", "a.b=c=d",
                                            "projectile.crh=[1,", "impact.velocity=1_000", f"mesh.size={HUGE}",
                                            "impact.velocity=" + "9" * 5000]), max_size=1), st.data())
def test_fuzz_set_items(flat, odd, data):
    items = [f"{k}={toml_value(v) if data.draw(st.booleans()) or not isinstance(v, str) else v}"
             for k, v in flat.items()] + odd
    keys = [parse_set(i)[0] if "=" in i and i.split("=", 1)[0].strip() else "--set" for i in items]
    resolves_or_refuses(lambda: Scene(None, items), keys)


GEOMETRY = [n for n in NAMES if n.startswith("projectile.") and ".material." not in n and SCHEMA[n].kind is float
            and n not in ("projectile.cad_scale",)] + ["projectile.nose", "effects.charge"]


@settings(max_examples=150, **FUZZ)
@given(st.lists(st.sampled_from(GEOMETRY), min_size=1, max_size=5, unique=True).flatmap(
    lambda names: st.fixed_dictionaries({n: value(n, bad=False) for n in names})))
def test_fuzz_projectile_is_built_or_refused_before_any_mesh(flat):
    """The exact projectile of any in-range geometry: built with a positive, finite mass, or refused."""
    def build():
        sc = Scene(flat)
        setup.check_supported(sc)
        built = setup.projectile(sc)
        mass = built.shape.mass(built.shell_density)
        assert math.isfinite(mass) and mass > 0.0, (flat, mass)
        return sc

    resolves_or_refuses(build, flat)


# ----------------------------------------------------------------------------------------- the command line
COMMANDS = ["run", "mesh", "validate", "validate-depth", "study", "sweep", "keys", "view"]
#: no real option starts so (argparse takes unique prefixes: --wor would be --workers); file names with any
#: character a file name can hold, newlines included (the error line collapses them)
BOGUS = st.builds(lambda s: "--bogus-" + s, st.text("abcxyz-=0", max_size=6))
NAME = st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters="/\x00"), min_size=1,
               max_size=10).filter(lambda s: not s.startswith("-") and s.strip() not in ("", ".", ".."))
NOT_INT = st.one_of(TEXT.filter(lambda s: not re.fullmatch(r"\s*[-+]?[0-9_]+\s*", s)), st.just("1.5"))
NOT_FLOAT = TEXT.filter(lambda s: _not_float(s))


def _not_float(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return True
    return False


def _bad_set() -> st.SearchStrategy:
    """A --set item that is wrong on its own: no '=', no key, an unknown key, or a value its key refuses."""
    def refused(item):
        try:
            k, v = parse_set(item)
            if k not in SCHEMA:
                return True
            SCHEMA[k].check(k, v)
        except InputError:
            return True
        return False

    known = st.sampled_from(NAMES).flatmap(lambda n: value(n).map(lambda v: f"{n}={toml_value(v)}"))
    return st.one_of(NAME, st.builds(lambda v: "=" + v, TEXT), st.builds(lambda k: f"{k}=1", _unknown_key()),
                     known).filter(refused)


def _argv() -> st.SearchStrategy:
    """Argument lists that are wrong somewhere, so that nothing runs."""
    scene_cmd = st.sampled_from([["run"], ["mesh"], ["validate"], ["study", "ballistic-limit"],
                                 ["study", "ricochet"]])
    return st.one_of(
        st.builds(lambda c: [c], NAME.filter(lambda s: s not in COMMANDS)),  # unknown command
        st.builds(lambda c, o: [c, o], st.sampled_from(COMMANDS), BOGUS),  # unknown option
        st.builds(lambda c, s: [*c, "--set", s], scene_cmd, _bad_set()),
        st.builds(lambda s: ["validate-depth", "--data", "missing.csv", "--set", s], _bad_set()),
        st.builds(lambda c, f: [*c, f + ".toml"], scene_cmd, NAME),  # missing scene file
        st.builds(lambda f, o: ["sweep", f, *o], NAME, st.sampled_from([[], ["--workers", "1"], ["--fresh"]])),
        st.builds(lambda f: ["validate-depth", "--data", f, "--only"], NAME),
        st.builds(lambda f: ["run", "--resume", f], NAME),
        st.builds(lambda f: ["view", f], NAME),
        st.builds(lambda w: ["sweep", "s.toml", "--workers", w], st.one_of(NOT_INT, st.sampled_from(["0", "-2"]))),
        st.builds(lambda w: ["sweep", "s.toml", "--ranks-per-shot", w], st.one_of(NOT_INT, st.just("0"))),
        st.builds(lambda w: ["study", "ballistic-limit", "--ranks-per-shot", w], st.one_of(NOT_INT, st.just("0"))),
        st.builds(lambda w: ["validate-depth", "--workers", w], NOT_INT),
        st.builds(lambda w: ["study", "accuracy-cost", "--ranks", w], st.one_of(NOT_INT, st.sampled_from(["0", "-1"]))),
        st.builds(lambda c, s: ["study", c, "--speeds", s], st.sampled_from(["ballistic-limit", "ricochet"]),
                  st.one_of(TEXT, st.sampled_from(["", "100,", "nan,900", "-1,5", "inf", "0,100"])).filter(
                      lambda s: not re.fullmatch(r"\s*[0-9.e+]+(\s*,\s*[0-9.e+]+)*\s*", s) or _bad_speeds(s))),
        st.builds(lambda s: ["study", "ballistic-limit", "--speeds", s], st.sampled_from(["5", "5,6,7"])),
        st.builds(lambda c, t: ["study", c, "--tol", t], st.sampled_from(["ballistic-limit", "ricochet"]),
                  st.sampled_from(["-1", "0", "nan", "inf"])),
        st.builds(lambda t: ["study", "ricochet", "--obliquity-max", t], st.sampled_from(["120", "0", "-5", "nan"])),
        st.builds(lambda t: ["study", "ballistic-limit", "--tol", t], NOT_FLOAT),
        st.builds(lambda t: ["study", "ricochet", "--obliquity-max", t], NOT_FLOAT),
        st.builds(lambda t: ["view", "d", "--time", t], NOT_FLOAT),
        st.builds(lambda c: ["study", c], NAME.filter(lambda s: s not in ("accuracy-cost", "ballistic-limit",
                                                                           "ricochet"))),
    )


def _bad_speeds(s: str) -> bool:
    try:
        return not all(math.isfinite(float(x)) and float(x) > 0 for x in s.split(","))
    except ValueError:
        return True


@pytest.fixture
def empty_dir(tmp_path, monkeypatch):
    """An empty working directory, and whatever would run a shot, a mesh, a study or a process fails at once
    (exit 1 with its name) instead of running."""
    import subprocess

    from fepen import api, runs
    from fepen.geometry import mesh as fmesh
    from fepen.studies import engine, study

    def ran(*args, **kwargs):
        raise RuntimeError("the fuzz's argument list started a run")

    for owner, name in [(api, "run"), (runs, "run_scene"), (study, "run"), (engine, "execute"), (setup, "mesh"),
                        (fmesh, "create"), (subprocess, "Popen")]:
        monkeypatch.setattr(owner, name, ran)
    monkeypatch.chdir(tmp_path)
    return tmp_path


@settings(max_examples=250, **FUZZ)
@given(argv=_argv())
def test_fuzz_command_line_refuses_in_one_line(empty_dir, argv):
    assume(not any(os.path.exists(a) for a in argv if a and "\x00" not in a))
    err, out = io.StringIO(), io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
        code = cli.main(list(argv))
    lines = err.getvalue().splitlines()
    assert code == 2, (argv, code, err.getvalue())
    assert len(lines) == 1 and lines[0].startswith("fepen: bad input: "), (argv, err.getvalue())
    assert out.getvalue() == "" and not os.listdir(empty_dir), (argv, os.listdir(empty_dir))
