"""probes.csv: the user's point and cell histories ([[output.probes]], LS-DYNA's nodout/elout, OpenRadioss'
/TH), one row per history row (the same times as history.csv), ``t_s`` then ``<name>_<quantity>_<unit>``.

Node probes (the target's frame, as fields.xdmf: metres, y = 0 the target face, the target at y < 0):
``_ux_m, _uy_m, _uz_m`` the displacement from the undeformed projectile's point (the placement at t = 0
included), ``_vx_m_s, ...`` the velocity and ``_ax_m_s2, ...`` the acceleration. Cell probes:
``_von_mises_Pa``, ``_axial_stress_Pa`` (along the axis, tail to nose; positive in tension), ``_pressure_Pa``
(positive in compression), ``_peeq`` and ``_temperature_K``. Values are written with the digits that give
back the same double (the rank-count invariance is checked on the file itself).
"""

from __future__ import annotations

import io
from pathlib import Path

from mpi4py import MPI

from fepen.io import files

__all__ = ["NODE_COLUMNS", "CELL_COLUMNS", "columns", "write"]

#: a node probe's quantities, in the order of its values
NODE_COLUMNS = ("ux_m", "uy_m", "uz_m", "vx_m_s", "vy_m_s", "vz_m_s", "ax_m_s2", "ay_m_s2", "az_m_s2")
#: a cell probe's quantities, in the order of its values
CELL_COLUMNS = ("von_mises_Pa", "axial_stress_Pa", "pressure_Pa", "peeq", "temperature_K")


def columns(probes) -> list[str]:
    """probes.csv's header.

    Args:
        probes: the probes as the scene gives them ({"name", "point", "kind"}, ...).

    Returns:
        ``t_s`` then each probe's columns.
    """
    out = ["t_s"]
    for p in probes:
        out += [f"{p['name']}_{q}" for q in (NODE_COLUMNS if p["kind"] == "node" else CELL_COLUMNS)]
    return out


def write(rows, out: Path, header: list[str], comm=MPI.COMM_WORLD) -> None:
    """probes.csv (rank 0, atomically; collective: a failed write raises MachineFault on every rank, and the
    file keeps its last complete version).

    Args:
        rows: the rows, each t then the values in the header's order.
        out: the results directory. header: columns(probes). comm: the run's communicator.
    """

    def write_file():
        buf = io.StringIO()
        buf.write(",".join(header) + "\n")
        for r in rows:
            buf.write(",".join(repr(float(v)) for v in r) + "\n")
        files.write_text(Path(out) / "probes.csv", buf.getvalue(), comm)

    files.agree(comm, f"{Path(out) / 'probes.csv'}", write_file)
