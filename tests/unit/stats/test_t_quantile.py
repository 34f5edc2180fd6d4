"""The interval's quantiles without scipy (fepen.stats.interval.quantile_t, quantile_z): against the closed forms
of Student's t at one and two degrees of freedom, and against scipy's own (less exact: its cdflib search stops
near 1e-10) at every degree of freedom a set of a few shots can have."""

import math

import pytest
from scipy.special import ndtri, stdtrit

from fepen.stats.interval import quantile_t, quantile_z

P = (1e-4, 0.001, 0.05, 0.1, 0.3, 0.5, 0.7, 0.9, 0.95, 0.999)


@pytest.mark.parametrize("p", P)
def test_one_and_two_degrees_of_freedom_have_closed_forms(p):
    # to the last few bits where the interval reads it (10 % and 90 %); the far tails lose a few more digits to
    # 0.5 + 0.5 a with a near -1
    rel = 1e-14 if 0.01 < p < 0.99 else 1e-12
    assert quantile_t(p, 1) == pytest.approx(math.tan(math.pi * (p - 0.5)), rel=rel, abs=1e-15)
    assert quantile_t(p, 2) == pytest.approx((2 * p - 1) / math.sqrt(2 * p * (1 - p)), rel=rel, abs=1e-15)


@pytest.mark.parametrize("dof", [1, 2, 3, 4, 5, 7, 10, 15, 30, 60])
def test_the_quantile_is_scipys_and_symmetric(dof):
    for p in P:
        t = quantile_t(p, dof)
        assert t == pytest.approx(float(stdtrit(dof, p)), rel=1e-8, abs=1e-12)
        assert quantile_t(1.0 - p, dof) == pytest.approx(-t, rel=1e-12, abs=1e-14)


def test_many_degrees_of_freedom_tend_to_the_normal():
    assert quantile_t(0.9, 400) == pytest.approx(quantile_z(0.9), rel=2e-3)
    assert quantile_t(0.9, 400) > quantile_z(0.9)  # the t's tails are heavier at any finite dof


def test_the_normal_quantile_is_scipys():
    for p in P:
        assert quantile_z(p) == pytest.approx(float(ndtri(p)), rel=1e-14, abs=1e-15)


@pytest.mark.parametrize("dof", [0, 2.5, -1])
def test_a_dof_that_is_not_a_whole_positive_number_is_refused(dof):
    with pytest.raises(ValueError, match="degrees of freedom"):
        quantile_t(0.9, dof)
