"""The projectile's frame in the world: its axis from the tracked nose tip and tail centre."""

from __future__ import annotations

import numpy as np


def unit_axis(tip: np.ndarray, tail: np.ndarray) -> np.ndarray:
    """Unit vector of the projectile axis, tail to nose."""
    return (tip - tail) / np.linalg.norm(tip - tail)
