"""``fepen study charge-safety`` with a point whose shot cannot finish (run.end_time far shorter than its
penetration): charge_safety.csv says its outcome, that it did not finish and why, and its verdict is not
"safe"; the report marks its margin as an upper bound and names it undecided."""

import csv
import json

from conftest import run_fepen

ARGS = ["study", "charge-safety", "--speeds", "150", "--obliquities", "0", "--set", "mesh.size=0.006",
        "--set", "run.end_time=2e-5", "--set", "run.fields=false", "--set", "run.figures=false",
        "--set", "run.checkpoint_interval=0"]


def test_an_unfinished_point_is_not_called_safe(tmp_path):
    out = tmp_path / "cs"
    r = run_fepen(*ARGS, "--out", out)
    assert r.returncode == 0, r.stderr[-2000:]
    with open(out / "charge_safety.csv", newline="") as f:
        (row,) = list(csv.DictReader(f))
    assert {"outcome", "finished", "verdict", "message"} <= set(row)
    assert (row["status"], row["outcome"], row["finished"]) == ("ok", "ended", "false")
    assert row["verdict"] != "safe"
    assert "run.end_time = 2e-05 s" in row["message"] and "lower bounds" in row["message"]
    margin = float(row["margin"])  # 3 mm into the target at 150 m/s: nothing near its threshold yet
    assert margin > 1.0 and row["verdict"] == "undecided"
    res = json.loads((out / "charge_safety.json").read_text())
    assert res["verdicts"] == {"undecided": 1}
    assert res["boundary"][0]["margins"] == [None]  # a lower bound of the demand is not a point of the boundary
    md = (out / "charge_safety.md").read_text()
    assert f"≤ {margin:.3g}" in md and "150 m/s, 0 deg, attack 0 deg: undecided (ended)" in md
    assert "undecided (ended): reached run.end_time" in r.stdout
