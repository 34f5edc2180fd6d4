"""Scenes: defaults, --set, validation; bad input gives one line, exit code 2, nothing written."""

import numpy as np
import pytest

from fepen import scene
from fepen.data import SHOTS
from fepen.errors import InputError


def test_defaults_are_the_paper_and_shot_c3():
    sc = scene.load()
    assert sc.projectile.diameter == 0.0236 and sc.projectile.length == 0.144
    assert sc.projectile.mass == 0.367
    m = sc.projectile.material
    assert (m.A, m.B, m.C, m.m, m.n, m.melt_temperature) == (950e6, 725e6, 0.015, 0.625, 0.375, 1765.0)
    t = sc.target
    assert (t.density, t.compressive_strength, t.pressure_hardening) == (2400.0, 40e6, 0.67)
    assert sc.get("target.youngs_modulus") is None  # from fc (ACI 318) unless given
    assert sc.get("target.strength_basis") == "cube"  # the paper's C40 (docs/theory.md §8.1)
    assert t.tensile_strength == pytest.approx(3.1875e6)  # fc / 10 when not given, of the cylinder strength
    assert (sc.impact.velocity, sc.impact.obliquity_deg, sc.impact.attack_deg) == (584.3, 10.5, 0.10)
    assert sc.get("impact.shot") is None and sc.get("target.thickness") is None


def test_shot_fills_the_striking_conditions():
    for name, row in SHOTS.items():
        sc = scene.load(None, [f'impact.shot="{name}"'])
        assert (sc.impact.velocity, sc.impact.obliquity_deg, sc.impact.attack_deg) == (
            row.v0, row.obliquity_deg, row.attack_deg)


def test_set_values_in_toml_syntax_and_bare_words(tmp_path):
    f = tmp_path / "s.toml"
    f.write_text('[impact]\nvelocity = 650\n[effects]\ncrater = "linear"\n')
    sc = scene.load(f, ["impact.velocity=700", "effects.crater=none", "effects.thermal=false",
                        "mesh.size=3e-3"])
    assert sc.impact.velocity == 700.0 and isinstance(sc.impact.velocity, float)
    assert sc.effects.crater == "none" and sc.effects.thermal is False and sc.mesh.size == 0.003
    assert "impact.velocity" in sc.explicit and "projectile.crh" not in sc.explicit


def test_resolved_scene_round_trips_through_toml(tmp_path):
    sc = scene.load(None, ['impact.shot="C7"', "target.thickness=0.15"])
    f = tmp_path / "resolved.toml"
    f.write_text(scene.to_toml(sc))
    again = scene.load(f)
    assert again.as_dict() == sc.as_dict()


@pytest.mark.parametrize("sets", [
    ['projectile.cad="body.step"'],  # the CAD body's derived keys would be refused if given
    ['projectile.profile="outer.csv"'],
    ['projectile.inner_profile="inner.csv"'],
    ["projectile.cavity_sections=[[0.01, 0.005], [0.05, 0.01]]"],
    ["projectile.mass=0.2"],  # the mass rule adapts only a cavity the user did not give
    ['target.layers=[{material="soil", thickness=0.1}, {material="granite"}]'],  # soil keeps its own crater
    ['projectile.profile="a\\"b\\\\c d.csv"'],  # a quote and a backslash in a path
])
def test_scene_toml_resolves_to_the_same_scene_with_the_same_given_keys(sets):
    """scene.toml (fepen run --resume, api.load) gives the keys the user gave as values, the rest as comments:
    the mass rule, drawn and CAD bodies and a layer's crater depend on which keys were given."""
    sc = scene.load(None, sets)
    text = scene.to_toml(sc)
    again = scene.Scene(text)
    assert again.as_dict() == sc.as_dict() and again.explicit == sc.explicit
    assert "# crh = 3.0" in text or "crh" in str(sets)  # every default is still there to read


def test_the_mass_rule_builds_the_same_projectile_from_scene_toml():
    from fepen.runs import setup

    sc = scene.load(None, ["projectile.mass=0.2"])
    first, again = setup.projectile(sc), setup.projectile(scene.Scene(scene.to_toml(sc)))
    assert first.note and again.shape == first.shape and again.shell_density == first.shell_density


@pytest.mark.parametrize("item, key, words", [
    ("impact.velocty=600", "impact.velocty", "did you mean 'impact.velocity'"),
    ("impact.velocity=-50", "impact.velocity", "(0, 3000] m/s"),
    ("impact.velocity=fast", "impact.velocity", "expected a number"),
    ("projectile.crh=0.3", "projectile.crh", "[0.5, 50]"),
    ("effects.fidelity=quantum", "effects.fidelity", "'rigid', 'elastic', 'plastic'"),
    ("effects.thermal=1", "effects.thermal", "true or false"),
    ("target.pressure_hardening=3", "target.pressure_hardening", "[0, 3)"),
    ("mesh.size=0", "mesh.size", "[0.0002, 0.05] m"),
    ("friction=0.2", "friction", "did you mean 'target.friction'"),
    ('impact.shot="C9"', "impact.shot", "'C1'"),
])
def test_bad_values_name_the_key_and_the_range(item, key, words):
    with pytest.raises(InputError) as err:
        scene.load(None, [item])
    assert err.value.key == key
    assert words in str(err.value)
    assert "\n" not in str(err.value)


