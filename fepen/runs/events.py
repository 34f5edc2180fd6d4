"""Stop rules, one definition for the rigid and the deformable run (docs/theory.md §11).

    embedded     the centre of mass stops advancing along the axis (V·a ≤ 0), or the kinetic energy of
                 its motion ½ M |V|² falls to STOP_ENERGY of the striking kinetic energy; checked only
                 when the scene gives no run.end_time
    perforated   every load point is beyond the rear face of a finite target
    ricochet     after entering, every load point is back above the face and the centre moves away
    rebound      on the rigid wall: no node has touched it for REBOUND_FREE_S after a contact
    eroded       erosion left less than ERODED_FRACTION of the projectile's mass (effects.erosion)
    beyond the method   the equivalent plastic strain passed projectile.failure_strain, when the scene
                 gives one (fepen.errors)

The rules are pure functions of a few reduced numbers; ``StopRules`` keeps their memory (entered,
touched) for a run and its checkpoints.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

#: the projectile is at rest (embedded) when ½ M |V|² falls to this fraction of the striking kinetic energy
STOP_ENERGY = 1e-5
#: a body off the rigid wall for this long after touching it has rebounded (s)
REBOUND_FREE_S = 20e-6


def embedded(v_cm: np.ndarray, axis: np.ndarray, mass: float, ke0: float) -> bool:
    """The centre of mass no longer advances along the axis, or its kinetic energy is spent."""
    return float(v_cm @ axis) <= 0.0 or 0.5 * mass * float(v_cm @ v_cm) <= STOP_ENERGY * ke0


def perforated(y_max: float, thickness: float | None) -> bool:
    """Every load point (highest y: y_max) is beyond the rear face y = −thickness."""
    return thickness is not None and y_max < -thickness


def ricochet(y_min: float, vy: float) -> bool:
    """Every load point (lowest y: y_min) is above the face and the centre of mass moves away."""
    return y_min > 0.0 and vy > 0.0


#: the run stops ("eroded") when erosion has left less than this fraction of the projectile's mass
ERODED_FRACTION = 0.05


def beyond_method(max_peeq: float, failure_strain: float | None) -> bool:
    """The user's projectile.failure_strain is passed (None: never)."""
    return failure_strain is not None and max_peeq > failure_strain


@dataclass
class StopRules:
    """The stop rules of one run and their memory.

    Args:
        thickness: the target's thickness (m), None for semi-infinite.
        until_stopped: the run has no end time: it ends when embedded (or rebounded).
    """

    thickness: float | None
    until_stopped: bool
    entered: bool = False
    touched: bool = False
    free_since: float | None = None

    def penetration(self, y_min: float, y_max: float, v_cm: np.ndarray, axis: np.ndarray, mass: float,
                    ke0: float) -> str | None:
        """The outcome in a concrete target from the load points' extent in y, or None to go on."""
        self.entered = self.entered or y_min < 0.0
        if not self.entered:
            return None
        if perforated(y_max, self.thickness):
            return "perforated"
        if ricochet(y_min, float(v_cm[1])):
            return "ricochet"
        if self.until_stopped and embedded(v_cm, axis, mass, ke0):
            return "embedded"
        return None

    def rebound(self, t: float, contact_nodes: int) -> str | None:
        """On the rigid wall: "rebound" once the body has been free of it for REBOUND_FREE_S."""
        if contact_nodes > 0:
            self.touched, self.free_since = True, None
        elif self.touched and self.free_since is None:
            self.free_since = t
        if self.until_stopped and self.free_since is not None and t - self.free_since > REBOUND_FREE_S:
            return "rebound"
        return None

    def state(self) -> dict:
        """The rules' memory (for checkpoints)."""
        return {k: v for k, v in asdict(self).items() if k in ("entered", "touched", "free_since")}

    def restore(self, state: dict) -> None:
        """Put back what state() returned."""
        self.entered, self.touched, self.free_since = state["entered"], state["touched"], state["free_since"]
