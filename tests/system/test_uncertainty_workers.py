"""``fepen study uncertainty --workers W`` as ``fepen sweep``'s and ``fepen validate``'s: started without mpirun,
the study runs under ``mpirun -n W`` and its ranks share the shots; the tables and numbers are those of the
study run in one process (a small rigid C3 scatter: 8 samples, fepen's own error drawn)."""

import json

import pytest
from conftest import run_fepen

from fepen.studies import processes

ARGS = ["study", "uncertainty", "--scatter", processes.ROOT / "demos" / "studies" / "c3_scatter.toml",
        "--samples", "8", "--seed", "3"]
TABLES = ("combined.csv", "inputs.csv", "model_draws.csv", "combined/sweep.csv", "inputs/sweep.csv")


@pytest.mark.skipif(processes.launcher() is None, reason="no MPI launcher")
@pytest.mark.parametrize("ranks", [2])
def test_workers_share_the_shots_and_give_the_same_numbers(tmp_path, ranks):
    one, many = tmp_path / "one", tmp_path / "many"
    r = run_fepen(*ARGS, "--out", one)
    assert r.returncode == 0, r.stderr[-2000:]
    r = run_fepen(*ARGS, "--workers", str(ranks), "--out", many)
    assert r.returncode == 0, r.stderr[-2000:]
    assert f"({ranks} ranks)" in r.stdout  # the study ran on the workers' ranks, not in this process
    for name in TABLES:
        assert (many / name).read_bytes() == (one / name).read_bytes(), name
    a, b = (json.loads((d / "uncertainty.json").read_text()) for d in (one, many))
    assert (a["ranks"], b["ranks"]) == (1, ranks)
    assert {k: v for k, v in a.items() if k not in ("wall_s", "ranks")} == \
        {k: v for k, v in b.items() if k not in ("wall_s", "ranks")}
    assert a["samples"]["combined"]["depth"]["shots"] == 8
