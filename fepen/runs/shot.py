"""A scene resolved once into what a run reads: the built projectile, the target law, the placement, the
crater's inputs, the wear and erosion parameters, the end time and the output settings (a frozen ``Shot``).

``resolve(scene)`` is the only reader of the scene in fepen.runs: the rigid and the deformable run, the
deformable model and the outputs take a Shot. It builds the projectile once (a CAD file is imported once per
run) with fepen.runs.setup, the builders of every law and shape.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fepen.errors import InputError
from fepen.geometry.mass_rule import Built
from fepen.laws import target as tg
from fepen.laws import wear
from fepen.runs import probes as run_probes
from fepen.runs import setup, targets
from fepen.scene import to_toml

#: the longest a run without run.end_time may last (s): deformable, rigid
MAX_TIME = {"deformable": 5e-3, "rigid": 5e-2}


@dataclass(frozen=True)
class WearParameters:
    """The nose wear of both fidelities (docs/theory.md §14): interface friction μ, melt efficiency η, the
    enthalpy to melt a kilogram h (J/kg) and the steel's density (kg/m^3)."""

    friction: float
    efficiency: float
    enthalpy: float
    density: float
    distribution: str = "nose"  #: where the mass leaves: "nose" (the nose shortens) or "surface" (where heated)


@dataclass(frozen=True)
class ErosionParameters:
    """Element erosion (docs/theory.md §15): the strain and the step ratio that erode a cell."""

    strain: float | None
    step_ratio: float


@dataclass(frozen=True)
class OutputSettings:
    """What a run writes and how often (s of simulated time)."""

    history_interval: float
    output_interval: float
    fields: bool
    field_names: tuple[str, ...]
    checkpoint_interval: float
    acceleration_filter_hz: float
    figures: bool = True  #: run.figures: the PNG figures drawn
    acceleration_filter: str = "butterworth"  #: run.acceleration_filter: fepen.post.signals.FILTERS


@dataclass(frozen=True)
class SafetyThresholds:
    """The thresholds of the charge-safety criteria (fepen.laws.explosive; None: no threshold, no margin) and
    where each came from.

    Attributes:
        explosive: charge.explosive. density: the charge's (kg/m^3).
        values: {criterion: threshold or None} in fepen.laws.explosive.CRITERIA's order (Pa, Pa, J/m^2,
            W/m^2, m, m/s, g).
        sources: {criterion: "charge.safety.KEY" (the user's), the named explosive's source, or the charge
            law's yield stress}.
    """

    explosive: str
    density: float
    values: dict
    sources: dict


def safety_thresholds(scene) -> SafetyThresholds:
    """The charge-safety thresholds of a scene: each charge.safety.* key given, else the named explosive's
    (fepen/data/explosives.toml), else none; the strength's last resort the charge law's yield stress."""
    from fepen.data.explosives import EXPLOSIVES

    name = scene.charge.explosive
    entry = EXPLOSIVES[name]
    keys = {"strength": "strength", "tension": "tensile_strength", "friction_work": "friction_work",
            "friction_power": "friction_power", "gap": "gap", "closure_speed": "closure_speed",
            "acceleration_g": "acceleration_g"}
    values, sources = {}, {}
    for criterion, key in keys.items():
        given = scene.get(f"charge.safety.{key}")
        if given is not None:
            values[criterion], sources[criterion] = float(given), f"charge.safety.{key}"
        elif key in entry:
            values[criterion] = float(entry[key])
            sources[criterion] = f"{name}: " + entry.get(f"{key}_source", entry["source"])
        else:
            values[criterion], sources[criterion] = None, "none given"
    if values["strength"] is None:
        values["strength"] = float(scene.charge.material.yield_stress)
        sources["strength"] = "the charge law's yield stress (charge.material.yield_stress): the onset of damage"
    return SafetyThresholds(name, float(scene.charge.material.density), values, sources)


