"""The tunnel the projectile opens in the target (docs/theory.md §8.7): its state in Python, for the law's one
home in C (fepen/laws/tunnel_kernel.c, which fepen/laws/target_kernel.c includes).

The tunnel is recorded along the path of the body's widest section (the shoulder) as it goes, a station every
``spacing`` along the path, each with the radius the cavity has been opened to in ``SECTORS`` angular sectors;
the wall yields outward where the body presses it past its reload limit. Any surface point behind the shoulder
is in the tunnel: the target loads it only where it presses into that wall, elastically (2G/a times its push)
up to the wall's limit (the reload fraction of σ_s and the inertia of its outward speed), whatever the separation
angle. The nose, ahead of the shoulder, opens the tunnel under the law of the open face.

    t = Tunnel.of_points(X, radius)                from a body's load points (body frame: tip at y = 0, axis +y)
    t.at(shoulder, axis)                           before each force evaluation: where the shoulder is now
    t.commit = True                                before a step's first stage: record and expand there
    t.stations()                                   what has been recorded (for outputs)
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fepen import native

__all__ = ["Tunnel", "SECTORS", "CAPACITY", "HEADER", "STATION", "shoulder_of", "zones", "ZONES", "split"]

#: angular sectors of a station's radius
SECTORS = 16
#: stations a tunnel has room for (then it ends where it is: 2048 calibres at the default spacing)
CAPACITY = 4096
#: tunnel_kernel.h's layout, read from its enums (declared once, in C): the header's length, its fields, a
#: station's fixed part
_HEADER = Path(__file__).with_name("tunnel_kernel.h")
HEADER, STATION = native.enum_values(_HEADER, "T_HEADER", "T_STATION")
T_M, T_CAP, T_S, T_SPACING, T_XI_SH, T_A0, T_COMMIT, T_CS, T_TS, T_FACE = native.enum_values(
    _HEADER, "T_M", "T_CAP", "T_S", "T_SPACING", "T_XI_SH", "T_A0", "T_COMMIT", "T_CS", "T_TS", "T_FACE")
#: a station's fields: its centre (3), direction (3) and arc length, then its radii from STATION
T_C, T_T, T_ARC = native.enum_values(_HEADER, "T_C", "T_T", "T_ARC")


def shoulder_of(X: np.ndarray, radius: np.ndarray) -> tuple[float, float]:
    """The body's widest section from its load points (body frame): (its distance behind the tip xi_sh (m),
    its radius a0 (m)), where the points first reach (1 − 1e-3) of the largest radius."""
    a0 = float(np.max(radius))
    wide = radius >= (1.0 - 1e-3) * a0
    return float(np.min(X[wide, 1])), a0


#: the body's zones, by their distance behind the tip: the nose (ahead of the shoulder), the shank, the tail (the
#: last calibre)
ZONES = ("nose", "shank", "tail")


def zones(xi: np.ndarray, xi_sh: float, length: float, calibre: float) -> np.ndarray:
    """Each point's zone (0 nose, 1 shank, 2 tail) from its distance xi behind the tip (m): the nose ahead of the
    shoulder xi_sh, the tail the last calibre of the body's length, the shank between."""
    out = np.ones(len(xi), dtype=np.int64)
    out[xi < xi_sh] = 0
    out[xi > length - calibre] = 2
    out[xi < xi_sh] = 0  # a body shorter than its nose and a calibre: the nose first
    return out


def split(force: np.ndarray, zone: np.ndarray) -> np.ndarray:
    """The target's force summed by zone, (3 zones, 3) (N), and the loaded points by zone (3,), as one (3, 4)
    array: [:, :3] the forces, [:, 3] the counts (a point is loaded when its force is not zero)."""
    out = np.zeros((3, 4))
    loaded = np.any(force != 0.0, axis=1)
    for j in range(3):
        out[:, j] = np.bincount(zone, weights=force[:, j], minlength=3)
    out[:, 3] = np.bincount(zone, weights=loaded.astype(float), minlength=3)
    return out


@dataclass
class Tunnel:
    """One run's tunnel: the flat state tunnel_kernel.c reads and writes (``buf``), owned here.

    Args:
        xi_sh: the shoulder's distance behind the tip, body frame (m). a0: its radius (m).
        spacing: the path between stations (m; default a0 / 2).
    """

    xi_sh: float
    a0: float
    spacing: float | None = None

    def __post_init__(self):
        self.buf = np.zeros(HEADER + CAPACITY * (STATION + SECTORS))
        b = self.buf
        b[T_CAP], b[T_S] = CAPACITY, SECTORS
        b[T_SPACING] = self.spacing if self.spacing is not None else 0.5 * self.a0
        b[T_XI_SH], b[T_A0] = self.xi_sh, self.a0

    @classmethod
    def of_points(cls, X: np.ndarray, radius: np.ndarray) -> Tunnel:
        """The tunnel of a body with load points X (body frame) at distances ``radius`` from its axis."""
        xi_sh, a0 = shoulder_of(X, radius)
        return cls(xi_sh, a0)

    def at(self, shoulder: np.ndarray, axis: np.ndarray) -> None:
        """Where the shoulder's centre is now and the axis (tail to nose), before the law is called."""
        self.buf[T_CS:T_CS + 3] = shoulder
        self.buf[T_TS:T_TS + 3] = axis

    @property
    def commit(self) -> bool:
        return bool(self.buf[T_COMMIT])

    @commit.setter
    def commit(self, value: bool) -> None:
        self.buf[T_COMMIT] = 1.0 if value else 0.0

    @property
    def count(self) -> int:
        """Stations recorded."""
        return int(self.buf[T_M])

    def stations(self) -> dict[str, np.ndarray]:
        """The recorded stations: centre (m, 3), direction (3), arc length s (m) and radius per sector (m)."""
        m = self.count
        st = self.buf[HEADER:HEADER + m * (STATION + SECTORS)].reshape(m, STATION + SECTORS)
        return {"centre": st[:, T_C:T_C + 3].copy(), "direction": st[:, T_T:T_T + 3].copy(), "s": st[:, T_ARC].copy(),
                "radius": st[:, STATION:].copy()}

    def recorded(self) -> np.ndarray:
        """The recorded stations, as a view into the state (a distributed surface takes the largest of every
        rank's radii in it: the stations themselves are the same on every rank)."""
        return self.buf[HEADER:HEADER + self.count * (STATION + SECTORS)]

    def state(self) -> np.ndarray:
        """The recorded part of the state (for checkpoints)."""
        return self.buf[:HEADER + self.count * (STATION + SECTORS)].copy()

    def restore(self, state: np.ndarray) -> None:
        """Put back what state() returned."""
        self.buf[:len(state)] = state
