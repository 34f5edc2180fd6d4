"""A user's files are sacred, and fepen never answers from inputs other than the ones it reports (issue 43).

Each case failed on the main before this issue (the docstring says how) and passes now: --force by manifest,
never by pattern; planted links; a scene or input profile inside --out; an edited or moved resume; a forged or
shared mesh cache; a disk full at the reserve and at the last figure; the slowest and coarsest allowed
inputs; huge values, files and sweeps. Rigid runs in this process where they can (a second each), whole
processes where a fault is injected, short coarse deformable runs where the case needs fields."""

import json
import os
import subprocess
import time

import pytest
from conftest import run_fepen

from fepen import cli
from fepen.io import rundir
from fepen.studies import processes

RIGID = ["--set", "effects.fidelity=rigid"]
#: a short deformable shot on a coarse mesh: fields, figures, checkpoints (a few seconds)
COARSE = ["--set", "mesh.size=0.006", "--set", "run.end_time=1e-4", "--set", "run.output_interval=2e-5",
          "--set", "run.checkpoint_interval=4e-5"]
#: a file of every extension a run writes, and of the names the old --force removed by pattern
FOREIGN = ["photo.png", "lab.csv", "notes.json", "cut.vtu", "field.xdmf", "data.h5", "profile_1.csv",
           "strains_old.csv", "hazard_mine.csv", "charge_test.json", "~$report.docx.tmp1", "run.log", "notes.toml",
           "gauges_lab.csv", "sections_a.csv", "nose_profile_lab.csv", "view_mine.py", "fields_old.xdmf",
           "mesh.msh", "state.npz"]


def fepen(capsys, *argv):
    """(exit code, stdout, the stderr lines) of ``fepen ARGV`` in this process."""
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, [ln for ln in err.splitlines() if ln.strip()]


def plant(d, names=FOREIGN):
    d.mkdir(parents=True, exist_ok=True)
    for n in names:
        (d / n).write_text(f"the user's {n}")
    (d / "checkpoints_mine").mkdir()
    (d / "checkpoints_mine" / "a.txt").write_text("the user's")


def foreign_intact(d, names=FOREIGN):
    return all((d / n).read_text() == f"the user's {n}" for n in names) and (
        (d / "checkpoints_mine" / "a.txt").read_text() == "the user's")


def record(d):
    return json.loads((d / "run.json").read_text())


# ---------------------------------------------------------------------------------------------- item 1
def test_force_keeps_twenty_foreign_files_of_every_extension(tmp_path, capsys):
    """Before: --force removed 8 of 9 such files by glob (*.png, *.tmp*, profile*.csv, ...) even where no run
    had been. Now: a first run and a --force run beside 20 of them keep all 20."""
    out = tmp_path / "mixed"
    plant(out)
    assert fepen(capsys, "run", *RIGID, "--out", out, "--force")[0] == 0  # --force with no run there: nothing removed
    assert foreign_intact(out)
    code, stdout, err = fepen(capsys, "run", *RIGID, "--set", "impact.velocity=700", "--out", out, "--force")
    assert code == 0, err
    assert foreign_intact(out)
    files = record(out)["files"]
    assert not set(files) & set(FOREIGN) and "checkpoints_mine" not in files
    written = [ln for ln in stdout.splitlines() if ln.startswith("written: ")][0]  # exactly what the run wrote
    assert written == f"written: {out}/ " + ", ".join(sorted(n for n in files if n != rundir.RESERVE))


def test_rerun_into_a_finished_deformable_run_leaves_no_file_of_the_old_run(tmp_path):
    """A deformable run on 2 ranks (fields, checkpoints, pictures, CSVs), then a rigid --force run into its
    directory: of the old run only what the new one wrote again is left, and the user's files all stay."""
    out = tmp_path / "rerun"
    plant(out)
    r = run_fepen("run", *COARSE, "--out", out, ranks=2)  # rank 1 writes its checkpoint files into rank 0's folder
    assert r.returncode == 0, r.stderr[-2000:]
    old = set(record(out)["files"])
    assert {"fields.xdmf", "fields.h5", "hazard.png", "strains.csv", "view.py"} <= old
    r = run_fepen("run", *RIGID, "--out", out, "--force")
    assert r.returncode == 0, r.stderr[-2000:]
    new = set(record(out)["files"])
    left = {p.name for p in out.iterdir()} - set(FOREIGN) - {"checkpoints_mine"}
    assert left == new and not (old - new) & left
    assert foreign_intact(out)


