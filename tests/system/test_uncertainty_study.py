"""``fepen study uncertainty`` as a user runs it, rigid and small: the C3 scatter writes its files, and fepen's
own error widens the depth's P10-P90 beyond the inputs' alone; the response carries the resistance factor as
the lead's normal-incidence runs say; a 150 mm slab at its ballistic limit is perforated with a probability
strictly between 0 and 1, inside its Wilson interval, and moves with the systematic error the right way; the
table is the same on 1 and 2 ranks."""

import csv
import json

import numpy as np
import pytest
from conftest import run_fepen
from mpi4py import MPI

from fepen.studies import processes, uncertainty

pytestmark = pytest.mark.xdist_group("test_uncertainty_study")

DEMO = processes.ROOT / "demos" / "studies" / "c3_scatter.toml"
N = 80


@pytest.fixture(scope="module")
def c3(tmp_path_factory):
    out = tmp_path_factory.mktemp("unc") / "c3"
    r = run_fepen("study", "uncertainty", "--scatter", DEMO, "--samples", N, "--seed", 5, "--out", out)
    assert r.returncode == 0, r.stderr
    return out, r.stdout


def test_c3_study_writes_its_files_and_the_model_widens_the_depth(c3):
    out, stdout = c3
    for f in ("uncertainty.json", "uncertainty.md", "combined.csv", "inputs.csv", "model_draws.csv",
              "combined/shots.jsonl", "inputs/sweep.csv"):
        assert (out / f).is_file(), f
    assert (out / "uncertainty.png").stat().st_size > 20_000
    res = json.loads((out / "uncertainty.json").read_text())
    comb, inp = res["samples"]["combined"]["depth"], res["samples"]["inputs"]["depth"]
    assert comb["shots"] == inp["shots"] == N
    assert comb["P90_mm"] - comb["P10_mm"] > 1.5 * (inp["P90_mm"] - inp["P10_mm"])
    assert 200 < inp["P50_mm"] < 400 and inp["P10_mm"] < comb["P50_mm"] < inp["P90_mm"] * 1.1
    t = res["scene"]["test"]
    assert (t["shot"], t["depth_mm"], t["Hx_mm"], t["Ty_mm"]) == ("C3", 349.6, 81.4, 212.0)
    # the paths' bands and the designer's probabilities: C3 neither ricochets nor perforates; its axis bands
    # hold the deterministic 11 deg (the scatter's ±1° of obliquity and ±0.5° of yaw about C3's)
    a = res["samples"]["inputs"]["paths"]["final_axis_angle_deg"]
    assert a["P10"] < 11.0 < a["P90"] and a["P90"] - a["P10"] < 10.0
    assert res["samples"]["inputs"]["ricochet"]["ricochets"] == 0 and res["samples"]["inputs"]["ricochet"]["shots"] == N
    assert 0 <= res["samples"]["inputs"]["axis_beyond"]["beyond"] <= N
    assert "final axis (inputs alone): P10" in stdout and "P(ricochet, inputs alone) 0.000" in stdout
    assert res["envelope"]["inside"]
    assert "depth (inputs and model, 80 shots): P10" in stdout and "written:" in stdout
    # the table holds the drawn factors, each the inverse of its eps through the response
    draws = list(csv.DictReader((out / "model_draws.csv").open()))
    r = res["model_scatter"]["response"]
    resp = uncertainty.Response(tuple(r["resistance_factor"]), tuple(r["depth_ratio"]), r["depth_at_1_mm"] * 1e-3)
    eps = np.array([float(d["eps"]) for d in draws])
    lam = np.array([float(d["target.resistance_factor"]) for d in draws])
    assert np.allclose(resp.g(lam), np.exp(eps), rtol=1e-9)


def test_combined_depth_carries_the_models_error_shot_by_shot(c3):
    """Each combined shot's depth over its inputs-only twin is exp(eps) to the response's accuracy: the same
    inputs, only the resistance differs (the response is of the nominal shot, so a few per cent off)."""
    out, _ = c3
    recs = {name: {r["shot"]: r["summary"]["depth_mm"] for r in map(json.loads, (out / name / "shots.jsonl")
                                                                        .read_text().splitlines())}
            for name in ("combined", "inputs")}
    eps = np.array([float(d["eps"]) for d in csv.DictReader((out / "model_draws.csv").open())])
    ratio = np.array([recs["combined"][i] / recs["inputs"][i] for i in range(N)])
    assert np.median(np.abs(np.log(ratio) - eps)) < 0.03


def test_the_response_matches_the_leads_normal_incidence_runs():
    """C3 at normal incidence: factor 0.8 gives 1.225x the depth, 1.25 gives 0.82x, 2 gives 0.55x."""
    base = {"impact.velocity": 584.3, "impact.obliquity_deg": 0.0, "impact.attack_deg": 0.0,
            "target.thickness": 0.15}  # the thickness is removed for the response
    r = uncertainty.calibrate(base, MPI.COMM_SELF)
    assert r.g(1.0) == 1.0
    for lam, ratio in ((0.8, 1.225), (1.25, 0.82), (2.0, 0.55)):
        assert r.g(lam) == pytest.approx(ratio, rel=0.02), lam


def test_a_slab_at_its_ballistic_limit_is_perforated_sometimes(tmp_path):
    """At the 150 mm slab's limit (315.3 m/s, fepen study ballistic-limit) the scatter perforates some shots,
    not all; fepen more optimistic about the concrete (b at its 90 %: deeper) perforates more."""
    out = tmp_path / "slab"
    r = run_fepen("study", "uncertainty", "--scatter", DEMO, "--samples", 30, "--seed", 5, "--out", out,
                  "--set", "target.thickness=0.15", "--set", "impact.velocity=315.3")
    assert r.returncode == 0, r.stderr
    res = json.loads((out / "uncertainty.json").read_text())
    for name in ("combined", "inputs"):
        p = res["samples"][name]["perforation"]
        assert 0 < p["perforated"] < p["shots"] == 30
        assert p["wilson95"][0] < p["probability"] < p["wilson95"][1]
    band = res["samples"]["combined"]["perforation"]["systematic"]["probability"]
    assert band[0] < res["samples"]["combined"]["perforation"]["probability"] < band[1]
    assert "P(perforation of the 150 mm slab, inputs and model)" in r.stdout
    assert "outside the validated envelope: target thickness 150 mm" in r.stdout
    assert res["scene"]["test"] is None


@pytest.mark.mpi
def test_the_table_is_the_same_on_one_and_two_ranks(tmp_path_factory):
    """Under mpirun -n 2: the study on COMM_WORLD (two groups taking shots from the queue) and on COMM_SELF
    give the same drawn table and the same records."""
    world = MPI.COMM_WORLD
    assert world.size == 2
    root = world.bcast(str(tmp_path_factory.mktemp("unc-mpi")) if world.rank == 0 else None, root=0)
    p = uncertainty.plan(None, DEMO, samples=16, seed=9)
    quiet = dict(say=lambda *a: None, progress=False)
    two = uncertainty.study(p, f"{root}/two", world, **quiet)
    one = uncertainty.study(p, f"{root}/one", MPI.COMM_SELF, **quiet) if world.rank == 0 else None
    if world.rank == 0:
        from pathlib import Path

        for f in ("combined.csv", "model_draws.csv", "inputs.csv", "combined/sweep.csv", "inputs/sweep.csv"):
            assert (Path(root) / "two" / f).read_text() == (Path(root) / "one" / f).read_text(), f
        assert two["samples"] == one["samples"]
        assert two["ranks"] == 2 and one["ranks"] == 1
    world.barrier()
