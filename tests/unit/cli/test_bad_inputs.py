"""Bad scenes and command lines as a new user writes them (issue 18, acceptance 1): each is answered with exit
code 2 and exactly one line on stderr, "fepen: bad input: KEY: ...", naming the key or argument and what is
allowed, before anything is meshed, run or written. A row is (argv for fepen.cli.main, the scene text written
to SCENE (None: no file), the key the line names, a regex the rest of the line matches). In argv, SCENE
stands for the scene file's path; the working directory is an empty temporary one.
"""


import pytest

from fepen import cli
from fepen.runs import setup

MESH = ["mesh", "SCENE", "--out", "out"]
RUN = ["run", "SCENE", "--out", "out"]


def row(id, argv, text, key, words):
    return pytest.param(argv, text, key, words, id=id)


def sets(*items, command="mesh"):
    """argv of a command with no scene file and these --set items."""
    return [command, "--out", "out", *[a for item in items for a in ("--set", item)]]


CASES = [
    # --- malformed TOML ---
    row("toml-missing-value", MESH, "[impact]\nvelocity =\n", "SCENE", r"is not valid TOML: Invalid value"),
    row("toml-unclosed-table", MESH, "[impact\nvelocity = 600\n", "SCENE", r"is not valid TOML"),
    row("toml-unclosed-string", MESH, '[projectile]\nnose = "ogive\n', "SCENE", r"is not valid TOML"),
    row("toml-duplicate-key", MESH, "[impact]\nvelocity = 600\nvelocity = 700\n", "SCENE", r"not valid TOML"),
    row("toml-duplicate-table", MESH, "[impact]\nvelocity = 600\n[impact]\nobliquity_deg = 1\n", "SCENE",
        r"not valid TOML"),
    row("toml-decimal-comma", MESH, "[impact]\nvelocity = 600,5\n", "SCENE", r"not valid TOML"),
    row("toml-bare-word", MESH, "[effects]\nfidelity = rigid\n", "SCENE", r"not valid TOML: Invalid value"),
    row("toml-json-file", MESH, '{"impact": {"velocity": 600}}\n', "SCENE", r"not valid TOML"),
    row("toml-not-utf8", MESH, b"[impact]\nvelocity = 600 # \xff\xfe\n", "SCENE", r"not valid TOML: .*utf-8"),
    row("toml-integer-of-5000-digits", MESH, "[impact]\nvelocity = " + "9" * 5000 + "\n", "SCENE",
        r"not valid TOML: Exceeds the limit \(4300 digits\)"),
    row("toml-empty-table", MESH, "[impact]\n", "impact", r"^empty table$"),
    # --- NaN, inf, numbers no float holds ---
    row("nan-velocity", MESH, "[impact]\nvelocity = nan\n", "impact.velocity",
        r"got nan, expected a number in \(0, 3000\] m/s"),
    row("inf-velocity", MESH, "[impact]\nvelocity = inf\n", "impact.velocity", r"got inf, expected a number"),
    row("minus-inf-mass", MESH, "[projectile]\nmass = -inf\n", "projectile.mass", r"got -inf, expected"),
    row("set-nan-crh", sets("projectile.crh=nan"), None, "projectile.crh", r"got nan, expected a number in "
                                                                             r"\[0.5, 50\]"),
    row("set-inf-thickness", sets("target.thickness=inf"), None, "target.thickness", r"got inf"),
    row("set-integer-too-large-for-a-float", sets("mesh.size=1" + "0" * 400), None, "mesh.size",
        r"got 1000+\.\.\., expected a number in \[0.0002, 0.05\] m"),
    # --- wrong types ---
    row("string-velocity", MESH, '[impact]\nvelocity = "fast"\n', "impact.velocity", r"got 'fast', expected a "
                                                                                       r"number"),
    row("string-flag", MESH, '[effects]\ncharge = "yes"\n', "effects.charge", r"got 'yes', expected true or false"),
    row("integer-flag", MESH, "[effects]\ncharge = 1\n", "effects.charge", r"got 1, expected true or false"),
    row("bool-velocity", MESH, "[impact]\nvelocity = true\n", "impact.velocity", r"got True, expected a number"),
    row("string-cavity-sections", MESH, '[projectile]\ncavity_sections = "12mm"\n', "projectile.cavity_sections",
        r"expected a list of \[length, diameter\] pairs"),
    row("bad-cavity-section", sets("projectile.cavity_sections=[[0.05, -0.01]]"), None,
        "projectile.cavity_sections[0]", r"got \[0.05, -0.01\], expected \[length, diameter\] in metres, each > 0"),
    row("number-layers", MESH, "[target]\nlayers = 5\n", "target.layers", r"expected a list of tables"),
    row("number-nose", MESH, "[projectile]\nnose = 3\n", "projectile.nose", r"got 3, expected one of 'ogive'"),
    row("list-mesh-size", MESH, "[mesh]\nsize = [0.001]\n", "mesh.size", r"got \[0.001\], expected a number"),
    row("number-profile", MESH, "[projectile]\nprofile = 1\n", "projectile.profile", r"expected a file path"),
    row("empty-profile", MESH, '[projectile]\nprofile = ""\n', "projectile.profile", r"got '', expected a file "
                                                                                     r"path \(CSV\)"),
    # --- out of range ---
    row("zero-velocity", MESH, "[impact]\nvelocity = 0\n", "impact.velocity", r"got 0, expected .* \(0, 3000\]"),
    row("velocity-5000", sets("impact.velocity=5000"), None, "impact.velocity", r"got 5000"),
    row("obliquity-90", sets("impact.obliquity_deg=90"), None, "impact.obliquity_deg", r"\[0, 90\) deg"),
    row("poisson-0.5", sets("projectile.material.poisson_ratio=0.5"), None, "projectile.material.poisson_ratio",
        r"got 0.5, expected a number in \[0, 0.5\)"),
    row("crh-0.4", sets("projectile.crh=0.4"), None, "projectile.crh", r"\[0.5, 50\]"),
    row("mesh-size-10-microns", sets("mesh.size=1e-5"), None, "mesh.size", r"got 1e-05, .* \[0.0002, 0.05\] m"),
    row("negative-thickness", sets("target.thickness=-0.1"), None, "target.thickness", r"\(0, 100\] m"),
    row("half-mm-calibre", sets("projectile.diameter=0.0005"), None, "projectile.diameter", r"\[0.001, 1\] m"),
    row("safety-factor-1.5", sets("run.safety_factor=1.5"), None, "run.safety_factor", r"\(0, 1\]"),
    row("zero-mass", sets("projectile.mass=0"), None, "projectile.mass", r"got 0, expected .* \(0, 10000\] kg"),
    row("unknown-fidelity", sets("effects.fidelity=wobbly"), None, "effects.fidelity",
        r"got 'wobbly', expected one of 'rigid', 'elastic', 'plastic'"),
    row("unknown-shot", sets('impact.shot="C9"'), None, "impact.shot", r"got 'C9', expected one of 'C1'"),
    row("unknown-steel", sets('projectile.material.name="steel"'), None, "projectile.material.name",
        r"expected one of '45-steel'"),
    row("unknown-target-material", MESH, '[target]\nmaterial = "wood"\n', "target.material",
        r"got 'wood', expected one of 'concrete'"),
    # --- unknown keys and sections ---
    row("misspelt-key", MESH, "[impact]\nvelocty = 600\n", "impact.velocty", r"did you mean 'impact.velocity'"),
    row("misspelt-section", MESH, "[projectil]\ndiameter = 0.03\n", "projectil.diameter",
        r"unknown key \(did you mean 'projectile.diameter'\?\)"),
    row("unknown-section", MESH, "[solver]\ndt = 1e-7\n", "solver.dt",
        r"unknown key \(sections: charge, effects, impact, mesh, output, projectile, run, target\)"),
    row("key-in-the-wrong-section", MESH, "[target]\ncrh = 3\n", "target.crh", r"did you mean 'projectile.crh'"),
    row("misspelt-layer-key", MESH, '[[target.layers]]\nmaterial = "concrete"\nthikness = 0.1\n',
        "target.layers[0].thikness", r"unknown key \(did you mean 'thickness'\?\)"),
    row("layer-without-thickness", MESH, '[[target.layers]]\nmaterial = "soil"\n[[target.layers]]\nmaterial = '
                                         '"concrete"\n', "target.layers[0].thickness", r"every layer but the last"),
    # --- impossible geometry, unreachable mass ---
    row("cavity-wider-than-the-body", MESH, "[projectile]\ncavity_diameter = 0.03\n", "projectile.cavity_diameter",
        r"leaves no wall: must be at most diameter - 2 x 0.00118 m = 0.02124 m"),
    row("cavity-longer-than-the-body", MESH, "[projectile]\ncavity_length = 0.2\n", "projectile.cavity_length",
        r"does not fit: must be in \(0, 0.11"),
    row("step-longer-than-the-body", sets("projectile.cavity_step_length=0.2"), None, "projectile.cavity_step_length",
        r"the cavity \(12 mm rear section behind 200 mm of forward sections\) does not fit"),
    row("body-shorter-than-its-nose", sets("projectile.length=0.03"), None, "projectile.length",
        r"too short for the ogive nose"),
    row("meplat-wider-than-the-body", sets("projectile.meplat_diameter=0.03"), None, "projectile.meplat_diameter",
        r"must be less than projectile.diameter = 0.0236 m"),
    row("boat-tail-wider-than-the-body", sets("projectile.boattail_length=0.03", "projectile.boattail_diameter=0.03"),
        None, "projectile.boattail_diameter", r"must be in \(0, 0.0236\) m"),
    row("cone-without-length", sets('projectile.nose="cone"'), None, "projectile.nose_length",
        r"a cone nose needs its axial length"),
    row("secant-longer-than-tangent", sets('projectile.nose="secant"', "projectile.nose_length=0.05"), None,
        "projectile.nose_length", r"must be at most the tangent ogive's 0.0391"),
    row("base-thicker-than-the-body", sets("projectile.base_thickness=0.2"), None, "projectile.base_thickness",
        r"must be less than the body behind the nose"),
    row("mass-too-heavy", sets("projectile.mass=5"), None, "projectile.mass",
        r"5 kg cannot be reached in this outside: must be in \[0.1377, 0.542\] kg"),
    row("mass-too-light", ["run", "--out", "out", "--set", "projectile.mass=0.01"], None, "projectile.mass",
        r"must be in \[0.1377, 0.542\] kg"),
    row("mass-out-of-the-given-cavity", sets("projectile.mass=0.2", "projectile.cavity_diameter=0.012"), None,
        "projectile.mass", r"unreachable with this shape and cavity diameters: must be in \[0.3371, 0.4257\] kg"),
    row("mass-and-cavity-length", sets("projectile.mass=0.3", "projectile.cavity_length=0.05"), None,
        "projectile.mass", r"give projectile.mass or projectile.cavity_length, not both"),
    row("mass-of-a-solid-body", sets("projectile.cavity_diameter=0", "projectile.mass=0.3"), None, "projectile.mass",
        r"a solid body .* drop projectile.mass"),
    row("profile-file-missing", sets('projectile.profile="nope.csv"'), None, "projectile.profile",
        r"cannot read the profile '/\S*/nope.csv'"),
    row("cad-file-missing", sets('projectile.cad="nope.step"'), None, "projectile.cad", r"no such file"),
    # --- checks across keys ---
    row("melt-below-room-temperature", RUN, "[projectile.material]\nmelt_temperature = 200\n",
        "projectile.material.melt_temperature", r"melting temperature 200 K must exceed room temperature 294 K"),
    row("charge-without-cavity", sets("effects.charge=true", "projectile.cavity_diameter=0"), None, "effects.charge",
        r"needs a cavity to fill"),
    row("charge-tangent-above-youngs", sets("charge.material.tangent_modulus=2e10"), None,
        "charge.material.tangent_modulus", r"must be below its Young's modulus 1.01e\+10 Pa"),
    row("axis-past-the-target-face", sets("impact.obliquity_deg=60", "impact.attack_deg=35"), None,
        "impact.attack_deg",
        r"obliquity 60 deg with attack 35 deg in the plane at 0 deg turns the projectile's axis 95 deg .* < 90 deg"),
    row("tensile-above-compressive", sets("target.tensile_strength=5e7"), None, "target.tensile_strength",
        r"tensile strength 5e\+07 Pa must be below compressive strength 3.1875e\+07 Pa \(of the 4e\+07 Pa cube\)"),
    row("soft-concrete-modulus", sets("target.youngs_modulus=1e6"), None, "target.youngs_modulus",
        r"leave no plastic zone around the cavity"),
    row("metal-yield-above-2E/3", sets('target.material="6061-T6511"', "target.yield_stress=5e10"), None,
        "target.yield_stress", r"must be below 2/3 of its Young's modulus"),
    row("metal-law-for-concrete", sets('target.strength_model="metal"'), None, "target.strength_model",
        r"'metal' is the law of a metal target.material"),
    row("rigid-step-after-the-end", sets("run.end_time=1e-4", "run.rigid_step=1e-3"), None, "run.rigid_step",
        r"0.001 s: must be at most run.end_time = 0.0001 s"),
    row("erosion-with-rigid", sets("effects.erosion=true", "effects.fidelity=rigid"), None, "effects.erosion",
        r"use it with effects.fidelity = 'elastic' or 'plastic'"),
    row("layers-and-thickness", MESH, '[target]\nthickness = 0.2\n[[target.layers]]\nmaterial = "concrete"\n',
        "target.thickness", r"give it per layer"),
    row("linear-crater-with-layers", MESH, '[effects]\ncrater = "linear"\n[[target.layers]]\nmaterial = "soil"\n',
        "effects.crater", r"'linear' is Forrestal's crater of one target"),
    row("lock-density-below-density", sets("target.lock_density=2000"), None, "target.lock_density",
        r"must exceed target.density = 2400 kg/m\^3"),
    row("sliding-friction-above-static", sets("target.friction_dynamic=0.5"), None, "target.friction_dynamic",
        r"must be at most target.friction = 0.1"),
    row("nose-mesh-coarser-than-mesh", sets("mesh.nose_size=0.01"), None, "mesh.nose_size",
        r"must be at most mesh.size = 0.0025 m"),
    row("rigid-on-a-rigid-wall", ["run", "--out", "out", "--set", "effects.fidelity=rigid", "--set",
                                  'target.kind="rigid-wall"'], None, "effects.fidelity", r"nothing to compute"),
    row("shot-and-velocity", sets('impact.shot="C3"', "impact.velocity=700"), None, "impact.velocity",
        r"conflicts with impact.shot = 'C3'"),
    # --- bad --set ---
    row("set-without-equals", sets("impact.velocity"), None, "--set", r"expected KEY=VALUE, got 'impact.velocity'"),
    row("set-without-key", sets("=600"), None, "--set", r"expected KEY=VALUE, got '=600'"),
    row("set-unknown-key", sets("impact.velocty=600"), None, "impact.velocty", r"did you mean 'impact.velocity'"),
    row("set-bad-toml-value", sets("projectile.crh=[1,"), None, "projectile.crh", r"got '\[1,', expected a number"),
    row("set-empty-value", sets("effects.fidelity="), None, "effects.fidelity", r"got '', expected one of"),
    row("set-units-in-value", sets("mesh.size=1mm"), None, "mesh.size", r"got '1mm', expected a number"),
    row("set-impact-in-validate", ["validate", "--out", "out", "--set", "impact.velocity=600"], None,
        "impact.velocity", r"validate sets impact.\* from Table 1"),
    # --- missing files ---
    row("run-missing-scene", ["run", "missing.toml", "--out", "out"], None, "SCENE",
        r"no such scene file: missing.toml"),
    row("mesh-missing-scene", ["mesh", "missing.toml"], None, "SCENE", r"no such scene file"),
    row("validate-depth-missing-data", ["validate-depth", "--data", "missing.csv", "--out", "out"], None, "--data",
        r"missing.csv: no such file or folder"),
    row("sweep-missing-file", ["sweep", "missing.toml", "--workers", "1", "--out", "out"], None, "SWEEP",
        r"cannot read missing.toml"),
    row("resume-missing-directory", ["run", "--resume", "missing"], None, "--resume",
        r"missing is not a results directory \(no scene.toml\)"),
    row("view-missing-directory", ["view", "missing"], None, "dir", r"missing holds no fields.xdmf"),
    # --- the command line itself ---
    row("no-command", [], None, "command line", r"name a command: run, mesh"),
    row("unknown-command", ["simulate", "SCENE"], "", "command line", r"invalid choice: 'simulate'"),
    row("unknown-option", ["run", "--speed", "600"], None, "command line", r"unrecognized arguments: --speed$"),
    row("two-scene-files", ["mesh", "SCENE", "SCENE"], "", "command line", r"unrecognized arguments"),
    row("resume-with-a-scene", ["run", "SCENE", "--resume", "missing"], "", "--resume", r"give no scene file"),
    row("workers-not-a-number", ["sweep", "s.toml", "--workers", "two"], None, "command line",
        r"argument --workers: invalid int value: 'two'"),
    row("workers-zero", ["sweep", "s.toml", "--workers", "0"], None, "--workers", r"must be at least 1, got 0"),
    row("ranks-per-shot-zero", ["sweep", "s.toml", "--ranks-per-shot", "0"], None, "--ranks-per-shot",
        r"must be at least 1"),
    row("speeds-not-numbers", ["study", "ballistic-limit", "--speeds", "fast,slow"], None, "--speeds",
        r"comma-separated positive numbers, got 'fast,slow'"),
    row("study-ranks-zero", ["study", "accuracy-cost", "--ranks", "0"], None, "--ranks", r"must be at least 1"),
    row("unknown-study", ["study", "penetration"], None, "command line", r"invalid choice: 'penetration'"),
    # each study has only its own options (issue 28), and one --ranks-per-shot rule with fepen sweep
    row("accuracy-cost-speeds", ["study", "accuracy-cost", "--speeds", "100,900"], None, "command line",
        r"unrecognized arguments: --speeds 100,900$"),
    row("ballistic-limit-obliquity", ["study", "ballistic-limit", "--obliquity-max=80"], None, "command line",
        r"unrecognized arguments: --obliquity-max=80$"),
    row("ricochet-quick", ["study", "ricochet", "--quick"], None, "command line", r"unrecognized arguments: --quick$"),
    row("limit-ranks-per-shot-zero", ["study", "ballistic-limit", "--ranks-per-shot", "0"], None, "--ranks-per-shot",
        r"must be at least 1, got 0"),
    row("limit-ranks-per-shot-not-dividing", ["study", "ricochet", "--ranks-per-shot", "2"], None,
        "--ranks-per-shot", r"must divide the number of ranks \(1\), got 2"),
]


