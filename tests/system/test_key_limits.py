"""Every allowed value of every numeric scene key ends a rigid shot in a result or a one-line refusal, within
a bounded amount of work (issue 43, acceptance 3; the deformable side is fepen.runs.budget's,
tests/unit/runs/test_budget.py).

Hypothesis draws a key and a value in its allowed range (log-uniform over a positive range, the bounds
themselves often) and runs the rigid C3 shot with it in this process. The work is counted, not timed: RK4 steps
at most fepen.runs.budget.MAX_RIGID_STEPS, and steps x load points at most WORK (the default shot is 199 steps
of 984 points; 20,000 steps of them take about 10 s on one core). Before issue 43 a rigid shot at 1 m/s took
185,000 steps (88 s) and at 0.1 m/s hours; a run.rigid_step of 1e-12 s never ended; and a run.end_time of 1 s
took 164,500 steps (150 s on CI) until the budget counted the steps of an end time."""

import json
import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fepen import cli
from fepen.runs import budget
from fepen.scene import SCHEMA

#: the most point-steps (RK4 steps x load points) of one rigid shot: the step budget at the default rings, and
#: the finest mesh.rigid_panel (19,008 points) over the default shot's steps
WORK = 25e6

NUMERIC = sorted(k for k, key in SCHEMA.items() if key.kind in (float, int) and not key.choices)


def _values(name):
    key = SCHEMA[name]
    lo = key.lo if key.lo is not None else -1e6
    hi = key.hi if key.hi is not None else 1e9
    if key.lo_open:
        lo = lo + 1e-9 * max(1.0, abs(lo)) if lo != 0 else min(1e-12, hi / 2)
    if key.hi_open:
        hi = hi - 1e-9 * max(1.0, abs(hi))
    edges = st.sampled_from([lo, hi])
    if lo > 0:
        inner = st.floats(math.log(lo), math.log(hi)).map(math.exp)
    else:
        inner = st.floats(lo, hi)
    return st.one_of(edges, inner).map(lambda v: min(max(v, lo), hi))


CASES = st.sampled_from(NUMERIC).flatmap(lambda k: st.tuples(st.just(k), _values(k)))


@pytest.mark.filterwarnings("ignore")
@settings(max_examples=25, deadline=None, suppress_health_check=list(HealthCheck))
@given(case=CASES)
def test_every_allowed_value_ends_a_rigid_shot_in_bounded_work(tmp_path_factory, case):
    name, value = case
    out = tmp_path_factory.mktemp("limits")
    code = cli.main(["run", "--set", "effects.fidelity=rigid", "--set", f"{name}={value!r}", "--out",
                     str(out / "run")])
    assert code in (0, 2, 3), (name, value, code)
    if code == 2 or (code == 3 and not (out / "run" / "summary.json").exists()):
        return  # refused before any work, or stopped as unstable before its first record
    summary = json.loads((out / "run" / "summary.json").read_text())
    assert summary["steps"] <= budget.MAX_RIGID_STEPS, (name, value, summary["steps"])
    if summary["outcome"] == "stopped":  # unstable (run.rigid_step=0.001: non-finite at step 3), stopped with
        assert code == 3 and summary["stop_reason"] and "load_points" not in summary  # what and when, no figures
        return
    assert summary["steps"] * summary["load_points"] <= WORK, (name, value, summary["steps"], summary["load_points"])
