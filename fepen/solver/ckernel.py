"""The deformable step in C (fepen/solver/cell_kernel.c), built once per machine and called with ctypes: the
node update, the kinematics pass, the nodal pressure and the fused stress-and-force pass. The numba kernels
(fepen.solver.kernels: volumes_and_step, stress_update, internal_force) stay the reference
(docs/theory.md §3.3)."""

from __future__ import annotations

import numpy as np

from fepen import native

#: kinematics_pass's out, read from cell_kernel.h; cell_pass's totals as fepen.solver.explicit and the numba
#: kernels index them (plastic work, heat, 0, the largest increment), held to the header when the kernel is loaded
KIN_J_MIN, KIN_J_CELL, KIN_DT_MIN, KIN_DT_CELL, KIN_COUNT = native.enum_values(
    native.PACKAGE / native.KERNELS["cells"].header, "KIN_J_MIN", "KIN_J_CELL", "KIN_DT_MIN", "KIN_DT_CELL",
    "KIN_COUNT")
native.shares("cells", "TOT_", [("TOT_PLASTIC", 1), ("TOT_HEAT", 1), ("TOT_RESERVED", 1), ("TOT_D_MAX", 1)])


def library():
    """The loaded C kernel (fepen.native's "cells"), or None (then ``why_not()`` says why) — built on first use."""
    return native.kernel("cells")


def why_not() -> str | None:
    """Why the C kernel is not used (None when it is)."""
    return native.why_not("cells")


def _addr(a: np.ndarray, dtype=np.float64) -> int:
    """The address of a C-contiguous array of the given dtype (AssertionError if it is not one)."""
    assert a.dtype == dtype and a.flags.c_contiguous, (a.dtype, a.flags.c_contiguous)
    return a.ctypes.data


class CellPasses:
    """The C cell passes bound to a body's arrays (their addresses are taken once: the arrays must live as
    long as this object and be changed only in place — erosion and a receding surface do so).

    Args:
        x, v: current positions and velocities of the nodes (n_nodes, 3).
        dofs: (n_cells, 4) node indices (copied as int32: never changed); mat: (n_cells,) int64 material
            index, −1 for an eroded cell (read live).
        orient: (n_cells,) ±1, the sign of the reference edge determinant; vol0: (n_cells,) reference volume.
        speed: dilatational wave speed per material; params: (n_materials, N_PARAMS) material parameters;
            G_m: shear modulus per material (Pa).
        nodal_p: (n_nodes, n_materials) nodal mean stress.
        sT: (6, n_cells) deviatoric stress, component-major; eps_p, temp, sy0: (n_cells,) cell state.
        cvol: (n_cells,) output of the current cell volumes; cell_dt: (n_cells,) output of h/c per cell.
        Fc: (n_cells, 4, 3) output of each cell's internal force on its four nodes, or None (not stored).
        totals: (4,) output: plastic work, heat, 0, largest plastic increment of the last cell pass.
        nvol: (n_nodes, n_materials) output of the nodal volumes per material, summed by the kinematics pass
            (before ghosts are summed), or None. fint: (n_nodes, 3) output of the internal forces, summed by the
            cell pass (before ghosts are summed), or None. Both sums are those of NodePasses.scatter_volumes and
            scatter_forces, on the grids given at each call, made while each block of cells is in cache.

    All float arrays float64 and C-contiguous.
    """

    def __init__(self, x, v, dofs, mat, orient, vol0, speed, params, G_m, nodal_p, sT, eps_p, temp, sy0,
                 cvol, cell_dt, Fc, totals, nvol=None, fint=None):
        lib = library()
        if lib is None:
            raise RuntimeError(why_not())
        n = len(mat)
        self.n = n
        self.dofs32 = np.ascontiguousarray(dofs, dtype=np.int32)
        assert sT.shape == (6, n) and x.shape == v.shape and (Fc is None or Fc.shape == (n, 4, 3))
        assert nvol is None or (nvol.ndim == 2 and len(nvol) == len(x)) and (fint is None or fint.shape == x.shape)
        self._out = np.zeros(KIN_COUNT)
        self._keep = (x, v, mat, orient, vol0, speed, params, G_m, nodal_p, sT, eps_p, temp, sy0, cvol,
                      cell_dt, Fc, totals, nvol, fint)
        a = _addr

        def a_or_null(arr):
            return None if arr is None else a(arr)

        self._kin = (n, a(x), a(self.dofs32, np.int32), a(mat, np.int64), a(orient), a(vol0), a(speed))
        self._kin_out = (a(cvol), a(cell_dt), a(self._out))
        self._kin_sum = (0 if nvol is None else nvol.shape[1], len(x), a_or_null(nvol))
        self._cell_x = (n, a(x), a(v))
        self._cell_rest = (a(self.dofs32, np.int32), a(mat, np.int64), a(orient), params.shape[0], a(params), a(G_m),
                           a(nodal_p), a(sT), a(eps_p), a(temp), a(sy0), a_or_null(Fc))
        self._cell_sum = (len(x), a_or_null(fint), a(totals))
        self._lib = lib

    def kinematics(self, with_step: bool, quantum: float = 1.0) -> tuple[float, int, float, int]:
        """Current volumes into cvol (and, with_step, h/c per cell into cell_dt); the nodal volumes into nvol on
        the grid ``quantum`` (a power of two), if nvol was given.

        Returns:
            (smallest J over live cells (NaN if any is NaN), its cell, smallest h/c (inf unless with_step),
            its cell); cells −1 for none.
        """
        self._lib.kinematics_pass(*self._kin, int(with_step), *self._kin_out, quantum, *self._kin_sum)
        o = self._out
        return float(o[KIN_J_MIN]), int(o[KIN_J_CELL]), float(o[KIN_DT_MIN]), int(o[KIN_DT_CELL])

    def cells(self, dt: float, quantum: float = 1.0) -> int:
        """The fused pass over a step dt: stress, return, plastic work, Fc (if given), the internal forces into
        fint on the grid ``quantum`` (a power of two; if fint was given). Returns how many cells yielded."""
        return self._lib.cell_pass(*self._cell_x, dt, *self._cell_rest, quantum, *self._cell_sum)


