"""How sensitive a single run's attitude is to the striking yaw nobody measured (docs/uncertainty.md, "A single
run's sensitivity"): two extra rigid shots of the same scene, the in-plane attack at ± the declared yaw's standard
deviation (fepen.stats.striking.PRIOR.yaw_deg) about the scene's, and the gain of the final axis on it. A run
stays one deterministic path; this says how far that path would move for the yaw a test does not record.

Printed by ``fepen run`` and kept in summary.json as ``attitude_sensitivity``: {"yaw_deg": δ,
"final_axis_angle_deg": [at −δ, at +δ], "nose_offset_mm": [...], "Hx_mm": [...], "gain_deg_per_deg": the
final axis's change over the attack's (2δ)}, or {"none": why} where the two shots could not run.
"""

from __future__ import annotations

import math

from fepen.errors import InputError, SimulationError
from fepen.stats import striking

__all__ = ["attitude", "perturbed", "line", "YAW_DEG"]

#: the half-step of the in-plane attack (deg): the declared unmeasured yaw's standard deviation
YAW_DEG = striking.PRIOR.yaw_deg


def perturbed(attack_deg: float, plane_deg: float, delta_deg: float) -> dict:
    """The attack and its plane with the in-plane component moved by delta_deg (the out-of-plane one kept).

    Returns:
        {"impact.attack_deg": ..., "impact.attack_plane_deg": ...}.
    """
    p = math.radians(plane_deg)
    attack, plane = striking.attack_in_plane(attack_deg * math.cos(p) + delta_deg, attack_deg * math.sin(p))
    return {"impact.attack_deg": attack, "impact.attack_plane_deg": plane}


def attitude(scene, delta_deg: float = YAW_DEG, built=None) -> dict:
    """The final axis, the nose offset and Hx of the scene's shot, rigid, at the in-plane attack ± delta_deg, and
    the final axis's gain (one process, no MPI: a caller on many ranks runs it on one and shares the result).

    Args:
        scene: a resolved Scene (any fidelity: the two shots are rigid, the rest of the scene the same).
        delta_deg: the half-step (deg, > 0).
        built: the scene's projectile when already built (fepen.api.run's: a CAD body is not read again).

    Returns:
        The summary's ``attitude_sensitivity`` (module docstring).
    """
    from fepen.runs import batch, shot

    a, p = float(scene.impact.attack_deg), float(scene.get("impact.attack_plane_deg") or 0.0)
    from fepen.scene import Scene

    given = {k: scene.get(k) for k in scene.explicit if k != "impact.shot"}  # a Table 1 shot's speed and angles,
    given.update({k: scene.get(k) for k in ("impact.velocity", "impact.obliquity_deg")})  # the attack moved below
    try:
        scenes = [Scene(given, {"effects.fidelity": "rigid", **perturbed(a, p, s * delta_deg)}) for s in (-1, 1)]
        shots = [shot.resolve(sc, toml=False, built=built) for sc in scenes]
    except InputError as err:
        return {"none": f"the rigid shots refuse the scene: {err}"}
    got = batch.summaries(shots, history=False)
    bad = [g for g in got if isinstance(g, (InputError, SimulationError))]
    if bad:
        return {"none": f"a rigid shot did not run: {bad[0]}"}
    axis = [float(g["final_axis_angle_deg"]) for g in got]
    return {"yaw_deg": float(delta_deg), "final_axis_angle_deg": axis,
            "nose_offset_mm": [float(g["nose_offset_mm"]) for g in got], "Hx_mm": [float(g["Hx_mm"]) for g in got],
            "outcome": [g["outcome"] for g in got], "gain_deg_per_deg": (axis[1] - axis[0]) / (2.0 * delta_deg)}


def line(summary: dict) -> str | None:
    """The line ``fepen run`` prints, or None without the block."""
    s = summary.get("attitude_sensitivity")
    if not s:
        return None
    if "none" in s:
        return f"attitude_sensitivity = none ({s['none']})"
    lo, hi = s["final_axis_angle_deg"]
    return (f"attitude_sensitivity = final axis {lo:.1f} to {hi:.1f} deg for the in-plane attack -/+ {s['yaw_deg']:g} "
            f"deg (gain {s['gain_deg_per_deg']:.2f} deg/deg; nose offset {s['nose_offset_mm'][0]:.0f} and "
            f"{s['nose_offset_mm'][1]:.0f} mm; rigid shots; the spread a test's unrecorded yaw gives, "
            f"docs/uncertainty.md)")