@dataclass(frozen=True, eq=False)
class Shot:
    """One resolved shot.

    Attributes:
        fidelity: "rigid", "elastic" or "plastic".
        built: the projectile (fepen.geometry.shape.Built), built once.
        law: the target law (TargetLaw, or Layered), None on the rigid wall.
        target: the target's kind (fepen.runs.targets): what differs between a target of one material, a layered
            target and the rigid wall (the hard end, the tunnel, the layer crossings).
        rotation, velocity: the body's rotation about the nose tip (3x3) and its velocity at impact (3,).
        angular_velocity: the body's angular velocity at impact (3, rad/s, world).
        crh: the nose's calibre-radius-head (for Forrestal's linear crater).
        wear, erosion: their parameters, or None when off.
        end_time: run.end_time (s) or None (until a stop rule fires).
        hard_end: the time the run ends at the latest (s).
        failure_strain: projectile.failure_strain or None.
        outputs: OutputSettings.
        mesh: the volume mesh asked for (fepen.runs.setup.MeshRequest).
        materials: the deformable fidelities' materials (fepen.laws.materials), shell first; () when rigid.
        safety_factor, stable_step: the explicit step's safety factor and estimate ("eigenvalue", "altitude").
        charge_friction: the shell-charge friction coefficient.
        rigid_step: run.rigid_step or None.
        tunnel: effects.tunnel in a target of one material: the run keeps the tunnel the projectile opens
            (fepen.laws.tunnel).
        load_points: target.load_points, where a deformable run evaluates the target law: "facets" or "nodes".
        nominal_diameter: projectile.diameter (m), which the rigid step has always been sized on (a drawn profile's
            or a CAD body's own calibre may differ from it).
        experiment: the Table 1 shot's name (impact.shot) or None.
        scene: the resolved scene as a dict (summary.json's "scene"); scene_toml: as scene.toml (the given keys).
        body_key: what identifies the projectile (a sweep's shots share a body).
        probes: output.probes, the user's point and cell histories ({"name", "point", "kind"}, ...; each point
            checked inside the exact body: fepen.runs.probes.check_inside).
        envelope: what the validated envelope looks at (fepen.runs.setup.envelope_facts).
        inputs: what the shot was made of (inputs_record): the resolved scene, the files it read by content and
            their digest, recorded in run.json and in every checkpoint (a resume compares its own with it).
        safety: the charge-safety thresholds (SafetyThresholds) of a deformable charged shot, else None.
    """

    fidelity: str
    built: Built
    law: object
    target: targets.TargetKind
    rotation: np.ndarray
    velocity: np.ndarray
    crh: float
    wear: WearParameters | None
    erosion: ErosionParameters | None
    end_time: float | None
    hard_end: float
    failure_strain: float | None
    outputs: OutputSettings
    mesh: setup.MeshRequest
    materials: tuple
    safety_factor: float
    stable_step: str
    charge_friction: float
    rigid_step: float | None
    nominal_diameter: float
    experiment: str | None
    scene: dict = field(repr=False)
    body_key: tuple = field(repr=False, default=())
    scene_toml: str = field(repr=False, default="")
    probes: tuple = ()
    tunnel: bool = False
    load_points: str = "facets"
    envelope: dict = field(repr=False, default_factory=dict)
    inputs: dict = field(repr=False, default_factory=dict)
    safety: SafetyThresholds | None = None
    angular_velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))

    @property
    def rigid(self) -> bool:
        return self.fidelity == "rigid"

    @property
    def speed(self) -> float:
        """The striking speed (m/s)."""
        return float(np.linalg.norm(self.velocity))

    def crater(self, mass: float) -> tg.ForrestalCrater | None:
        """Forrestal's linear crater for a projectile of ``mass`` (kg) when effects.crater = "linear", else None
        (the energy crater is in the law)."""
        return self.target.crater(self.law, mass, self.speed, self.crh, self.built.shape.crater_nose_factor())



