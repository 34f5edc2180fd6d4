"""Material laws on plain arrays (numba): elastic, Johnson-Cook with rate, adiabatic heating and thermal
softening, bilinear; the fully consistent radial return (docs/theory.md §4). Deviatoric stress ``s`` is
stored as 6 Voigt components (xx, yy, zz, xy, yz, xz), tension positive.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

#: fast-math flags that keep IEEE NaN/inf semantics (inverted or NaN elements must still be detected)
_FAST = {"nsz", "arcp", "contract", "afn", "reassoc"}

# Layout of the parameter vector handed to compiled code
KIND, E_, NU, RHO, A_, B_, N_, C_, M_, TMELT, TROOM, EPS0, CP, BETA, RATE_ON, THERMAL_ON, H_ = range(17)
N_PARAMS = 17
ELASTIC, JOHNSON_COOK, BILINEAR = 0, 1, 2


@dataclass(frozen=True)
class Material:
    """A material as fepen's compiled kernels see it.

    Attributes:
        params: float64 vector, layout given by the module constants (KIND, E_, NU, ...).
    """

    params: np.ndarray

    @property
    def E(self):
        return self.params[E_]

    @property
    def nu(self):
        return self.params[NU]

    @property
    def density(self):
        return self.params[RHO]

    @property
    def shear_modulus(self):
        return self.params[E_] / (2.0 * (1.0 + self.params[NU]))

    @property
    def bulk_modulus(self):
        return self.params[E_] / (3.0 * (1.0 - 2.0 * self.params[NU]))

    @property
    def kind(self):
        return int(self.params[KIND])


def elastic(E: float, nu: float, density: float) -> Material:
    """Linear (hypo)elastic material."""
    p = np.zeros(N_PARAMS)
    p[[KIND, E_, NU, RHO]] = ELASTIC, E, nu, density
    return Material(p)


def johnson_cook(E, nu, density, A, B, n, C, m, melt_temperature, room_temperature,
                 reference_strain_rate=1.0, specific_heat=470.0, taylor_quinney=0.9,
                 strain_rate=True, thermal=True) -> Material:
    """Johnson-Cook plasticity with optional strain-rate and thermal-softening terms.

    Args:
        E, nu, density: elastic constants (Pa, -, kg/m^3).
        A, B, n, C, m: Johnson-Cook constants (Pa, Pa, -, -, -).
        melt_temperature, room_temperature: K.
        reference_strain_rate: eps_dot_0 (1/s).
        specific_heat: J/(kg K); taylor_quinney: fraction of plastic work turned into heat.
        strain_rate, thermal: switch the rate term and thermal softening + adiabatic heating.
    """
    p = np.zeros(N_PARAMS)
    p[[KIND, E_, NU, RHO, A_, B_, N_, C_, M_, TMELT, TROOM, EPS0, CP, BETA, RATE_ON, THERMAL_ON]] = (
        JOHNSON_COOK, E, nu, density, A, B, n, C, m, melt_temperature, room_temperature,
        reference_strain_rate, specific_heat, taylor_quinney, float(strain_rate), float(thermal))
    return Material(p)


def bilinear(E, nu, density, yield_stress, tangent_modulus) -> Material:
    """Bilinear isotropic hardening: sigma_y = sigma_0 + H eps_p, H = E E_t / (E - E_t)."""
    if tangent_modulus >= E:
        raise ValueError("tangent modulus must be below Young's modulus")
    p = np.zeros(N_PARAMS)
    p[[KIND, E_, NU, RHO, A_, H_]] = BILINEAR, E, nu, density, yield_stress, E * tangent_modulus / (E - tangent_modulus)
    return Material(p)


# ---------------------------------------------------------------------------------------------------------
# Compiled scalar laws
# ---------------------------------------------------------------------------------------------------------
@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def homologous_temperature(T, p):
    """T* clipped to [0, 1]."""
    ts = (T - p[TROOM]) / (p[TMELT] - p[TROOM])
    return min(max(ts, 0.0), 1.0)


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def yield_stress(eps_p, rate, T, p):
    """Flow stress (Pa) at plastic strain eps_p, plastic strain rate ``rate`` (1/s), temperature T (K)."""
    kind = int(p[KIND])
    if kind == BILINEAR:
        return p[A_] + p[H_] * eps_p
    if kind != JOHNSON_COOK:
        return np.inf
    s = p[A_] + p[B_] * max(eps_p, 0.0) ** p[N_]
    if p[RATE_ON] > 0.0 and rate > p[EPS0]:
        s *= 1.0 + p[C_] * math.log(rate / p[EPS0])
    if p[THERMAL_ON] > 0.0:
        s *= 1.0 - homologous_temperature(T, p) ** p[M_]
    return s


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def _yield_and_slope(eps_p, d, dt, T0, p, s_heat):
    """sigma_y(eps_p + d, d/dt, T) and its derivative in d, with the adiabatic temperature
    T = T0 + beta s_heat d / (rho c_p) computed from the flow stress s_heat of the previous Newton iterate
    (at convergence s_heat equals the returned flow stress: hardening, rate and heating are consistent).

    Returns:
        (sigma_y, d sigma_y / d d, T).
    """
    kind = int(p[KIND])
    if kind == BILINEAR:
        return p[A_] + p[H_] * (eps_p + d), p[H_], T0
    e = eps_p + d
    emin = 1e-12
    ee = max(e, emin)
    en = ee ** p[N_]
    h0 = p[A_] + p[B_] * en
    dh0 = p[N_] * p[B_] * en / ee if e > emin else 0.0
    if dh0 > 1e3 * p[E_]:  # n < 1: infinite slope at eps_p = 0; cap it for Newton
        dh0 = 1e3 * p[E_]
    r, dr = 1.0, 0.0
    if p[RATE_ON] > 0.0 and dt > 0.0:
        rate = d / dt
        if rate > p[EPS0]:
            r = 1.0 + p[C_] * math.log(rate / p[EPS0])
            dr = p[C_] / d
    g = h0 * r
    dg = dh0 * r + h0 * dr
    if p[THERMAL_ON] <= 0.0:
        return g, dg, T0
    k = p[BETA] / (p[RHO] * p[CP])
    T = T0 + k * s_heat * d
    ts = homologous_temperature(T, p)
    if ts <= 0.0:
        return g, dg, T
    tm = ts ** p[M_]
    s = g * (1.0 - tm)
    ds = dg * (1.0 - tm)
    if ts < 1.0:  # dT/dd = k s_heat
        ds -= g * p[M_] * tm / ts * k * s_heat / (p[TMELT] - p[TROOM])
    return s, ds, T


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def radial_return(q_trial, eps_p, T, dt, G, p):
    """Solve q_trial - 3 G d - sigma_y(eps_p + d, d/dt, T(d)) = 0 for the plastic increment d >= 0.

    Args:
        q_trial: von Mises stress of the elastic trial state (Pa).
        eps_p, T: equivalent plastic strain and temperature (K) at the start of the step.
        dt: time step (s), for the strain rate d/dt.
        G: shear modulus (Pa).
        p: material parameter vector.

    Returns:
        (d, sigma_y, T_new): plastic strain increment, flow stress, temperature after the step. d = 0 when
        the trial state is elastic.
    """
    kind = int(p[KIND])
    if kind == ELASTIC:
        return 0.0, np.inf, T
    s0, _, _ = _yield_and_slope(eps_p, 0.0, dt, T, p, 0.0)
    if q_trial <= s0:
        return 0.0, s0, T
    # bracket: f(0) > 0, f(q_trial / 3G) <= 0 since sigma_y >= 0
    lo, hi = 0.0, q_trial / (3.0 * G)
    d = min(max((q_trial - s0) / (3.0 * G), 1e-14), hi)
    s, Tn = s0, T
    s_heat = s0
    for _ in range(100):
        s, ds, Tn = _yield_and_slope(eps_p, d, dt, T, p, s_heat)
        f = q_trial - 3.0 * G * d - s
        if abs(f) <= 1e-12 * q_trial and abs(s - s_heat) <= 1e-12 * q_trial:
            break
        s_heat = s
        if f > 0.0:
            lo = d
        else:
            hi = d
        dn = d + f / (3.0 * G + ds)
        if not (lo < dn < hi):  # Newton left the bracket: bisect
            dn = 0.5 * (lo + hi)
        d = dn
    return d, s, Tn
