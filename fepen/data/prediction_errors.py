"""fepen's errors on the public data (prediction_errors.csv): one row per shot, law, fidelity and quantity,
with the shot's features, fepen's prediction and the measurement. Written by ``fepen study prediction-errors
--table fepen/data/prediction_errors.csv``; read by the validated envelope (fepen.stats.envelope) and the
prediction intervals (fepen.stats.interval)."""

from __future__ import annotations

import csv
import functools
import io
from importlib import resources
from pathlib import Path

__all__ = ["COLUMNS", "TEXT_COLUMNS", "path", "read"]

COLUMNS = ("set", "shot", "role", "law", "fidelity", "quantity", "D_m", "L_over_D", "crh", "mass_kg", "V_m_s",
           "fc_cylinder_Pa", "rho_kg_m3", "obliquity_deg", "attack_deg", "predicted_m", "measured_m")
#: the columns that are words; the others are numbers (SI, or the unit in the name)
TEXT_COLUMNS = COLUMNS[:6]


def path() -> Path:
    """fepen/data/prediction_errors.csv."""
    return Path(str(resources.files("fepen").joinpath("data/prediction_errors.csv")))


def read(file=None) -> list[dict]:
    """The rows of a prediction-error table (numbers as floats; ``#`` lines skipped), the shipped one by default."""
    if file is None:
        return [dict(r) for r in _shipped()]
    return _parse(Path(file).read_text())


@functools.lru_cache(maxsize=1)
def _shipped() -> tuple:
    return tuple(_parse(path().read_text()))


def _parse(text: str) -> list[dict]:
    text = "\n".join(line for line in text.splitlines() if not line.startswith("#"))
    rows = csv.DictReader(io.StringIO(text))
    return [{k: (v if k in TEXT_COLUMNS else float(v)) for k, v in r.items()} for r in rows]