def _hard_end(target: targets.TargetKind, law, end_time: float | None, speed: float, kind: str) -> float:
    """run.end_time, else MAX_TIME as the target's kind lengthens it (a layered target's: to reach its last
    face)."""
    if end_time is not None:
        return end_time
    return target.hard_end(law, MAX_TIME[kind], speed)


def _wear(scene) -> WearParameters | None:
    if not scene.effects.wear:
        return None
    m, w = scene.projectile.material, scene.projectile.wear
    mu = scene.get("projectile.wear.friction")
    return WearParameters(scene.target.friction if mu is None else mu, w.efficiency,
                          wear.melt_enthalpy(m.specific_heat, m.melt_temperature, m.room_temperature, w.latent_heat),
                          m.density, w.distribution)


#: the stress tensor's six fields (run.stress_tensor_fields), in the order of the solver's stress columns
#: (fepen.solver.diagnostics.stress_fields)
STRESS_TENSOR_FIELDS = tuple(f"stress_{c}_Pa" for c in ("xx", "yy", "zz", "xy", "yz", "xz"))


def _outputs(scene) -> OutputSettings:
    r = scene.run
    names = ["von_mises_Pa", "axial_stress_Pa", "pressure_Pa", "triaxiality"]
    if scene.get("run.stress_tensor_fields"):  # asked for: six more cell fields
        names += STRESS_TENSOR_FIELDS
    # fields of switched-off physics are not written
    if scene.effects.fidelity == "plastic":
        names.append("peeq")
        if scene.effects.thermal:
            names.append("temperature_K")
    names.append("cell_tag")  # 1 shell, 2 charge, 0 eroded: for ParaView's Threshold
    return OutputSettings(min(r.output_interval / 10.0, 1e-6), r.output_interval, bool(r.fields), tuple(names),
                          r.checkpoint_interval, r.acceleration_filter_hz, bool(r.figures), r.acceleration_filter)


def resolve(scene, toml: bool = True, built: Built | None = None) -> Shot:
    """The Shot of a resolved Scene (InputError on what this version cannot simulate, before any mesh).

    Args:
        scene: a resolved fepen.Scene.
        toml: False leaves scene_toml empty, for a shot that writes no results directory (fepen.runs.batch:
            the text costs a rigid shot's set-up a third).
        built: the scene's projectile when already built (another shot of the same projectile: a CAD body is
            read once).

    Returns:
        The frozen Shot.
    """
    built = setup.check_supported(scene, built)
    rigid = scene.effects.fidelity == "rigid"
    target = targets.of(scene)
    law = target.law(scene)  # a rigid wall's: None
    R, v, w = setup.placement(scene)
    end = scene.get("run.end_time")
    materials = () if rigid else tuple(setup.materials(scene, built))
    from fepen.runs import budget

    hard_end = _hard_end(target, law, end, float(np.linalg.norm(v)), "rigid" if rigid else "deformable")
    if not rigid:
        budget.check_outputs(hard_end, scene.run.output_interval,
                             bool(scene.run.fields), scene.run.checkpoint_interval)
    else:
        budget.check_rigid_step(scene.get("run.rigid_step"), built.shape, built.shell_density,
                                float(np.linalg.norm(v)), law, end)
    e = scene.projectile.erosion
    probes = tuple(scene.get("output.probes") or ())
    run_probes.check_inside(built.shape, probes, scene.effects.charge)
    return Shot(
        fidelity=scene.effects.fidelity, built=built, law=law, target=target, rotation=R, velocity=v,
        angular_velocity=w,
        crh=scene.projectile.crh,
        wear=_wear(scene), erosion=ErosionParameters(e.strain, e.step_ratio) if scene.effects.erosion else None,
        end_time=end, hard_end=hard_end,
        failure_strain=scene.get("projectile.failure_strain"), outputs=_outputs(scene), mesh=setup.mesh_request(scene),
        materials=materials, safety_factor=scene.run.safety_factor, stable_step=scene.run.stable_step,
        charge_friction=scene.charge.friction, rigid_step=scene.get("run.rigid_step"),
        nominal_diameter=scene.projectile.diameter,
        experiment=scene.get("impact.shot"), scene=scene.as_dict(), body_key=setup.body_key(scene),
        scene_toml=to_toml(scene) if toml else "", probes=probes, envelope=setup.envelope_facts(scene, built),
        tunnel=target.tunnel(scene),
        load_points=_load_points(scene),
        inputs=inputs_record(scene) if toml else {},
        safety=safety_thresholds(scene) if scene.effects.charge and not rigid else None)


