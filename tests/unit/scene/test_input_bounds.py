"""Every input bounded and checked, the input side (issue 57, item 6). Each case failed on the main before this
issue (its docstring says how) and is now one line on stderr naming the key, exit 2, before any meshing, or it
works: files that are not regular files (a FIFO), a drawn profile or probes past what a shot can use, TOML nested
too deep, odd CSV tables of shots, a key given twice, a scene whose written scene.toml could not be read back,
charge keys without the charge. In this process, without running a shot."""

import csv
import math
import os
import re
import threading
import tomllib

import pytest

from fepen import cli
from fepen.errors import InputError
from fepen.geometry import profile
from fepen.runs import rigid, setup
from fepen.scene import SCENE_MAX, Scene, flatten, read_toml, to_toml
from fepen.scene.keys import DEPTH_MAX
from fepen.scene.schema import PROBE_NAME_MAX, PROBES_MAX
from fepen.studies import spec
from fepen.studies.sweep import read as read_sweep

RIGID = '[base]\neffects.fidelity = "rigid"\n'
#: the default body's calibre and length (m) and its ogive's radius (crh 3)
D, L, CRH = 0.0236, 0.144, 3.0


def fepen(capsys, *argv):
    """(exit code, stderr) of ``fepen ARGV`` in this process."""
    code = cli.main([str(a) for a in argv])
    return code, capsys.readouterr().err


def write(path, text):
    path.write_text(text)
    return path


def refused(call, key, words):
    """call() raises InputError naming ``key``, one line matching ``words``."""
    with pytest.raises(InputError) as err:
        call()
    assert err.value.key == key, str(err.value)
    assert re.search(words, err.value.message), err.value.message
    assert "\n" not in str(err.value)


# ------------------------------------------------------------------------------------------- 1: not regular files
def unblocked(fifo, call, seconds=10.0):
    """call()'s result, called in a thread: when it has not returned after ``seconds`` it is blocked opening the
    FIFO (waiting for a writer for ever): the FIFO is opened for writing and closed so that it returns, and the
    test fails."""
    out = {}
    thread = threading.Thread(target=lambda: out.setdefault("result", call()), daemon=True)
    thread.start()
    thread.join(seconds)
    blocked = thread.is_alive()
    if blocked:
        os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
        thread.join(seconds)
    assert not blocked, f"blocked opening the FIFO {fifo} for {seconds:g} s"
    return out.get("result")


@pytest.mark.parametrize("case", ["table", "scene", "sweep", "sweep-scene", "profile", "inner-profile", "cad"])
def test_a_fifo_is_refused_at_once_naming_its_key(tmp_path, capsys, bad_input_line, case):
    """Before: a sweep whose [table] file is a FIFO blocked in open() for ever; a FIFO named as a scene file, a
    sweep file, a sweep's scene or projectile.cad was "no such file"; a profile was refused by a stat before its
    open (a FIFO put in its place between the two blocked). Now each is opened without blocking and refused at
    once: "KEY: PATH is a pipe, not a regular file"."""
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    out = tmp_path / "out"
    rigid_run = ["--set", "effects.fidelity=rigid"]
    argv, key = {
        "table": (["sweep", write(tmp_path / "t.toml", RIGID + '[table]\nfile = "fifo"\n'), "--workers", "1"],
                  "table.file"),
        "scene": (["run", fifo], "SCENE"),
        "sweep": (["sweep", fifo, "--workers", "1"], "SWEEP"),
        "sweep-scene": (["sweep", write(tmp_path / "s.toml", 'scene = "fifo"\n' + RIGID +
                                        '[grid]\n"impact.velocity" = [500.0]\n'), "--workers", "1"], "scene"),
        "profile": (["run", *rigid_run, "--set", f"projectile.profile={str(fifo)!r}"], "projectile.profile"),
        "inner-profile": (["run", *rigid_run, "--set", f"projectile.inner_profile={str(fifo)!r}"],
                          "projectile.inner_profile"),
        "cad": (["run", "--set", f"projectile.cad={str(fifo)!r}"], "projectile.cad"),
    }[case]
    code = unblocked(fifo, lambda: cli.main([str(a) for a in [*argv, "--out", out]]))
    bad_input_line(code, capsys.readouterr().err, key, r"is a pipe, not a regular file")
    assert not out.exists()


