"""Acceleration records filtered as instrumented penetration tests filter theirs (docs/theory.md §13).

Accelerometers in a penetrator ring at the body's axial modes; test reports low-pass the record to keep
the rigid-body deceleration. fepen does the same to its computed records, with one of two filters
(``run.acceleration_filter``), each zero-phase (forward-backward) on the record resampled to a uniform step:

- ``"butterworth"`` (the default): a Butterworth low-pass of order 4 each way at ``run.acceleration_filter_hz``
  (10 kHz). Zero phase keeps the time of the peak; the forward-backward pass squares the gain (−6 dB at the
  cut-off).
- ``"CFC60"``, ``"CFC180"``, ``"CFC600"``, ``"CFC1000"``: the channel frequency classes of SAE J211-1 (Appendix C):
  a 2-pole Butterworth applied forward and backward (4 poles, phaseless), designed at 2.0775 CFC so that the
  gain is −0.45 dB at F_H = CFC and −3 dB at 1.665 CFC (F_N = 100, 300, 1000, 1650 Hz). ``cfc_filter``.
"""

from __future__ import annotations

import math

import numpy as np

#: the SAE J211-1 channel frequency classes: name -> (CFC = F_H, the corner F_N), Hz
CFC_CLASSES = {"CFC60": (60.0, 100.0), "CFC180": (180.0, 300.0), "CFC600": (600.0, 1000.0),
               "CFC1000": (1000.0, 1650.0)}
#: SAE J211-1's design frequency of one 2-pole pass over the class frequency: wd = 2 pi CFC 2.0775
J211_DESIGN = 2.0775
#: the filters of run.acceleration_filter, the default first
FILTERS = ("butterworth", *CFC_CLASSES)


def lowpass(t: np.ndarray, y: np.ndarray, cutoff_hz: float, order: int = 4) -> np.ndarray:
    """Zero-phase Butterworth low-pass of a record sampled at times t (any spacing).

    Args:
        t: sample times (s), increasing. y: values (any unit). cutoff_hz: cut-off frequency (Hz).
        order: Butterworth order of each pass.

    Returns:
        The filtered values at the times t. Records shorter than ~3 filter lengths are returned as they are
        (too short to filter without edge effects).
    """
    from scipy.signal import butter, sosfiltfilt

    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    if len(t) < 4 or cutoff_hz <= 0:
        return y.copy()
    dt = float(np.median(np.diff(t)))
    fs = 1.0 / dt
    if cutoff_hz >= 0.5 * fs:
        return y.copy()
    tu = np.arange(t[0], t[-1] + 0.5 * dt, dt)
    yu = np.interp(tu, t, y)
    sos = butter(order, cutoff_hz, btype="low", fs=fs, output="sos")
    if len(yu) <= 3 * (2 * len(sos) + 1):
        return y.copy()
    return np.interp(t, tu, sosfiltfilt(sos, yu))


def cfc_coefficients(cfc: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """The 2-pole pass of SAE J211-1's CFC filter (Appendix C): Y[t] = a0 X[t] + a1 X[t-1] + a2 X[t-2]
    + b1 Y[t-1] + b2 Y[t-2], with wd = 2 pi CFC 2.0775, wa = tan(wd T/2), a0 = wa^2/(1 + sqrt2 wa + wa^2),
    a1 = 2 a0, a2 = a0, b1 = -2 (wa^2 - 1)/(1 + sqrt2 wa + wa^2), b2 = (-1 + sqrt2 wa - wa^2)/(1 + sqrt2 wa + wa^2).

    Args:
        cfc: the channel frequency class (Hz: 60, 180, 600, 1000; any positive value). dt: the sample step T (s).

    Returns:
        (numerator, denominator) as scipy.signal.lfilter takes them: [a0, a1, a2], [1, -b1, -b2].

    Raises:
        ValueError: a step too coarse for the class (its design frequency at or past the Nyquist frequency).
    """
    if not (cfc > 0 and dt > 0) or J211_DESIGN * cfc * dt >= 0.5:
        raise ValueError(f"CFC {cfc:g} needs a sample step below {0.5 / (J211_DESIGN * cfc):.3g} s, got {dt:.3g}")
    wa = math.tan(math.pi * J211_DESIGN * cfc * dt)  # tan(wd T / 2)
    d = 1.0 + math.sqrt(2.0) * wa + wa * wa
    a0 = wa * wa / d
    b1 = -2.0 * (wa * wa - 1.0) / d
    b2 = (-1.0 + math.sqrt(2.0) * wa - wa * wa) / d
    return np.array([a0, 2.0 * a0, a0]), np.array([1.0, -b1, -b2])


def cfc_filter(signal: np.ndarray, dt: float, cfc: float) -> np.ndarray:
    """SAE J211-1's phaseless 4-pole filter of channel frequency class ``cfc`` on a uniformly sampled record:
    the 2-pole pass of ``cfc_coefficients`` forward, then backward.

    Start-up (J211 leaves it to the user): scipy.signal.filtfilt's, each pass starting from its steady state
    on the record's odd extension by 9 samples; a constant record comes out unchanged.

    Args:
        signal: the values (any unit), one per step. dt: the step (s). cfc: the class (Hz).

    Returns:
        The filtered values (a copy of a record of 9 samples or fewer: too short to extend).

    Raises:
        ValueError: as cfc_coefficients.
    """
    from scipy.signal import filtfilt

    b, a = cfc_coefficients(cfc, dt)
    y = np.asarray(signal, dtype=float)
    if len(y) <= 3 * len(a):
        return y.copy()
    return filtfilt(b, a, y)


def acceleration_filter(t: np.ndarray, y: np.ndarray, name: str, cutoff_hz: float) -> np.ndarray:
    """A record filtered by the run's acceleration filter (run.acceleration_filter), on the record resampled
    to its median step and read back at the times t.

    Args:
        t: sample times (s), increasing. y: values (any unit). name: one of FILTERS. cutoff_hz: the cut-off of
            "butterworth" (run.acceleration_filter_hz; 0: none).

    Returns:
        The filtered values at the times t; the record as it is when it is too short, or sampled too coarsely
        for the filter (as ``lowpass``).
    """
    if name == "butterworth":
        return lowpass(t, y, cutoff_hz)
    cfc = CFC_CLASSES[name][0]
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    if len(t) < 4:
        return y.copy()
    dt = float(np.median(np.diff(t)))
    if J211_DESIGN * cfc * dt >= 0.5:
        return y.copy()
    tu = np.arange(t[0], t[-1] + 0.5 * dt, dt)
    return np.interp(t, tu, cfc_filter(np.interp(tu, t, y), dt, cfc))


def corner_hz(name: str, cutoff_hz: float) -> float:
    """The corner frequency of a filter of FILTERS (Hz): the cut-off of "butterworth" (−6 dB after both
    passes), F_N of a CFC class (−3 dB)."""
    return cutoff_hz if name == "butterworth" else CFC_CLASSES[name][1]
