"""Checks across scene keys, before anything is meshed (issue 18, item 2): each refused combination names a key
and says what is allowed in one line; what is only doubtful (a target thinner than the nose) is a note; the
shipped scenes, sweep files and material libraries still resolve. Mesh-free: fepen.scene resolves, and
fepen.runs.setup builds the exact projectile, as ``fepen mesh`` and ``fepen run`` do before any mesh."""

import math
import re
import tomllib
from pathlib import Path

import pytest

from fepen import cli
from fepen.data import STEELS, TARGETS
from fepen.errors import InputError
from fepen.runs import setup
from fepen.scene import Scene

ROOT = Path(__file__).resolve().parents[3]
METAL = [name for name, t in TARGETS.items() if t["family"] == "metal"]


def refused(sets, key, words, built=False):
    """The scene of these --set items is refused by resolution (or, built=True, by building its projectile),
    naming ``key``, with a one-line message matching ``words``."""
    with pytest.raises(InputError) as err:
        sc = Scene(None, sets)
        if built:
            setup.check_supported(sc)
    assert err.value.key == key, str(err.value)
    assert re.search(words, err.value.message), err.value.message
    assert "\n" not in str(err.value)
    return err.value.message


def _laws(sc):
    """The target law of a scene, one per layer."""
    law = setup.target_law(sc)
    return [layer.law for layer in law.layers] if hasattr(law, "layers") else [law]


# ---------------------------------------------------------------------------------------------- materials
@pytest.mark.parametrize("sets, key", [
    (["projectile.material.melt_temperature=200"], "projectile.material.melt_temperature"),
    (["projectile.material.melt_temperature=294"], "projectile.material.melt_temperature"),
    (["projectile.material.room_temperature=2000"], "projectile.material.room_temperature"),
    (["projectile.material.room_temperature=900", "projectile.material.melt_temperature=800"],
     "projectile.material.melt_temperature"),
])
def test_melting_temperature_must_exceed_room_temperature(sets, key):
    refused(sets, key, r"melting temperature .* must exceed room temperature")


def test_melting_just_above_room_temperature_is_accepted():
    sc = Scene(None, ["projectile.material.melt_temperature=295"])
    assert sc.projectile.material.melt_temperature == 295.0


@pytest.mark.parametrize("sets, key", [
    (["charge.material.tangent_modulus=2e10"], "charge.material.tangent_modulus"),
    (["effects.charge=true", "charge.material.youngs_modulus=5e8"], "charge.material.youngs_modulus"),
    (["charge.material.tangent_modulus=1.01e10"], "charge.material.tangent_modulus"),
])
def test_charge_tangent_modulus_below_youngs_modulus(sets, key):
    refused(sets, key, r"tangent modulus .* must be below its Young's modulus")


# ------------------------------------------------------------------------------------------------- target
@pytest.mark.parametrize("sets, key, words", [
    (["target.tensile_strength=5e7"], "target.tensile_strength", r"must be below compressive strength 3.1875e\+07 Pa "
     r"\(of the 4e\+07 Pa cube\)"),
    (["target.tensile_strength=4e7"], "target.tensile_strength", r"must be below compressive strength"),
    (['target.material="limestone"', "target.compressive_strength=4e6"], "target.compressive_strength",
     r"tensile strength 5e\+06 Pa must be below compressive strength 4e\+06"),
    (["target.youngs_modulus=1e6"], "target.youngs_modulus", r"leave no plastic zone .* = 160 must be below 1"),
    (["target.tensile_strength=1"], "target.tensile_strength", r"leave no plastic zone"),
    (['target.material="6061-T6511"', "target.yield_stress=5e10"], "target.yield_stress",
     r"must be below 2/3 of its Young's modulus"),
    (['target.material="armour-steel"', "target.youngs_modulus=1e9"], "target.youngs_modulus",
     r"must be below 2/3 of its Young's modulus"),
    (['target.material="6061-T6511"', 'target.strength_model="scaled-S"'], "target.strength_model",
     r"a metal target's law is 'metal'"),
    (['target.strength_model="metal"'], "target.strength_model", r"'metal' is the law of a metal target"),
    (['target.layers=[{material="concrete", thickness=0.2, tensile_strength=5e7}, {material="concrete"}]'],
     "target.layers[0].tensile_strength", r"must be below compressive strength"),
    (['target.layers=[{material="concrete", thickness=0.2}, {material="granite", youngs_modulus=1e8}]'],
     "target.layers[1].youngs_modulus", r"leave no plastic zone"),
    (['target.layers=[{material="armour-steel", thickness=0.01, youngs_modulus=1e9}, {material="concrete"}]'],
     "target.layers[0].youngs_modulus", r"must be below 2/3"),
    (['target.layers=[{material="soil", strength_model="metal"}]'], "target.layers[0].strength_model",
     r"not of a soil one"),
])
def test_target_constants_must_make_a_law(sets, key, words):
    refused(sets, key, words)