def test_a_device_and_a_folder_are_refused_naming_the_key(tmp_path):
    """Before: a folder named as the scene file was "no such scene file". Now each says what it is."""
    refused(lambda: read_toml(tmp_path), "SCENE", r"is a folder, not a regular file: a scene file")
    refused(lambda: read_toml("/dev/zero"), "SCENE", r"is a device, not a regular file")
    refused(lambda: profile.read_points("/dev/zero", "projectile.profile"), "projectile.profile",
            r"is a device, not a regular file")
    refused(lambda: read_toml(tmp_path / "none.toml"), "SCENE", r"^no such scene file: ")


# --------------------------------------------------------------------------------------- 2: profiles and probes
def ogive_points(n):
    """n points of the default body drawn: its tangent ogive nose (n - 2 points on the arc), then its shank."""
    a, R = D / 2, CRH * D
    ln = math.sqrt(R * R - (R - a) ** 2)
    pts = [(ln * i / (n - 3), math.sqrt(R * R - (ln - ln * i / (n - 3)) ** 2) - (R - a)) for i in range(n - 2)]
    return [(z, max(r, 0.0)) for z, r in pts] + [((L + ln) / 2, a), (L, a)], ln


def write_profile(path, n):
    pts, _ = ogive_points(n)
    path.write_text("z_m, r_m\n" + "".join(f"{z!r}, {r!r}\n" for z, r in pts))
    return path


def test_a_profile_past_its_point_count_is_refused_and_one_at_it_is_the_body_it_draws(tmp_path):
    """Before: a drawn profile of any number of points under 16 MiB was read, and each segment became rings of
    load points: 200,000 points (8.5 MB) were 4,800,672 load points and 524 s of one rigid shot (3.9 GB), 20,000
    points 480,672 and 27 s, 2,000 points 48,672 and 2.6 s. Now at most PROFILE_POINTS_MAX: one more is refused
    in one line, and at the cap the body is the ogive it draws (its volume within the chords' error)."""
    cap = profile.PROFILE_POINTS_MAX
    big = write_profile(tmp_path / "big.csv", cap + 1)
    refused(lambda: setup.projectile(Scene(None, [f"projectile.profile={str(big)!r}"])), "projectile.profile",
            rf"more than {cap} points; a drawn profile holds at most {cap}")
    sc = Scene(None, [f"projectile.profile={str(write_profile(tmp_path / 'cap.csv', cap))!r}"])
    shape = setup.projectile(sc).shape
    assert len(profile.read_points(sc.projectile.profile, "projectile.profile")) == cap
    assert shape.diameter == pytest.approx(D) and shape.length == pytest.approx(L)
    exact = setup.projectile(Scene(None, ["projectile.cavity_diameter=0"])).shape  # the ogive's exact solid
    assert shape.outer_volume() == pytest.approx(exact.outer_volume(), rel=1e-5)
    assert len(rigid.ring_points(shape)["area0"]) < 50_000  # the rigid fidelity's load points at the cap


def test_probes_past_their_count_or_name_length_are_refused(tmp_path):
    """Before: any number of probes was taken (10,000 node probes of a rigid shot: 42 s, a 412 MB probes.csv, a
    0.8 MB scene.toml), with names of any length. Now at most PROBES_MAX probes, names of PROBE_NAME_MAX."""
    def probes(n, name=lambda i: f"p{i}"):
        return [{"name": name(i), "point": [0.0, 0.01, 0.0]} for i in range(n)]

    assert len(Scene({"output": {"probes": probes(PROBES_MAX)}}).output.probes) == PROBES_MAX
    refused(lambda: Scene({"output": {"probes": probes(PROBES_MAX + 1)}}), "output.probes",
            rf"{PROBES_MAX + 1} probes: a scene holds at most {PROBES_MAX}")
    assert Scene({"output": {"probes": probes(1, lambda i: "n" * PROBE_NAME_MAX)}}).output.probes[0]["name"]
    refused(lambda: Scene({"output": {"probes": probes(1, lambda i: "n" * (PROBE_NAME_MAX + 1))}}),
            "output.probes[0].name", rf"a name of at most {PROBE_NAME_MAX} letters")


# -------------------------------------------------------------------------------------------- 3: TOML too deep
DEEP = "[" * 3000 + "]" * 3000


