"""A study's folder as safe as a run's (issue 57, items 1-5): each case as a user or a batch scheduler met it on
0.5.0 (the docstring says what happened then) and what happens now. Rigid shots in this process where they
can (a fraction of a second each); whole processes where a kill or a signal is the case."""

import json
import signal
import subprocess
import time
from pathlib import Path

import pytest
from conftest import run_fepen

from fepen import cli
from fepen.io import rundir
from fepen.studies import processes

#: three rigid shots that keep their folders (the figures off: a second in all)
KEPT = """[base]
effects.fidelity = "rigid"
run.figures = false
[grid]
"impact.velocity" = [{speeds}]
[output]
keep_results = true
"""


def fepen(capsys, *argv):
    """(exit code, stdout, the stderr lines) of ``fepen ARGV`` in this process."""
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, [ln for ln in err.splitlines() if ln.strip()]


def kept_sweep(tmp_path, speeds=(500.0, 600.0, 700.0)) -> Path:
    f = tmp_path / "kept.toml"
    f.write_text(KEPT.format(speeds=", ".join(map(str, speeds))))
    return f


def tree(d: Path) -> set[str]:
    """Every path below ``d``, relative (folders end in /)."""
    return {p.relative_to(d).as_posix() + ("/" if p.is_dir() else "") for p in d.rglob("*")}


def plant_users(out: Path) -> dict:
    """The user's files in a sweep's folder: beside the shots, in a folder of their own there, in a shot's folder,
    and at the top."""
    files = {"shots/README.md": "my notes on the shots", "shots/mine/a.txt": "mine", "shots/00000/user.txt": "u",
             "notes.txt": "top"}
    for rel, text in files.items():
        (out / rel).parent.mkdir(parents=True, exist_ok=True)
        (out / rel).write_text(text)
    return files


def users_intact(out: Path, files: dict) -> bool:
    return all((out / rel).is_file() and (out / rel).read_text() == text for rel, text in files.items())


# ---------------------------------------------------------------------------------------------- item 1
def test_sweep_fresh_keeps_the_users_files_in_and_beside_its_shots(tmp_path, capsys):
    """Before: --fresh deleted shots/README.md and shots/mine/a.txt, the user's file in shots/00000 kept that
    folder so shots/ left the manifest, every shot was then refused as "shots is a file fepen did not write"
    and the sweep exited 0 with no numbers. Now every user file stays and the three shots run again."""
    spec, out = kept_sweep(tmp_path), tmp_path / "s"
    code, _, err = fepen(capsys, "sweep", spec, "--out", out, "--workers", "1")
    assert code == 0, err
    first = (out / "sweep.csv").read_text()
    users = plant_users(out)
    code, stdout, err = fepen(capsys, "sweep", spec, "--out", out, "--workers", "1", "--fresh")
    assert code == 0, err
    assert "ok 3" in stdout and "bad-input" not in stdout
    assert users_intact(out, users)
    assert (out / "sweep.csv").read_text() == first
    record = json.loads((out / "run.json").read_text())
    assert "shots" in record["files"] and "notes.txt" not in record["files"]
    assert {f"shots/{i:05d}/summary.json" for i in range(3)} <= tree(out)
    code, _, err = fepen(capsys, "sweep", spec, "--out", out, "--workers", "1", "--fresh")  # and again
    assert code == 0 and users_intact(out, users), err


def test_ballistic_limit_fresh_keeps_the_users_files_in_its_rounds(tmp_path, capsys):
    """Before: ``fepen study ballistic-limit --fresh`` deleted the user's files inside rounds/ (its round
    folders keep no record of their own, and a folder without one was removed whole)."""
    out = tmp_path / "bl"
    args = ["study", "ballistic-limit", "--set", "effects.fidelity=rigid", "--set", "target.thickness=0.1",
            "--speeds", "100,1500", "--tol", "20", "--out", out]
    code, _, err = fepen(capsys, *args)
    assert code == 0, err
    first = json.loads((out / "ballistic_limit.json").read_text())["v_bl_m_s"]
    rounds = sorted(p.name for p in (out / "rounds").iterdir())
    users = {"rounds/notes.md": "which rounds", f"rounds/{rounds[0]}/mine.csv": "1,2", "rounds/plots/a.png": "png"}
    for rel, text in users.items():
        (out / rel).parent.mkdir(parents=True, exist_ok=True)
        (out / rel).write_text(text)
    code, _, err = fepen(capsys, *args, "--fresh")
    assert code == 0, err
    assert users_intact(out, users)
    assert json.loads((out / "ballistic_limit.json").read_text())["v_bl_m_s"] == first


