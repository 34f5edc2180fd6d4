"""``SCHEMA``: every scene key declared once, dotted name -> :class:`~fepen.scene.keys.Key` (type, default,
unit, allowed range; docs/scenes.md). Nothing else is accepted.

Defaults are the paper's projectile (45 steel, D = 23.6 mm, L = 144 mm, 367 g), its concrete target
(Table 3) and the striking conditions of Table 1 shot C3. The choices the paper leaves open (nose CRH,
cavity, tensile strength, ...) are explained in docs/theory.md.
"""

from __future__ import annotations

from fepen.data import CONSTANTS, EXPLOSIVES, FAMILIES, SHOTS, STEELS, TARGETS, shot
from fepen.errors import InputError
from fepen.scene.keys import (
    ABSENT,
    Key,
    check_layers,
    check_sections,
    choice,
    display_name,
    finite,
    flag,
    number,
    positive,
    shown,
)

__all__ = ["SCHEMA", "SECTIONS", "LAYER_KEYS", "LAYER_FIELDS", "PROBE_FIELDS", "PROBES_MAX", "PROBE_NAME_MAX",
           "REMOVED"]

#: keys an earlier fepen had and this one refuses, each with why (CHANGELOG): a scene that gives one is told so
#: in one line, not "unknown key"
REMOVED = {
    "target.onset_speed": "removed in fepen 0.6: the nose carries sigma_s at any speed into the target (its static "
                          "limit) and the tunnel's wall is elastic, neither a ramp over the speed (docs/theory.md "
                          "§8.7); drop the key",
    "target.onset_angle_deg": "removed in fepen 0.6: it changed nothing beside the separation angle "
                              "(target.separation_angle_deg), which unloads grazing points; drop the key",
}


def _layers(key: Key, name: str, value) -> list:
    """target.layers' rows: each table's keys checked as LAYER_FIELDS declares them."""
    return check_layers(key, name, value, LAYER_FIELDS)


#: the most [[output.probes]] a scene holds: each is a history of every row in probes.csv (100 probes of a rigid
#: shot: about 4 MB of it, 1,000: 41 MB, 10,000: 412 MB and 42 s); the whole body's histories are in fields.xdmf
PROBES_MAX = 100
#: the longest probe name (characters): it starts each of its columns' names in probes.csv
PROBE_NAME_MAX = 64


def _probes(key: Key, name: str, value) -> list:
    """output.probes' rows: at most PROBES_MAX tables, each one's name (unique, at most PROBE_NAME_MAX letters,
    digits, '_' or '-'), point ([x, y, z], m) and kind ('node', 'cell' or 'accelerometer', default 'node');
    unknown keys refused.

    Args:
        key: the list key (for its allowed form). name: the key's name. value: what the user gave.

    Returns:
        The rows as {"name": str, "point": [x, y, z], "kind": str}.
    """
    if not isinstance(value, list) or not value or not all(isinstance(v, dict) for v in value):
        raise InputError(name, f"got {shown(value)}, expected {key.allowed()} ([[output.probes]] in TOML)")
    if len(value) > PROBES_MAX:
        raise InputError(name, f"{len(value)} probes: a scene holds at most {PROBES_MAX} (each is a history of every "
                               "row in probes.csv; fields.xdmf holds the whole body's)")
    out, seen = [], set()
    for i, table in enumerate(value):
        here = f"{name}[{i}]"
        for k in table:
            if k not in PROBE_FIELDS:
                raise InputError(f"{here}.{display_name(k)}", f"unknown key (allowed: {', '.join(PROBE_FIELDS)})")
        label, point = table.get("name"), table.get("point")
        if (not isinstance(label, str) or not label or len(label) > PROBE_NAME_MAX
                or not all(c.isascii() and (c.isalnum() or c in "_-") for c in label)):
            raise InputError(f"{here}.name", f"got {shown(label)}, expected a name of at most {PROBE_NAME_MAX} "
                                             "letters, digits, '_' or '-' (it starts the probe's column names in "
                                             "probes.csv)")
        if label in seen:
            raise InputError(f"{here}.name", f"{label!r} is given twice: each probe needs its own name")
        seen.add(label)
        if (not isinstance(point, list) or len(point) != 3
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and finite(v) for v in point)):
            raise InputError(f"{here}.point", f"got {shown(point)}, expected [x, y, z] in metres in the undeformed "
                                              "projectile's frame (nose tip at the origin, axis +y)")
        kind = PROBE_FIELDS["kind"].check(f"{here}.kind", table.get("kind", "node"))
        out.append({"name": label, "point": [float(v) for v in point], "kind": kind})
    return out


_C3 = shot("C3")

