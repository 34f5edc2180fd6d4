"""The C trial pass of the stress update (fepen/solver/cell_kernel.c), built once per machine and called
with ctypes; the numba kernel (fepen.solver.kernels.stress_update) stays the reference (docs/theory.md §3.3)."""

from __future__ import annotations

import ctypes
import os
from pathlib import Path

import numpy as np

from fepen import native

SOURCE = Path(__file__).with_name("cell_kernel.c")

_lib = None
_why_not = None


def library():
    """The loaded C kernel, or None (then ``why_not()`` says why) — built on first use."""
    global _lib, _why_not
    if _lib is not None or _why_not is not None:
        return _lib
    if os.environ.get("FEPEN_KERNEL", "").lower() == "numba":
        _why_not = "FEPEN_KERNEL=numba"
        return None
    lib, why = native.load(SOURCE)
    if lib is None:
        _why_not = why
        return None
    vp, i32, dbl = ctypes.c_void_p, ctypes.c_int32, ctypes.c_double
    lib.trial_pass.argtypes = [i32, vp, vp, vp, dbl, vp, vp, vp, vp, vp, i32, vp, vp, vp, vp]
    lib.trial_pass.restype = i32
    _lib = lib
    return lib


def why_not() -> str | None:
    """Why the C kernel is not used (None when it is)."""
    library()
    return _why_not


class TrialPass:
    """The C trial pass bound to a solver's arrays (their addresses are taken once: the arrays must live
    as long as this object and never be reallocated).

    Args:
        x, v, X: current positions, velocities and reference positions of the nodes (n_nodes, 3),
            C-contiguous float64.
        dofs: (n_cells, 4) node indices; mat: (n_cells,) material index.
        det_R: (n_cells,) det of the reference edge matrix (X1 − X0, X2 − X0, X3 − X0) = ±6 V0.
        G_m: shear modulus per material (Pa); nodal_p: (n_nodes, n_materials) nodal mean stress.
        sT: (6, n_cells) deviatoric stress, component-major (updated in place).
        sy0: (n_cells,) static flow stress. P_out: (≥ n_cells, 9) the packed coefficient of the form.
    """

    def __init__(self, x, v, X, dofs, mat, det_R, G_m, nodal_p, sT, sy0, P_out):
        lib = library()
        if lib is None:
            raise RuntimeError(why_not())
        n = len(mat)
        self.n = n
        self._dofs = np.ascontiguousarray(dofs, dtype=np.int32)
        self._mat = np.ascontiguousarray(mat, dtype=np.int32)
        self._inv_det = 1.0 / np.asarray(det_R, dtype=float)
        self.yielding = np.zeros(n, dtype=np.int32)
        for a in (x, v, X, G_m, nodal_p, sT, sy0, P_out):
            assert a.dtype == np.float64 and a.flags.c_contiguous
        assert sT.shape == (6, n) and P_out.shape[1] == 9 and x.shape == X.shape == v.shape
        self._keep = (x, v, X, G_m, nodal_p, sT, sy0, P_out)
        addr = lambda a: a.ctypes.data  # noqa: E731
        self._head = (n, addr(x), addr(v), addr(X))
        self._tail = (addr(self._dofs), addr(self._inv_det), addr(self._mat), addr(G_m), addr(nodal_p),
                      nodal_p.shape[1], addr(sT), addr(sy0), addr(P_out), addr(self.yielding))
        self._lib = lib

    def refresh(self, mat: np.ndarray, det_R: np.ndarray) -> None:
        """Take the cells' new materials (−1: eroded) and reference edge determinants, in place (after an
        erosion or a surface recession changed them)."""
        self._mat[:] = mat
        np.divide(1.0, det_R, out=self._inv_det)

    def __call__(self, dt: float) -> np.ndarray:
        """Trial state of every cell over a step dt; returns the cells over their flow stress."""
        k = self._lib.trial_pass(*self._head, dt, *self._tail)
        return self.yielding[:k]
