"""A single run's attitude sensitivity (fepen.runs.sensitivity, issue 59 item 4): two rigid shots at the in-plane
attack ± δ. At normal incidence without attack the target has no preferred side, so the two shots are mirror
images (final axes ±θ, the same nose offset, Hx the same); an oblique shot turns more when its nose points down
the slope; the block reaches summary.json and the printed line through fepen.api.run."""

import math

import pytest

from fepen import api
from fepen.runs import batch, sensitivity

pytestmark = pytest.mark.skipif(batch.kernel() is None, reason="the rigid batch kernel does not build here")


def test_the_in_plane_step_keeps_the_out_of_plane_attack():
    got = sensitivity.perturbed(1.0, 90.0, 0.5)  # 1° across the plane, 0.5° added in it
    assert got["impact.attack_deg"] == pytest.approx(math.hypot(1.0, 0.5), rel=1e-12)
    assert got["impact.attack_plane_deg"] == pytest.approx(math.degrees(math.atan2(1.0, 0.5)), rel=1e-12)
    assert sensitivity.perturbed(0.0, 0.0, -0.5) == {"impact.attack_deg": 0.5, "impact.attack_plane_deg": 180.0}


def test_at_normal_incidence_the_two_shots_are_mirror_images():
    s = sensitivity.attitude(api.Scene(None, sets=["impact.obliquity_deg=0", "impact.attack_deg=0",
                                                   "impact.velocity=893"]), 1.0)
    lo, hi = s["final_axis_angle_deg"]
    assert hi > 0.5  # a degree of yaw turns a fast body (measured: 2.7 deg)
    assert lo == pytest.approx(-hi, rel=1e-9, abs=1e-9)
    assert s["nose_offset_mm"][0] == pytest.approx(s["nose_offset_mm"][1], rel=1e-9)
    assert s["gain_deg_per_deg"] == pytest.approx(hi, rel=1e-9)


def test_an_oblique_shot_turns_more_when_its_nose_points_down_the_slope():
    s = sensitivity.attitude(api.Scene(None, sets=["impact.shot='C7'"]))
    lo, hi = s["final_axis_angle_deg"]
    assert s["yaw_deg"] == sensitivity.YAW_DEG
    assert 0.0 < lo < hi and s["gain_deg_per_deg"] > 0.0


def test_a_run_keeps_and_prints_its_sensitivity(tmp_path):
    r = api.run(api.Scene(None, sets=["effects.fidelity=rigid", "impact.shot='C2'"]), out=tmp_path / "r")
    s = r.summary["attitude_sensitivity"]
    assert len(s["final_axis_angle_deg"]) == 2 and s["final_axis_angle_deg"][0] < r.summary[
        "final_axis_angle_deg"] < s["final_axis_angle_deg"][1]
    from fepen.cli.run import sensitivity_lines

    assert sensitivity_lines(r.summary)[0].startswith("attitude_sensitivity = final axis")
    r2 = api.run(api.Scene(None, sets=["effects.fidelity=rigid", "impact.shot='C2'"]), out=tmp_path / "q",
                 sensitivity=False)
    assert "attitude_sensitivity" not in r2.summary
