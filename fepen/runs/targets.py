"""The target's kinds (docs/theory.md §8, §16, §17), each a class answering the same questions, so that no
caller asks which kind it holds: a cavity-expansion target of one material (concrete, rock, soil or metal:
fepen.laws.target.TargetLaw), a layered target (target.layers: fepen.laws.layers.Layered) and the rigid wall
(target.kind = "rigid-wall", no law: a Taylor test). Each gives its law, its checks, the plates whose
thickness the nose is compared to, its name in the validated envelope, the run's hard end, whether the tunnel
applies, and the layer crossings. ``of(scene)`` is the one place that reads target.kind and target.layers to
choose; the builders of the laws (target_law, material_law, strength_field) and check_friction live here too
(fepen.runs.setup names them).
"""

from __future__ import annotations

import math

from fepen.data import CONSTANTS, TARGETS
from fepen.errors import InputError
from fepen.laws import layers as fl
from fepen.laws import target as tg
from fepen.scene import SCHEMA

__all__ = ["TargetKind", "SingleTarget", "LayeredTarget", "RigidWall", "KINDS", "of", "target_law",
           "material_law", "strength_field", "check_friction"]


class TargetKind:
    """What every target kind answers; the defaults are those of a target without layers."""

    #: the target's name in the validated envelope (fepen.stats.envelope), when not its material's
    name = ""

    def __eq__(self, other) -> bool:  # stateless: one kind equals its copy (a Shot sent to another process)
        return type(other) is type(self) and other.name == self.name

    def __hash__(self) -> int:
        return hash((type(self).__name__, self.name))

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.name!r})"

    def law(self, scene):
        """The target's law for the run: a TargetLaw, a Layered target, or None (a rigid wall)."""
        raise NotImplementedError

    def check(self, scene) -> None:
        """InputError for what this version cannot simulate against this target (before anything is meshed):
        effects.friction with the calibrated strength (check_friction)."""
        check_friction(scene)

    def plates(self, scene) -> list[tuple[str, float | None]]:
        """(key, thickness (m) or None: semi-infinite) of every plate the nose's length is compared to
        (fepen.runs.setup.thin_target_note)."""
        return [("target.thickness", scene.get("target.thickness"))]

    def envelope_name(self, scene) -> str:
        """The target as the validated envelope names it (fepen.runs.setup.envelope_facts)."""
        return self.name or scene.target.material

    def hard_end(self, law, default: float, speed: float) -> float:
        """The latest a run without run.end_time lasts (s).

        Args:
            law: this kind's law. default: fepen.runs.shot.MAX_TIME of the fidelity (s). speed: the striking
                speed (m/s).

        Returns:
            The hard end (s): the default."""
        return default

    def tunnel(self, scene) -> bool:
        """Whether the tunnel the projectile opens loads it (docs/theory.md §8.7): effects.tunnel."""
        return bool(scene.effects.tunnel)

    def crossings(self, law) -> fl.Crossings | None:
        """The record of the layers' entries and exits of a run (None: no layers)."""
        return None

    def not_batched(self) -> str | None:
        """Why a rigid shot into this target cannot go in a batch (fepen.runs.batch), or None: it can."""
        return None

    def takes_rigid(self) -> bool:
        """Whether the rigid fidelity runs against this target (a deformable run's progress bar previews its end
        by the rigid shot)."""
        return True

    def thickness(self, law) -> float | None:
        """The target's depth to its last rear face (m; None: semi-infinite), for the perforation rule."""
        return law.thickness

    def splits_load(self) -> bool:
        """Whether the history splits the target's load by zone (nose, shank, tail: fepen.io.columns.LOADS)."""
        return True

    def crater(self, law, mass: float, speed: float, crh: float, nose_factor: float):
        """Forrestal's linear crater (fepen.laws.target.ForrestalCrater) when the law asks for it
        (effects.crater = "linear"), else None (the energy crater is in the law)."""
        if law.crater != "linear":
            return None
        return tg.ForrestalCrater(law, mass, speed, crh, nose_factor)

    def load(self, solver, pm, sh, tip: int, tail: int):
        """The deformable model's load of this target on ``solver`` (fepen.solver.target_load.TargetLoad on the
        outer surface's load points) and that surface: (surface, load).

        Args:
            solver: the ExplicitSolver. pm: the meshed projectile. sh: the Shot. tip, tail: their nodes.
        """
        from fepen.solver import surface, target_load

        surf = surface.outer_surface(solver.V, pm.facet_tags, pm.shape)
        return surf, target_load.TargetLoad(solver, surf, sh.law, tip, tail, sh.crater(solver.total_mass),
                                            sh.tunnel, sh.load_points)

    def no_public_errors(self, scene) -> str | None:
        """Why fepen's errors on public data (fepen.stats.interval) do not apply to this target, or None: they
        do, by its strength model."""
        return None

    def striking_prior(self, prior):
        """The prior of what a test does not record (fepen.stats.striking.Prior) for shots into this target:
        the concrete's random field (concrete_cv) lives in one concrete only."""
        from dataclasses import replace

        return replace(prior, concrete_cv=0.0)