def test_a_scene_inside_out_is_never_overwritten(tmp_path, capsys):
    """Before: ``fepen run DIR/scene.toml --out DIR`` replaced the user's commented scene with the resolved one.
    Now: refused in one line naming the file, before anything is written."""
    out = tmp_path / "own"
    out.mkdir()
    scene = out / "scene.toml"
    text = "# my commented scene\n[effects]\nfidelity = \"rigid\"\n"
    scene.write_text(text)
    for extra in ([], ["--force"]):
        code, _, err = fepen(capsys, "run", scene, "--out", out, *extra)
        assert code == 2 and len(err) == 1 and "scene.toml" in err[0] and "did not write" in err[0]
        assert scene.read_text() == text and sorted(p.name for p in out.iterdir()) == ["scene.toml"]


def test_an_input_profile_inside_out_survives_force(tmp_path, capsys):
    """Before: --force deleted DIR/profile.csv (pattern profile*.csv) before the run read it. Now it is read and
    kept, and the run's scene names it by its absolute path."""
    out = tmp_path / "drawn"
    out.mkdir()
    prof = out / "profile.csv"
    prof.write_text("0.0,0.0\n0.03,0.0118\n0.144,0.0118\n")
    sets = [*RIGID, "--set", f'projectile.profile="{prof}"']
    for extra in ([], ["--force"]):
        code, _, err = fepen(capsys, "run", *sets, "--out", out, *extra)
        assert code == 0, err
    assert prof.read_text().startswith("0.0,0.0")
    assert str(prof) in (out / "scene.toml").read_text()


# ---------------------------------------------------------------------------------------------- item 2
@pytest.mark.parametrize("name", [rundir.RESERVE, "fepen.log", "summary.json", "history.csv", "checkpoint",
                                  rundir.LOCK, "run.json"])
def test_a_planted_link_redirects_no_write(tmp_path, capsys, name):
    """Before: a planted .fepen.reserve link had a file elsewhere overwritten with zeros, a fepen.log link got
    the run's log appended. Now every name a run writes is refused when it is a link, the target untouched."""
    out = tmp_path / "linked"
    out.mkdir()
    victim = tmp_path / "victim"
    victim.write_text("precious")
    os.symlink(victim, out / name)
    code, _, err = fepen(capsys, "run", *RIGID, "--out", out)
    assert code == 2 and len(err) == 1 and name in err[0], err
    assert victim.read_text() == "precious" and sorted(p.name for p in out.iterdir()) == [name]


def test_a_forged_manifest_cannot_make_force_delete_outside(tmp_path, capsys):
    """A run.json whose manifest names a path (not one name in the directory) is no manifest fepen wrote:
    --force refuses, and the file it names survives."""
    out = tmp_path / "forged"
    assert fepen(capsys, "run", *RIGID, "--out", out)[0] == 0
    victim = tmp_path / "victim"
    victim.write_text("precious")
    rec = record(out)
    (out / "run.json").write_text(json.dumps({**rec, "files": [*rec["files"], "../victim"]}))
    code, _, err = fepen(capsys, "run", *RIGID, "--out", out, "--force")
    assert code == 2 and "manifest" in err[0] and victim.read_text() == "precious"


# ---------------------------------------------------------------------------------------------- item 3
def stopped_rigid(out, env_fault="summary:1", sets=(), cwd=None):
    """A rigid run stopped by a full disk (injected): exit 4, resumable by running it again."""
    env = processes.mpi_env(FEPEN_INJECT_FAULT=env_fault)
    r = subprocess.run(processes.command(["run", *RIGID, *sets, "--out", out], 1), env=env, capture_output=True,
                       text=True, cwd=cwd or processes.ROOT, timeout=600)
    assert r.returncode == 4, r.stderr[-2000:]
    return r


