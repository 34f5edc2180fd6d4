"""The columns of history.csv, declared once (issue 60): each a name with its unit and one-line meaning, in
groups that a run writes when it has what they describe. The run's header, the name lists of fepen.io.results
and docs/results.md's column tables (``markdown``, written by ``make docs`` and checked by
tests/unit/io/test_columns.py) all come from here; a new column is a line here and its value in its group's row.

A Group's ``when`` names the Run property that switches it on ("" : every run): ``charged`` (a charge),
``frictional`` (its frictional contact), ``removing`` (wear or erosion), ``splitting`` (a named target's load
zones). Its ``intro`` is the paragraph docs/results.md puts before its table (None: its rows continue the
previous group's table).
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass

__all__ = ["Quantity", "Group", "HISTORY", "history", "markdown", "BASE", "ACCELERATIONS", "BODIES", "RESULTANT",
           "INTERFACE", "REMOVAL", "LOADS", "ATTITUDE"]


@dataclass(frozen=True)
class Quantity:
    """One row of a column table: columns that share a unit and a meaning.

    Attributes:
        names: the columns, in their order in the file. unit: their unit ("–": none). doc: the meaning.
    """

    names: tuple
    unit: str
    doc: str


@dataclass(frozen=True)
class Group:
    """Columns a run writes together, in their order.

    Attributes:
        name: the group's name. when: the Run property that switches it on ("": always). intro: the docs'
            paragraph before its table (None: continues the previous table). quantities: its rows.
    """

    name: str
    when: str
    intro: str | None
    quantities: tuple

    @property
    def columns(self) -> list[str]:
        """The group's column names, in order."""
        return [n for q in self.quantities for n in q.names]

    def on(self, run) -> bool:
        """Whether ``run`` writes this group."""
        return not self.when or bool(getattr(run, self.when))


BASE = Group(
    'base', '',
    ('One row per recorded time, plus one for the final state. A deformable run records every µs, or every tenth of'
     ' `run.output_interval` if that is shorter, at the multiples of that interval exactly (1e-06, 2e-06, …: the '
     'explicit steps before an output time are evened out so that the last one lands on it; fields and checkpoints '
     'land on their multiples the same way); the last row is the end time. The rigid fidelity records at its RK4 '
     'steps (about 6 µs for C3, longer than the interval), so its times are not round. Columns, in this order:'),
    (
        Quantity(('t_s',), 's',
                 'time since the nose tip touched the face at O'),
        Quantity(('nose_x_mm', 'nose_y_mm'), 'mm',
                 'position of the nose tip: x along the face in the direction of travel, y depth into the target, '
                 'from O'),
        Quantity(('tail_x_mm', 'tail_y_mm'), 'mm',
                 'the same for the tail centre'),
        Quantity(('speed_m_s',), 'm/s',
                 'speed of the centre of mass'),
        Quantity(('decel_g',), 'g',
                 "the target's force along the projectile axis divided by the projectile's mass, in g (9.80665 "
                 'm/s²). It is positive while the target slows the projectile.'),
        Quantity(('vx_m_s', 'vy_m_s'), 'm/s',
                 'velocity of the centre of mass, same frame (vy > 0 moving deeper)'),
        Quantity(('force_x_N', 'force_y_N'), 'N',
                 "the target's (or rigid wall's) force on the projectile, same frame. `force_y_N` is negative while"
                 ' the target pushes the projectile back.'),
        Quantity(('length_mm',), 'mm',
                 'nose-tip to tail-centre distance'),
        Quantity(('kinetic_J',), 'J',
                 'kinetic energy'),
        Quantity(('internal_work_J',), 'J',
                 'work of the internal forces (stored elastic energy plus plastic dissipation; 0 for a rigid body)'),
        Quantity(('external_work_J',), 'J',
                 "work of the target's (or wall's) forces on the projectile"),
        Quantity(('elastic_J',), 'J',
                 'stored elastic energy (0 for a rigid body)'),
        Quantity(('plastic_J',), 'J',
                 'plastic dissipation (0 unless plastic)'),
        Quantity(('heat_J',), 'J',
                 'the part of the plastic dissipation turned into heat (Taylor–Quinney)'),
        Quantity(('energy_error',), '–',
                 'relative energy-balance error at this time ([theory.md §6](theory.md))'),
        Quantity(('contact_nodes',), '–',
                 'number of loaded surface load points (on the rigid wall: nodes in contact)'),
        Quantity(('dt_s',), 's',
                 'the coming time step (a step before an output time can be shorter than the stable step)'),
        Quantity(('max_peeq',), '–',
                 'largest equivalent plastic strain in the projectile (0 unless plastic)'),
        Quantity(('contact_area_m2',), 'm²',
                 "loaded area of the projectile's surface (0 on the rigid wall)"),
        Quantity(('total_energy_J',), 'J',
                 "the energy balance's total (LS-DYNA's glstat): `kinetic_J` + `internal_work_J` + `friction_J` − "
                 "the shell–charge normal contact work + `removed_kinetic_J` − `external_work_J`. The target's (or "
                 "wall's) work counts as energy the target took, so the total stays at the striking kinetic energy "
                 'KE₀ while the balance holds. Rigid: `kinetic_J` + the kinetic energy of the worn-off mass − '
                 '`external_work_J`.'),
        Quantity(('energy_ratio',), '–',
                 "`total_energy_J` / KE₀: 1 for a perfect balance. (KE₀ and not KE₀ + external work, glstat's "
                 'denominator: with the target outside the model, that sum is what the projectile keeps, which goes'
                 ' to 0 at rest.)'),
    ))

