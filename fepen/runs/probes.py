"""The user's point and cell histories (``[[output.probes]]``; probes.csv, fepen.io.probes): where each probe
is, and its values at every history row, on the meshed projectile (MeshProbes) or the rigid body
(RigidProbes).

A point outside the body is an input error: against the exact solid before any mesh (``check_inside``: the
outside of revolution and its cavity, a CAD body's bounding cylinder), then against the mesh before any step
(a node probe's nearest node at most mesh.size away, a cell probe's cell holding the point). The node and the
cell are chosen the same on any partition (fepen.solver.probes), so probes.csv is the same on any number of
ranks. The rigid fidelity has node probes only (fepen.scene.resolve refuses cell probes there): the rigid
motion of the point, its acceleration from the force and moment at the row's state.
"""

from __future__ import annotations

import functools

import numpy as np

from fepen.errors import InputError
from fepen.geometry.cad import CadBody
from fepen.geometry.frames import unit_axis
from fepen.geometry.shape import Shape
from fepen.io import probes as probes_io
from fepen.post import signals

__all__ = ["check_inside", "filtered", "Probes", "MeshProbes", "RigidProbes"]

#: points this close outside the exact outline (m) are taken as on it
OUTLINE_TOLERANCE = 1e-9


def _outside_why(shape, point, charged: bool) -> str | None:
    """Why a point (x, y, z) of the reference frame is outside the exact body, or None."""
    x, y, z = point
    r = float(np.hypot(x, z))
    tol = OUTLINE_TOLERANCE
    if not -tol <= y <= shape.length + tol:
        return f"y = {y:g} m is outside the body's length [0, {shape.length:g}] m (nose tip at the origin, axis +y)"
    return outside_radially(shape, y, r, charged, tol)


@functools.singledispatch
def outside_radially(shape, y: float, r: float, charged: bool, tol: float) -> str | None:
    """Why a point at y along the axis (within the body's length) and r from it lies outside the body, by the
    body's kind; None when inside.

    Args:
        shape: a Shape (its exact outline and cavity) or a CadBody (its enclosing cylinder). y, r: the point's
            axial position and distance from the axis (m). charged: the charge fills the cavity (a point there
            is inside). tol: how far outside still counts as on the outline (m).

    Returns:
        The reason, or None.
    """
    raise TypeError(f"no outline for a {type(shape).__name__}")


@outside_radially.register(CadBody)
def _outside_cylinder(shape, y, r, charged, tol):
    """A CAD body: its enclosing cylinder (no exact outline)."""
    return None if r <= shape.radius + tol else f"its radius {r:g} m is past the body's {shape.radius:g} m"


@outside_radially.register(Shape)
def _outside_exact(shape, y, r, charged, tol):
    """The exact solid: past its outside, or in its cavity unless charged."""
    outer = float(shape.outer_radius(y))
    if r > outer + tol:
        return f"its distance from the axis {r:g} m is past the outside's radius {outer:g} m at y = {y:g} m"
    if not charged:
        for z0, z1, rc in shape.cavity_sections():
            if z0 < y < z1 and r < rc:
                return f"it lies in the cavity (radius {rc:g} m between y = {z0:g} and {z1:g} m)"
    return None


def check_inside(shape, probes, charged: bool) -> None:
    """InputError naming the first probe whose point is outside the exact body (before any mesh).

    Args:
        shape: the built Shape or CadBody. probes: the scene's output.probes. charged: the cavity holds the
            charge (effects.charge): a point there is inside the body.
    """
    for i, p in enumerate(probes):
        why = _outside_why(shape, p["point"], charged)
        if why is not None:
            raise InputError(f"output.probes[{i}].point", f"{p['point']} is outside the projectile: {why}")


class Probes:
    """The rows of the probes of one run (every rank holds them) and probes.csv.

    Args:
        specs: the scene's output.probes.
    """

    def __init__(self, specs):
        self.specs = tuple(specs)
        self.header = probes_io.columns(self.specs)
        self.rows: list[list[float]] = []

    def values(self, run) -> list[float]:
        """The probes' values now, in the header's order (collective)."""
        raise NotImplementedError

    def record(self, run) -> None:
        """Append the row of the run's time (collective)."""
        self.rows.append([run.t, *self.values(run)])

    def write(self, out, comm, cutoff_hz: float = 0.0, kind: str = "butterworth") -> None:
        """probes.csv of the rows so far (collective); kind, cutoff_hz: the accelerometers' filter
        (run.acceleration_filter, run.acceleration_filter_hz)."""
        rows = filtered(self.rows, self.header, cutoff_hz, kind) if any(h.endswith("_g_raw") for h in self.header) \
            else self.rows
        probes_io.write(rows, out, self.header, comm)

    def state(self) -> dict:
        """The rows (a checkpoint's arrays)."""
        return {"rows": np.array(self.rows, dtype=float).reshape(len(self.rows), len(self.header))}

    def restore(self, state: dict) -> None:
        """Put back what state() returned."""
        self.rows = [list(r) for r in state["rows"]]


