"""Acceleration records filtered as instrumented penetration tests filter theirs (docs/theory.md §13).

Accelerometers in a penetrator ring at the body's axial modes; test reports low-pass the record to keep
the rigid-body deceleration. fepen does the same to its computed records: a zero-phase (forward-backward)
Butterworth low-pass, order 4 each way, on the record resampled to a uniform step. Zero phase keeps the
time of the peak; the forward-backward pass squares the gain (−6 dB at the cut-off).
"""

from __future__ import annotations

import numpy as np


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