ACCELERATIONS = Group(
    'accelerations', 'charged',
    ("With a charge (`effects.charge = true`, deformable fidelities), more columns follow: the bodies' "
     "accelerations, then each body's energies and momenta (LS-DYNA's matsum), then the force across the "
     'shell–charge interface (rcforc). A node of the tied wall counts in each body with the mass it takes from that'
     " body's cells, so shell + charge gives `kinetic_J`, `elastic_J` + `plastic_J`, and the mass times (`vx_m_s`, "
     '`vy_m_s`). Kinetic energies, momenta and the contact force are the same bits on any rank count.'),
    (
        Quantity(('shell_acc_g',), 'g',
                 "the shell's mass-averaged acceleration along the axis (tail to nose). It is negative while the "
                 'projectile decelerates.'),
        Quantity(('charge_acc_g',), 'g',
                 'the same for the charge'),
    ))

BODIES = Group(
    'bodies', 'charged',
    None,
    (
        Quantity(('shell_kinetic_J',), 'J',
                 "the shell's kinetic energy"),
        Quantity(('shell_internal_J',), 'J',
                 "the shell's internal energy: stored elastic energy plus plastic work (split between the bodies "
                 "exactly when only the shell heats, the default; with `effects.thermal = false` the charge's share"
                 ' is its bilinear closed form)'),
        Quantity(('shell_px_N_s', 'shell_py_N_s'), 'N s',
                 "the shell's momentum, reported frame (x along the face in the direction of travel, y depth: "
                 'positive while moving into the target, as `vx_m_s`, `vy_m_s`)'),
        Quantity(('charge_kinetic_J',), 'J',
                 "the charge's kinetic energy"),
        Quantity(('charge_internal_J',), 'J',
                 "the charge's internal energy, as the shell's"),
        Quantity(('charge_px_N_s', 'charge_py_N_s'), 'N s',
                 'the same for the charge'),
    ))

RESULTANT = Group(
    'resultant', 'charged',
    None,
    (
        Quantity(('contact_fx_N', 'contact_fy_N'), 'N',
                 'the resultant force of the shell on the charge across their interface, reported frame; '
                 '`contact_fy_N` is negative while the shell holds the charge back. Frictional contact: the sum of '
                 "the pair forces on the charge's wall nodes; tied: the rate of change of the charge's momentum "
                 '(nothing else loads it). Its impulse is the change of `charge_px_N_s`, `charge_py_N_s`.'),
        Quantity(('contact_force_N',), 'N',
                 'the magnitude of that force, its out-of-plane part included'),
    ))

INTERFACE = Group(
    'interface', 'frictional',
    ('With a charge in frictional contact (`charge.contact = "frictional"`, the default), six more columns follow:'),
    (
        Quantity(('friction_J',), 'J',
                 'friction dissipation at the shell–charge interface, so far'),
        Quantity(('interface_gap_max_mm',), 'mm',
                 "the largest gap over the wall's node pairs"),
        Quantity(('interface_penetration_max_mm',), 'mm',
                 'the largest interpenetration over the pairs'),
        Quantity(('interface_slip_max_mm',), 'mm',
                 'the largest slip (tangential relative displacement) over the pairs'),
        Quantity(('interface_free_fraction',), '–',
                 'fraction of the pairs carrying no force (open)'),
        Quantity(('interface_sliding_fraction',), '–',
                 'fraction of the pairs sliding'),
    ))

REMOVAL = Group(
    'removal', 'removing',
    ('With `effects.wear` or `effects.erosion` (either fidelity), four more columns follow last:'),
    (
        Quantity(('mass_kg',), 'kg',
                 "the projectile's mass at this time"),
        Quantity(('wear_heat_J',), 'J',
                 'the interface heat of the wear law, so far'),
        Quantity(('eroded_cells',), '–',
                 'cells removed by erosion, so far'),
        Quantity(('removed_kinetic_J',), 'J',
                 'the kinetic energy the worn or eroded material carried away, so far'),
    ))

