"""What a shot will cost, known before any work starts (docs/results.md, "Limits"): the cells and memory of a
deformable shot's mesh, refused before gmsh starts when they pass ``mesh.max_cells``, the machine's memory or
what a per-process limit leaves the process (``ulimit -v``, a batch system's h_vmem; ``ulimit -d``), and a mesh
too coarse for the body refused in one line naming ``mesh.size``.

The figures are measured on this project's machines (docs/results.md gives the measurements): gmsh makes
4.4 (1 mm) to 5.0 (2.5 mm) tetrahedra per (meshed volume / mesh.size³) on the default body, and a deformable
run holds 0.53 GB per process plus 1.84 kB per cell before its first step (15,000 to 204,000 cells on one
rank). The constants below carry a margin over both.
"""

from __future__ import annotations

import math
import os

import numpy as np

from fepen.errors import InputError, MachineFault, memory_limits

#: tetrahedra per (meshed volume / size³): the measured 5.0 with a tenth more
CELLS_PER_SIZE3 = 5.5
#: the graded nose's cells over the estimate below (measured: 7,100 more cells for a 0.5 mm tip at 2.5 mm, 1.9
#: times the integral's 3,750)
NOSE_MARGIN = 2.0
#: a run's memory per process and per cell (bytes): the measured 0.53 GB (0.72 GB when gmsh meshes in the process:
#: a 3 mm mesh built afresh; 0.26 GB before the closing figures, whose matplotlib and VTK take the rest; 0.86 and
#: 0.87 GB in CI's system lane at fepen 0.7.0, twice, the figures' render the larger there) and 1.84 kB, with a margin
PROCESS_BYTES, CELL_BYTES = 0.95e9, 2.2e3
#: the address space a meshing and running process maps once its libraries are in (dolfinx, PETSc, numba, gmsh,
#: matplotlib, pyvista and VTK: 0.85 GiB measured with fepen 0.7.0, Debian's stack). An address-space limit (ulimit
#: -v) is checked against at least this much held: since fepen 0.7.0 a command loads them after the check (the
#: check saw 0.5 GiB held at 0.6.0, whose command had loaded numba and matplotlib to build its parser), and
#: `fepen mesh` under 1300 MiB then ended in VTK's render with std::bad_alloc instead of this check's one line
LIBRARIES_VM_BYTES = 0.85 * (1 << 30)
#: the address space a process maps beyond its libraries besides its cells' (the mesh's making, the solver, the
#: closing pictures' VTK render): `fepen mesh` of 502 cells and its picture need 1,400 MiB in all, 0.52 GiB beyond
#: the libraries (measured, fepen 0.7.0); with a margin
RUN_VM_BYTES = 0.6 * (1 << 30)
#: the coarsest mesh.size, as a fraction of the calibre: two cells across the body (coarser, gmsh fails on the
#: default body's 5.8 mm wall, or the cavity cannot be sized to the mass on the mesh)
COARSEST = 0.5


def meshed_volume(shape, charge: bool) -> float:
    """The volume gmsh fills (m^3): the body's outside with a meshed charge, its shell without; a CAD body's
    enclosing cylinder (its exact volume is known only once meshed)."""
    return shape.meshed_volume(charge)


def expected_cells(shape, size: float, nose_size: float | None, charge: bool) -> float:
    """The tetrahedra gmsh is expected to make: CELLS_PER_SIZE3 per size³ of the meshed volume, and, when
    mesh.nose_size is finer, the graded nose (the size growing linearly from nose_size at the tip to size one nose
    length back, over a cross-section growing as the square of the distance from the tip), times NOSE_MARGIN."""
    volume = meshed_volume(shape, charge)
    cells = CELLS_PER_SIZE3 * volume / size ** 3
    if nose_size is not None and nose_size < size:
        length = shape.nose_length
        if length > 0.0:
            r = np.linspace(0.0, length, 401)
            area = math.pi / 4.0 * shape.diameter ** 2 * (r / length) ** 2
            local = nose_size + (size - nose_size) * r / length
            graded = np.sum(0.5 * (area[1:] / local[1:] ** 3 + area[:-1] / local[:-1] ** 3) * np.diff(r))
            plain = np.sum(0.5 * (area[1:] + area[:-1]) * np.diff(r)) / size ** 3
            cells += NOSE_MARGIN * CELLS_PER_SIZE3 * max(0.0, float(graded - plain))
    return cells