class MeshProbes(Probes):
    """The probes of a deformable run: the nearest node, the cell holding the point (located before any step,
    collective).

    Args:
        specs: the scene's output.probes. solver: the ExplicitSolver at its initial state. size: mesh.size (m),
            the farthest a node probe's node may be from its point.
    """

    def __init__(self, specs, solver, size: float):
        from fepen.solver import probes as sp

        super().__init__(specs)
        self.nodes, self.cells = [], []
        for i, p in enumerate(self.specs):
            where = f"output.probes[{i}].point"
            cell = sp.containing_cell(solver, p["point"])
            if p["kind"] == "cell":
                if cell[0] < 0:
                    raise InputError(where, f"{p['point']} is in no cell of the meshed projectile (outside it, or "
                                            "between the exact curved surface and the mesh's flat faces: move it "
                                            "inward)")
                self.cells.append(cell)
                continue
            node, dist = sp.nearest_node(solver, p["point"])
            if cell[0] < 0 and dist > size:
                raise InputError(where, f"{p['point']} is outside the meshed projectile: its nearest node is "
                                        f"{dist:.3g} m away (more than mesh.size = {size:g} m)")
            self.nodes.append(node)

    def values(self, run) -> list[float]:
        from fepen.solver import probes as sp

        s = run.solver
        x = s.positions()
        nodes = cells = np.zeros((0, 0))
        axis = None
        if self.cells or any(p["kind"] == "accelerometer" for p in self.specs):  # (collective: every rank's specs)
            axis = unit_axis(sp.node_value(s, run.model.tip, x), sp.node_value(s, run.model.tail, x))
        if self.nodes:
            u = sp.node_values(s, self.nodes, x - s.X0)
            v = sp.node_values(s, self.nodes, s.velocity_at_step())
            a = sp.node_values(s, self.nodes, s.acc)
            nodes = np.concatenate([u, v, a], axis=1)
        if self.cells:
            cells = sp.cell_values(s, self.cells, axis)
        return _in_order(self.specs, nodes, cells, axis)


class RigidProbes(Probes):
    """The node probes of a rigid run: the rigid motion of each point.

    Args:
        specs: the scene's output.probes (node probes only).
    """

    def __init__(self, specs):
        super().__init__(specs)
        self.X = np.array([p["point"] for p in self.specs], dtype=float).reshape(-1, 3)

    def values(self, run) -> list[float]:
        """Displacement c + R (X − c0) − X, velocity V + ω × r, acceleration F/m + α × r + ω × (ω × r), with
        α = R I⁻¹ Rᵀ (M − ω × L) from the force and moment at this state (the next step's first stage's)."""
        body, s = run.body, run.state
        _, F, M = body.derivative(s, run.force_fn)
        _, R, w, _ = body.at(s)
        r = (self.X - body.centre0) @ np.asarray(R).T
        u = s.c + r - self.X
        v = s.V + np.cross(w, r)
        alpha = R @ (body.I_body_inv @ (R.T @ (M - np.cross(w, s.L))))
        a = F / body.mass + np.cross(alpha, r) + np.cross(w, np.cross(w, r))
        axis = R @ np.array([0.0, -1.0, 0.0])  # tail to nose: the reference body's nose tip is at y = 0, its tail at +y
        return _in_order(self.specs, np.concatenate([u, v, a], axis=1), np.zeros((0, 0)), axis)


def filtered(rows, header: list[str], cutoff_hz: float, kind: str = "butterworth") -> list[list[float]]:
    """The rows with every accelerometer's filtered columns filled from its raw ones (zero-phase low-pass over
    the whole record, fepen.post.signals.acceleration_filter; the rows as given are left alone).

    Args:
        rows: the rows, t then the values in the header's order (the filtered columns' values are ignored).
        header: columns(probes). cutoff_hz: run.acceleration_filter_hz. kind: run.acceleration_filter.

    Returns:
        The rows, filtered columns filled.
    """
    table = np.array(rows, dtype=float).reshape(len(rows), len(header))
    for j, name in enumerate(header):
        if name + "_raw" in header:  # an accelerometer's filtered channel
            raw = header.index(name + "_raw")
            table[:, j] = signals.acceleration_filter(table[:, 0], table[:, raw], kind, cutoff_hz) if len(rows) \
                else []
    return table.tolist()


def _in_order(specs, nodes: np.ndarray, cells: np.ndarray, axis: np.ndarray | None) -> list[float]:
    """The node and cell probes' value rows merged back into the scene's order; an accelerometer's node
    acceleration resolved on the body's axes (its filtered columns left at 0: probes.csv's writer fills them
    from the whole record)."""
    out: list[float] = []
    i = j = 0
    for p in specs:
        if p["kind"] == "node":
            out += [float(v) for v in nodes[i]]
            i += 1
        elif p["kind"] == "accelerometer":
            out += probes_io.body_axes_g(nodes[i][6:9], axis) + [0.0, 0.0, 0.0]
            i += 1
        else:
            out += [float(v) for v in cells[j]]
            j += 1
    return out
