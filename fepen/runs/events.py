"""Stop rules, one definition for the rigid and the deformable run (docs/theory.md §11).

    embedded     the centre of mass stops advancing along the axis (V·a ≤ 0), or its speed |V| falls to
                 END_SPEED (or ½ M |V|² to STOP_ENERGY of the striking kinetic energy, whichever comes first:
                 stop_fraction); checked only when the scene gives no run.end_time
    perforated   every load point is beyond the rear face of a finite target
    ricochet     after entering, every load point is back above the face and the centre moves away
    rebound      on the rigid wall: no node has touched it for REBOUND_FREE_S after a contact
    eroded       erosion left less than ERODED_FRACTION of the projectile's mass (effects.erosion)
    beyond the method   the equivalent plastic strain passed projectile.failure_strain, when the scene
                 gives one (fepen.errors)

The penetration rules (perforated, ricochet, embedded) are written once, in C (events_kernel.c, beside this
module; its outcome codes and prototype in events_kernel.h), which the single and deformable runs call through
``penetration`` and the batched rigid shots (rigid_batch.c) include; ``StopRules`` keeps their memory (entered,
touched) for a run and its checkpoints.
"""

from __future__ import annotations

import ctypes
from dataclasses import asdict, dataclass

import numpy as np

from fepen import native

#: the projectile is at rest (embedded) when ½ M |V|² falls to this fraction of the striking kinetic energy
STOP_ENERGY = 1e-5
#: ... or when its speed falls to END_SPEED (m/s): the end of the path (docs/theory.md §8.7, §11). At vanishing
#: speed the rate-independent law is no longer a function of the motion (σ_s, the static limit of the cavity
#: pressure, on whichever side of the nose the wandering motion turns to, against the tunnel's elastic wall): the
#: run ends there, short of the rest by at most END_SPEED² M / (2 F), F the nose's static axial force
#: (end_of_path: 0.024 mm for C3)
END_SPEED = 5.0


def stop_fraction(mass: float, ke0: float) -> float:
    """The fraction of the striking kinetic energy at which a run ends embedded: STOP_ENERGY, or the kinetic
    energy ½ M END_SPEED² of the end of the path if larger (a shot striking slower than END_SPEED ends once in).

    Args:
        mass: the projectile's mass (kg). ke0: its striking kinetic energy (J).
    """
    return max(STOP_ENERGY, 0.5 * mass * END_SPEED * END_SPEED / ke0) if ke0 > 0.0 else STOP_ENERGY


def end_of_path(mass: float, force: float, speed: float = END_SPEED) -> float:
    """The most a run ended at ``speed`` is short of the rest (m): M v² / (2 F), the distance the body at v would
    still cover against at least the force F (the nose's static axial force, σ_s times the projected area of its
    loaded points: the inertial term only adds to it).

    Args:
        mass: the body's mass (kg). force: F (N). speed: v (m/s).
    """
    return mass * speed * speed / (2.0 * force)
#: a body off the rigid wall for this long after touching it has rebounded (s)
REBOUND_FREE_S = 20e-6


#: the outcomes of events_kernel.c's penetration_rule, by its return code: events_kernel.h's OUTCOME_ members
#: (None: OUTCOME_NONE, go on), checked against the header, name by name, when the kernel is loaded
OUTCOMES = (None, "perforated", "ricochet", "embedded")
native.shares("events", "OUTCOME_", [(f"OUTCOME_{(o or 'none').upper()}", 1) for o in OUTCOMES])


def penetration(y_min: float, y_max: float, v_cm: np.ndarray, axis: np.ndarray, mass: float, ke0: float,
                thickness: float | None, until_stopped: bool, entered: bool) -> tuple[str | None, bool]:
    """The penetration rules (perforated, ricochet, embedded) of events_kernel.c, their one home.

    Args:
        y_min, y_max: the load points' extent in y (m; the face is y = 0, the target below).
        v_cm, axis: the centre of mass's velocity (m/s) and the unit axis, tail to nose.
        mass, ke0: the projectile's mass (kg) and striking kinetic energy (J).
        thickness: the target's (m), None for semi-infinite.
        until_stopped: the run has no end time (only then is "embedded" an outcome).
        entered: whether some load point has been below the face before.

    Returns:
        (the outcome or None to go on, entered now).
    """
    flag = ctypes.c_int32(int(entered))
    v = np.ascontiguousarray(v_cm, dtype=np.float64)
    a = np.ascontiguousarray(axis, dtype=np.float64)
    code = native.kernel("events").penetration_outcome(
        float(y_min), float(y_max), v.ctypes.data, a.ctypes.data, float(mass), float(ke0),
        -1.0 if thickness is None else float(thickness), int(until_stopped), stop_fraction(mass, ke0),
        ctypes.byref(flag))
    return OUTCOMES[code], bool(flag.value)


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
        outcome, self.entered = penetration(y_min, y_max, v_cm, axis, mass, ke0, self.thickness, self.until_stopped,
                                            self.entered)
        return outcome

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