def expected_bytes(cells: float, processes: int) -> float:
    """The memory of a deformable run before its first step (bytes)."""
    return processes * PROCESS_BYTES + cells * CELL_BYTES


def machine_bytes() -> float | None:
    """The memory this machine has available now (MemAvailable of /proc/meminfo), or None where unknown."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return 1024.0 * float(line.split()[1])
    except (OSError, ValueError, IndexError):
        pass
    try:
        return float(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def process_room() -> tuple[float, str, float, float] | None:
    """What the tightest per-process memory limit leaves this process: ``(bytes left, the limit's name ("ulimit
    -v": the address space, less what the process maps now, /proc/self/status VmSize; "ulimit -d": the data
    segment, less VmData), the limit (bytes), what the process holds against it (bytes))``, or None when no
    limit is set (fepen.errors.memory_limits)."""
    rooms = [(limit - (held or 0), name, limit, held or 0) for name, _, limit, held in memory_limits()]
    return min(rooms) if rooms else None


def available_bytes() -> float | None:
    """The memory this process can still take (bytes): the least of the machine's (machine_bytes) and what a
    per-process limit leaves it (process_room), or None where neither is known."""
    room = process_room()
    found = [b for b in (machine_bytes(), None if room is None else room[0]) if b is not None]
    return min(found) if found else None


_MIB = float(1 << 20)


def _up(x: float) -> float:
    """``x`` rounded up to two significant digits: a size said to fit does."""
    step = 10.0 ** (math.floor(math.log10(x)) - 1)
    return math.ceil(x / step * (1.0 - 1e-12)) * step


def _check_room(room: tuple, size: float, cells: float, processes: int, coarsest: float) -> None:
    """Refuse a mesh past what a per-process limit leaves (process_room): each process takes PROCESS_BYTES, and
    rank 0 the whole mesh's cells (gmsh makes it there, and dolfinx distributes it from there). InputError
    naming mesh.size when a coarser mesh fits; MachineFault naming the limit when none does."""
    left, name, limit, held = room
    base = PROCESS_BYTES
    if name == "ulimit -v":  # the address space: the libraries still to load count, then the run's own maps
        if held < LIBRARIES_VM_BYTES:
            held = LIBRARIES_VM_BYTES
            left = limit - held
        base = RUN_VM_BYTES
    need = base + cells * CELL_BYTES
    if need <= left:
        return
    what = f"the {'address-space' if name == 'ulimit -v' else 'data'} limit {name}"
    raise_it = f"raise {name} (a batch system's h_vmem)" if name == "ulimit -v" else f"raise {name}"
    whole = "the whole mesh on rank 0 while it is made" if processes > 1 else ""
    fits = size * (cells * CELL_BYTES / max(left - base, 1.0)) ** (1.0 / 3.0)
    if left <= base or fits > coarsest:
        raise MachineFault(f"{what} is {limit / _MIB:.0f} MiB and this process maps {held / _MIB:.0f} MiB with its "
                           f"libraries: "
                           f"a deformable run needs about {need / _MIB:.0f} MiB more per process before its first "
                           f"step ({cells:.3g} cells at mesh.size = {size:g} m{', ' + whole if whole else ''}): "
                           f"{raise_it} to at least {(held + need) / _MIB:.0f} MiB")
    raise InputError("mesh.size", f"{size:g} m makes about {cells:.3g} cells, about {need / _MIB:.0f} MiB more per "
                                  f"process before the first step{' (' + whole + ')' if whole else ''}; {what} "
                                  f"({limit / _MIB:.0f} MiB) leaves this process {left / _MIB:.0f} MiB: use "
                                  f"mesh.size >= {_up(fits):.2g} m, or {raise_it}")


def check_mesh(shape, size: float, nose_size: float | None, charge: bool, max_cells: float, processes: int) -> dict:
    """Refuse, before gmsh starts, a mesh too coarse for the body or too large for ``mesh.max_cells``, for the
    machine's memory or for what a per-process limit leaves each process (``ulimit -v``: InputError naming the
    key, the estimate and what would do; MachineFault naming the limit when no mesh would do).

    Args:
        shape: the exact body (a Shape or a CadBody). size, nose_size: mesh.size and mesh.nose_size (m).
        charge: the cavity is meshed as the charge. max_cells: mesh.max_cells. processes: the run's processes.

    Returns:
        {"cells": expected cells, "bytes": expected memory before the first step}.
    """
    coarsest = COARSEST * shape.diameter
    if size > coarsest * (1.0 + 1e-12):
        raise InputError("mesh.size", f"{size:g} m is coarser than half the calibre ({coarsest:g} m): at most "
                                      f"{coarsest:g} m, two cells across the body")
    cells = expected_cells(shape, size, nose_size, charge)
    need = expected_bytes(cells, processes)
    finest = size * (cells / max_cells) ** (1.0 / 3.0)
    if cells > max_cells:
        raise InputError("mesh.size", f"{size:g} m makes about {cells:.3g} cells (about {need / 1e9:.1f} GB before the "
                                      f"first step), more than mesh.max_cells = {max_cells:.3g}: use mesh.size >= "
                                      f"{finest:.2g} m, or raise mesh.max_cells on a machine that has the memory")
    free, room = available_bytes(), process_room()
    if room is not None and (free is None or room[0] <= free):  # a per-process limit binds: each process's own
        _check_room(room, size, cells, processes, coarsest)
        free = machine_bytes()  # and the machine's, for all the processes
    if free is not None and need > free:
        fits = size * ((need - processes * PROCESS_BYTES) / max(free - processes * PROCESS_BYTES, 1.0)) ** (1 / 3)
        raise InputError("mesh.size", f"{size:g} m makes about {cells:.3g} cells, about {need / 1e9:.1f} GB before "
                                      f"the first step on {processes} process(es); this machine has "
                                      f"{free / 1e9:.1f} GB available: use mesh.size >= {fits:.2g} m, or fewer ranks")
    return {"cells": cells, "bytes": need}


#: a given run.rigid_step may be at most this many times finer than the shot's own step (default_step), whose
#: results are converged (docs/theory.md): finer only costs time, up to about a minute at this factor
RIGID_STEP_FINER = 50.0


#: the most RK4 steps a rigid shot given run.end_time may take (about 10 s of a run on one core): the run goes on
#: to its end time even after the projectile has stopped or turned back, so an end time of a second would take
#: 160,000 steps of the default shot, minutes of a free flight no test measured
MAX_RIGID_STEPS = 20_000


def check_rigid_step(rigid_step: float | None, shape, shell_density: float, v0: float, law,
                     end_time: float | None = None) -> None:
    """Refuse a run.rigid_step so fine that a rigid shot would run for minutes or hours (InputError naming it):
    more than RIGID_STEP_FINER times finer than the shot's own step (fepen.runs.rigid.default_step, on the body's
    mass from its exact volume, a CAD body's from its enclosing cylinder); and a run.end_time that needs more than
    MAX_RIGID_STEPS steps of the step the run will take."""
    if v0 <= 0.0:
        return
    mass = shell_density * meshed_volume(shape, False)
    own = default_step(mass, v0, shape.diameter, law)
    if rigid_step is not None and rigid_step < own / RIGID_STEP_FINER:
        raise InputError("run.rigid_step", f"{rigid_step:g} s is {own / rigid_step:.3g} times finer than this shot's "
                                           f"own step ({own:.3g} s, whose results are converged): at least "
                                           f"{own / RIGID_STEP_FINER:.3g} s, or leave it out")
    step = rigid_step if rigid_step is not None else own
    if end_time is not None and end_time / step > MAX_RIGID_STEPS:
        raise InputError("run.end_time", f"{end_time:g} s is about {end_time / step:.3g} RK4 steps of {step:.3g} s "
                                         f"for this rigid shot; at most {MAX_RIGID_STEPS}: at most "
                                         f"{MAX_RIGID_STEPS * step:.3g} s, or leave it out (the run then ends when "
                                         "the projectile stops, perforates or ricochets)")


#: the rigid fidelity's default RK4 step (default_step): the time to travel this fraction of a diameter at the
#: striking speed, and at most 1/STOP_STEPS of the longer of the stop's time scales (time_scales)
STEP_FRACTION = 0.2
STOP_STEPS = 150


def time_scales(mass: float, v0: float, diameter: float, law) -> tuple[float, float]:
    """The two times a rigid shot's step resolves (s): ``t_stop``, the time the quasi-static force
    σ_s π D²/4 alone takes to stop the projectile (m v0 / F), and ``t_crater``, the time scale of the crater
    stage, where the force grows from the face to that force over the crater depth k D
    (sqrt(m k D / F): at low speed the projectile rides this spring, whatever v0)."""
    force = law.sigma_s * np.pi * 0.25 * diameter * diameter
    return mass * v0 / force, float(np.sqrt(mass * getattr(law, "k", 2.37) * diameter / force))


#: the tunnel's wall is a spring on a body pressed into it (docs/theory.md §8.7): stiffness wall_shear2 / a per unit
#: of wall, on up to the body's projected side D L, so the body's sideways (and turning) frequency is at most
#: ω = sqrt(wall_shear2 D L / (a m)). The classical RK4 step is stable below 2.8 / ω; a rigid run's step is at most
#: WALL_STEPS / ω, which the default shots' steps are within (C3: 6.0 µs against 11.8 µs)
WALL_STEPS = 1.0


def wall_step(mass: float, diameter: float, length: float, law) -> float:
    """The longest RK4 step the tunnel's elastic wall lets a rigid body take (s): WALL_STEPS / ω, ω the body's
    frequency on the wall's spring over its whole projected side (inf without a wall)."""
    k = getattr(law, "wall_shear2", 0.0) / (0.5 * diameter)
    if not k > 0.0:
        return float("inf")
    return WALL_STEPS / float(np.sqrt(k * diameter * length / mass))