def test_toml_too_deep_to_read_is_one_line_and_exit_2(tmp_path, capsys, bad_input_line):
    """Before: a 6 kB scene `a = [[[...]]]` 3,000 deep, the same as a --set value or in a sweep file, and 3,000
    dotted table names, were exit 1 (RecursionError in tomllib, or in flatten). Now exit 2 naming the file's key
    or the --set key."""
    words = rf"nests tables and arrays (too deep to read|more than {DEPTH_MAX} levels deep)"
    deep = write(tmp_path / "deep.toml", f"a = {DEEP}\n")
    bad_input_line(*fepen(capsys, "run", deep, "--out", tmp_path / "a"), "SCENE", words)
    bad_input_line(*fepen(capsys, "run", "--set", f"impact.velocity={DEEP}", "--out", tmp_path / "b"),
                   "impact.velocity", words)
    tables = write(tmp_path / "tables.toml", "[" + ".".join(["a"] * 3000) + "]\nx = 1\n")
    bad_input_line(*fepen(capsys, "run", tables, "--out", tmp_path / "c"), "SCENE", words)
    sweep = write(tmp_path / "s.toml", RIGID + f"x = {DEEP}\n" + '[grid]\n"impact.velocity" = [500.0]\n')
    bad_input_line(*fepen(capsys, "sweep", sweep, "--workers", "1", "--out", tmp_path / "d"), "SWEEP", words)
    refused(lambda: Scene(f"a = {DEEP}\n"), "SCENE", words)
    assert not any((tmp_path / d).exists() for d in "abcd")


def test_a_tree_deeper_than_any_scene_uses_is_refused_saying_the_bound(tmp_path):
    """Before: 17 levels of arrays were read and refused as any bad value, 1,000 levels of a Python dict given
    to fepen.Scene (or one that holds itself) were exit 1. Now DEPTH_MAX (16) levels is the bound, said in the
    line; 16 levels are read (and the value refused for what it is)."""
    def nested(n):
        return "[" * n + "1.0" + "]" * n

    refused(lambda: Scene(f"[impact]\nvelocity = {nested(DEPTH_MAX)}\n"), "SCENE",
            rf"the scene nests tables and arrays more than {DEPTH_MAX} levels deep")
    refused(lambda: Scene(f"[impact]\nvelocity = {nested(DEPTH_MAX - 1)}\n"), "impact.velocity",
            r"expected a number")
    refused(lambda: Scene(None, [f"impact.velocity={nested(DEPTH_MAX + 1)}"]), "impact.velocity",
            rf"more than {DEPTH_MAX} levels")
    tree = {}
    node = tree
    for _ in range(1000):
        node = node.setdefault("a", {})
    node["b"] = 1.0
    refused(lambda: Scene(tree), "SCENE", rf"more than {DEPTH_MAX} levels")
    loop = {"impact": {}}
    loop["impact"]["velocity"] = loop
    refused(lambda: Scene(loop), "SCENE", rf"more than {DEPTH_MAX} levels")
    refused(lambda: Scene(None, {"output.probes": [[[[[[[[[[[[[[[[[[]]]]]]]]]]]]]]]]]]}), "output.probes",
            rf"more than {DEPTH_MAX} levels")
    refused(lambda: read_sweep({"grid": {"impact.velocity": [[[[[[[[[[[[[[[[[1.0]]]]]]]]]]]]]]]]]}}), "SWEEP",
            rf"more than {DEPTH_MAX} levels")


# ------------------------------------------------------------------------------------------------ 4: CSV tables
def table(tmp_path, content, name="shots.csv"):
    """A sweep file of a [table] of ``content`` (str or bytes)."""
    path = tmp_path / name
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    return write(tmp_path / "s.toml", RIGID + f'[table]\nfile = "{name}"\n')


def test_a_cell_past_csvs_field_limit_and_a_column_given_twice_are_refused(tmp_path, capsys, bad_input_line):
    """Before: a cell larger than csv's field limit (131,072 characters) was exit 1 (csv.Error), and a column
    given twice (impact.velocity,impact.velocity) ran every shot with its last value. Now each is one line naming
    table.file and the column."""
    big = table(tmp_path, "impact.velocity\n" + "9" * (spec.CELL_MAX + 1) + "\n")
    bad_input_line(*fepen(capsys, "sweep", big, "--workers", "1", "--out", tmp_path / "a"), "table.file",
                   rf"line 2, column 1 \(impact.velocity\): a cell of {spec.CELL_MAX + 1} characters; .* at most "
                   rf"{spec.CELL_MAX}")
    twice = table(tmp_path, "impact.obliquity_deg,impact.velocity,impact.velocity\n0.0,500.0,900.0\n")
    bad_input_line(*fepen(capsys, "sweep", twice, "--workers", "1", "--out", tmp_path / "b"), "table.file",
                   r"line 1, column 3 \(impact.velocity\): given twice \(also column 2\)")
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()
    assert csv.field_size_limit() == 131072  # csv's own limit is as it was


