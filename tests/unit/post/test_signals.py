"""The acceleration filters of fepen.post.signals (docs/theory.md §13): SAE J211-1's channel frequency classes
(CFC 60, 180, 600, 1000) inside the standard's response corridor, phaseless, a constant passed unchanged;
"butterworth", the default, exactly the low-pass fepen always used.

The corridor (SAE J211-1, Figure 1 and Table 1; ISO 6487 has the same): ±0.5 dB up to F_H = CFC, +0.5/−1 dB at
F_H, +0.5/−4 dB at F_N (100, 300, 1000, 1650 Hz), beyond F_N an upper limit falling 9 dB per octave (to a
floor of −30 dB) and a lower one falling 24 dB per octave. The lower limit between F_H and F_N is taken as the
straight line (in dB over log f) from −1 to −4 dB.
"""

import math

import numpy as np
import pytest

from fepen.post import signals

CLASSES = list(signals.CFC_CLASSES)
#: the frequencies checked, as multiples of F_H (passband and F_H) and of F_N (F_N and beyond)
PASS = (0.25, 0.5, 0.75, 0.9, 1.0)
BETWEEN = (1.2, 1.4)  # of F_H, below F_N = 1.65 F_H
STOP = (1.0, 1.41, 2.0, 4.0, 8.0, 16.0)


def corridor(f: float, fh: float, fn: float) -> tuple[float, float]:
    """J211-1's (lower, upper) gain limits (dB) at f (Hz) for a class of F_H, F_N."""
    if f <= fh:
        return (-0.5 if f < fh else -1.0), 0.5
    if f <= fn:
        return -1.0 - 3.0 * math.log(f / fh) / math.log(fn / fh), 0.5
    octaves = math.log2(f / fn)
    return -4.0 - 24.0 * octaves, max(0.5 - 9.0 * octaves, -30.0)


def frequencies(fh: float, fn: float, dt: float) -> list[float]:
    """The checked frequencies below a fifth of the sampling rate (nearer the Nyquist frequency the bilinear
    transform's warping takes the digital filter's gain below any analog line)."""
    return [f for f in [k * fh for k in PASS + BETWEEN] + [k * fn for k in STOP] if f <= 0.2 / dt]


def two_pass_gain_db(name: str, f: float, dt: float) -> float:
    """The gain (dB) of the class's coefficients applied forward and backward: |H(e^{i w T})|^2."""
    b, a = signals.cfc_coefficients(signals.CFC_CLASSES[name][0], dt)
    z = np.exp(-2j * np.pi * f * dt * np.arange(3))
    h = abs(np.dot(b, z) / np.dot(a, z))
    return 20.0 * math.log10(h * h)


def outside(name: str, dt: float) -> list[tuple[float, float]]:
    """The (frequency, gain dB) of the checked frequencies whose two-pass gain leaves the corridor."""
    fh, fn = signals.CFC_CLASSES[name]
    out = []
    for f in frequencies(fh, fn, dt):
        g = two_pass_gain_db(name, f, dt)
        lo, hi = corridor(f, fh, fn)
        if not lo <= g <= hi:
            out.append((f, g))
    return out


@pytest.mark.parametrize("name", CLASSES)
@pytest.mark.parametrize("rate", [10.0, 100.0])  # the sampling rate over F_N: J211 asks at least 10 F_H
def test_the_gain_of_each_class_lies_in_j211s_corridor(name, rate):
    fh, fn = signals.CFC_CLASSES[name]
    assert outside(name, 1.0 / (rate * fn)) == []
    # its -3 dB point is 1.667 CFC (the analog design puts it at 0.8015 x 2.0775 = 1.665 CFC), F_N rounded
    dt = 1.0 / (100.0 * fn)
    f3 = next(f for f in np.linspace(fh, 2 * fn, 20001) if two_pass_gain_db(name, f, dt) <= -3.0103)
    assert f3 == pytest.approx(1.667 * fh, rel=0.005) and f3 == pytest.approx(fn, rel=0.015)