def test_charge_safety_fresh_keeps_the_users_files_and_fails_when_no_shot_runs(tmp_path):
    """Before: after the user added shots/summary_notes.txt and a file in shots/00000, ``fepen study charge-safety
    --fresh`` deleted the first, dropped shots/ from the manifest, refused its one shot as "shots is a file fepen
    did not write" and exited 0 printing "governing: none". Now both files stay and the point gets its verdict."""
    out = tmp_path / "cs"
    args = ["study", "charge-safety", "--speeds", "800", "--obliquities", "0", "--set", "mesh.size=0.006",
            "--set", "run.end_time=4e-5", "--set", "run.fields=false", "--set", "run.figures=false",
            "--set", "run.checkpoint_interval=0", "--out", out]
    r = run_fepen(*args)
    assert r.returncode == 0, r.stderr
    users = {"shots/summary_notes.txt": "what I saw", "shots/00000/gauge_photo.txt": "photo"}
    for rel, text in users.items():
        (out / rel).write_text(text)
    r = run_fepen(*args, "--fresh")
    assert r.returncode == 0, r.stderr
    assert users_intact(out, users)
    assert "governing: none" not in r.stdout
    rows = (out / "charge_safety.csv").read_text().splitlines()
    head = rows[0].split(",")
    assert "status" in head and "outcome" in head
    assert rows[1].split(",")[head.index("status")] == "ok"


def test_force_refuses_a_record_listing_names_no_run_writes(tmp_path, capsys):
    """Before: a run.json whose files listed notes.txt and a folder thesis/ made --force delete both, the folder
    with all it held. Now --force is refused in one line naming them, and both stay."""
    out = tmp_path / "r"
    assert fepen(capsys, "run", "--set", "effects.fidelity=rigid", "--out", out)[0] == 0
    (out / "notes.txt").write_text("mine")
    (out / "thesis").mkdir()
    (out / "thesis" / "ch1.tex").write_text("chapter")
    rec = json.loads((out / "run.json").read_text())
    (out / "run.json").write_text(json.dumps({**rec, "files": [*rec["files"], "notes.txt", "thesis"]}))
    code, _, err = fepen(capsys, "run", "--set", "effects.fidelity=rigid", "--out", out, "--force")
    assert code == 2 and len(err) == 1, err
    assert "notes.txt, thesis" in err[0] and "never writes" in err[0]
    assert (out / "notes.txt").read_text() == "mine" and (out / "thesis" / "ch1.tex").read_text() == "chapter"
    assert (out / "summary.json").is_file()  # the run's own results untouched too


# ---------------------------------------------------------------------------------------------- item 2
def test_temporaries_a_kill_left_are_swept_by_a_rerun_a_resume_and_fresh(tmp_path, capsys):
    """Before: a kill while a file was being written left run.json.tmpPID-..., sweep.parquet.tmpPID-...,
    shots/00000/summary.json.tmpPID-... for ever (neither a re-run nor --fresh removed them), and one inside a
    kept shot folder made a later ``sweep --fresh`` exit 0 with 0 of 3 shots run. Now each is fepen's by its name
    and swept; a user's file that merely looks alike stays."""
    spec, out = kept_sweep(tmp_path), tmp_path / "s"
    assert fepen(capsys, "sweep", spec, "--out", out, "--workers", "1")[0] == 0
    left = ["run.json.tmp4242-abcd1234", "sweep.parquet.tmp4242-x_y7zq12.parquet",
            "shots/00000/summary.json.tmp4242-0a1b2c3d", "shots/00001/history.csv.tmp99-qqqqqqqq"]
    alike = ["notes.txt.tmp1-abcdefgh", "shots/mine.tmp1-abcdefgh"]  # not temporaries of anything fepen writes
    for rel in left + alike:
        (out / rel).write_text("cut short")
    code, stdout, err = fepen(capsys, "sweep", spec, "--out", out, "--workers", "1", "--fresh")
    assert code == 0 and "ok 3" in stdout, err
    assert not any((out / rel).exists() for rel in left)
    assert all((out / rel).read_text() == "cut short" for rel in alike)
    assert "temporaries a killed command left removed" in (out / "fepen.log").read_text()
    (out / "sweep.csv.tmp7-zzzzzzzz.csv").write_text("cut")  # a continued study sweeps them too
    assert fepen(capsys, "sweep", spec, "--out", out, "--workers", "1")[0] == 0
    assert not (out / "sweep.csv.tmp7-zzzzzzzz.csv").exists()
    run = tmp_path / "run"  # and a resumed run
    assert fepen(capsys, "run", "--set", "effects.fidelity=rigid", "--out", run)[0] == 0
    (run / "summary.json.tmp5-abcdefgh").write_text("cut")
    assert fepen(capsys, "run", "--resume", run)[0] == 0
    assert not (run / "summary.json.tmp5-abcdefgh").exists()


