"""The Recht–Ipson fit (fepen.studies.limits) recovers a and p from exact residual speeds, and the curve
vanishes at and below the ballistic limit."""

import numpy as np
import pytest

from fepen.studies import limits


@pytest.mark.parametrize("a, p", [(0.9, 2.0), (0.75, 2.6), (1.0, 1.5)])
def test_fit_recovers_the_curve(a, p):
    v = np.linspace(410.0, 700.0, 9)
    vr = limits.recht_ipson(v, 400.0, a, p)
    fa, fp, rms = limits.fit_recht_ipson(v, vr, 400.0)
    assert fa == pytest.approx(a, rel=1e-4) and fp == pytest.approx(p, rel=1e-4) and rms < 1e-3


def test_curve_is_zero_below_the_limit():
    assert np.all(limits.recht_ipson([100.0, 399.9, 400.0], 400.0, 0.9, 2.0) == 0.0)
    assert limits.recht_ipson(500.0, 400.0, 1.0, 2.0) == pytest.approx(300.0)