@pytest.mark.parametrize("material", sorted(TARGETS))
def test_every_target_material_resolves_to_a_finite_law(material):
    for sc in (Scene(None, [f'target.material="{material}"']),
               Scene(None, [f'target.layers=[{{material="{material}", thickness=0.1}}, {{material="concrete"}}]'])):
        for law in _laws(sc):
            assert math.isfinite(law.sigma_s) and law.sigma_s > 0.0


@pytest.mark.parametrize("steel", sorted(STEELS))
def test_every_named_steel_resolves(steel):
    sc = Scene(None, [f'projectile.material.name="{steel}"'])
    m = sc.projectile.material
    assert m.melt_temperature > m.room_temperature
    setup.projectile_material(sc)


# --------------------------------------------------------------------------------------- striking and run
@pytest.mark.parametrize("sets, key", [
    (["impact.obliquity_deg=80", "impact.attack_deg=10"], "impact.attack_deg"),
    (["impact.obliquity_deg=89.95"], "impact.obliquity_deg"),  # with C3's attack of 0.1 deg
    (["impact.obliquity_deg=45", "impact.attack_deg=45"], "impact.attack_deg"),  # each in range, the sum not
    (["impact.obliquity_deg=60", "impact.attack_deg=40", "impact.attack_plane_deg=10"], "impact.attack_deg"),
])
def test_axis_must_point_into_the_target(sets, key):
    msg = refused(sets, key, r"turns the projectile's axis [\d.]+ deg from the normal, .* must be < 90 deg")
    assert "tail would start inside the target" in msg


def test_steep_but_possible_attitudes_are_accepted():
    sc = Scene(None, ["impact.obliquity_deg=80", "impact.attack_deg=9.9"])
    assert sc.impact.obliquity_deg + sc.impact.attack_deg < 90.0
    Scene(None, ["impact.obliquity_deg=85", "impact.attack_deg=-89"])
    # out of the plane of fire the axis is at acos(cos 60 cos 40) = 67.5 deg from the normal; turned back, 65
    Scene(None, ["impact.obliquity_deg=60", "impact.attack_deg=40", "impact.attack_plane_deg=90"])
    Scene(None, ["impact.obliquity_deg=80", "impact.attack_deg=15", "impact.attack_plane_deg=180"])


def test_rigid_step_within_the_end_time_when_both_are_given():
    refused(["run.end_time=1e-4", "run.rigid_step=2e-4"], "run.rigid_step", r"must be at most run.end_time = 0.0001 s")


def test_a_field_interval_past_the_end_is_allowed():
    """Fields at the first and the last state only: a short test run of a scene file with its interval."""
    sc = Scene(None, ["run.end_time=1e-5", "run.output_interval=5e-5"])
    assert sc.run.output_interval > sc.run.end_time


# ----------------------------------------------------------------------------------------- charge, cavity
@pytest.mark.parametrize("sets, key, words", [
    (["effects.charge=true", "projectile.cavity_diameter=0"], "effects.charge", r"needs a cavity to fill"),
    (["effects.charge=true", "projectile.cavity_diameter=0", "projectile.mass=0.4"], "projectile.mass",
     r"solid body"),
    (["effects.charge=true", 'projectile.cad="body.step"'], "effects.charge", r"a CAD body has no charge"),
])
def test_charge_only_with_a_cavity(sets, key, words):
    refused(sets, key, words)


def test_charge_fills_the_default_and_a_drawn_cavity_table():
    for sets in (["effects.charge=true"], ["effects.charge=true", "projectile.cavity_sections=[[0.02, 0.008], "
                                                                  "[0.05, 0.012]]"]):
        built = setup.projectile(Scene(None, sets))
        assert built.shape.has_cavity


@pytest.mark.parametrize("sets, key, words", [
    (["projectile.cavity_diameter=0.03"], "projectile.cavity_diameter", r"leaves no wall: must be at most"),
    (["projectile.cavity_diameter=0.022"], "projectile.cavity_diameter", r"at most diameter - 2 x"),
    (["projectile.cavity_length=0.2"], "projectile.cavity_length", r"does not fit: must be in \(0, 0.11"),
    (["projectile.cavity_step_length=0.2"], "projectile.cavity_step_length", r"does not fit this nose"),
    (["projectile.cavity_sections=[[0.13, 0.005], [0.05, 0.01]]"], "projectile.cavity_sections",
     r"behind 130 mm of forward sections\) does not fit"),
    (["projectile.cavity_sections=[[0.01, 0.05], [0.05, 0.01]]"], "projectile.cavity_sections",
     r"diameters in \(0, 0.02124\] m"),
    (["projectile.boattail_length=0.1", "projectile.boattail_diameter=0.001", "projectile.cavity_diameter=0.012"],
     "projectile.cavity_diameter", r"does not fit this nose, diameter, boat-tail"),
    (["projectile.base_thickness=0.2"], "projectile.base_thickness", r"must be less than the body behind the nose"),
    (["projectile.base_thickness=0.2", "projectile.cavity_diameter=0.01"], "projectile.base_thickness",
     r"must be less than the body behind the nose, 0.10486"),
    (["projectile.meplat_diameter=0.03"], "projectile.meplat_diameter", r"must be less than projectile.diameter"),
    (["projectile.length=0.03"], "projectile.length", r"too short for the ogive nose"),
    (['projectile.nose="cone"', "projectile.nose_length=0.2"], "projectile.length", r"too short for the cone"),
    (["projectile.boattail_length=0.05", "projectile.boattail_diameter=0.03"], "projectile.boattail_diameter",
     r"must be in \(0, 0.0236\)"),
])
def test_cavity_and_outside_must_fit(sets, key, words):
    refused(sets, key, words, built=True)