def test_conflicting_keys():
    with pytest.raises(InputError, match="impact.velocity: conflicts with impact.shot"):
        scene.load(None, ['impact.shot="C3"', "impact.velocity=600"])
    with pytest.raises(InputError, match="projectile.mass: give projectile.mass or"):
        scene.load(None, ["projectile.mass=0.36", "projectile.cavity_length=0.05"])
    with pytest.raises(InputError, match="effects.charge"):
        scene.load(None, ["effects.charge=true", "projectile.cavity_diameter=0"])


BAD = [
    ("unknown key", ["--set", "impact.velocty=600"], "impact.velocty"),
    ("negative speed", ["--set", "impact.velocity=-600"], "impact.velocity"),
    ("wrong type", ["--set", "projectile.diameter=wide"], "projectile.diameter"),
    ("CRH below 0.5", ["--set", "projectile.crh=0.4"], "projectile.crh"),
    ("cavity wider than the body", ["--set", "projectile.cavity_diameter=0.03"], "projectile.cavity_diameter"),
    ("unknown fidelity", ["--set", "effects.fidelity=soft"], "effects.fidelity"),
    ("unreachable mass", ["--set", "projectile.mass=1.2"], "projectile.mass"),
    ("missing file", ["no_such_scene.toml"], "no such scene file"),
]


@pytest.mark.parametrize("what, args, key", BAD, ids=[b[0] for b in BAD])
def test_cli_bad_input_exits_2_with_one_line(fepen_cli, tmp_path, what, args, key):
    out = tmp_path / "out"
    r = fepen_cli("mesh", *args, "--out", out)
    assert r.returncode == 2, r.stderr
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and key in lines[0] and lines[0].startswith("fepen: bad input:"), r.stderr
    assert "Traceback" not in r.stderr and r.stdout == ""
    assert not out.exists()


def test_cli_bad_toml_file(fepen_cli, tmp_path):
    f = tmp_path / "broken.toml"
    f.write_text("[impact\nvelocity = 3\n")
    r = fepen_cli("mesh", f, "--out", tmp_path / "o")
    assert r.returncode == 2 and "not valid TOML" in r.stderr and "Traceback" not in r.stderr


def test_sliding_friction_must_not_exceed_the_static_one():
    with pytest.raises(InputError) as err:
        scene.load(None, ["target.friction=0.1", "target.friction_dynamic=0.2"])
    assert err.value.key == "target.friction_dynamic"
    assert scene.load(None, ["target.friction_dynamic=0.05"]).target.friction_dynamic == 0.05


def test_named_steels_fill_the_material_and_explicit_keys_win():
    from fepen.data import STEELS

    default = scene.load(None, [])
    assert default.projectile.material.name == "45-steel"
    for key, value in STEELS["45-steel"].items():  # the paper's steel is the default material, key by key
        if key != "source":
            assert getattr(default.projectile.material, key) == value, key
    for name, steel in STEELS.items():
        assert steel["source"].strip()
        m = scene.load(None, [f"projectile.material.name={name}"]).projectile.material
        assert all(getattr(m, k) == v for k, v in steel.items() if k != "source")
        assert 0.0 < m.A < 3e9 and 1000.0 < m.melt_temperature < 2000.0
    m = scene.load(None, ["projectile.material.name=aisi-4340", "projectile.material.A=800e6"]).projectile.material
    assert m.A == 800e6 and m.B == STEELS["aisi-4340"]["B"]
    with pytest.raises(InputError, match="projectile.material.name"):
        scene.load(None, ["projectile.material.name=unobtainium"])


@pytest.mark.parametrize("value", [np.float64(160181857.99361405), np.float32(0.25), np.int64(3), 1e-300,
                                   float("inf"), np.bool_(True), False, 7, 'C3 "quoted"', "a\\b"])
def test_set_item_gives_back_the_value_whatever_its_type(value):
    """scene.set_item writes a value as --set reads it: numpy 2's scalars (repr np.float64(...), not TOML), numpy's
    booleans and integers, and text with quotes and backslashes come back equal."""
    key, back = scene.parse_set(scene.set_item("target.quasi_static_stress", value))
    plain = value.item() if isinstance(value, np.generic) else value
    assert key == "target.quasi_static_stress" and back == plain and type(back) is type(plain)
    with pytest.raises(TypeError, match="target.density"):
        scene.set_item("target.density", [1.0])
