"""The columns of history.csv, declared once (issue 60): each a name with its unit, its one-line meaning and how
it is computed from the run's state, in groups that a run writes when it has what they describe. The run's header,
its rows (``values``), the name lists of fepen.io.results and docs/results.md's column tables (``markdown``,
written by ``make docs`` and checked by tests/unit/io/test_columns.py) all come from here: a new column is one
declaration here, in both fidelities.

A Group's ``when`` names the Run property that switches it on ("" : every run): ``charged`` (a charge),
``frictional`` (its frictional contact), ``removing`` (wear or erosion), ``splitting`` (a named target's load
zones). Its ``intro`` is the paragraph docs/results.md puts before its table (None: its rows continue the
previous group's table).

A Quantity's ``value`` takes a ``Row`` (the time, the body's snapshot fepen.runs.run.Snapshot, and what the run
hands over on demand: the removal, the load's split by zone) and returns its columns' numbers. A quantity without
one is the body's own: its snapshot's ``extra`` holds it by name (the charge's and the interface's columns,
which only the deformable body computes).
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from fepen.geometry.frames import unit_axis

__all__ = ["Quantity", "Group", "Row", "HISTORY", "history", "values", "markdown", "final_axis_deg", "G0", "BASE",
           "TABLES", "HAZARD", "STRAINS", "ACCELERATION_TABLE", "ACCELERATION_CHARGE", "CHARGE_SECTIONS",
           "tables_markdown", "table_columns",
           "ACCELERATIONS", "BODIES", "RESULTANT", "INTERFACE", "REMOVAL", "LOADS", "ATTITUDE"]


@dataclass(frozen=True)
class Quantity:
    """One row of a column table: columns that share a unit and a meaning.

    Attributes:
        names: the columns, in their order in the file. unit: their unit ("–": none). doc: the meaning.
        value: Row -> their numbers (None: the body's own, by name in the snapshot's ``extra``).
    """

    names: tuple
    unit: str
    doc: str
    value: Callable | None = None

    def values(self, row: Row) -> list:
        """Its columns' numbers in ``row`` (the body's own, from the snapshot's ``extra``, without a value)."""
        if self.value is None:
            return [row.s.extra[n] for n in self.names]
        out = list(self.value(row))
        if len(out) != len(self.names):
            raise ValueError(f"history columns {self.names}: {len(out)} values")
        return out


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


G0 = 9.80665  # m/s^2, for accelerations in g


def final_axis_deg(Hx_mm, Hy_mm, Tx_mm, Ty_mm):
    """The projectile's axis at the end (deg from the face's normal, toward +x): atan2(Hx − Tx, Hy − Ty) of the
    nose and tail positions in the reported frame (x along the face, y depth); numbers or arrays."""
    return np.degrees(np.arctan2(np.subtract(Hx_mm, Tx_mm), np.subtract(Hy_mm, Ty_mm)))


class Row:
    """What one history row is computed from.

    Args:
        t: the run's time (s). s: the body's snapshot (fepen.runs.run.Snapshot: world frame, SI). run: the Run,
            asked on demand (collectively, in the groups' order on every rank) for ``removal()`` (unless the
            snapshot has it) and ``load_split()``.
    """

    def __init__(self, t: float, s, run):
        self.t, self.s, self.run = t, s, run

    @cached_property
    def axis(self) -> np.ndarray:
        """The unit axis, tail to nose."""
        return unit_axis(self.s.tip, self.s.tail)

    @cached_property
    def removal(self):
        """What wear and erosion took off (fepen.runs.run.Removal)."""
        return self.s.removal or self.run.removal()

    @cached_property
    def loads(self) -> list:
        """The load's split by zone: three forces (N), then three point counts."""
        return list(self.run.load_split())


def _yaw(r: Row) -> tuple:
    # atan2(|a × v|, a · v): a small yaw to full precision (acos of a cosine near 1 keeps only its square root)
    a, v = r.axis, r.s.velocity
    return (math.degrees(math.atan2(float(np.linalg.norm(np.cross(a, v))), float(a @ v))),)