@pytest.mark.parametrize("sets, words", [
    (["projectile.mass=5"], r"5 kg cannot be reached in this outside: must be in \[0.1377, 0.542\] kg"),
    (["projectile.mass=0.01"], r"must be in \[0.1377, 0.542\] kg"),
    (["projectile.mass=0.2", "projectile.cavity_diameter=0.012"], r"unreachable .* must be in \[0.3371, 0.4257\]"),
    (["projectile.mass=0.5", "effects.charge=true"], r"unreachable .* must be in \[0.3599, 0.4276\]"),
    (["projectile.diameter=0.005"], r"must be in \[0.00491, 0.02702\] kg"),
])
def test_mass_must_be_reachable(sets, words):
    refused(sets, "projectile.mass", words, built=True)


def test_masses_at_the_ends_of_the_reachable_range_are_built():
    for mass in (0.1378, 0.541):
        built = setup.projectile(Scene(None, [f"projectile.mass={mass}"]))
        assert built.shape.mass(built.shell_density) == pytest.approx(mass, rel=1e-9)


# --------------------------------------------------------------------------------------- thin target note
@pytest.mark.parametrize("sets, key", [
    (["target.thickness=0.02"], "target.thickness"),
    (['target.layers=[{material="armour-steel", thickness=0.006}, {material="concrete"}]'],
     "target.layers[0].thickness"),
])
def test_a_target_thinner_than_the_nose_is_run_with_a_note(sets, key):
    sc = Scene(None, sets)
    setup.check_supported(sc)
    note = setup.thin_target_note(sc, setup.projectile(sc))
    assert note.startswith(f"{key} ") and "less than the nose length 39.1 mm" in note and "\n" not in note


@pytest.mark.parametrize("sets", [["target.thickness=0.05"], [], ['projectile.nose="flat"', "target.thickness=1e-3"],
                                  ['target.kind="rigid-wall"', "target.thickness=1e-3"]])
def test_no_note_for_a_target_thicker_than_the_nose(sets):
    sc = Scene(None, sets)
    assert setup.thin_target_note(sc, setup.projectile(sc)) is None


def test_target_thickness_must_be_positive():
    refused(["target.thickness=0"], "target.thickness", r"expected a number in \(0, 100\] m")


# --------------------------------------------------------------------------------- the command line path
@pytest.fixture
def no_mesh(monkeypatch, tmp_path):
    """Meshing fails the test: every refusal below comes before it."""
    from fepen.geometry import mesh as fmesh

    def meshed(*args, **kwargs):
        raise AssertionError("meshed")

    monkeypatch.setattr(fmesh, "create", meshed)
    monkeypatch.setattr(setup, "mesh", meshed)
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.parametrize("command", ["mesh", "run"])
@pytest.mark.parametrize("item, key", [
    ("projectile.material.melt_temperature=200", "projectile.material.melt_temperature"),
    ("projectile.cavity_diameter=0.03", "projectile.cavity_diameter"),
    ("projectile.mass=5", "projectile.mass"),
    ("impact.attack_deg=85", "impact.attack_deg"),
    ("charge.material.tangent_modulus=2e10", "charge.material.tangent_modulus"),
])
def test_cli_refuses_before_meshing(no_mesh, capsys, command, item, key):
    out = no_mesh / "out"
    assert cli.main([command, "--out", str(out), "--set", item]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith(f"fepen: bad input: {key}: "), err
    assert not out.exists()


# ------------------------------------------------------------------------------ what fepen ships resolves
def _shipped():
    return sorted([*ROOT.glob("scenes/*.toml"), *ROOT.glob("demos/**/*.toml")])


@pytest.mark.parametrize("path", _shipped(), ids=lambda p: str(p.relative_to(ROOT)))
def test_every_shipped_scene_and_sweep_resolves(path):
    tree = tomllib.loads(path.read_text())
    if "base" in tree or "scene" in tree:  # a sweep file: every shot resolved, every distinct body built
        from fepen.studies import sweep

        assert sweep.read(path).shots
        return
    sc = Scene(path)
    setup.check_supported(sc)
    assert all(math.isfinite(law.sigma_s) and law.sigma_s > 0.0 for law in _laws(sc))
    if sc.effects.fidelity != "rigid":
        setup.projectile_material(sc)
        if sc.effects.charge:
            setup.charge_material(sc)


def test_the_default_scene_and_the_table1_shots_resolve():
    from fepen.data import SHOTS

    for name in [None, *SHOTS]:
        sc = Scene(None, [f'impact.shot="{name}"'] if name else [])
        setup.check_supported(sc)
        assert setup.thin_target_note(sc, setup.projectile(sc)) is None