def default_step(mass: float, v0: float, diameter: float, law) -> float:
    """The rigid fidelity's RK4 step without run.rigid_step: min(STEP_FRACTION D / v0, max(t_stop, t_crater) /
    STOP_STEPS) (time_scales). Above about 140 m/s t_stop is the larger (the step of every earlier fepen); below,
    t_crater bounds the step from below, so that a shot at 1 m/s takes about STOP_STEPS x 4 steps, not 1/v0 times
    more (docs/theory.md, the rigid body)."""
    t_stop, t_crater = time_scales(mass, v0, diameter, law)
    return min(STEP_FRACTION * diameter / v0, max(t_stop, t_crater) / STOP_STEPS)


#: the most field outputs and checkpoints of one deformable run: each field output is a file of about 80 bytes
#: per cell (a 1.2 mm mesh: 11 MB), each checkpoint the whole state; more would fill a disk, or spend the run
#: writing, not computing
MAX_FIELD_OUTPUTS, MAX_CHECKPOINTS = 5000, 1000


def check_outputs(end: float, output_interval: float, fields: bool, checkpoint_interval: float) -> None:
    """Refuse a deformable run's run.output_interval (with fields) or run.checkpoint_interval so short that the
    run would write more than MAX_FIELD_OUTPUTS field files or MAX_CHECKPOINTS checkpoints over ``end``, its
    end time (run.end_time, else the longest a deformable run goes: fepen.runs.shot.MAX_TIME)."""
    if fields and end / output_interval > MAX_FIELD_OUTPUTS:
        raise InputError("run.output_interval", f"{output_interval:g} s writes about {end / output_interval:.3g} "
                                                f"field outputs over {end:g} s; at most {MAX_FIELD_OUTPUTS}: at "
                                                f"least {end / MAX_FIELD_OUTPUTS:.3g} s, or run.fields = false")
    if checkpoint_interval > 0.0 and end / checkpoint_interval > MAX_CHECKPOINTS:
        raise InputError("run.checkpoint_interval", f"{checkpoint_interval:g} s writes about "
                                                    f"{end / checkpoint_interval:.3g} checkpoints over {end:g} s; at "
                                                    f"most {MAX_CHECKPOINTS}: at least {end / MAX_CHECKPOINTS:.3g} s, "
                                                    "or 0 for none")
