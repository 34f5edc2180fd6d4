"""probes.csv: the user's point and cell histories ([[output.probes]], LS-DYNA's nodout/elout, OpenRadioss'
/TH), one row per history row (the same times as history.csv), ``t_s`` then ``<name>_<quantity>_<unit>``.

Node probes (the target's frame, as fields.xdmf: metres, y = 0 the target face, the target at y < 0):
``_ux_m, _uy_m, _uz_m`` the displacement from the undeformed projectile's point (the placement at t = 0
included), ``_vx_m_s, ...`` the velocity and ``_ax_m_s2, ...`` the acceleration. Cell probes:
``_von_mises_Pa``, ``_axial_stress_Pa`` (along the axis, tail to nose; positive in tension), ``_pressure_Pa``
(positive in compression), ``_peeq`` and ``_temperature_K``. Accelerometer probes (a node probe read as an
accelerometer fixed in the body, as instrumented penetrators carry): the node's acceleration resolved on the
body's axes, in g (9.80665 m/s²), ``_axial_g`` along the axis tail to nose (negative while the body slows, as
every acceleration fepen writes), ``_lateral_g`` across it in the plane of fire (ẑ × axis) and
``_out_of_plane_g`` (the third, toward +z), each low-pass filtered like accelerations.csv (zero-phase,
run.acceleration_filter_hz, over the whole record so far), and each raw as its ``_raw`` twin
(``_axial_g_raw``, ...: the node's acceleration at the row). Values are
written with the digits that give back the same double (the rank-count invariance is checked on the file
itself).
"""

from __future__ import annotations

from pathlib import Path

from mpi4py import MPI

from fepen.io import files, table
from fepen.io.results import G0

__all__ = ["NODE_COLUMNS", "CELL_COLUMNS", "ACCELEROMETER_COLUMNS", "ACCELEROMETER_FILTERED", "quantities", "columns",
           "body_axes_g",
           "write"]

#: a node probe's quantities, in the order of its values
NODE_COLUMNS = ("ux_m", "uy_m", "uz_m", "vx_m_s", "vy_m_s", "vz_m_s", "ax_m_s2", "ay_m_s2", "az_m_s2")
#: a cell probe's quantities, in the order of its values
CELL_COLUMNS = ("von_mises_Pa", "axial_stress_Pa", "pressure_Pa", "peeq", "temperature_K")
#: an accelerometer probe's filtered channels (g, body axes: what an instrumented penetrator's record shows)
ACCELEROMETER_FILTERED = ("axial_g", "lateral_g", "out_of_plane_g")
#: an accelerometer probe's raw channels, each its filtered channel's name with _raw
ACCELEROMETER_RAW = tuple(c + "_raw" for c in ACCELEROMETER_FILTERED)
#: an accelerometer probe's columns: the raw channels, then the filtered ones
ACCELEROMETER_COLUMNS = ACCELEROMETER_RAW + ACCELEROMETER_FILTERED


def quantities(kind: str) -> tuple[str, ...]:
    """The columns (without the probe's name) of one probe kind ('node', 'cell' or 'accelerometer')."""
    return {"node": NODE_COLUMNS, "cell": CELL_COLUMNS, "accelerometer": ACCELEROMETER_COLUMNS}[kind]


def body_axes_g(acc, axis) -> list[float]:
    """An acceleration resolved on the body's axes, in g.

    Args:
        acc: the acceleration (3,), m/s², the target's frame. axis: the body's unit axis, tail to nose.

    Returns:
        [axial, lateral, out of plane] (g): along the axis; along ẑ × axis (across the axis in the plane of
        fire, +x for a normal shot); along the rest of ẑ (toward +z). An axis along z (never a shot's) takes
        x as its plane's normal instead.
    """
    import numpy as np

    a, e = np.asarray(acc, dtype=float), np.asarray(axis, dtype=float)
    z = np.array([0.0, 0.0, 1.0]) if abs(e[2]) < 0.999 else np.array([1.0, 0.0, 0.0])
    lat = np.cross(z, e)
    lat /= np.linalg.norm(lat)
    out = np.cross(e, lat)
    return [float(a @ e) / G0, float(a @ lat) / G0, float(a @ out) / G0]


def columns(probes) -> list[str]:
    """probes.csv's header.

    Args:
        probes: the probes as the scene gives them ({"name", "point", "kind"}, ...).

    Returns:
        ``t_s`` then each probe's columns.
    """
    out = ["t_s"]
    for p in probes:
        out += [f"{p['name']}_{q}" for q in quantities(p["kind"])]
    return out


def write(rows, out: Path, header: list[str], comm=MPI.COMM_WORLD) -> None:
    """probes.csv (rank 0, atomically; collective: a failed write raises MachineFault on every rank, and the
    file keeps its last complete version).

    Args:
        rows: the rows, each t then the values in the header's order.
        out: the results directory. header: columns(probes). comm: the run's communicator.
    """

    def write_file():
        files.write_text(Path(out) / "probes.csv", table.text(header, rows, digits=None), comm)

    files.agree(comm, f"{Path(out) / 'probes.csv'}", write_file)