#: Every scene key, dotted name -> Key. Units are SI. ``ABSENT`` defaults are optional keys whose absence
#: has a meaning given in their doc.
SCHEMA: dict[str, Key] = {
    # --- projectile geometry (docs/theory.md, "The projectile") ---
    "projectile.nose": choice("ogive", "ogive", "secant", "cone", "hemisphere", "ellipsoid", "flat", "profile",
                              doc="tangent or secant ogive, cone, hemisphere, ellipsoid, flat (a plain cylinder), "
                                  "or a drawn profile (projectile.profile); docs/projectiles-and-targets.md"),
    "projectile.nose_length": positive(ABSENT, "m", 10.0, doc="axial length of a secant ogive, cone or ellipsoid nose "
                                                              "(before any meplat)"),
    "projectile.meplat_diameter": number(0.0, "m", 0.0, 1.0, doc="flat blunt tip of an ogive, cone, hemisphere or "
                                                                  "ellipsoid nose; 0: pointed"),
    "projectile.boattail_length": number(0.0, "m", 0.0, 10.0, doc="tapered rear; 0: none"),
    "projectile.boattail_diameter": positive(ABSENT, "m", 1.0, doc="rear-face diameter of the boat-tail"),
    "projectile.profile": Key(str, ABSENT, doc="CSV of the outer profile, rows z_m, r_m[, arc_radius_m] from the "
                                               "nose (projectile.nose = 'profile'; sets diameter and length)",
                              form="a file path (CSV)"),
    "projectile.inner_profile": Key(str, ABSENT, doc="CSV of the cavity profile, rows z_m, r_m[, arc_radius_m] "
                                                     "(a fixed cavity: the mass follows from it)",
                                    form="a file path (CSV)"),
    "projectile.cavity_sections": Key(list, ABSENT, doc="cavity as [[length_m, diameter_m], ...] front to rear; "
                                                        "the rear one's length is sized to projectile.mass",
                                      form="a list of [length, diameter] pairs in metres, each > 0",
                                      rows=check_sections),
    "projectile.cad": Key(str, ABSENT, doc="STEP or BREP file of the projectile body (axis +y, nose toward -y); "
                                           "meshed as is, mass from the mesh (docs/projectiles-and-targets.md)",
                          form="a file path (STEP or BREP)"),
    "projectile.cad_scale": positive(1.0, "m per file unit", 1.0e3, doc="lengths of projectile.cad times this are "
                                                                         "metres (0.001 for a file in mm)"),
    "projectile.diameter": number(0.0236, "m", 1.0e-3, 1.0, doc="calibre (fepen's laws are for 1 mm and more)"),
    "projectile.length": number(0.144, "m", 1.0e-3, 10.0, doc="overall length, nose tip to rear face (nose and "
                                                             "boat-tail included)"),
    "projectile.crh": number(3.0, "", 0.5, 50.0, doc="ogive radius over diameter (0.5: hemisphere)"),
    "projectile.mass": positive(0.367, "kg", 1.0e4,
                                doc="total mass; the cavity is sized, reduced or dropped to reach it (theory §1.1)"),
    "projectile.cavity_diameter": number(0.012, "m", 0.0, 1.0, doc="main (rear) cavity diameter; 0: solid"),
    "projectile.cavity_length": positive(ABSENT, "m", 10.0,
                                         doc="total cavity length; absent: sized from projectile.mass"),
    "projectile.cavity_step_diameter": number(0.008, "m", 0.0, 1.0,
                                              doc="diameter of the narrower forward cavity section (the step)"),
    "projectile.cavity_step_length": number(0.020, "m", 0.0, 10.0,
                                            doc="length of the narrower forward cavity section; 0: no step"),
    "projectile.base_thickness": positive(0.015, "m", 10.0, doc="solid rear wall behind the cavity"),
    # --- projectile material: 45 steel, Johnson-Cook (Table 2) ---
    "projectile.material.name": choice("45-steel", *STEELS, doc="a named steel of fepen/data/steels.toml: sets "
                                       "every projectile.material key not given explicitly (sources: "
                                       "docs/theory.md §4)"),
    "projectile.material.density": number(7850.0, "kg/m^3", 100.0, 30000.0,
                                          doc="density of the steel body (shell); with projectile.mass it sizes "
                                              "the cavity"),
    "projectile.material.youngs_modulus": number(210.0e9, "Pa", 1.0e6, 1.0e13,
                                                 doc="E of the steel (elastic and plastic fidelities; it sets "
                                                     "the stable time step)"),
    "projectile.material.poisson_ratio": number(0.3, "", 0.0, 0.5, hi_open=True, doc="nu of the steel"),
    "projectile.material.A": number(950.0e6, "Pa", 0.0, 1.0e11, lo_open=True,
                                    doc="Johnson-Cook yield stress at zero plastic strain: sigma_y = (A + B "
                                        "eps_p^n)(1 + C ln(rate/rate_0))(1 - T*^m) (plastic fidelity; "
                                        "docs/theory.md §4)"),
    "projectile.material.B": number(725.0e6, "Pa", 0.0, 1.0e11,
                                    doc="Johnson-Cook hardening modulus: the B of B eps_p^n"),
    "projectile.material.n": number(0.375, "", 0.0, 2.0, lo_open=True,
                                    doc="Johnson-Cook hardening exponent: the n of B eps_p^n"),
    "projectile.material.C": number(0.015, "", 0.0, 1.0,
                                    doc="Johnson-Cook strain-rate coefficient of 1 + C ln(rate/rate_0), the factor "
                                        "floored at 1 (effects.strain_rate)"),
    "projectile.material.m": number(0.625, "", 0.0, 10.0, lo_open=True,
                                    doc="Johnson-Cook thermal-softening exponent of 1 - T*^m, T* = (T - "
                                        "room_temperature)/(melt_temperature - room_temperature) in [0, 1] "
                                        "(effects.thermal)"),
    "projectile.material.melt_temperature": number(1765.0, "K", 0.0, 1.0e4, lo_open=True,
                                                   doc="T_melt of T* (no strength at it), and of the heat that "
                                                       "melts the surface under effects.wear"),
    "projectile.material.room_temperature": number(294.0, "K", 0.0, 1.0e4, lo_open=True,
                                                   doc="T_room of T*: the projectile's initial temperature"),
    "projectile.material.reference_strain_rate": positive(1.0, "1/s", 1.0e9,
                                                          doc="rate_0 of the rate term: no rate hardening "
                                                              "below it"),
    "projectile.material.specific_heat": positive(470.0, "J/(kg K)", 1.0e5,
                                                  doc="c_p of the adiabatic heating (effects.thermal) and of the "
                                                      "melt enthalpy of effects.wear"),
    "projectile.material.taylor_quinney": number(0.9, "", 0.0, 1.0,
                                                 doc="beta: the fraction of the plastic work turned into heat "
                                                     "(effects.thermal)"),
    "projectile.wear.efficiency": number(0.4431, "", 0.0, 1.0,
                                         doc="eta: the fraction of the interface heat that melts the surface off "
                                             "(effects.wear; docs/theory.md §14), calibrated once on the paper's "
                                             "recovered projectiles (docs/wear.md §2)"),
    "projectile.wear.friction": number(ABSENT, "", 0.0, 2.0,
                                       doc="mu of the interface heat mu sigma_n v_t (v_t the sliding speed); "
                                           "absent: target.friction"),
    "projectile.wear.distribution": choice("nose", "nose", "surface",
                                           doc="where the melted mass leaves: 'nose', the nose shortens along its "
                                               "axis keeping its kind (docs/theory.md §14.3); 'surface', each "
                                               "point recedes by its own heat (meshed projectile; the rigid "
                                               "fidelity then only loses mass)"),
    "projectile.wear.latent_heat": number(2.7e5, "J/kg", 0.0, 1.0e7, doc="latent heat of fusion of the steel"),
    "projectile.erosion.strain": number(1.0, "", 0.0, 100.0, lo_open=True,
                                        doc="equivalent plastic strain at which a cell erodes (effects.erosion; "
                                            "docs/theory.md §15)"),
    "projectile.erosion.step_ratio": number(0.1, "", 0.0, 1.0, hi_open=True,
                                            doc="a cell whose own stable step falls below this times the initial "
                                                "step erodes (effects.erosion; 0: never)"),
    "projectile.failure_strain": number(ABSENT, "", 0.0, 100.0, lo_open=True,
                                        doc="PEEQ at which a concrete-target run stops, beyond the method "
                                           "(docs/theory.md); absent: never (a mushrooming nose keeps running)"),
    # --- explosive charge (Table 4) ---
    "charge.material.density": number(1850.0, "kg/m^3", 100.0, 30000.0,
                                      doc="density of the explosive filling the cavity (effects.charge; Table 4)"),
    "charge.material.youngs_modulus": number(10.1e9, "Pa", 1.0e5, 1.0e13, doc="E of the charge"),
    "charge.material.poisson_ratio": number(0.3, "", 0.0, 0.5, hi_open=True, doc="nu of the charge"),
    "charge.material.yield_stress": positive(45.0e6, "Pa", 1.0e11,
                                             doc="sigma_0 of the charge's bilinear hardening sigma_y = sigma_0 + "
                                                 "H eps_p"),
    "charge.material.tangent_modulus": number(600.0e6, "Pa", 0.0, 1.0e12,
                                              doc="E_t, the slope of stress against total strain past yield: "
                                                  "H = E E_t/(E - E_t)"),
    "charge.friction": number(0.1, "", 0.0, 2.0, doc="Coulomb mu of the shell-charge interface (charge.contact "
                                                     "= 'frictional'; docs/theory.md §13)"),
    "charge.contact": choice("frictional", "frictional", "tied",
                             doc="the shell-charge interface: 'frictional', the charge has nodes of its own on "
                                 "the cavity wall, the interface opens and slides with Coulomb friction "
                                 "(charge.friction); 'tied', shell and charge share the wall's nodes (bonded)"),
    # --- the charge's safety (docs/charge.md, docs/theory.md §20) ---
    "charge.explosive": choice("paper-fill", *EXPLOSIVES,
                               doc="a named explosive of fepen/data/explosives.toml: the thresholds of the "
                                   "charge-safety criteria it gives (each charge.safety.* key overrides one)"),
    "charge.safety.strength": positive(ABSENT, "Pa", 1.0e11,
                                       doc="the equivalent stress at which the explosive's damage begins; absent: "
                                           "the named explosive's, else the charge law's yield stress"),
    "charge.safety.tensile_strength": positive(ABSENT, "Pa", 1.0e10,
                                               doc="the largest principal stress the charge bears in tension; "
                                                   "absent: the named explosive's (none: no margin)"),
    "charge.safety.friction_work": positive(ABSENT, "J/m^2", 1.0e12,
                                            doc="the friction work per unit area of the shell-charge interface "
                                                "that ignites the explosive; absent: the named explosive's "
                                                "(none: no margin)"),
    "charge.safety.friction_power": positive(ABSENT, "W/m^2", 1.0e16,
                                             doc="the friction power per unit area (mu p v) that ignites it; "
                                                 "absent: the named explosive's (none: no margin)"),
    "charge.safety.gap": positive(ABSENT, "m", 1.0,
                                  doc="the largest safe gap at the charge's ends; absent: the named explosive's "
                                      "(none: no margin)"),
    "charge.safety.closure_speed": positive(ABSENT, "m/s", 1.0e5,
                                            doc="the largest safe speed at which an end gap closes; absent: the "
                                                "named explosive's (none: no margin)"),
    "charge.safety.acceleration_g": positive(ABSENT, "g", 1.0e8,
                                             doc="the largest acceleration the charge survives (g); absent: the "
                                                 "named explosive's (none: no margin)"),
    # --- target (Table 3; the law: docs/paper.md §4) ---
    "target.kind": choice("concrete", "concrete", "rigid-wall",
                          doc="'concrete': a cavity-expansion target of target.material (or target.layers); "
                              "'rigid-wall': a Taylor test"),
    "target.material": choice("concrete", *TARGETS, doc="a named target of fepen/data/targets.toml: its law's "
                              "family and every target constant not given explicitly (docs/theory.md §16)"),
    "target.layers": Key(list, ABSENT, doc="[[target.layers]] tables front to back: material, thickness (m; "
                                           "absent on the last: semi-infinite), gap (m, the air gap after it), "
                                           "crater ('none' or 'energy'; absent: effects.crater when given, else "
                                           "the material's), and any target constant overriding the material's "
                                           "(docs/theory.md §17); absent: one target of target.material",
                         form="a list of tables {material, thickness, gap, ...}", rows=_layers),
    "target.yield_stress": positive(ABSENT, "Pa", 1.0e11, doc="Y of a metal target (strength_model 'metal')"),
    "target.hardening_exponent": number(ABSENT, "", 0.0, 1.0, hi_open=True,
                                        doc="n of a metal target's power-law hardening sigma = Y (E eps / Y)^n "
                                            "(strength_model 'metal')"),
    "target.compressive_strength": number(40.0e6, "Pa", 1.0e5, 1.0e10,
                                          doc="f_c, the unconfined compressive strength, on "
                                              "target.strength_basis (a cube value is converted); the default "
                                              "'concrete' gives 40 MPa on cubes (31.9 MPa cylinder)"),
    "target.strength_basis": choice("cylinder", "cylinder", "cube",
                                    doc="what compressive_strength was measured on: 'cylinder' (f_c, ACI/ASTM), "
                                        "or 'cube' (150 mm cubes, e.g. GB 50010 grades), converted to f_c by "
                                        "Eurocode 2 Table 3.1 (docs/theory.md §8.1)"),
    "target.density": number(2400.0, "kg/m^3", 100.0, 30000.0,
                             doc="rho of the target: the inertial term B rho (v.n)^2 of the normal stress and "
                                 "the energy crater (docs/theory.md §8.2-8.3); target.material's when not given"),
    "target.youngs_modulus": positive(ABSENT, "Pa", 1.0e13, doc="E of the target; absent: 4.7 sqrt(f_c / MPa) GPa "
                                                                       "(ACI 318, f_c the cylinder strength)"),
    "target.tensile_strength": positive(ABSENT, "Pa", 1.0e10, doc="f_t; absent: the cylinder f_c / 10"),
    "target.pressure_hardening": number(0.67, "", 0.0, 3.0, hi_open=True,
                                        doc="lambda of the Mohr-Coulomb shear strength Y + lambda p of the cavity "
                                            "expansion (its sigma_s, the plastic-zone ratio c/a)"),
    "target.crater_depth_factor": number(2.37, "", 0.0, 50.0,
                                         doc="k: the crater stage (effects.crater) reaches k projectile "
                                             "diameters deep ('linear': while the nose tip is shallower; "
                                             "'energy': on the surface points shallower)"),
    "target.strength_model": choice("scaled-S", "scaled-S", "forrestal-S", "cavity-expansion", "metal",
                                    doc="sigma_s = S fc with S = S_coefficient fc^-S_exponent / sqrt(1 + D/S_size) "
                                        "(fc in MPa): fepen's calibrated scaled-S or Forrestal's S = 82.6 "
                                        "fc^-0.544; or the paper's elastic-cracked-plastic cavity expansion; or "
                                        "'metal': Forrestal-Warren's power-law metal (yield_stress, "
                                        "hardening_exponent)"),
    "target.S_coefficient": positive(ABSENT, "", 1.0e4,
                                     doc="a of S = a (f_c/MPa)^-b / sqrt(1 + D/S_size), sigma_s = S f_c "
                                         "(strength_model 'scaled-S' or 'forrestal-S'); absent: the model's "
                                         "(scaled-S 134.1, with effects.wear 124.6; forrestal-S 82.6)"),
    "target.S_exponent": number(ABSENT, "", 0.0, 2.0, doc="b of S (above); absent: the strength model's 0.544"),
    "target.S_size": positive(ABSENT, "m", 1.0e6,
                              doc="D0 of S (above), Bazant's size effect in the projectile diameter D; absent: "
                                  "the model's (scaled-S 0.05404, with wear 0.06292; "
                                  "forrestal-S none)"),
    "target.quasi_static_stress": positive(ABSENT, "Pa", 1.0e11,
                                           doc="overrides the strength model's sigma_s; absent: computed"),
    "target.inertial_factor": number(1.0, "", 0.0, 10.0,
                                     doc="B of the normal stress sigma_n = sigma_s + B rho (v.n)^2 (v.n: the "
                                         "surface's speed into the target); metals 1.5"),
    "target.resistance_factor": number(1.0, "", 0.05, 20.0,
                                       doc="multiplies the normal stress sigma_n (sigma_s and B rho (v.n)^2) of "
                                           "every target material: the model's own error, as fepen study "
                                           "uncertainty draws it (docs/uncertainty.md); 1: the law as calibrated"),
    "target.friction": number(0.1, "", 0.0, 2.0, doc="Coulomb (static) coefficient, used when effects.friction"),
    "target.friction_dynamic": number(ABSENT, "", 0.0, 2.0,
                                      doc="mu_d of mu(v_t) = mu_d + (mu - mu_d) exp(-c v_t); absent: target.friction"),
    "target.friction_decay": number(0.0, "s/m", 0.0, 1.0e3, doc="c of the sliding law; 0: constant Coulomb mu"),
    "target.separation_angle_deg": number(0.0, "deg", 0.0, 90.0, hi_open=True,
                                          doc="phi_min of effects.separation: a surface point that meets its "
                                              "direction of motion at less than this angle (sin phi = v.n / speed "
                                              "<= sin phi_min) carries no load; 0: only points moving off the "
                                              "surface (v.n <= 0) are unloaded; the default target.material "
                                              "'concrete' gives 12 (calibrated; docs/theory.md §8.4)"),
    "target.thickness": positive(ABSENT, "m", 100.0,
                                 doc="slab thickness along the normal: the rear face at depth thickness (outcome "
                                     "'perforated' past it); absent: semi-infinite"),
    "target.lock_density": number(2650.0, "kg/m^3", 100.0, 30000.0,
                                  doc="Q1, density of fully compacted concrete (energy crater); rock: its "
                                      "grain density"),
    "target.crush_strain": number(ABSENT, "", 0.0, 1.0, lo_open=True,
                                  doc="epsilon of the energy crater's strength energy; absent: 1 - density / "
                                      "lock_density; the default 'concrete' gives 0.376 (calibrated)"),
    "target.load_points": choice("facets", "facets", "nodes",
                                 doc="where a deformable run evaluates the target law: 'facets', one point per "
                                     "outer facet on the exact surface, its force shared by the facet's nodes; "
                                     "'nodes', one per surface node (the paper's), a third of its facets' area; "
                                     "the rigid fidelity has its rings (docs/theory.md §8.5)"),
    "target.tunnel_reload": number(ABSENT, "", 0.0, 1.0, lo_open=True,
                                   doc="the tunnel wall's reload strength: the fraction of sigma_s that re-expands "
                                       "the cracked wall the nose left (effects.tunnel); absent: the cavity "
                                       "expansion with the comminuted ring's cohesion removed, 0.52 for the "
                                       "default concrete; a metal's 1 (docs/theory.md §8.7)"),
    "target.heterogeneity_cv": number(0.0, "", 0.0, 2.0,
                                      doc="the concrete's heterogeneity: the coefficient of variation of a "
                                          "lognormal random field of mean 1 on sigma_s, fixed in the target and "
                                          "seeded (target.heterogeneity_seed); 0: none (docs/theory.md §8.8)"),
    "target.heterogeneity_length": number(0.02, "m", 0.0, 10.0, lo_open=True,
                                          doc="the field's correlation length: its covariance exp(-r^2/(2 l^2)), "
                                              "of the order of the largest aggregate (docs/theory.md §8.8)"),
    "target.heterogeneity_seed": Key(int, 0, "", 0, 2**32 - 1,
                                     doc="the seed of the field's modes (numpy's PCG64): the same seed, the "
                                         "same concrete, on any rank count"),
    "target.free_surface_range": number(1.0, "", 0.0, 20.0, lo_open=True,
                                        doc="reach of the free face on sigma_s, in plastic-zone widths "
                                            "(effects.free_surface; docs/theory.md §8.4); the default "
                                            "'concrete' gives 2 (calibrated)"),
    # --- striking conditions (Table 1; defaults are shot C3) ---
    "impact.velocity": number(_C3.v0, "m/s", 0.0, 3000.0, lo_open=True,
                              doc="striking speed of the whole projectile when its nose tip touches the face at "
                                  "the impact point O, along impact.obliquity_deg"),
    "impact.obliquity_deg": number(_C3.obliquity_deg, "deg", 0.0, 90.0, hi_open=True,
                                   doc="angle of the velocity from the target's normal; the velocity is v (sin a, "
                                       "cos a) in the reported frame (x along the face, y depth; "
                                       "docs/results.md), so +x is the direction of travel along the face; 0: "
                                       "normal impact"),
    "impact.attack_deg": number(_C3.attack_deg, "deg", -90.0, 90.0, lo_open=True, hi_open=True,
                                doc="angle of attack: the projectile's axis from its velocity, in the same plane; "
                                    "positive turns the nose further from the normal, toward +x (the axis at "
                                    "obliquity + attack from the normal), negative back toward the normal "
                                    "(docs/theory.md §7)"),
    "impact.attack_plane_deg": number(0.0, "deg", -180.0, 180.0,
                                      doc="the plane of the angle of attack, about the velocity from the plane of "
                                          "fire: 0 turns the nose in the plane of fire toward +x (as "
                                          "impact.attack_deg says), 90 out of it toward +z, 180 back toward the "
                                          "normal (docs/theory.md §7)"),
    "impact.pitch_rate_rad_s": number(0.0, "rad/s", -1.0e4, 1.0e4,
                                      doc="the body's angular velocity at impact in the plane of fire (about z): "
                                          "positive turns the nose toward +x (docs/theory.md §7)"),
    "impact.yaw_rate_rad_s": number(0.0, "rad/s", -1.0e4, 1.0e4,
                                    doc="the body's angular velocity at impact out of the plane of fire: positive "
                                        "turns the nose toward +z (docs/theory.md §7)"),
    "impact.shot": Key(str, ABSENT, choices=tuple(SHOTS),
                       doc="a test of the paper's Table 1: sets the three above to the shot's and compares the "
                           "result with the test (summary.json experiment)"),
    # --- effects: what is off costs nothing ---
    "effects.fidelity": choice("plastic", "rigid", "elastic", "plastic",
                               doc="the projectile: 'rigid', a rigid body of revolution without a mesh (RK4, "
                                   "under a second a shot; docs/theory.md §9); 'elastic', a meshed deformable "
                                   "body, elastic (explicit dynamics); 'plastic', the same with Johnson-Cook "
                                   "plasticity (the paper's)"),
    "effects.crater": choice("energy", "none", "linear", "energy",
                             doc="the crater stage near the face (target.crater_depth_factor): 'none', the "
                                 "tunnel law from the face; 'linear', Forrestal's force rising linearly with "
                                 "depth; 'energy', the paper's splash streamline (the medium thrown out unloads "
                                 "the point); not given: the target material's ('none' for metals and soil; "
                                 "docs/theory.md §8.3)"),
    "effects.separation": flag(True, doc="flow separation: surface points meeting their motion at less than "
                                         "target.separation_angle_deg carry no load (docs/theory.md §8.4)"),
    "effects.tunnel": flag(True, doc="the tunnel the nose opens is kept: the body behind the nose is loaded only "
                                     "where it presses into the tunnel's wall (tail slap), whatever the "
                                     "separation angle; targets of one material (docs/theory.md §8.7)"),
    "effects.free_surface": flag(True, doc="the target's faces cut the cavity expansion's plastic zone: sigma_s "
                                           "falls toward the strength near a face (target.free_surface_range)"),
    "effects.friction": flag(False, doc="Coulomb friction of the target: shear target.friction sigma_n against "
                                        "the sliding velocity (with scaled-S only given target.S_coefficient and "
                                        "S_size fitted with friction: its own constants hold the interface's "
                                        "share; docs/theory.md §8.1, §8.4); off: frictionless"),
    "effects.wear": flag(False, doc="nose wear: the interface heat melts mass off the surface (rigid fidelity: "
                                    "the mass loss; deformable: the surface recedes; docs/theory.md §14)"),
    "effects.erosion": flag(False, doc="element erosion of the meshed projectile: cells past projectile.erosion.* "
                                       "are removed, the faces they expose loaded (docs/theory.md §15)"),
    "effects.thermal": flag(True, doc="plastic fidelity: adiabatic heating (taylor_quinney) and Johnson-Cook's "
                                      "thermal softening 1 - T*^m, the temperature_K field; off: the projectile "
                                      "stays at room_temperature"),
    "effects.strain_rate": flag(True, doc="plastic fidelity: Johnson-Cook's rate term 1 + C ln(rate/rate_0); "
                                          "off: rate-independent"),
    "effects.charge": flag(False, doc="the cavity filled with the explosive charge (charge.*): meshed as a "
                                      "second body by the elastic and plastic fidelities, its mass and "
                                      "inertia counted by the rigid one (docs/charge.md)"),
    # --- mesh ---
    "mesh.size": number(0.0025, "m", 2.0e-4, 0.05,
                        doc="nominal tetrahedron size of the elastic and plastic fidelities' mesh (the rigid "
                            "fidelity has none: mesh.rigid_panel)"),
    "mesh.rigid_panel": number(ABSENT, "m", 2.0e-4, 0.5,
                               doc="meridian panel of the rigid fidelity's load rings; absent: diameter / 6"),
    "mesh.nose_size": number(ABSENT, "m", 2.0e-4, 0.05, doc="element size at the nose tip; absent: mesh.size"),
    "mesh.max_cells": number(1.0e6, "", 1.0e3, 1.0e9,
                             doc="the most tetrahedra fepen meshes unless told more: a finer mesh.size is refused "
                                 "before gmsh starts (about 2.2 kB per cell before the first step, 1e6 cells about "
                                 "3.0 GB on one process); a mesh past the machine's memory is refused all the same"),
    "mesh.optimize": choice("hxt", "hxt", "netgen", "gmsh", "none",
                            doc="tetrahedron mesher and optimiser: 'hxt' gmsh's parallel Delaunay with its optimiser, "
                                "'netgen' Delaunay with Netgen's and gmsh's optimisers (the default before 0.5: "
                                "4-5x slower), 'gmsh' Delaunay with gmsh's; the stable step is set by the worst "
                                "element"),
    # --- run control ---
    "run.end_time": positive(ABSENT, "s", 1.0,
                             doc="simulated time after the first contact at which the run ends (outcome "
                                 "'ended'); absent: until the projectile stops, perforates, ricochets or "
                                 "rebounds (at most 5 ms deformable, 50 ms rigid, or 20 times the time to "
                                 "reach a layered target's last face if longer); a rigid run may take at most "
                                 "20,000 steps to it"),
    "run.output_interval": positive(5.0e-5, "s", 1.0,
                                    doc="simulated time between field outputs (fields.xdmf); a deformable run's "
                                        "history.csv records every tenth of it, at most 1 us apart"),
    "run.safety_factor": number(0.8, "", 0.0, 1.0, lo_open=True,
                                doc="stable step = factor * (the estimate of run.stable_step)"),
    "run.stable_step": choice("eigenvalue", "altitude", "eigenvalue",
                              doc="eigenvalue: 2/omega_max of the discrete body (power iteration), tracked "
                                  "by h/c as it deforms; altitude: min h/c (conservative)"),
    "run.fields": flag(True, doc="write fields.xdmf + fields.h5 and the pictures made from them (elastic and "
                                 "plastic fidelities; a rigid run writes no fields)"),
    "run.figures": flag(True, doc="draw the run's PNG figures (history.png, attitude.png, hazard.png, "
                                  "nose_profile.png, stress_maps_*.png, trajectory.png, deformed.png, "
                                  "charge_histories.png); "
                                  "false: their CSV, VTU and JSON only, for sweeps of many shots (a charged "
                                  "run's report pictures from its fields are drawn regardless: they carry "
                                  "its summary's numbers)"),
    "run.stress_tensor_fields": flag(False, doc="also write the Cauchy stress tensor's six components "
                                                "(stress_xx_Pa ... stress_xz_Pa) and the tensor as one attribute "
                                                "(stress_Pa) in fields.xdmf: 2.5 times the field data (the "
                                                "default C3's fields.h5: 30 -> about 75 MB)"),
    "run.acceleration_filter_hz": number(1.0e4, "Hz", 0.0, 1.0e7,
                                         doc="low-pass cut-off of the filtered accelerations (accelerations.csv) "
                                             "under run.acceleration_filter = 'butterworth', and of the charge-"
                                             "safety stress; 0: none"),
    "run.acceleration_filter": choice("butterworth", "butterworth", "CFC60", "CFC180", "CFC600", "CFC1000",
                                      doc="the filter of the filtered accelerations (accelerations.csv, "
                                          "accelerometer probes), zero-phase: 'butterworth' order 4 each way at "
                                          "run.acceleration_filter_hz; 'CFC<n>' SAE J211-1's channel frequency "
                                          "class n (4-pole phaseless, -3 dB at 1.667 n Hz; docs/theory.md §13)"),
    "run.checkpoint_interval": number(1.0e-4, "s", 0.0, 1.0,
                                      doc="simulated time between checkpoints (fepen run --resume DIR); 0: none"),
    "run.rigid_step": positive(ABSENT, "s", 1e-3,
                               doc="RK4 step of the rigid fidelity; absent: min(0.1 D/v0, t_stop/300)"),
    # --- user-chosen histories (LS-DYNA nodout/elout, OpenRadioss /TH) ---
    "output.probes": Key(list, ABSENT, doc="[[output.probes]] tables {name, point, kind}: histories written to "
                                           "probes.csv at the history rows' times. point: [x, y, z] (m) in the "
                                           "undeformed projectile's frame (nose tip at the origin, axis +y), "
                                           "inside the body. kind 'node' (default): the nearest mesh node's "
                                           "displacement, velocity and acceleration (the rigid fidelity: the "
                                           "rigid motion of the point), in the target's frame (m, m/s, m/s^2, as "
                                           "fields.xdmf); 'cell': the cell holding the point, its von Mises and "
                                           "axial stress, pressure (Pa), PEEQ and temperature (K), meshed "
                                           "fidelities only; 'accelerometer': the nearest node's acceleration "
                                           "on the body's axes (axial, lateral, out of plane; g), raw and "
                                           "low-pass filtered (run.acceleration_filter). Columns "
                                           "<name>_<quantity>_<unit> (docs/results.md)",
                         form="a list of tables {name, point = [x, y, z], kind = 'node', 'cell' or 'accelerometer'}",
                         rows=_probes),
}

#: the tables of the scene (the first part of every key)
SECTIONS = sorted({name.split(".")[0] for name in SCHEMA})

#: what one [[output.probes]] table may hold (name and point are checked by _probes)
PROBE_FIELDS: dict[str, Key] = {
    "name": Key(str, ABSENT, doc="the probe's name, unique: its columns in probes.csv start with it"),
    "point": Key(list, ABSENT, "m", doc="[x, y, z] in the undeformed projectile's frame"),
    "kind": choice("node", "node", "cell", "accelerometer"),
}

#: the keys of one [[target.layers]] table besides the target constants
LAYER_KEYS = ("material", "thickness", "gap", "crater", "family")

#: what one [[target.layers]] table may hold, each with its Key: LAYER_KEYS, then the target constants
LAYER_FIELDS: dict[str, Key] = {
    "material": SCHEMA["target.material"],
    "thickness": SCHEMA["target.thickness"],
    "gap": Key(float, 0.0, "m", 0.0, 1.0e3),
    "crater": choice("none", "none", "energy"),
    "family": choice("concrete", *FAMILIES),  # as a resolved scene writes it back: must be the material's
    **{k: SCHEMA[f"target.{k}"] for k in CONSTANTS},
}