class SingleTarget(TargetKind):
    """A cavity-expansion target of one material (target.kind = "concrete" without target.layers)."""

    def striking_prior(self, prior):
        """The prior as it is: the random field is this concrete's."""
        return prior

    def law(self, scene) -> tg.TargetLaw:
        """The TargetLaw of target.material with the scene's constants."""
        c = {k: scene.get(f"target.{k}") for k in CONSTANTS}
        c["fc_cylinder"] = scene.derived["target.fc_cylinder"]
        c["crater"] = scene.effects.crater
        c["family"] = TARGETS[scene.target.material]["family"]
        return material_law(scene, c, scene.get("target.thickness"))


class LayeredTarget(TargetKind):
    """Layers of target materials one behind the other, with air gaps (target.layers; docs/theory.md §17)."""

    name = "layered"

    def law(self, scene) -> fl.Layered:
        """The Layered target of target.layers, each layer's TargetLaw of its own material."""
        fc = scene.derived["target.fc_cylinder"]
        layers = [{**c, "fc_cylinder": f} for c, f in zip(scene.get("target.layers"), fc)]
        return fl.build(layers, lambda c: material_law(scene, c, c.get("thickness")))

    def plates(self, scene) -> list[tuple[str, float | None]]:
        """Every layer's thickness."""
        return [(f"target.layers[{i}].thickness", layer.get("thickness"))
                for i, layer in enumerate(scene.get("target.layers"))]

    def hard_end(self, law: fl.Layered, default: float, speed: float) -> float:
        """Long enough to reach the last face (fepen.laws.layers.Layered.hard_end)."""
        return law.hard_end(default, speed)

    def tunnel(self, scene) -> bool:
        """No tunnel: the layers go layer by layer."""
        return False

    def crossings(self, law: fl.Layered) -> fl.Crossings:
        """Each layer's entry and exit (fepen.laws.layers.Layered.crossings)."""
        return law.crossings()

    def not_batched(self) -> str:
        return "a layered target"


class RigidWall(TargetKind):
    """The rigid wall of a Taylor test (target.kind = "rigid-wall"): no law, the deformable fidelities only.

    Args:
        name: its name in the validated envelope ("a rigid wall"; "layered" when target.layers are given
            beside it, as fepen always named it).
    """

    def __init__(self, name: str = "a rigid wall"):
        self.name = name

    def law(self, scene) -> None:
        """None: the penalty wall of the deformable model (fepen.solver.rigid_wall) stands in for a law."""
        return None

    def takes_rigid(self) -> bool:
        """No: a rigid projectile on a rigid wall has nothing to compute."""
        return False

    def thickness(self, law) -> None:
        """A wall is not perforated."""
        return None

    def splits_load(self) -> bool:
        """A wall's load has no zones."""
        return False

    def crater(self, law, mass: float, speed: float, crh: float, nose_factor: float) -> None:
        """No crater in a wall."""
        return None

    def load(self, solver, pm, sh, tip: int, tail: int):
        """The penalty wall y = 0 on the nodes (fepen.solver.rigid_wall.RigidWall), no load surface."""
        from fepen.solver import rigid_wall

        return None, rigid_wall.RigidWall(solver)

    def check(self, scene) -> None:
        """Refuse the rigid fidelity (a rigid projectile on a rigid wall has nothing to compute)."""
        if scene.effects.fidelity == "rigid" and not self.takes_rigid():
            raise InputError("effects.fidelity", "'rigid' runs against target.kind = 'concrete'; a rigid "
                                                 "projectile on a rigid wall has nothing to compute")

    def plates(self, scene) -> list[tuple[str, float | None]]:
        """None: a wall is not a plate the nose passes."""
        return []

    def tunnel(self, scene) -> bool:
        """No tunnel in a wall."""
        return False

    def not_batched(self) -> str:
        return "a rigid wall"

    def no_public_errors(self, scene) -> str:
        return f"no errors on public data for target.material = {scene.target.material!r}"


#: the kinds by (target.kind, whether target.layers are given)
KINDS = {("concrete", False): SingleTarget(), ("concrete", True): LayeredTarget(),
         ("rigid-wall", False): RigidWall(), ("rigid-wall", True): RigidWall("layered")}


def of(scene, kind: str | None = None) -> TargetKind:
    """The target kind of a scene.

    Args:
        scene: a resolved Scene. kind: a target.kind to take instead of the scene's (target_law: "concrete").

    Returns:
        The TargetKind (one shared instance per kind: they hold no state).
    """
    return KINDS[kind or scene.target.kind, bool(scene.get("target.layers"))]


def target_law(scene):
    """The law of the scene's target material (docs/theory.md §8, §16, §17), whatever target.kind: a TargetLaw
    of target.material, or a Layered target of target.layers (the cavity-expansion kinds' law)."""
    return of(scene, "concrete").law(scene)