BASE = Group(
    'base', '',
    ('One row per recorded time, plus one for the final state. A deformable run records every µs, or every tenth of'
     ' `run.output_interval` if that is shorter, at the multiples of that interval exactly (1e-06, 2e-06, …: the '
     'explicit steps before an output time are evened out so that the last one lands on it; fields and checkpoints '
     'land on their multiples the same way); the last row is the end time. The rigid fidelity records at its RK4 '
     'steps (about 6 µs for C3, longer than the interval), so its times are not round. Columns, in this order:'),
    (
        Quantity(('t_s',), 's',
                 'time since the nose tip touched the face at O',
                 lambda r: (r.t,)),
        Quantity(('nose_x_mm', 'nose_y_mm'), 'mm',
                 'position of the nose tip: x along the face in the direction of travel, y depth into the target, '
                 'from O',
                 lambda r: (r.s.tip[0] * 1e3, -r.s.tip[1] * 1e3)),
        Quantity(('tail_x_mm', 'tail_y_mm'), 'mm',
                 'the same for the tail centre',
                 lambda r: (r.s.tail[0] * 1e3, -r.s.tail[1] * 1e3)),
        Quantity(('speed_m_s',), 'm/s',
                 'speed of the centre of mass',
                 lambda r: (float(np.linalg.norm(r.s.velocity)),)),
        Quantity(('decel_g',), 'g',
                 "the target's force along the projectile axis divided by the projectile's mass, in g (9.80665 "
                 'm/s²). It is positive while the target slows the projectile.',
                 lambda r: (-float(np.dot(r.s.force, r.axis)) / r.s.mass / G0,)),
        Quantity(('vx_m_s', 'vy_m_s'), 'm/s',
                 'velocity of the centre of mass, same frame (vy > 0 moving deeper)',
                 lambda r: (r.s.velocity[0], -r.s.velocity[1])),
        Quantity(('force_x_N', 'force_y_N'), 'N',
                 "the target's (or rigid wall's) force on the projectile, same frame. `force_y_N` is negative while"
                 ' the target pushes the projectile back.',
                 lambda r: (r.s.force[0], -r.s.force[1])),
        Quantity(('length_mm',), 'mm',
                 'nose-tip to tail-centre distance',
                 lambda r: (float(np.linalg.norm(r.s.tip - r.s.tail)) * 1e3,)),
        Quantity(('kinetic_J',), 'J',
                 'kinetic energy',
                 lambda r: (r.s.energies['kinetic'],)),
        Quantity(('internal_work_J',), 'J',
                 'work of the internal forces (stored elastic energy plus plastic dissipation; 0 for a rigid body)',
                 lambda r: (r.s.energies['internal_work'],)),
        Quantity(('external_work_J',), 'J',
                 "work of the target's (or wall's) forces on the projectile",
                 lambda r: (r.s.energies['external_work'],)),
        Quantity(('elastic_J',), 'J',
                 'stored elastic energy (0 for a rigid body)',
                 lambda r: (r.s.energies['elastic'],)),
        Quantity(('plastic_J',), 'J',
                 'plastic dissipation (0 unless plastic)',
                 lambda r: (r.s.energies['plastic'],)),
        Quantity(('heat_J',), 'J',
                 'the part of the plastic dissipation turned into heat (Taylor–Quinney)',
                 lambda r: (r.s.energies['heat'],)),
        Quantity(('energy_error',), '–',
                 'relative energy-balance error at this time ([theory.md §6](theory.md))',
                 lambda r: (r.s.energies['energy_error'],)),
        Quantity(('contact_nodes',), '–',
                 'number of loaded surface load points (on the rigid wall: nodes in contact)',
                 lambda r: (r.s.contact,)),
        Quantity(('dt_s',), 's',
                 'the coming time step (a step before an output time can be shorter than the stable step)',
                 lambda r: (r.s.dt,)),
        Quantity(('max_peeq',), '–',
                 'largest equivalent plastic strain in the projectile (0 unless plastic)',
                 lambda r: (r.s.peeq,)),
        Quantity(('contact_area_m2',), 'm²',
                 "loaded area of the projectile's surface (0 on the rigid wall)",
                 lambda r: (r.s.area,)),
        Quantity(('total_energy_J',), 'J',
                 "the energy balance's total (LS-DYNA's glstat): `kinetic_J` + `internal_work_J` + `friction_J` − "
                 "the shell–charge normal contact work + `removed_kinetic_J` − `external_work_J`. The target's (or "
                 "wall's) work counts as energy the target took, so the total stays at the striking kinetic energy "
                 'KE₀ while the balance holds. Rigid: `kinetic_J` + the kinetic energy of the worn-off mass − '
                 '`external_work_J`.',
                 lambda r: (r.s.energies['total_energy'],)),
        Quantity(('energy_ratio',), '–',
                 "`total_energy_J` / KE₀: 1 for a perfect balance. (KE₀ and not KE₀ + external work, glstat's "
                 'denominator: with the target outside the model, that sum is what the projectile keeps, which goes'
                 ' to 0 at rest.)',
                 lambda r: (r.s.energies['energy_ratio'],)),
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
                 "the projectile's mass at this time",
                 lambda r: (r.s.mass,)),
        Quantity(('wear_heat_J',), 'J',
                 'the interface heat of the wear law, so far',
                 lambda r: (r.removal.heat_J,)),
        Quantity(('eroded_cells',), '–',
                 'cells removed by erosion, so far',
                 lambda r: (r.removal.eroded_cells,)),
        Quantity(('removed_kinetic_J',), 'J',
                 'the kinetic energy the worn or eroded material carried away, so far',
                 lambda r: (r.removal.kinetic_J,)),
    ))