@pytest.mark.parametrize("content, works", [
    ("\ufeffimpact.velocity\n500.0\n", True),  # a byte-order mark (Excel's UTF-8): before, "not a scene key"
    ("impact.velocity\r\n500.0\r\n", True),
    ('"impact.velocity"\n"500.0"\n', True),
    ("impact.velocity\n\n# a comment\n500.0\n\n", True),
    ("impact.velocity,\n500.0,1\n", False),  # an empty header cell: before, the key "table.file."
    (",\n,\n", False),
    ("impact.velocity\n500.0\n60\x000.0\n", False),
    ("impact.velo\x00city\n500.0\n", False),
    ("impact.velocity\n" + "[" * 3000 + "]" * 3000 + "\n", False),  # before: exit 1 (RecursionError)
    ('impact.velocity\n"500.0\n', True),  # a quote left open: csv reads to the end
    ("impact.velocity\n1e999\n", False),
    ("impact.velocity\n" + "9" * 5000 + "\n", False),
    (b"impact.velocity\n\xff\xfe\n", False),
    ("\ufeff", False),
    ("a\rb,c\n1,2\n", False),
])
def test_odd_but_well_formed_tables_work_or_are_refused_never_a_bug(tmp_path, content, works):
    """Odd but well-formed content of a table of shots is read or refused in one line (InputError), never
    another exception (exit 1)."""
    path = table(tmp_path, content)
    if works:
        s = read_sweep(path)
        assert s.keys == ["impact.velocity"] and s.scene(len(s.shots) - 1).impact.velocity == 500.0
    else:
        with pytest.raises(InputError) as err:
            read_sweep(path)
        assert "\n" not in str(err.value) and "\x00" not in str(err.value)


# --------------------------------------------------------------------------------------------- 5: a key twice
def test_a_key_given_twice_in_a_scene_file_is_one_line(tmp_path, capsys, bad_input_line):
    """Before: "impact.velocity" = 900.0 beside [impact] velocity = 500.0 in one scene file ran at 500 silently.
    Now one line naming the key, before anything is written."""
    twice = write(tmp_path / "twice.toml", '"impact.velocity" = 900.0\n[impact]\nvelocity = 500.0\n')
    bad_input_line(*fepen(capsys, "run", twice, "--set", "effects.fidelity=rigid", "--out", tmp_path / "a"),
                   "impact.velocity", r"given twice")
    assert not (tmp_path / "a").exists()


@pytest.mark.parametrize("source, key", [
    ('[impact]\n"velocity" = 1.0\n[projectile]\n"material.A" = 1e9\n[projectile.material]\nA = 2e9\n',
     "projectile.material.A"),
    ('"projectile.material" = { A = 1e9 }\n[projectile.material]\nA = 2e9\n', "projectile.material.A"),
    ('"target.layers" = [{ material = "soil" }]\n[[target.layers]]\nmaterial = "concrete"\n', "target.layers"),
    ({"impact.velocity": 900.0, "impact": {"velocity": 500.0}}, "impact.velocity"),
    ({"impact": {"velocity": 500.0, "obliquity_deg": 0.0}, "impact.obliquity_deg": 5.0}, "impact.obliquity_deg"),
])
def test_a_key_given_twice_is_refused_in_scene_text_and_dicts(source, key):
    """Before: the last of the two forms TOML text or a dict given to fepen.Scene held was taken silently. Now
    the key given twice, in any mix of quoted dotted and nested forms, is refused naming it."""
    refused(lambda: Scene(source), key, r"given twice")


@pytest.mark.parametrize("text, key", [
    ('[grid]\n"impact.velocity" = [900.0]\nimpact.velocity = [500.0, 600.0]\n', "grid.impact.velocity"),
    ('"impact.velocity" = 900.0\nimpact.velocity = 500.0\n[grid]\n"impact.obliquity_deg" = [0.0]\n',
     "impact.velocity"),
    ('[monte_carlo]\nsamples = 2\n[monte_carlo.vary]\n"impact.velocity" = { distribution = "normal", std = 1.0 }\n'
     'impact.velocity = { distribution = "normal", std = 2.0 }\n', "monte_carlo.vary.impact.velocity"),
])
def test_a_key_given_twice_is_refused_in_a_sweep(tmp_path, text, key):
    """Before: in a sweep's [grid], a quoted key's values beside the same key as a nested table vanished (the
    shots were the nested one's), and likewise in [base] and [monte_carlo.vary]. Now one line naming it."""
    refused(lambda: read_sweep(write(tmp_path / "s.toml", RIGID + text)), key, r"given twice")