def material_law(scene, c: dict, thickness: float | None) -> tg.TargetLaw:
    """The TargetLaw of one target material's constants ``c`` (target.* names without the prefix, absent ones
    None or missing, plus "crater", "family" and "fc_cylinder", Scene.derived's strength), with the scene's
    effects, friction and separation.

    Families (fepen/data/targets.toml): concrete, rock and soil by the Mohr–Coulomb cavity expansion (σ_s by
    target.strength_model), metal by Forrestal–Warren's power-law cavity expansion (fepen.laws.target.
    metal_cavity_stress)."""
    t, e = scene.target, scene.effects
    get = c.get
    B = get("inertial_factor") if get("inertial_factor") is not None else SCHEMA["target.inertial_factor"].default
    lock = get("lock_density") or SCHEMA["target.lock_density"].default
    k = get("crater_depth_factor") if get("crater_depth_factor") is not None else SCHEMA[
        "target.crater_depth_factor"].default
    given = get("quasi_static_stress")
    model = get("strength_model")
    if c.get("family") == "metal":
        Y, E, n = get("yield_stress"), get("youngs_modulus"), get("hardening_exponent")
        sigma_s = given if given is not None else tg.metal_cavity_stress(E, Y, n)
        T, lam, ca, crush, density = Y, 0.0, tg.metal_cavity_ratio(E, Y), 0.0, get("density")
        given_flag = True
    else:
        Y = get("fc_cylinder")  # the compressive strength on the cylinder basis (Scene.derived)
        T, lam = get("tensile_strength"), get("pressure_hardening")
        E = get("youngs_modulus") or tg.youngs_modulus_aci(Y)
        density = get("density")
        if given is not None:
            sigma_s = given
        elif model in tg.S_MODELS:
            a, b, size = tg.S_MODELS[model]
            if model == "scaled-S" and e.wear:  # refitted with the calibrated wear on (docs/wear.md §2)
                a, b, size = tg.SCALED_S_WEAR
            a = get("S_coefficient") or a
            b = get("S_exponent") if get("S_exponent") is not None else b
            size = get("S_size") or size
            sigma_s = tg.strength_S(Y, scene.projectile.diameter, a, b, size) * Y
        else:
            sigma_s = float(tg.quasi_static_stress(Y, E, T, lam))
        ca, crush = tg.cavity_ratio(Y, E, T), get("crush_strain") or 1.0 - density / lock
        given_flag = given is not None or model != "cavity-expansion"
    factor = scene.get("target.resistance_factor")  # the whole normal stress σ_s + B ρ (v·n)² times it
    if factor != 1.0:
        sigma_s, B, given_flag = sigma_s * factor, B * factor, True  # given: the free face scales it (§8.3)
    return tg.TargetLaw(
        density=density, Y=Y, E=E, T=T, lam=lam, sigma_s=sigma_s, B=B,
        thickness=thickness, crater=get("crater"), k=k,
        D=scene.projectile.diameter, separation=e.separation,
        phi_min=math.radians(get("separation_angle_deg") if get("separation_angle_deg") is not None
                             else t.separation_angle_deg),
        free_surface=e.free_surface, friction=e.friction, mu=t.friction,
        mu_dynamic=scene.get("target.friction_dynamic"), mu_decay=t.friction_decay,
        lock_density=lock, crush_strain=crush, c_over_a=ca, given_sigma_s=given_flag,
        surface_range=get("free_surface_range") or SCHEMA["target.free_surface_range"].default,
        wall_shear2=tg.wall_modulus(E, tg.WALL_POISSON.get(c.get("family"), tg.WALL_POISSON_DEFAULT),
                                    1.0 if c.get("family") == "metal" else ca),
        reload=scene.get("target.tunnel_reload") if scene.get("target.tunnel_reload") is not None else (
            1.0 if c.get("family") == "metal" else tg.reload_fraction(Y, lam, ca)),
        **strength_field(scene))


def strength_field(scene) -> dict:
    """The TargetLaw's random field on σ_s (docs/theory.md §8.8) of target.heterogeneity_*: none at cv 0."""
    cv = scene.get("target.heterogeneity_cv")
    if not cv > 0.0:
        return {}
    return {"field_sigma": tg.field_log_sigma(cv),
            "field_modes": tg.random_field_modes(scene.get("target.heterogeneity_seed"),
                                                 scene.get("target.heterogeneity_length"))}


def check_friction(scene) -> None:
    """Refuse effects.friction with the calibrated scaled-S strength and no constants of the user's own
    (InputError on effects.friction): its σ_s was fitted to depths that contain the interface's resistance, so
    friction on top counts it twice, and the friction refit predated the separation angle, the free face and
    the tunnel (it drove C3 37 % too deep); docs/theory.md §8.1."""
    t = scene.target
    if scene.effects.friction and t.strength_model == "scaled-S" and not scene.get("target.S_coefficient") \
            and scene.get("target.quasi_static_stress") is None:
        raise InputError("effects.friction", "true needs a strength fitted with friction on: give target.S_coefficient "
                                             "and target.S_size (refit: fepen study calibration --set "
                                             "effects.friction=true), target.quasi_static_stress, or another "
                                             "target.strength_model (the scaled-S constants have friction's share "
                                             "in sigma_s; docs/theory.md 8.1)")