LOADS = Group(
    'loads', 'splitting',
    ("In a concrete (or any named) target, both fidelities, six more columns follow last: where the target's load "
     'acts on the body. The zones are by distance behind the tip in the body frame: the **nose** ahead of the '
     'shoulder (the widest section, where the load points first reach the full calibre), the **tail** the last '
     'calibre of the body, the **shank** between ([theory.md §8.7](theory.md)).'),
    (
        Quantity(('nose_force_N', 'shank_force_N', 'tail_force_N'), 'N',
                 "the size of the resultant of the target's forces on each zone",
                 lambda r: r.loads[:3]),
        Quantity(('nose_points', 'shank_points', 'tail_points'), '–',
                 'the load points each zone has loaded',
                 lambda r: r.loads[3:6]),
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
                 "the nose tip's and the tail centre's z",
                 lambda r: (r.s.tip[2] * 1e3, r.s.tail[2] * 1e3)),
        Quantity(('vz_m_s',), 'm/s',
                 "the centre of mass's z velocity",
                 lambda r: (float(r.s.velocity[2]),)),
        Quantity(('force_z_N',), 'N',
                 "the target's force along z",
                 lambda r: (float(r.s.force[2]),)),
        Quantity(('centre_x_mm', 'centre_y_mm', 'centre_z_mm'), 'mm',
                 "the centre of mass, in the history's frame (y depth)",
                 lambda r: (r.s.centre[0] * 1e3, -r.s.centre[1] * 1e3, r.s.centre[2] * 1e3)),
        Quantity(('axis_angle_deg',), 'deg',
                 "the axis (tail to nose) from the target's normal in the plane of fire, positive toward +x: "
                 "atan2(nose_x − tail_x, nose_y − tail_y); summary.json's `final_axis_angle_deg` is its last value",
                 lambda r: (float(final_axis_deg(r.s.tip[0], -r.s.tip[1], r.s.tail[0], -r.s.tail[1])),)),
        Quantity(('yaw_deg',), 'deg',
                 "the angle between the axis and the centre of mass's velocity (3-D, 0 to 180)",
                 _yaw),
        Quantity(('angular_velocity_x_rad_s', 'angular_velocity_y_rad_s', 'angular_velocity_z_rad_s'), 'rad/s',
                 "the body's angular velocity (rigid: ω; deformable: I⁻¹ H of the nodes about the centre of mass)",
                 lambda r: tuple(map(float, r.s.omega))),
        Quantity(('moment_x_N_m', 'moment_y_N_m', 'moment_z_N_m'), 'N m',
                 "the target's moment about the centre of mass at that instant (its forces on the load points; the "
                 'load changes every step, so the rows sample it; 0 against the rigid wall, whose moment is not '
                 'summed)',
                 lambda r: tuple(map(float, r.s.moment))),
        Quantity(('angular_momentum_x_N_m_s', 'angular_momentum_y_N_m_s', 'angular_momentum_z_N_m_s'), 'N m s',
                 'the angular momentum about the centre of mass',
                 lambda r: tuple(map(float, r.s.momentum))),
        Quantity(('angular_impulse_x_N_m_s', 'angular_impulse_y_N_m_s', 'angular_impulse_z_N_m_s'), 'N m s',
                 "the target's angular impulse about O since the run began, integrated every step (RK4's weights; "
                 "the central difference's trapezoid): the angular momentum about O, H + x_c × M v_c, has grown by "
                 'exactly it (`tests/system/test_attitude.py`: to 1e-6 of it)',
                 lambda r: tuple(map(float, r.s.impulse))),
    ))