def test_resume_after_the_scene_was_edited_is_refused_naming_the_key(tmp_path, capsys):
    """Before: a resume ran the rest with the edited values and labelled the whole result with them (a 40 MPa
    shot finished as "100 MPa"). Now refused in one line naming the key and both values; summary.json and
    run.json still say the run stopped and can be resumed."""
    out = tmp_path / "edited"
    stopped_rigid(out)
    before = {n: (out / n).read_text() for n in ("summary.json", "run.json")}
    scene = out / "scene.toml"
    scene.write_text(scene.read_text() + "\n[target]\ncompressive_strength = 100e6\n")
    code, _, err = fepen(capsys, "run", "--resume", out)
    assert code == 2 and len(err) == 1 and "target.compressive_strength" in err[0] and "1e+08" in err[0], err
    assert {n: (out / n).read_text() for n in before} == before
    assert json.loads(before["summary.json"])["outcome"] == "fault"


def test_resume_from_another_directory_reads_the_same_profile_and_refuses_a_changed_one(tmp_path, capsys,
                                                                                         monkeypatch):
    """Before: a relative profile path in a run's scene.toml made --resume read whatever file of that name the
    working directory held. Now the scene holds the absolute path, the resume works from anywhere, and a
    profile changed since the run began is refused by its digest."""
    work, elsewhere = tmp_path / "work", tmp_path / "elsewhere"
    work.mkdir()
    elsewhere.mkdir()
    (work / "shape.csv").write_text("0.0,0.0\n0.03,0.0118\n0.144,0.0118\n")
    (elsewhere / "shape.csv").write_text("0.0,0.0\n0.05,0.0150\n0.200,0.0150\n")  # another body of the same name
    out = tmp_path / "prof"
    sets = ["--set", 'projectile.profile="shape.csv"']
    stopped_rigid(out, sets=sets, cwd=work)
    monkeypatch.chdir(elsewhere)
    code, _, err = fepen(capsys, "run", "--resume", out)
    assert code == 0, err
    assert json.loads((out / "summary.json").read_text())["scene"]["projectile"]["profile"] == str(work / "shape.csv")
    stopped_rigid(tmp_path / "prof2", sets=sets, cwd=work)
    (work / "shape.csv").write_text("0.0,0.0\n0.03,0.0110\n0.144,0.0110\n")
    code, _, err = fepen(capsys, "run", "--resume", tmp_path / "prof2")
    assert code == 2 and "shape.csv changed since the run began" in err[0]


# ---------------------------------------------------------------------------------------------- item 4
def test_a_disk_too_small_for_the_reserve_leaves_a_true_record_and_a_retry_runs(tmp_path, capsys):
    """Before: run.json stayed "running" beside a partial reserve, and a retry was refused as "another run's
    results". Now exit 4 in one line, run.json says fault, no reserve and no lock are left, and the retry runs."""
    out = tmp_path / "small"
    env = processes.mpi_env(FEPEN_INJECT_FAULT="reserve:1")
    r = subprocess.run(processes.command(["run", *RIGID, "--out", out], 1), env=env, capture_output=True, text=True,
                       cwd=processes.ROOT, timeout=600)
    assert r.returncode == 4 and "no space left" in r.stderr and "Traceback" not in r.stderr, r.stderr[-2000:]
    rec = record(out)
    assert rec["outcome"] == "fault" and rec["exit_code"] == 4 and "no space left" in rec["message"]
    assert sorted(p.name for p in out.iterdir()) == ["run.json"]
    code, _, err = fepen(capsys, "run", *RIGID, "--out", out)
    assert code == 0, err


def test_a_disk_full_at_the_last_figure_is_exit_4_and_every_record_says_so(tmp_path):
    """Before: history.png failing at the end (``except OSError: pass``) exited 0 and printed "written: ...
    history.png" with no history.png. Now exit 4, summary.json and run.json say fault, and the resume (a rigid
    run runs again) completes."""
    out = tmp_path / "figure"
    r = stopped_rigid(out, "figure:1")
    assert "written:" not in r.stdout and "no space left" in r.stderr
    assert json.loads((out / "summary.json").read_text())["outcome"] == "fault"
    assert record(out)["exit_code"] == 4
    r = run_fepen("run", "--resume", out)
    assert r.returncode == 0 and json.loads((out / "summary.json").read_text())["outcome"] == "embedded"
    assert (out / "history.png").stat().st_size > 1000


