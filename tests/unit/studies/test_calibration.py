"""The calibration procedure on synthetic depth curves (no run): it recovers the constants that made the
data, the bootstrap resolves only real differences, and the closed-form bound is found when it can be met."""

import math

import numpy as np
import pytest

from fepen.studies import calibration as cal
from fepen.studies import depth


def synthetic(a, b, D0, noise=0.0, seed=1):
    """Two sets whose depths follow P = 10 m / S exactly (the curves), at S of the scaled-S law (a, b, D0)."""
    rng = np.random.default_rng(seed)
    sets, curves = {}, {}
    for name, sizes in (("small", [0.012, 0.02, 0.03]), ("large", [0.076, 0.15, 0.2])):
        rows = []
        for D in sizes:
            for fc in (15e6, 40e6, 100e6):
                S = a * (fc / 1e6) ** -b / math.sqrt(1.0 + D / D0)
                rows.append(depth.Row(f"{name}{D}{fc}", D, 10 * D, 1.0, 3.0, 500.0, fc, 2300.0,
                                      10.0 / S * math.exp(noise * rng.standard_normal())))
        sets[name] = rows
        curves[name] = np.tile(np.log(10.0 / cal.GRID), (len(rows), 1))
    return sets, curves


def test_fit_recovers_the_constants_that_made_the_data():
    sets, curves = synthetic(90.0, cal.EXPONENT, 0.06)
    a, b, D0 = cal.fit(sets, curves)
    assert b == cal.EXPONENT
    assert a == pytest.approx(90.0, rel=1e-3) and D0 == pytest.approx(0.06, rel=1e-2)
    assert cal.objective([math.log(a), b, math.log(D0)], sets, curves) < 1e-4
    a, b, D0 = cal.fit(sets, curves, exponent=None)  # b free: found too
    assert b == pytest.approx(cal.EXPONENT, abs=2e-3)


def test_bootstrap_resolves_only_real_differences():
    sets, curves = synthetic(90.0, cal.EXPONENT, 0.06, noise=0.1)
    theta = (90.0, cal.EXPONENT, 0.06)
    assert cal.difference_sd(sets, curves, theta, curves, theta) == 0.0
    sd = cal.difference_sd(sets, curves, theta, curves, (100.0, cal.EXPONENT, 0.06))
    assert 0.0 < sd < 0.05


def test_closed_form_bound():
    sets, curves = synthetic(90.0, cal.EXPONENT, 0.06)
    bound, best = cal.closed_form_bound(sets, curves)
    assert set(bound) == set(sets) and all(v >= 0.0 for v in bound.values())
    # the data follow the scaled-S law exactly, so some (a, D0) has (nearly) no error: the bound is met
    assert best is not None and best[0] < 0.05