#: every group, in the order a history writes them
HISTORY = (BASE, ACCELERATIONS, BODIES, RESULTANT, INTERFACE, REMOVAL, LOADS, ATTITUDE)


# ------------------------------------------------------------------------------------- a run's other tables
#: hazard.csv (deformable runs): per 2 mm bin of the undeformed axis, the surface's and the whole section's peaks
HAZARD = Group(
    'hazard.csv', '',
    ('`hazard.csv` (deformable runs), the paper\'s hazard map ([paper.md §8](paper.md)): one row per 2 mm bin of '
     'the undeformed axis, from the nose tip.'),
    (
        Quantity(('axial_from_nose_mm',), 'mm', 'the centre of the bin, from the nose tip along the undeformed axis'),
        Quantity(('max_surface_peeq',), '–', 'the largest PEEQ of the surface cells in the bin, at the end'),
        Quantity(('peak_surface_von_mises_Pa',), 'Pa',
                 'the largest von Mises stress of the surface cells in the bin over the history rows: where an '
                 'elastic shot came nearest to yielding'),
        Quantity(('max_peeq',), '–',
                 'the largest PEEQ over every cell of the bin, the inside included (bending yields the skin, a '
                 'nose crushed along its axis the core)'),
        Quantity(('peak_von_mises_Pa',), 'Pa', 'the largest von Mises stress over every cell of the bin'),
    ))
#: strains.csv (deformable runs): the strain gauges, a column per gauge
STRAINS = Group(
    'strains.csv', '',
    ('`strains.csv` (deformable runs): the strain gauges, four surface cells at 1/3 L and at 1/2 L from the '
     'nose; top and bottom lie in the plane of incidence (±x of the body), the sides across it (±z). Bending '
     'shows as top/bottom ≫ sides.'),
    (
        Quantity(('t_s',), 's', 'the history row\'s time'),
        Quantity(('top_33pctL', 'bottom_33pctL', 'side+_33pctL', 'side-_33pctL', 'top_50pctL', 'bottom_50pctL',
                  'side+_50pctL', 'side-_50pctL'), '–',
                 'the axial logarithmic strain ln ‖F a0‖ (a0 the reference axis) of the gauge\'s cell'),
    ))
#: accelerations.csv (deformable runs): raw and filtered
ACCELERATION_TABLE = Group(
    'accelerations.csv', '',
    ('`accelerations.csv` (deformable runs): the history\'s accelerations, raw and low-pass filtered by '
     '`run.acceleration_filter` (zero-phase Butterworth at `run.acceleration_filter_hz`, or an SAE J211-1 '
     'channel frequency class; summary.json\'s `acceleration_filter` names it, [theory.md §13](theory.md)).'),
    (
        Quantity(('t_s',), 's', 'the history row\'s time'),
        Quantity(('decel_g', 'decel_filtered_g'), 'g', 'history.csv\'s `decel_g`, raw and filtered'),
    ))
