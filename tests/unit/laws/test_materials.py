"""Material laws as pure array functions: Johnson-Cook, adiabatic heating, bilinear hardening."""

import math

import numpy as np
import pytest

from fepen.laws import materials as M
from fepen.laws import uniaxial

STEEL = dict(E=210e9, nu=0.3, density=7850.0, A=950e6, B=725e6, n=0.375, C=0.015, m=0.625,
             melt_temperature=1765.0, room_temperature=294.0)


def jc(**kw):
    args = dict(STEEL)
    args.update(kw)
    return M.johnson_cook(**args)


def test_quasi_static_isothermal_curve_is_johnson_cook():
    mat = jc(strain_rate=False, thermal=False)
    sig, ep, T = uniaxial.uniaxial_stress_path(mat, np.linspace(0, 0.4, 801), 1.0)
    plastic = ep > 0
    assert plastic.sum() > 700
    ref = 950e6 + 725e6 * ep[plastic] ** 0.375
    assert np.max(np.abs(sig[plastic] / ref - 1)) < 1e-8
    # elastic part: sigma = E eps below yield, no plastic strain
    first = np.flatnonzero(plastic)[0]
    e = np.linspace(0, 0.4, 801)
    assert np.allclose(sig[:first], 210e9 * e[:first], rtol=1e-9)
    assert np.all(T == 294.0)


@pytest.mark.parametrize("rate", [1e2, 1e4, 1e6])
def test_strain_rate_term(rate):
    mat = jc(thermal=False)
    ref = jc(strain_rate=False, thermal=False)
    e = np.linspace(0, 0.2, 401)
    dt = (e[1] - e[0]) / rate
    sig, ep, _ = uniaxial.uniaxial_stress_path(mat, e, dt)
    sig0, ep0, _ = uniaxial.uniaxial_stress_path(ref, e, dt)
    # at the same plastic strain, the flow stress carries (1 + C ln(rate)) (plastic rate ~ total rate)
    flow = 950e6 + 725e6 * ep[-1] ** 0.375
    assert sig[-1] / flow == pytest.approx(1 + 0.015 * math.log(rate), rel=2e-3)
    assert sig[-1] > sig0[-1]


def test_adiabatic_heating_and_softening():
    mat = jc()
    e = np.linspace(0, 0.5, 2001)
    sig, ep, T = uniaxial.uniaxial_stress_path(mat, e, (e[1] - e[0]) / 1e4)
    plastic_work = np.sum(0.5 * (sig[1:] + sig[:-1]) * np.diff(ep))
    assert T[-1] - 294.0 == pytest.approx(0.9 * plastic_work / (7850 * 470), rel=1e-3)
    # the flow stress at the end is the Johnson-Cook value at the final strain, rate and temperature
    ts = (T[-1] - 294) / (1765 - 294)
    rate = (ep[-1] - ep[-2]) / ((e[1] - e[0]) / 1e4)
    expect = (950e6 + 725e6 * ep[-1] ** 0.375) * (1 + 0.015 * math.log(rate)) * (1 - ts**0.625)
    assert sig[-1] == pytest.approx(expect, rel=1e-3)


def test_radial_return_is_consistent():
    mat = jc()
    p = mat.params
    G = mat.shear_modulus
    for q, ep, T, dt in [(1.5e9, 0.0, 294.0, 1e-7), (2.5e9, 0.3, 500.0, 5e-8), (1.2e9, 1.0, 1200.0, 1e-6)]:
        d, sy, Tn = M.radial_return(q, ep, T, dt, G, p)
        assert d > 0
        assert q - 3 * G * d == pytest.approx(sy, rel=1e-11)
        assert sy == pytest.approx(M.yield_stress(ep + d, d / dt, Tn, p), rel=1e-11)
        assert Tn - T == pytest.approx(0.9 * sy * d / (7850 * 470), rel=1e-11)


def test_melt_and_elastic_limits():
    mat = jc()
    assert M.yield_stress(0.1, 1.0, 1765.0, mat.params) == 0.0
    assert M.yield_stress(0.0, 0.5, 294.0, mat.params) == pytest.approx(950e6)
    el = M.elastic(210e9, 0.3, 7850.0)
    sig, ep, _ = uniaxial.uniaxial_stress_path(el, np.linspace(0, 0.05, 11), 1e-6)
    assert np.all(ep == 0) and sig[-1] == pytest.approx(210e9 * 0.05, rel=1e-9)


def test_bilinear_charge_hardening_slope_is_tangent_modulus():
    mat = M.bilinear(10.1e9, 0.3, 1850.0, 45e6, 600e6)
    e = np.linspace(0, 0.05, 501)
    sig, ep, _ = uniaxial.uniaxial_stress_path(mat, e, 1e-6)
    slope = np.diff(sig[-100:]) / np.diff(e[-100:])
    assert np.allclose(slope, 600e6, rtol=1e-6)
    assert sig[-1] == pytest.approx(45e6 + 600e6 * (0.05 - 45e6 / 10.1e9), rel=1e-6)
