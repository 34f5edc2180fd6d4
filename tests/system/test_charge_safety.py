"""``fepen study charge-safety`` (docs/charge.md): the verdict mapped over speed × obliquity on coarse, short
charged shots; the same table on 1 rank and on 2 ranks (two groups), and a study stopped by SIGTERM on 2 ranks
that, started again, runs only the missing shots and writes that table again. The physics of each criterion:
tests/unit/laws/test_explosive.py and tests/system/test_interface.py."""

import csv
import json
import os
import signal
import time

import pytest
from conftest import run_fepen

from fepen.studies import processes

ARGS = ["study", "charge-safety", "--speeds", "700,1000", "--obliquities", "0,20", "--set", "mesh.size=0.006",
        "--set", "run.end_time=1.2e-4", "--set", "run.fields=false", "--set", "run.checkpoint_interval=0"]


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    out = tmp_path_factory.mktemp("charge-safety") / "serial"
    r = run_fepen(*ARGS, "--out", out)
    assert r.returncode == 0, r.stderr
    return out, r.stdout


def test_the_map_orders_the_margins_and_names_the_governing_criterion(serial):
    """Every point has a verdict; at each obliquity the faster shot has the smaller governing margin, and the
    table, report, map and the console's boundary lines are written."""
    out, stdout = serial
    res = json.loads((out / "charge_safety.json").read_text())
    rows = res["rows"]
    assert len(rows) == 4 and all(r["status"] == "ok" and r["margin"] is not None for r in rows)
    for o in (0.0, 20.0):
        slow, fast = (next(r for r in rows if r["obliquity_deg"] == o and r["velocity_m_s"] == v) for v in (700, 1000))
        assert fast["margin"] < slow["margin"], (o, slow["margin"], fast["margin"])
    assert all(r["governing"] in ("strength", "tension") for r in rows)
    assert len(res["boundary"]) == 2 and "obliquity 0 deg, attack 0 deg: governing margins" in stdout
    assert (out / "charge_safety.png").stat().st_size > 10_000
    assert "| speed (m/s) |" in (out / "charge_safety.md").read_text()


def test_two_ranks_and_a_resumed_study_give_the_same_table(serial, tmp_path):
    out = tmp_path / "two"
    proc = processes.start([*ARGS, "--out", out], ranks=2)
    t0 = time.time()
    while time.time() - t0 < 300:
        if (out / "shots.jsonl").is_file() and (out / "shots.jsonl").read_text().count("\n") >= 1:
            break
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGTERM)
    proc.wait()
    if (out / ".fepen.lock").exists():  # the ranks ended by mpirun before they stopped; it may return before them
        lock = json.loads((out / ".fepen.lock").read_text())["pid"]
        t0 = time.time()
        while os.path.exists(f"/proc/{lock}") and time.time() - t0 < 60:
            time.sleep(0.1)
    done = (out / "shots.jsonl").read_text().count("\n")
    assert done >= 1 and not (out / "charge_safety.csv").exists(), "the study was not stopped part way"
    r = run_fepen(*ARGS, "--out", out, ranks=2)
    assert r.returncode == 0, r.stderr
    assert f"{done} done before" in r.stdout
    shots = [json.loads(line)["shot"] for line in (out / "shots.jsonl").read_text().splitlines()]
    assert sorted(shots) == [0, 1, 2, 3], "a finished shot ran twice, or one is missing"
    assert (out / "charge_safety.csv").read_text() == (serial[0] / "charge_safety.csv").read_text()
    assert list(csv.reader((out / "charge_safety.csv").open()))[0][:4] == ["point", "velocity_m_s", "obliquity_deg",
                                                                            "attack_deg"]


def test_a_rigid_or_uncharged_base_is_refused_before_any_shot(tmp_path):
    """Bad input is one InputError naming the key, from the study's plan: before any folder or shot."""
    from fepen.errors import InputError
    from fepen.studies import study

    st = study.get("charge-safety")()
    for kw, key in (({"sets": ["effects.fidelity=rigid"]}, "effects.fidelity"),
                    ({"sets": ["effects.charge=false"]}, "effects.charge"), ({"speeds": [0.0]}, "--speeds"),
                    ({"sets": ["charge.safety.gap=-1"]}, "charge.safety.gap")):
        with pytest.raises(InputError) as err:
            st.plan(**kw)
        assert key in err.value.key, (kw, err.value.key)
    r = run_fepen(*ARGS, "--obliquities", "95", "--out", tmp_path / "o")
    assert r.returncode == 2 and "--obliquities" in r.stderr and "Traceback" not in r.stderr
    assert not (tmp_path / "o").exists()
