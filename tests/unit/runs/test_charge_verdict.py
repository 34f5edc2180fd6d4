"""A shot's verdict on its charge from its own end state (fepen.runs.charge_safety.settled): only a shot that
finished by its own physics can be safe; a demand past its threshold is unsafe whether or not the shot finished;
a shot that reached run.end_time first, or stopped, has no verdict and says why."""

import pytest

from fepen.runs.charge_safety import FINISHED, VERDICTS, settled


def summary(outcome, margin, **extra):
    return {"outcome": outcome, "Hx_mm": 1.0, "end_time_s": 2e-5, "residual_speed_m_s": 143.5,
            "charge_safety": {"governing": None if margin is None else "strength", "margin": margin}, **extra}


@pytest.mark.parametrize("outcome", FINISHED)
def test_a_finished_shot_is_safe_or_unsafe_by_its_margin(outcome):
    assert settled(summary(outcome, 1.43)) == {"outcome": outcome, "finished": True, "verdict": "safe", "reason": ""}
    assert settled(summary(outcome, 0.97))["verdict"] == "unsafe"
    assert settled(summary(outcome, 1.0))["verdict"] == "safe"  # at the threshold, not past it
    assert settled(summary(outcome, None))["verdict"] == "no threshold"


def test_a_shot_that_reached_its_end_time_is_never_safe():
    got = settled(summary("ended", 1.43))
    assert (got["outcome"], got["finished"], got["verdict"]) == ("ended", False, "undecided")
    assert "run.end_time = 2e-05 s" in got["reason"] and "143.5 m/s" in got["reason"]
    assert settled(summary("ended", None))["verdict"] == "undecided"
    assert settled(summary("ended", 0.8))["verdict"] == "unsafe"  # past the threshold already: it stays past it


def test_a_shot_without_a_result_is_undecided_with_its_reason():
    got = settled(None, "stopped", "inverted element 7 at t = 31 us")
    assert got == {"outcome": "stopped", "finished": False, "verdict": "undecided",
                   "reason": "inverted element 7 at t = 31 us"}
    assert settled(None, "missing")["reason"] == "no result (missing)"
    assert settled(None, "bad-input", "impact.velocity: too fast")["verdict"] == "undecided"
    assert {settled(summary(o, m))["verdict"] for o in (*FINISHED, "ended") for m in (None, 0.5, 2.0)} <= \
        set(VERDICTS)