@pytest.fixture
def nothing_runs(tmp_path, monkeypatch):
    """An empty working directory; meshing, running a shot, a study or a process fails the row (exit 1)."""
    import subprocess

    from fepen import runs
    from fepen.geometry import mesh as fmesh
    from fepen.studies import engine, study

    def ran(*args, **kwargs):
        raise RuntimeError("the bad input got as far as running or meshing")

    for owner, name in [(runs, "run_scene"), (study, "run"), (engine, "execute"), (setup, "mesh"), (fmesh, "create"),
                        (subprocess, "Popen")]:
        monkeypatch.setattr(owner, name, ran)
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.parametrize("argv, text, key, words", CASES)
def test_bad_input_is_one_line_and_exit_2(nothing_runs, capsys, bad_input_line, argv, text, key, words):
    scene = nothing_runs / "scene.toml"
    if text is not None:
        scene.write_bytes(text if isinstance(text, bytes) else text.encode())
    code = cli.main([str(scene) if a == "SCENE" else a for a in argv])
    captured = capsys.readouterr()
    bad_input_line(code, captured.err, key, words)
    assert captured.out == "" and sorted(p.name for p in nothing_runs.iterdir()) == (["scene.toml"] if text is not
                                                                                      None else [])


def test_the_table_is_large_and_names_its_rows_once():
    ids = [case.id for case in CASES]
    assert len(ids) >= 70 and len(set(ids)) == len(ids)
