"""The inputs of a test that nobody measured, as distributions (docs/uncertainty.md, "Paths as distributions"):
the striking yaw out of the plane of fire and the error of the recorded in-plane attack, the body's angular rates
at impact, the striking speed's and the obliquity's measurement errors, and the concrete's heterogeneity. Plain
numbers in, scene values out: no scene, no MPI.

Each default is declared with its source in docs/uncertainty.md; none was chosen by looking at Table 1's
outcomes (the recorded attacks are inputs: a member's in-plane attack is the recorded one plus its reading's
error)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["StrikingPrior", "PRIOR", "draw", "member_rng", "attack_in_plane"]


@dataclass(frozen=True)
class StrikingPrior:
    """The distributions of a shot's unmeasured inputs, each normal about the recorded value (zero where nothing
    was recorded) with these standard deviations.

    Attributes:
        yaw_deg: the yaw out of the plane of fire (deg), unrecorded: its mean 0.
        attack_error_deg: the recorded in-plane attack's reading error (deg).
        rate_rad_s: each of the pitch and the yaw rate at impact (rad/s).
        speed_fraction: the striking speed's error, a fraction of it.
        obliquity_error_deg: the obliquity's error (deg).
        concrete_cv: the concrete's heterogeneity (target.heterogeneity_cv; 0: none).
        concrete_length_m: its correlation length (target.heterogeneity_length, m).
    """

    yaw_deg: float
    attack_error_deg: float
    rate_rad_s: float
    speed_fraction: float
    obliquity_error_deg: float
    concrete_cv: float
    concrete_length_m: float

    @property
    def zero(self) -> bool:
        """Whether every distribution has no width (each member is the recorded shot)."""
        return not any((self.yaw_deg, self.attack_error_deg, self.rate_rad_s, self.speed_fraction,
                        self.obliquity_error_deg, self.concrete_cv))


#: fepen's defaults (docs/uncertainty.md names each one's source)
PRIOR = StrikingPrior(yaw_deg=0.49, attack_error_deg=0.05, rate_rad_s=0.0, speed_fraction=0.0,
                      obliquity_error_deg=0.05, concrete_cv=0.15, concrete_length_m=0.02)


def attack_in_plane(inplane_deg: float, out_deg: float) -> tuple[float, float]:
    """The attack and its plane (impact.attack_deg, impact.attack_plane_deg) of an attack whose components are
    inplane_deg in the plane of fire and out_deg across it (the plane 0 without attack)."""
    attack = math.hypot(inplane_deg, out_deg)
    return attack, math.degrees(math.atan2(out_deg, inplane_deg)) if attack > 0.0 else 0.0


def member_rng(seed: int, shot: str, member: int) -> np.random.Generator:
    """The generator of one member of one shot's ensemble: numpy's PCG64 from (seed, the shot's name, the member),
    so that a member's draw depends on nothing else (not the other shots, not the order, not the ranks)."""
    key = [int(seed), member, *shot.encode()]
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(key)))


def draw(prior: StrikingPrior, velocity: float, obliquity_deg: float, attack_deg: float,
         rng: np.random.Generator) -> dict:
    """One member's striking state and concrete: scene values by key.

    The in-plane attack is the recorded one plus its error, the yaw out of the plane is drawn about 0; together
    they are the attack impact.attack_deg in the plane impact.attack_plane_deg. The speed and the obliquity are
    the recorded ones plus their errors (the obliquity kept in [0, 89]); the concrete gets its own seed.

    Returns:
        {scene key: value}.
    """
    z = rng.standard_normal(6)
    attack, plane = attack_in_plane(attack_deg + prior.attack_error_deg * z[0], prior.yaw_deg * z[1])
    values = {"impact.velocity": velocity * (1.0 + prior.speed_fraction * z[2]),
              "impact.obliquity_deg": min(max(obliquity_deg + prior.obliquity_error_deg * z[3], 0.0), 89.0),
              "impact.attack_deg": attack, "impact.attack_plane_deg": plane,
              "impact.pitch_rate_rad_s": prior.rate_rad_s * z[4], "impact.yaw_rate_rad_s": prior.rate_rad_s * z[5]}
    values = {k: float(v) for k, v in values.items()}  # plain numbers (numpy 2's repr is np.float64(...))
    seed = int(rng.integers(0, 2**32 - 1))
    if prior.concrete_cv > 0.0:
        values.update({"target.heterogeneity_cv": prior.concrete_cv,
                       "target.heterogeneity_length": prior.concrete_length_m, "target.heterogeneity_seed": seed})
    return values