def test_without_the_design_factor_the_filter_leaves_the_corridor(monkeypatch):
    """Designed at the CFC itself instead of 2.0775 CFC, the gain at F_H is −6 dB, outside +0.5/−1 dB."""
    monkeypatch.setattr(signals, "J211_DESIGN", 1.0)
    for name, (fh, fn) in signals.CFC_CLASSES.items():
        bad = dict(outside(name, 1.0 / (100.0 * fn)))
        assert fh in bad and bad[fh] == pytest.approx(-6.02, abs=0.05), bad


def amplitude_phase(y: np.ndarray, t: np.ndarray, f: float) -> tuple[float, float]:
    """The amplitude and phase (rad) of the sinusoid of frequency f that fits y(t) best (least squares)."""
    m = np.column_stack([np.sin(2 * np.pi * f * t), np.cos(2 * np.pi * f * t)])
    s, c = np.linalg.lstsq(m, y, rcond=None)[0]
    return math.hypot(s, c), math.atan2(c, s)


@pytest.mark.parametrize("name", CLASSES)
def test_a_sinusoid_comes_out_with_the_two_pass_gain_and_no_phase_shift(name):
    """Sinusoids through cfc_filter (the filter as runs apply it): the steady-state amplitude in the middle of
    the record is the two-pass gain |H|^2 within 0.05 dB, inside the corridor, and the phase is unchanged
    (a filter run forward only would keep the corridor but shift the phase by tens of degrees)."""
    fh, fn = signals.CFC_CLASSES[name]
    dt = 1.0 / (100.0 * fn)
    t = np.arange(0.0, 40.0 / (PASS[0] * fh), dt)
    mid = slice(len(t) // 4, 3 * len(t) // 4)
    for f in frequencies(fh, fn, dt):
        amp, phase = amplitude_phase(signals.cfc_filter(np.sin(2 * np.pi * f * t + 0.3), dt, fh)[mid], t[mid], f)
        gain = 20.0 * math.log10(amp)
        lo, hi = corridor(f, fh, fn)
        assert lo <= gain <= hi, (f, gain)
        assert gain == pytest.approx(two_pass_gain_db(name, f, dt), abs=0.05), f
        assert phase == pytest.approx(0.3, abs=1e-3), f


@pytest.mark.parametrize("name", CLASSES)
def test_a_constant_passes_unchanged(name):
    cfc = signals.CFC_CLASSES[name][0]
    y = np.full(5000, -3.7e4)
    assert np.abs(signals.cfc_filter(y, 1e-6, cfc) - y).max() < 1e-9 * 3.7e4
    t = np.cumsum(np.random.default_rng(1).uniform(0.9e-6, 1.1e-6, 3000))  # a history's rows: not quite uniform
    assert np.abs(signals.acceleration_filter(t, y[:3000], name, 1e4) - y[:3000]).max() < 1e-9 * 3.7e4


def test_a_step_too_coarse_for_the_class_is_refused_and_a_record_of_it_kept():
    """CFC 1000 is designed at 2077.5 Hz: a step of 1/4155 s or more has it at or past the Nyquist frequency."""
    with pytest.raises(ValueError, match="CFC 1000"):
        signals.cfc_coefficients(1000.0, 2.5e-4)
    signals.cfc_coefficients(1000.0, 2.3e-4)
    t = np.arange(50) * 2.5e-4
    y = np.sin(t * 1e3)
    assert np.array_equal(signals.acceleration_filter(t, y, "CFC1000", 1e4), y)


def test_butterworth_is_the_low_pass_as_before():
    """run.acceleration_filter = "butterworth" (the default) is fepen.post.signals.lowpass at the cut-off, so
    published numbers do not move; a CFC class filters the same record otherwise."""
    t = np.linspace(0.0, 1e-3, 1001)
    y = np.sin(np.pi * t / 1e-3) ** 2 + 0.3 * np.sin(2 * np.pi * 5e4 * t)
    assert np.array_equal(signals.acceleration_filter(t, y, "butterworth", 1e4), signals.lowpass(t, y, 1e4))
    assert np.abs(signals.acceleration_filter(t, y, "CFC1000", 1e4) - signals.lowpass(t, y, 1e4)).max() > 0.01
    assert signals.FILTERS[0] == "butterworth"
    assert signals.corner_hz("butterworth", 1e4) == 1e4 and signals.corner_hz("CFC180", 1e4) == 300.0
