"""The paper's Table 1: eight shots of the 23.6 mm steel projectile into 40 MPa concrete.

Shipped as fepen/data/table1.csv. Displacements are magnitudes in mm
of the nose tip (Hx, Hy) and tail centre (Tx, Ty) from the impact point at the end of penetration.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from importlib import resources

__all__ = ["Shot", "SHOTS", "shot"]


@dataclass(frozen=True)
class Shot:
    """One row of Table 1 (speeds in m/s, angles in degrees, displacements in mm)."""

    name: str
    v0: float
    obliquity_deg: float
    attack_deg: float
    Hx_mm: float
    Hy_mm: float
    Tx_mm: float
    Ty_mm: float


def _read() -> dict[str, Shot]:
    text = resources.files("fepen.data").joinpath("table1.csv").read_text()
    rows = csv.DictReader(text.splitlines())
    return {
        r["shot"]: Shot(r["shot"], float(r["v0_m_s"]), float(r["obliquity_deg"]), float(r["attack_deg"]),
                        float(r["Hx_mm"]), float(r["Hy_mm"]), float(r["Tx_mm"]), float(r["Ty_mm"]))
        for r in rows
    }


SHOTS: dict[str, Shot] = _read()


def shot(name: str) -> Shot:
    """The Table 1 row of a shot.

    Args:
        name: "C1" ... "C8".

    Returns:
        The Shot (KeyError for another name).
    """
    return SHOTS[name]