LOADS = Group(
    'loads', 'splitting',
    ("In a concrete (or any named) target, both fidelities, six more columns follow last: where the target's load "
     'acts on the body. The zones are by distance behind the tip in the body frame: the **nose** ahead of the '
     'shoulder (the widest section, where the load points first reach the full calibre), the **tail** the last '
     'calibre of the body, the **shank** between ([theory.md §8.7](theory.md)).'),
    (
        Quantity(('nose_force_N', 'shank_force_N', 'tail_force_N'), 'N',
                 "the size of the resultant of the target's forces on each zone"),
        Quantity(('nose_points', 'shank_points', 'tail_points'), '–',
                 'the load points each zone has loaded'),
    ))

ATTITUDE = Group(
    'attitude', '',
    ('Every history ends with the third dimension and the attitude (both fidelities). The plane of fire is x–y; z '
     "is across it (a deformable body's unsymmetric mesh moves it a millimetre out of plane over a shot). The "
     "pseudo-vectors (angular velocity, moment, angular momentum and impulse) are in the scene's right-handed "
     'frame: x along the face, y **out of** the target toward the gun, z = x × y; so a positive '
     '`angular_velocity_z_rad_s` turns the nose toward +x and the axis angle grows.'),
    (
        Quantity(('nose_z_mm', 'tail_z_mm'), 'mm',
                 "the nose tip's and the tail centre's z"),
        Quantity(('vz_m_s',), 'm/s',
                 "the centre of mass's z velocity"),
        Quantity(('force_z_N',), 'N',
                 "the target's force along z"),
        Quantity(('centre_x_mm', 'centre_y_mm', 'centre_z_mm'), 'mm',
                 "the centre of mass, in the history's frame (y depth)"),
        Quantity(('axis_angle_deg',), 'deg',
                 "the axis (tail to nose) from the target's normal in the plane of fire, positive toward +x: "
                 "atan2(nose_x − tail_x, nose_y − tail_y); summary.json's `final_axis_angle_deg` is its last value"),
        Quantity(('yaw_deg',), 'deg',
                 "the angle between the axis and the centre of mass's velocity (3-D, 0 to 180)"),
        Quantity(('angular_velocity_x_rad_s', 'angular_velocity_y_rad_s', 'angular_velocity_z_rad_s'), 'rad/s',
                 "the body's angular velocity (rigid: ω; deformable: I⁻¹ H of the nodes about the centre of mass)"),
        Quantity(('moment_x_N_m', 'moment_y_N_m', 'moment_z_N_m'), 'N m',
                 "the target's moment about the centre of mass at that instant (its forces on the load points; the "
                 'load changes every step, so the rows sample it; 0 against the rigid wall, whose moment is not '
                 'summed)'),
        Quantity(('angular_momentum_x_N_m_s', 'angular_momentum_y_N_m_s', 'angular_momentum_z_N_m_s'), 'N m s',
                 'the angular momentum about the centre of mass'),
        Quantity(('angular_impulse_x_N_m_s', 'angular_impulse_y_N_m_s', 'angular_impulse_z_N_m_s'), 'N m s',
                 "the target's angular impulse about O since the run began, integrated every step (RK4's weights; "
                 "the central difference's trapezoid): the angular momentum about O, H + x_c × M v_c, has grown by "
                 'exactly it (`tests/system/test_attitude.py`: to 1e-6 of it)'),
    ))
#: every group, in the order a history writes them
HISTORY = (BASE, ACCELERATIONS, BODIES, RESULTANT, INTERFACE, REMOVAL, LOADS, ATTITUDE)


def history(run) -> list[str]:
    """The history.csv header of a run (a Run: its properties say which groups it writes)."""
    return [c for g in HISTORY if g.on(run) for c in g.columns]


def markdown(groups=HISTORY, width: int = 115) -> str:
    """docs/results.md's column tables: each group's intro, then its table (a group without one continues the
    previous table)."""
    out: list[str] = []
    for g in groups:
        if g.intro is not None:
            out += ([""] if out else []) + textwrap.wrap(g.intro, width, break_long_words=False,
                                                             break_on_hyphens=False)
            out += ["", "| `history.csv` column | unit | meaning |", "|---|---|---|"]
        out += [f"| {', '.join(f'`{n}`' for n in q.names)} | {q.unit} | {q.doc} |" for q in g.quantities]
    return "\n".join(out).strip("\n")
