"""The distributions of a test's unmeasured inputs (fepen.stats.striking): each member's draw is its own (seed,
shot, member), the recorded values are the means, the widths are the declared ones, and a prior of no width gives
the recorded shot."""

import dataclasses
import math

import numpy as np
import pytest

from fepen.stats import striking


def draws(prior, n=4000, attack=0.46, shot="C1"):
    return [striking.draw(prior, 516.8, 5.96, attack, striking.member_rng(7, shot, i)) for i in range(n)]


def test_the_recorded_values_are_the_means_and_the_widths_the_declared_ones():
    prior = dataclasses.replace(striking.PRIOR, rate_rad_s=10.0, speed_fraction=0.01)
    d = draws(prior)
    a = np.array([x["impact.attack_deg"] for x in d])
    phi = np.radians([x["impact.attack_plane_deg"] for x in d])
    inplane, out = a * np.cos(phi), a * np.sin(phi)
    n = len(d)
    assert inplane.mean() == pytest.approx(0.46, abs=3 * prior.attack_error_deg / math.sqrt(n))
    assert inplane.std() == pytest.approx(prior.attack_error_deg, rel=0.05)
    assert out.mean() == pytest.approx(0.0, abs=3 * prior.yaw_deg / math.sqrt(n))
    assert out.std() == pytest.approx(prior.yaw_deg, rel=0.05)
    v = np.array([x["impact.velocity"] for x in d])
    assert v.std() / 516.8 == pytest.approx(0.01, rel=0.05)
    q = np.array([x["impact.pitch_rate_rad_s"] for x in d])
    assert q.std() == pytest.approx(10.0, rel=0.05)
    assert len({x["target.heterogeneity_seed"] for x in d}) > 0.99 * n  # each member its own concrete


def test_a_member_s_draw_is_its_own():
    one = striking.draw(striking.PRIOR, 500.0, 5.0, 0.1, striking.member_rng(3, "C4", 17))
    again = striking.draw(striking.PRIOR, 500.0, 5.0, 0.1, striking.member_rng(3, "C4", 17))
    assert one == again
    assert one != striking.draw(striking.PRIOR, 500.0, 5.0, 0.1, striking.member_rng(3, "C5", 17))
    assert one != striking.draw(striking.PRIOR, 500.0, 5.0, 0.1, striking.member_rng(4, "C4", 17))


def test_a_prior_of_no_width_draws_the_recorded_shot():
    zero = striking.StrikingPrior(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.02)
    assert zero.zero and not striking.PRIOR.zero
    d = striking.draw(zero, 516.8, 5.96, 0.46, striking.member_rng(0, "C1", 0))
    assert all(type(v) in (float, int) for v in d.values())  # as a --set line writes them (numpy 2's repr)
    assert d == {"impact.velocity": 516.8, "impact.obliquity_deg": 5.96, "impact.attack_deg": 0.46,
                 "impact.attack_plane_deg": 0.0, "impact.pitch_rate_rad_s": 0.0, "impact.yaw_rate_rad_s": 0.0}