def test_sweep_killed_at_each_write_then_continued_and_freshed(tmp_path, capsys):
    """Acceptance 3: ``fepen sweep`` SIGKILLed at each of its writes (the temporary complete, not yet renamed:
    fepen.atomic's FEPEN_INJECT_KILL), then continued, then --fresh: the uninterrupted table every time, no file
    the uninterrupted sweep does not have, every user file kept."""
    spec = kept_sweep(tmp_path, (500.0, 700.0))
    ref = tmp_path / "ref"
    assert fepen(capsys, "sweep", spec, "--out", ref, "--workers", "1")[0] == 0
    table, files = (ref / "sweep.csv").read_text(), tree(ref)
    trace = tmp_path / "trace.txt"  # every write's temporary, in order
    env = processes.mpi_env(FEPEN_INJECT_KILL=f"trace:{trace}")
    r = subprocess.run(processes.command(["sweep", spec, "--out", tmp_path / "traced", "--workers", "1"]),
                       env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    paths = [Path(p).relative_to(tmp_path / "traced").as_posix().split(".tmp")[0]
             for p in trace.read_text().splitlines()]
    points = [i + 1 for i, p in enumerate(paths) if p not in paths[:i]] + [len(paths)]  # each file's first write
    assert len(points) >= 12, paths
    for k in points:
        out = tmp_path / f"k{k}"
        out.mkdir()
        (out / "notes.txt").write_text("top")
        r = subprocess.run(processes.command(["sweep", spec, "--out", out, "--workers", "1"]),
                           env=processes.mpi_env(FEPEN_INJECT_KILL=str(k)), capture_output=True, text=True,
                           timeout=120)
        assert r.returncode == -signal.SIGKILL, (k, paths[k - 1], r.returncode, r.stderr[-500:])
        if (out / "shots").is_dir():
            (out / "shots" / "README.md").write_text("mine")
        for fresh in ([], ["--fresh"]):
            code, _, err = fepen(capsys, "sweep", spec, "--out", out, "--workers", "1", *fresh)
            assert code == 0, (k, paths[k - 1], fresh, err)
            assert (out / "sweep.csv").read_text() == table, (k, paths[k - 1], fresh)
            users = {"notes.txt", "shots/README.md"} & tree(out)
            assert tree(out) - users == files, (k, paths[k - 1], fresh, tree(out) ^ files)
            assert (out / "notes.txt").read_text() == "top"


# ---------------------------------------------------------------------------------------------- item 3
def test_a_study_none_of_whose_shots_ran_fails_and_says_why(tmp_path, capsys):
    """Before: a sweep whose every shot was refused recorded each as bad-input and exited 0 with no numbers.
    Now it exits 2 naming the count and the first shot's reason; with one shot refused and the others run it
    succeeds, its table saying which."""
    import shutil

    spec, out = kept_sweep(tmp_path), tmp_path / "s"
    assert fepen(capsys, "sweep", spec, "--out", out, "--workers", "1")[0] == 0
    for i in range(3):  # the user's files where the shots' folders go
        shutil.rmtree(out / "shots" / f"{i:05d}")
        (out / "shots" / f"{i:05d}").write_text("a file where a shot's folder goes")
    code, _, err = fepen(capsys, "sweep", spec, "--out", out, "--workers", "1", "--fresh")
    assert code == 2 and len(err) == 1, err
    assert all((out / "shots" / f"{i:05d}").read_text().startswith("a file") for i in range(3))
    assert "no shot finished (3 bad-input); shot 0:" in err[0]
    assert json.loads((out / "run.json").read_text())["outcome"] == "bad-input"
    assert (out / "sweep.csv").is_file()  # each point's outcome, for the record
    for i in (1, 2):
        (out / "shots" / f"{i:05d}").unlink()
    code, stdout, err = fepen(capsys, "sweep", spec, "--out", out, "--workers", "1", "--fresh")
    assert code == 0 and "bad-input 1, ok 2" in stdout, err
    rows = [ln.split(",") for ln in (out / "sweep.csv").read_text().splitlines()]
    status = rows[0].index("status")
    assert [r[status] for r in rows[1:]] == ["bad-input", "ok", "ok"]


# ---------------------------------------------------------------------------------------------- item 4
def test_a_continued_study_refuses_other_data_or_another_fepen(tmp_path, capsys, monkeypatch):
    """Before: a rigid sweep killed after two shots and continued by a fepen whose fepen/data/targets.toml had
    changed ran the rest with the new data and kept the old (depths 273, 319, 308, 351 mm), exit 0: its digest
    covered the given keys only. Now a change of a shipped data file, of fepen's version or of a file the shots
    read is refused before any shot runs, naming it."""
    from fepen import data

    spec, out = kept_sweep(tmp_path), tmp_path / "s"
    assert fepen(capsys, "sweep", spec, "--out", out, "--workers", "1")[0] == 0
    lines = (out / "shots.jsonl").read_text().splitlines()
    (out / "shots.jsonl").write_text("\n".join(lines[:2]) + "\n")  # as if killed after two shots
    (out / "sweep.csv").unlink()
    real = data.digests()
    monkeypatch.setattr(data, "digests", lambda: {**real, "targets.toml": "0" * 64})  # a recalibrated target
    code, _, err = fepen(capsys, "sweep", spec, "--out", out, "--workers", "1")
    assert code == 2 and len(err) == 1 and "fepen/data/targets.toml changed" in err[0], err
    assert len((out / "shots.jsonl").read_text().splitlines()) == 2  # no shot ran
    monkeypatch.setattr(data, "digests", lambda: real)
    monkeypatch.setattr("fepen.version.__version__", "9.9.9")
    code, _, err = fepen(capsys, "sweep", spec, "--out", out, "--workers", "1")
    assert code == 2 and "fepen 0." in err[0] and "-> 9.9.9" in err[0], err
    monkeypatch.undo()
    code, stdout, err = fepen(capsys, "sweep", spec, "--out", out, "--workers", "1")  # the same inputs: continued
    assert code == 0 and "1 run now, 2 recorded before" in stdout, err
    profile = tmp_path / "nose.csv"  # a file the shots read, by content
    profile.write_text("z_m, r_m, arc_radius_m\n0, 0\n0.039136, 0.0118, 0.0708\n0.124, 0.0118\n0.144, 0.009\n")
    base = ["--set", "effects.fidelity=rigid", "--set", f"projectile.profile={profile}", "--speeds", "100,1500",
            "--tol", "50", "--set", "target.thickness=0.1"]
    assert fepen(capsys, "study", "ballistic-limit", *base, "--out", tmp_path / "bl")[0] == 0
    from fepen.studies import record, study

    plan = study.get("ballistic-limit")().plan(None, ["effects.fidelity=rigid", f"projectile.profile={profile}",
                                                      "target.thickness=0.1"], 100.0, 1500.0, 50.0)
    assert ("projectile.profile", str(profile)) in record.scene_files(plan)
    profile.write_text("z_m, r_m, arc_radius_m\n0, 0\n0.039136, 0.0118, 0.0708\n0.124, 0.0118\n0.144, 0.010\n")
    code, _, err = fepen(capsys, "study", "ballistic-limit", *base, "--out", tmp_path / "bl")
    assert code == 2 and f"{profile} changed" in err[0], err


def test_validate_into_a_folder_of_other_settings_is_refused_not_answered_from_it(tmp_path, capsys):
    """Before: ``fepen validate --set target.compressive_strength=80e6`` into the folder of an earlier validate
    printed the earlier shots' figures (its records were taken as this run's). Now it is refused, and --fresh
    runs it."""
    out = tmp_path / "v"
    rigid = ["--set", "effects.fidelity=rigid", "--set", "run.figures=false"]
    code, first, err = fepen(capsys, "validate", *rigid, "--out", out)
    assert code == 0, err
    code, _, err = fepen(capsys, "validate", *rigid, "--set", "target.compressive_strength=80e6", "--out", out)
    assert code == 2 and "validate made of other inputs" in err[0] and "--fresh" in err[0], err
    code, second, err = fepen(capsys, "validate", *rigid, "--set", "target.compressive_strength=80e6", "--out", out,
                              "--fresh")
    assert code == 0, err
    c3 = [ln for ln in first.splitlines() if ln.startswith("C3:")], [ln for ln in second.splitlines()
                                                                     if ln.startswith("C3:")]
    assert c3[0] != c3[1]  # a stronger target: another depth


# ---------------------------------------------------------------------------------------------- item 5
def _running(pid: int) -> bool:
    """A process that exists and is not a zombie (an exited rank its launcher has not reaped)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.two_ranks
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP, signal.SIGINT])
def test_a_signal_to_a_relaunched_sweep_reaches_every_rank(tmp_path, sig):
    """Before: SIGTERM to a ``fepen sweep`` that had relaunched itself under mpirun ended the command and left
    mpirun and both ranks running: they went on writing into --out (2 -> 32 shot folders in 6 s) and kept the
    lock. Now the signal is passed on to every rank, the sweep stops at a shot boundary (exit 4, run.json
    "interrupted", no lock, no process left), and the same command continues it to the uninterrupted table. A
    signal that reaches a rank while it still loads (shots.jsonl is written before every rank catches signals)
    is kept until its study does (errors.catch_early_stop): the sweep may then stop before its first shot; it had
    ended 138, the rank killed by the forwarded SIGUSR1."""
    speeds = [500.0 + 10 * i for i in range(30)]
    spec, out = kept_sweep(tmp_path, speeds), tmp_path / "s"
    proc = subprocess.Popen(processes.command(["sweep", spec, "--out", out, "--workers", "2"]), env=processes.mpi_env(),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    t0 = time.time()
    while time.time() - t0 < 120 and not (out / "shots.jsonl").is_file():
        time.sleep(0.02)
    ranks = processes.rank_pids(proc.pid)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 4, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("fepen: interrupted:") and "shot boundary" in lines[0], lines
    def shot_folders():  # none when the signal came before the first shot: a rank still loading keeps it
        return len(list((out / "shots").iterdir())) if (out / "shots").is_dir() else 0

    folders = shot_folders()
    t0 = time.time()
    while any(_running(pid) for pid in ranks) and time.time() - t0 < 20:  # mpirun may return before they are gone
        time.sleep(0.1)
    assert not any(_running(pid) for pid in ranks)
    time.sleep(1)
    assert shot_folders() == folders  # nothing writes into it any more
    assert not (out / rundir.LOCK).exists()
    record = json.loads((out / "run.json").read_text())
    assert record["outcome"] == "interrupted" and record["exit_code"] == 4
    done = len((out / "shots.jsonl").read_text().splitlines())
    assert done < len(speeds), "the sweep was not stopped part way"
    if sig != signal.SIGTERM:
        return
    r = run_fepen("sweep", spec, "--out", out, "--workers", "2")
    assert r.returncode == 0, r.stderr
    assert f"{len(speeds) - done} run now, {done} recorded before" in r.stdout
    r = run_fepen("sweep", spec, "--out", tmp_path / "whole", "--workers", "1")
    assert (out / "sweep.csv").read_text() == (tmp_path / "whole" / "sweep.csv").read_text()


@pytest.mark.two_ranks
def test_a_refusal_after_the_relaunch_is_one_line(tmp_path):
    """Before: a sweep refused after relaunching itself under mpirun printed mpirun's banner after fepen's line
    (11 lines on stderr). Now one line."""
    spec = kept_sweep(tmp_path)
    out = tmp_path / "s"
    out.mkdir()
    (out / "sweep.csv").write_text("the user's table")  # a name the sweep writes: refused when OUT is claimed
    r = run_fepen("sweep", spec, "--out", out, "--workers", "2")
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert r.returncode == 2 and len(lines) == 1 and lines[0].startswith("fepen: bad input: --out:"), r.stderr
    assert (out / "sweep.csv").read_text() == "the user's table"


@pytest.mark.two_ranks
def test_a_study_that_keeps_no_shot_folders_runs_on_two_groups(tmp_path):
    """A study whose shots keep no folder (validate-depth) on two groups: the engine does not claim a shots/
    folder it would never write (it raised UndeclaredName on rank 0, and the other rank, left waiting in a
    collective, hung until the job was killed; an internal error on one rank now aborts the job)."""
    data = tmp_path / "mine.csv"
    data.write_text("shot,d_mm,m_kg,crh,L_mm,v_ms,fc_mpa,rho_kgm3,depth_m\n"
                    "a,26.9,0.906,2,242.4,277,35.2,2370,0.173\nb,30.5,1.6,3,305,800,51,2300,0.9\n")
    r = run_fepen("validate-depth", "--data", data, "--only", "--out", tmp_path / "out", "--workers", "2",
                  timeout=300)
    assert r.returncode == 0, r.stderr
    assert "mine: 2 shots" in r.stdout and not (tmp_path / "out" / "shots").exists()
