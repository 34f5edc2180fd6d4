"""Element erosion criteria (docs/theory.md §15): pure functions on cell arrays.

Two criteria, either enough:

- ductile failure: the equivalent plastic strain reached ``strain`` (LS-DYNA's *MAT_ADD_EROSION maximum
  effective strain; OpenRadioss /FAIL);
- inversion risk: the cell's own stable step fell below ``step_ratio`` times the run's initial step
  (OpenRadioss /DT/BRICK/DEL: "the element which is controlling the time step is removed so that the
  constant time step ΔT_min can be maintained"). A cell that flat is about to invert; deleting it keeps the
  run going at an affordable step.
"""

from __future__ import annotations

import numpy as np

__all__ = ["failed"]


def failed(eps_p: np.ndarray, cell_step: np.ndarray, initial_step: float, strain: float | None,
           step_ratio: float) -> np.ndarray:
    """Which cells erode.

    Args:
        eps_p: equivalent plastic strain per cell.
        cell_step: each cell's own stable step (s): its altitude over its wave speed times the run's
            safety factor and step gain (inf for eroded cells).
        initial_step: the run's stable step at the start (s).
        strain: the erosion strain, or None (no strain criterion).
        step_ratio: the step criterion's ratio (0: none).

    Returns:
        bool mask of the cells that erode.
    """
    out = cell_step < step_ratio * initial_step
    if strain is not None:
        out |= eps_p >= strain
    return out