def _load_points(scene) -> str:
    """target.load_points, refused with effects that rework the facets as the run goes (erosion exposes new
    ones, the deformable wear recedes them by their own forces)."""
    points = scene.target.load_points
    if points == "nodes" and scene.effects.fidelity != "rigid":
        for key in ("erosion", "wear"):
            if getattr(scene.effects, key):
                raise InputError("target.load_points", f"'nodes' does not run with effects.{key} = true (it "
                                                       "reworks the surface's facets as the run goes): 'facets'")
    return points


def inputs_record(scene) -> dict:
    """What a shot is made of, for run.json and its checkpoints: ``scene`` (every resolved key, flat), ``files``
    ({path: SHA-256} of every file the projectile was read from: projectile.cad, .profile, .inner_profile) and
    ``sha256``, the digest of both."""
    import hashlib
    import json
    import os

    from fepen.atomic import sha256_file
    from fepen.scene import flatten

    flat = flatten(scene.as_dict())
    read = {}
    for key in setup.FILE_KEYS:
        path = scene.get(key)
        if path:
            path = os.path.abspath(path)
            try:
                read[path] = sha256_file(path)
            except OSError as err:
                from fepen.errors import InputError

                raise InputError(key, f"cannot be read: {err.strerror or err} ({path})") from None
    blob = json.dumps({"scene": flat, "files": read}, sort_keys=True, default=repr)
    return {"sha256": hashlib.sha256(blob.encode()).hexdigest(), "scene": flat, "given": sorted(scene.explicit),
            "files": read}


def inputs_changed(recorded: dict | None, now: dict) -> str | None:
    """What differs between a run's recorded inputs (inputs_record) and a resume's, in one phrase; None when the
    same (or nothing was recorded: a run of an earlier fepen)."""
    if not recorded or recorded.get("sha256") == now.get("sha256"):
        return None
    from fepen.scene.keys import shown

    before, after = recorded.get("scene") or {}, now.get("scene") or {}
    given = set(recorded.get("given") or ()) | set(now.get("given") or ())
    keys = sorted((k for k in set(before) | set(after) if before.get(k) != after.get(k)),
                  key=lambda k: (k not in given, k))  # the keys a user gives first, what follows from them after
    parts = [f"{k} {shown(before.get(k, 'absent'))} -> {shown(after.get(k, 'absent'))}" for k in keys[:3]]
    parts += [f"{len(keys) - 3} more keys"] if len(keys) > 3 else []
    old_files, new_files = recorded.get("files") or {}, now.get("files") or {}
    parts += [f"{path} changed since the run began" for path in sorted(set(old_files) | set(new_files))
              if old_files.get(path) != new_files.get(path)][:2]
    return "; ".join(parts) or "the inputs' digest differs"


def of(shot_or_scene) -> Shot:
    """A Shot as it is, or a Scene resolved (the runs take either)."""
    return shot_or_scene if isinstance(shot_or_scene, Shot) else resolve(shot_or_scene)


def rigid_version(scene) -> Shot:
    """The Shot of the same scene with the rigid projectile and no erosion (the progress bar's expected end)."""
    return resolve(scene.with_sets(["effects.fidelity=rigid", "effects.erosion=false"]))