ACCELERATION_CHARGE = Group(
    'accelerations.csv', 'charged', None,
    (
        Quantity(('shell_acc_g', 'shell_acc_filtered_g', 'charge_acc_g', 'charge_acc_filtered_g'), 'g',
                 'with a charge: history.csv\'s `shell_acc_g` and `charge_acc_g`, each raw and filtered'),
    ))
#: charge_sections.csv (charged deformable runs): a column per point and stress
CHARGE_SECTIONS = Group(
    'charge_sections.csv', 'charged',
    ('`charge_sections.csv` (with a charge): the charge\'s stresses at points of its sections. The points: '
     '`front_r0`, `front_r33`, `front_r67`, `front_r90` (at 0, 1/3, 2/3 and 0.9 of the cavity radius on the '
     'charge\'s front face), `nose_end_r0` … `nose_end_r90` (at the nose/cylinder interface), `mid_r0` … '
     '`mid_r90` (at half the charge\'s length), and `axis0` … `axis4` (five points along the axis, front to '
     'rear).'),
    (
        Quantity(('t_s',), 's', 'the history row\'s time'),
        Quantity(('<point>_axial_Pa', '<point>_shear_Pa'), 'Pa',
                 'the axial and the shear stress at the point (compression negative)'),
    ))
#: a run's other tables, each file's groups in order (docs/results.md's block "run-tables")
TABLES = {"hazard.csv": (HAZARD,), "strains.csv": (STRAINS,),
          "accelerations.csv": (ACCELERATION_TABLE, ACCELERATION_CHARGE), "charge_sections.csv": (CHARGE_SECTIONS,)}


def history(run) -> list[str]:
    """The history.csv header of a run (a Run: its properties say which groups it writes)."""
    return [c for g in HISTORY if g.on(run) for c in g.columns]


def values(run, t: float, s) -> list:
    """One history row of ``run`` at time ``t`` from its snapshot ``s``: the values of the groups it writes, in
    the header's order (collective when the run's removal or load split is).

    Raises:
        ValueError: the snapshot carries a body column that no group the run writes declares.
    """
    row = Row(t, s, run)
    cached = getattr(run, "_history_quantities", None)
    if cached is None:  # the run's groups, as its header has them (fixed when history.csv is opened): once a run
        groups = [g for g in HISTORY if g.on(run)]
        cached = ([q for g in groups for q in g.quantities],
                  frozenset(n for g in groups for q in g.quantities if q.value is None for n in q.names))
        try:
            run._history_quantities = cached
        except AttributeError:  # a run that keeps no attributes: computed each row
            pass
    quantities, declared = cached
    if s.extra and not declared.issuperset(s.extra):
        raise ValueError("history columns written but not declared in fepen.io.columns: "
                         f"{sorted(set(s.extra) - declared)}")
    return [v for q in quantities for v in q.values(row)]


def markdown(groups=HISTORY, width: int = 115, file: str = "history.csv") -> str:
    """docs/results.md's column tables: each group's intro, then its table (a group without one continues the
    previous table); ``file`` heads the tables' first column."""
    out: list[str] = []
    for g in groups:
        if g.intro is not None:
            out += ([""] if out else []) + textwrap.wrap(g.intro, width, break_long_words=False,
                                                             break_on_hyphens=False)
            out += ["", f"| `{file}` column | unit | meaning |", "|---|---|---|"]
        out += [f"| {', '.join(f'`{n}`' for n in q.names)} | {q.unit} | {q.doc} |" for q in g.quantities]
    return "\n".join(out).strip("\n")


def tables_markdown(width: int = 115) -> str:
    """docs/results.md's tables of a run's other CSV files (TABLES), each after its paragraph."""
    return "\n\n".join(markdown(groups, width, file) for file, groups in TABLES.items())


def table_columns(file: str, run=None) -> list[str]:
    """The declared columns of one of TABLES (the groups ``run`` writes; None: every group)."""
    return [c for g in TABLES[file] if run is None or g.on(run) for c in g.columns]