class NodePasses:
    """The C node passes (central-difference update, nodal pressure, the plain cell-to-node sums), on
    arrays passed at each call (addresses checked and taken once per array: an array is remembered with its
    address while it is passed; one that is replaced is checked and taken anew)."""

    def __init__(self):
        lib = library()
        if lib is None:
            raise RuntimeError(why_not())
        self._lib = lib
        self._known: dict[int, tuple[np.ndarray, int]] = {}

    def _a(self, a: np.ndarray, dtype=np.float64) -> int:
        """_addr of an array, remembered (the array is held, so its id is not reused while remembered)."""
        hit = self._known.get(id(a))
        if hit is not None and hit[0] is a:
            return hit[1]
        if len(self._known) > 64:
            self._known.clear()
        address = _addr(a, dtype)
        self._known[id(a)] = (a, address)
        return address

    def update_begin(self, h: float, dt: float, n_owned: int, acc, vel, u, X, x, du, fint, fext, work) -> None:
        """v += h a, du = dt v, u += du, x = X + u (all rows); each owned node's du·f_int / 2 and du·f_ext / 2
        added into work (n_nodes, 2)."""
        a = self._a
        self._lib.update_begin(len(u), n_owned, h, dt, a(acc), a(vel), a(u), a(X), a(x), a(du), a(fint), a(fext),
                               a(work))

    def update_end(self, n_owned: int, fint, fext, mass, fixed, du, acc, work) -> None:
        """a = (f_ext − f_int) / m on owned rows (0 where fixed: (n, 3) bool or None); each owned node's half
        of the new forces' work added into work (n_nodes, 2)."""
        a = self._a
        fx = None if fixed is None else a(fixed, np.bool_)
        self._lib.update_end(n_owned, a(fint), a(fext), a(mass), fx, a(du), a(acc), a(work))

    def nodal_pressure(self, vol, vol0, bulk, out) -> None:
        """p = K ln J / J per node and material (0 where no reference volume)."""
        a = self._a
        self._lib.nodal_pressure(vol.shape[0], a(vol), a(vol0), a(bulk), vol.shape[1], a(out))

    def scatter_volumes(self, dofs32, mat, cvol, quantum: float, out) -> None:
        """out (n_rows, n_materials) = Σ over live cells of cvol / 4 on each node, each term rounded to a
        multiple of ``quantum`` (a power of two: exact sums, the same in any order)."""
        self._lib.scatter_volumes(len(cvol), _addr(dofs32, np.int32), _addr(mat, np.int64), _addr(cvol),
                                  quantum, out.shape[1], out.shape[0], _addr(out))

    def scatter_forces(self, dofs32, Fc, quantum: float, out) -> None:
        """out (n_rows, 3) = Σ over cells of Fc on their nodes, each term rounded to a multiple of ``quantum``
        (a power of two: exact sums, the same in any order)."""
        self._lib.scatter_forces(len(Fc), _addr(dofs32, np.int32), _addr(Fc), quantum, out.shape[0], _addr(out))