# ---------------------------------------------------------------------------------------------- item 5
@pytest.mark.parametrize("speed", [1.0, 0.1])
def test_the_slowest_allowed_rigid_shots_end_in_seconds(tmp_path, capsys, speed):
    """Before: 1 m/s took 88 s (185,000 RK4 steps) and 0.1 m/s hours. Now a few thousand steps."""
    t0 = time.perf_counter()
    code, _, err = fepen(capsys, "run", *RIGID, "--set", f"impact.velocity={speed}", "--out", tmp_path / "slow")
    assert code == 0, err
    s = json.loads((tmp_path / "slow" / "summary.json").read_text())
    assert s["outcome"] == "embedded" and s["steps"] < 10_000 and time.perf_counter() - t0 < 30
    assert 0.0 < s["depth_mm"] < 5.0 and abs(s["energy_error"]) < 1e-3


@pytest.mark.parametrize("size, words", [
    (0.05, "coarser than half the calibre"), (0.03, "coarser than half the calibre"),
    (0.02, "coarser than half the calibre"), (2e-4, "mesh.max_cells")])
def test_mesh_sizes_the_body_cannot_take_are_refused_before_meshing(tmp_path, capsys, size, words):
    """Before: 0.05 and 0.03 m ended in an internal gmsh error (exit 1), 0.02 m blamed a key never set, 2e-4 m
    grew to 7.8 GB in gmsh. Now one line naming mesh.size, within a second, nothing written."""
    t0 = time.perf_counter()
    code, _, err = fepen(capsys, "run", "--set", f"mesh.size={size}", "--out", tmp_path / "m")
    assert code == 2 and len(err) == 1 and err[0].startswith("fepen: bad input: mesh.size:") and words in err[0]
    assert time.perf_counter() - t0 < 5 and not (tmp_path / "m").exists()


def test_huge_values_files_and_sweeps_are_refused_in_a_short_line(tmp_path, capsys):
    """Before: a 5 MB value was echoed in a 5 MB line, a huge scene file read whole, a grid of two 1e5 axes or
    1e7 Monte Carlo samples built in memory (4 GB in seconds). Now short lines, at once."""
    t0 = time.perf_counter()
    code, _, err = fepen(capsys, "run", "--set", "impact.velocity " + "9" * 5_000_000, "--out", tmp_path / "a")
    assert code == 2 and len(err) == 1 and len(err[0]) <= cli.LINE_MAX
    big = tmp_path / "big.toml"
    big.write_text("# " + "x" * (2 << 20) + "\n")
    code, _, err = fepen(capsys, "run", big, "--out", tmp_path / "b")
    assert code == 2 and "larger than 1024 KiB" in err[0]
    grid = tmp_path / "grid.toml"
    grid.write_text('[grid]\n"impact.velocity" = {start = 100.0, stop = 900.0, num = 100000}\n'
                    '"impact.obliquity_deg" = {start = 0.0, stop = 30.0, num = 100000}\n')
    code, _, err = fepen(capsys, "sweep", grid, "--out", tmp_path / "g")
    assert code == 2 and err[0].startswith("fepen: bad input: grid:") and "10000000000 shots" in err[0]
    mc = tmp_path / "mc.toml"
    mc.write_text('[monte_carlo]\nsamples = 10000000\n[monte_carlo.vary]\n'
                  '"impact.velocity" = {distribution = "normal", std = 20.0}\n')
    code, _, err = fepen(capsys, "sweep", mc, "--out", tmp_path / "mc")
    assert code == 2 and "monte_carlo.samples" in err[0]
    code, _, err = fepen(capsys, "run", *RIGID, "--set", 'projectile.profile="/dev/zero"', "--out", tmp_path / "z")
    assert code == 2 and "not a regular file" in err[0]  # once read (and hashed) for ever
    assert time.perf_counter() - t0 < 20


