"""One material point driven on plain arrays: the elastic trial and radial return of a single point, and
a uniaxial-stress driver (the material tests and verification use them; the solver's cell kernels do
the same arithmetic for every cell, fepen.solver.kernels)."""

from __future__ import annotations

import math

import numba
import numpy as np

from fepen.laws.materials import _FAST, A_, E_, NU, TROOM, Material, radial_return


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def update_deviatoric(s, de, eps_p, T, dt, p, out_dwp):
    """Elastic trial + radial return of one point, in place.

    Args:
        s: deviatoric Cauchy stress, 6 Voigt components (xx, yy, zz, xy, yz, xz), already rotated to the
           end of the step; updated in place.
        de: deviatoric strain increment, 6 components with tensor (not engineering) shears.
        eps_p, T: plastic strain and temperature at the start of the step.
        dt: step (s).
        p: material parameters.
        out_dwp: length-2 array: receives (plastic work per unit volume, plastic strain increment).

    Returns:
        (eps_p_new, T_new).
    """
    G = p[E_] / (2.0 * (1.0 + p[NU]))
    for i in range(6):
        s[i] += 2.0 * G * de[i]
    q = math.sqrt(1.5 * (s[0] ** 2 + s[1] ** 2 + s[2] ** 2 + 2.0 * (s[3] ** 2 + s[4] ** 2 + s[5] ** 2)))
    d, sy, Tn = radial_return(q, eps_p, T, dt, G, p)
    out_dwp[0] = 0.0
    out_dwp[1] = d
    if d > 0.0:
        scale = sy / q
        for i in range(6):
            s[i] *= scale
        out_dwp[0] = sy * d
    return eps_p + d, Tn


def uniaxial_stress_path(material: Material, strains: np.ndarray, dt: float, T0: float | None = None):
    """Drive one point along uniaxial stress (lateral stresses zero) through a strain history.

    A small driver for the material tests: the lateral strain is iterated each step so that the lateral
    stress vanishes (an incompressible plastic flow plus elastic Poisson contraction).

    Args:
        material: the material.
        strains: axial logarithmic strains, increasing from 0.
        dt: time per increment (s), sets the strain rate.
        T0: initial temperature (K); default the room temperature.

    Returns:
        (axial stress, plastic strain, temperature) arrays, one entry per strain.
    """
    p = material.params
    K = material.bulk_modulus
    T = p[TROOM] if T0 is None else T0
    s = np.zeros(6)
    ep, pres = 0.0, 0.0
    out = np.zeros((len(strains), 3))
    buf = np.zeros(2)
    prev = 0.0
    for i, e in enumerate(strains):
        dax = e - prev
        prev = e
        # lateral increment from the condition sigma_lat = 0, by secant iterations
        lat = -0.5 * dax

        def trial(lat, dax=dax, s=s, ep=ep, T=T, pres=pres):
            dv = dax + 2.0 * lat
            dev = np.array([dax - dv / 3.0, lat - dv / 3.0, lat - dv / 3.0, 0.0, 0.0, 0.0])
            st = s.copy()
            ep_n, T_n = update_deviatoric(st, dev, ep, T, dt, p, buf)
            pr = pres + K * dv
            return st, ep_n, T_n, pr, st[1] + pr

        x0, x1 = lat, -0.3 * dax
        f0, f1 = trial(x0)[4], trial(x1)[4]
        for _ in range(60):
            if abs(f1 - f0) < 1e-30:
                break
            x2 = x1 - f1 * (x1 - x0) / (f1 - f0)
            x0, f0 = x1, f1
            x1, f1 = x2, trial(x2)[4]
            if abs(f1) < 1e-9 * max(1.0, abs(p[A_])):
                break
        s, ep, T, pres, _ = trial(x1)
        out[i] = s[0] + pres, ep, T
    return out[:, 0], out[:, 1], out[:, 2]