def test_a_quoted_dotted_key_given_once_works_as_before(tmp_path):
    """A quoted dotted key given once reads as it did before (in a scene, in a sweep's [grid], in flatten): only
    the same key given twice is refused."""
    sc = Scene('"impact.velocity" = 900.0\n[effects]\nfidelity = "rigid"\n')
    assert sc.impact.velocity == 900.0 and "impact.velocity" in sc.explicit
    s = read_sweep(write(tmp_path / "s.toml", RIGID + '[grid]\n"impact.velocity" = [500.0, 600.0]\n'
                                                     'impact.obliquity_deg = [0.0]\n'))
    assert [sh["impact.velocity"] for sh in s.shots] == [500.0, 600.0] and s.keys[1] == "impact.obliquity_deg"
    assert flatten({"impact.velocity": 1.0, "impact": {"obliquity_deg": 2.0}}) == {
        "impact.velocity": 1.0, "impact.obliquity_deg": 2.0}


# -------------------------------------------------------------------------------------- 6: the written scene
def layers(n):
    return '[effects]\nfidelity = "rigid"\n' + '[[target.layers]]\nmaterial = "concrete"\nthickness = 0.001\n' * n


def test_a_scene_whose_written_scene_could_not_be_read_back_is_refused_before_the_run(tmp_path, capsys,
                                                                                         bad_input_line):
    """Before: a scene of 3,500 thin [[target.layers]] (a 0.2 MB file) ran to the end, then exited 2: the
    scene.toml it wrote (1.19 MB) was past the 1 MiB a scene file may be, and the folder could never be read
    back or resumed. Now it is refused before anything is written, naming target.layers."""
    path = write(tmp_path / "layers.toml", layers(3500))
    bad_input_line(*fepen(capsys, "run", path, "--out", tmp_path / "out"), "target.layers",
                   r"3500 layers would make the scene.toml fepen writes into the results 11\d\d KiB, past the 1024 "
                   r"KiB a scene file may be: it could not be read back .* at most about 3\d\d\d")
    assert not (tmp_path / "out").exists()
    refused(lambda: Scene({"projectile": {"cavity_sections": [[1e-4, 0.0123456789]] * 50_000}}),
            "projectile.cavity_sections", r"50000 sections would make the scene.toml")


def test_the_scene_fepen_writes_reads_back_as_the_same_scene_up_to_the_cap(tmp_path):
    """The largest layered scene that resolves (3,000 layers: 0.97 MiB written) reads back from its scene.toml
    as the same scene, with the same given keys."""
    sc = Scene(layers(3000))
    text = to_toml(sc)
    assert SCENE_MAX - 64 * 1024 < len(text.encode()) <= SCENE_MAX
    back = Scene(write(tmp_path / "scene.toml", text))
    assert flatten(back.as_dict()) == flatten(sc.as_dict()) and back.explicit == sc.explicit


# ------------------------------------------------------------------------------------------ 7: charge keys
def test_charge_keys_without_the_charge_are_one_line(tmp_path, capsys, bad_input_line):
    """Before: a [charge] table without effects.charge = true was ignored silently (the run had no charge). Now
    one line naming the key, before anything is written."""
    path = write(tmp_path / "c.toml", '[effects]\nfidelity = "rigid"\n[charge]\nfriction = 0.3\n')
    bad_input_line(*fepen(capsys, "run", path, "--out", tmp_path / "out"), "charge.friction",
                   r"a key of the charge, which is off: set effects.charge = true, or drop the key")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("item", ["charge.material.density=1000", 'charge.explosive="paper-fill"',
                                  "charge.safety.gap=0.001", 'charge.contact="tied"', "charge.friction=0.2"])
def test_each_charge_key_needs_the_charge(item):
    """Before: each was taken and changed nothing without effects.charge. Now refused naming it; with the charge
    it is taken as before."""
    key, value = item.split("=")
    refused(lambda: Scene(None, [item]), key, r"which is off")
    sc = Scene(None, ["effects.charge=true", item])
    assert sc.effects.charge is True and sc.get(key) == tomllib.loads(f"v = {value}")["v"]


def test_charge_keys_beside_a_charge_given_off_are_kept_for_a_sweep_that_varies_it(tmp_path):
    """A sweep over effects.charge = [true, false] with the charge's keys in its base (which says the charge is off
    unless varied): the uncharged shots say so, so the keys are meant for the charged ones, not forgotten."""
    from fepen.studies import spec

    sw = spec.read({"base": {"effects": {"fidelity": "rigid", "charge": False}, "charge": {"friction": 0.2}},
                    "grid": {"effects.charge": [True, False]}})
    assert [sw.scene(i).effects.charge for i in range(2)] == [True, False]
    assert Scene(None, ["effects.charge=false", "charge.friction=0.2"]).effects.charge is False