def test_the_mesh_estimate_bounds_a_measured_run(tmp_path):
    """The figures the refusals rest on (fepen.runs.budget): a 3 mm deformable run's cells and its peak memory
    before the first step are within the estimate (1 rank)."""
    from mpi4py import MPI

    from fepen import scene
    from fepen.runs import budget, setup

    out = tmp_path / "cost"
    r = run_fepen("run", "--set", "mesh.size=0.003", "--set", "run.end_time=2e-7", "--set", "run.fields=false",
                  "--out", out)
    assert r.returncode == 0, r.stderr[-2000:]
    s = json.loads((out / "summary.json").read_text())
    sc = scene.load(None, ["mesh.size=0.003"])
    cost = setup.check_mesh_cost(sc, MPI.COMM_SELF)
    assert s["cells"] <= cost["cells"] < 1.25 * s["cells"]
    assert s["peak_memory_bytes"] <= cost["bytes"] and budget.PROCESS_BYTES < 2 * s["peak_memory_bytes"]


# ---------------------------------------------------------------------------------------------- mesh command
def test_fepen_mesh_replaces_its_own_files_and_refuses_a_runs(tmp_path, capsys):
    """fepen mesh twice into one directory replaces its own files (make run does it); into a run's directory it
    refuses without --force, and with it removes exactly that run's files; the user's files stay."""
    out = tmp_path / "mesh"
    plant(out, ["photo.png", "notes.json"])
    sets = ["--set", "mesh.size=0.008", "--set", "mesh.optimize=none"]
    for _ in range(2):
        code, _, err = fepen(capsys, "mesh", *sets, "--out", out)
        assert code == 0, err
    run = tmp_path / "run"
    assert fepen(capsys, "run", *RIGID, "--out", run)[0] == 0
    plant(run, ["photo.png"])
    code, _, err = fepen(capsys, "mesh", *sets, "--out", run)
    assert code == 2 and "--force" in err[0]
    code, _, err = fepen(capsys, "mesh", *sets, "--out", run, "--force")
    assert code == 0, err
    assert not (run / "summary.json").exists() and (run / "mesh.json").exists()
    assert foreign_intact(run, ["photo.png"]) and foreign_intact(out, ["photo.png", "notes.json"])


# ---------------------------------------------------------------------------------------------- studies
def test_a_study_folder_is_owned_by_manifest_too(tmp_path, capsys):
    """A sweep's folder keeps a manifest as a run's does: --fresh removes exactly what the sweep wrote (its
    shots' folders by their own manifests, a user's file inside one of them kept), a foreign file under a name
    the sweep writes is refused before any shot runs, and a run's folder is not taken for a sweep's."""
    spec = tmp_path / "s.toml"
    spec.write_text('[base]\n"effects.fidelity" = "rigid"\n[grid]\n"impact.velocity" = [500.0, 600.0]\n'
                    "[output]\nkeep_results = true\n")
    out = tmp_path / "sweep"
    plant(out)
    argv = ["sweep", spec, "--workers", "1", "--out", out]
    assert fepen(capsys, *argv)[0] == 0
    (out / "shots" / "00000" / "mine.txt").write_text("the user's")
    assert "shots" in record(out)["files"] and (out / "shots" / "00001" / "summary.json").is_file()
    code, _, err = fepen(capsys, *argv, "--fresh")
    assert code == 0, err
    assert foreign_intact(out) and (out / "shots" / "00000" / "mine.txt").read_text() == "the user's"
    other = tmp_path / "other"
    plant(other, ["sweep.csv"])
    code, _, err = fepen(capsys, *argv[:-1], other)
    assert code == 2 and "sweep.csv" in err[0] and not (other / "shots.jsonl").exists()
    run = tmp_path / "run"
    assert fepen(capsys, "run", *RIGID, "--out", run)[0] == 0
    code, _, err = fepen(capsys, *argv[:-1], run)
    assert code == 2 and "results of a run" in err[0]
