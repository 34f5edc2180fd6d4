"""The shipped constants are the calibration's: re-running its runs at the shipped open constants and
re-fitting the strength gives back the shipped a and D0 within 1 % (docs/validation-depth.md)."""

import pytest

from fepen.laws import target as tg
from fepen.studies import calibration as cal


@pytest.mark.slow
def test_refit_at_the_shipped_constants_gives_them_back():
    node = cal.shipped_node()
    sets = cal.load_sets()
    table = cal.curves(sets, [node])
    a, D0, obj = cal.fit(sets, list(table[0]))
    a0, b0, D00 = tg.S_MODELS["scaled-S"]
    assert b0 == cal.EXPONENT
    assert a == pytest.approx(a0, rel=0.01) and D0 == pytest.approx(D00, rel=0.01)
