"""The calibration procedure on synthetic curves (no run): it recovers the strength constants that made the
data, and it picks the node of the open constants whose runs made them."""

import math

import numpy as np
import pytest

from fepen.laws import target as tg
from fepen.studies import calibration as cal
from fepen.studies import depth


def synthetic(a, D0, tilt=0.0, noise=0.0, seed=1):
    """Two depth sets whose depths follow P = 10 m / S (the curves; times (f_c/40 MPa)^tilt), measured at S of
    the scaled-S law (a, EXPONENT, D0)."""
    rng = np.random.default_rng(seed)
    sets, tables = {}, []
    for name, sizes in (("small", [0.012, 0.02, 0.03]), ("large", [0.076, 0.15, 0.2])):
        rows, table = [], []
        for D in sizes:
            for fc in (15e6, 40e6, 100e6):
                S = a * (fc / 1e6) ** -cal.EXPONENT / math.sqrt(1.0 + D / D0)
                rows.append(depth.Row(f"{name}{D}{fc}", D, 10 * D, 1.0, 3.0, 500.0, fc, 2300.0,
                                      10.0 / S * math.exp(noise * rng.standard_normal())))
                grid = cal.S_SPAN * tg.forrestal_S(fc)
                curve = np.zeros((len(grid), 4))
                curve[:, 1] = (fc / 40e6) ** tilt * 10.0 / grid
                table.append(curve)
        sets[name] = rows
        tables.append(np.array(table))
    return sets, tables


def test_fit_recovers_the_constants_that_made_the_data():
    sets, tables = synthetic(90.0, 0.06)
    a, D0, obj = cal.fit(sets, tables)
    assert a == pytest.approx(90.0, rel=1e-3) and D0 == pytest.approx(0.06, rel=1e-2)
    assert obj < 1e-4 and cal.objective([math.log(a), math.log(D0)], sets, tables) == pytest.approx(obj)


def test_calibrate_picks_the_node_that_made_the_data():
    """Two nodes: one whose runs made the data, one whose runs go deeper the stronger the target, which the
    strength constants (b held) cannot absorb. The first has the smaller objective."""
    sets, exact = synthetic(90.0, 0.06, noise=0.05)
    _, deeper = synthetic(90.0, 0.06, tilt=0.3)
    table = np.empty((2, 2), dtype=object)
    for j in range(2):
        table[0, j], table[1, j] = deeper[j], exact[j]
    nodes = [{"target.separation_angle_deg": 9.0}, {"target.separation_angle_deg": 3.0}]
    ranked = cal.calibrate(sets, table, nodes)
    assert ranked[0][1] == nodes[1] and ranked[0][0] <= ranked[1][0]


def test_table1_error_is_the_mean_of_nose_tail_and_axis_errors():
    """Table 1's shot error: positions equal to the test's give 0; the nose and the tail moved together by 10 %
    of |H| along x (the axis unchanged) give (10 % |H|/|H| + 10 % |H|/|T| + 0)/3; the tail alone turned about
    the nose by 5 degrees adds 5 x AXIS_WEIGHT_PER_DEG / 3 to the tail's own error."""
    import math

    from fepen.data import SHOTS

    rows = depth.table1_set()
    exact = np.array([[s.Hx_mm, s.Hy_mm, s.Tx_mm, s.Ty_mm] for s in SHOTS.values()]) / 1e3
    assert np.allclose(cal.group_errors("table1", rows, exact), 0.0)
    H = np.hypot(exact[:, 0], exact[:, 1])
    T = np.hypot(exact[:, 2], exact[:, 3])
    off = exact.copy()
    off[:, 0] += 0.1 * H
    off[:, 2] += 0.1 * H
    assert np.allclose(cal.group_errors("table1", rows, off), (0.1 + 0.1 * H / T) / 3.0)
    # the tail turned about the nose by 5 degrees (toward larger Hx - Tx)
    turned = exact.copy()
    d = exact[:, 2:] - exact[:, :2]
    c, s = math.cos(math.radians(5.0)), math.sin(math.radians(5.0))
    turned[:, 2] = exact[:, 0] + c * d[:, 0] - s * d[:, 1]
    turned[:, 3] = exact[:, 1] + s * d[:, 0] + c * d[:, 1]
    tail = np.linalg.norm(turned[:, 2:] - exact[:, 2:], axis=1) / T
    got = cal.group_errors("table1", rows, turned)
    assert np.allclose(got, (tail + 5.0 * cal.AXIS_WEIGHT_PER_DEG) / 3.0)
