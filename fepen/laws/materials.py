"""Material laws on plain arrays: elastic, Johnson-Cook with rate, adiabatic heating and thermal softening,
bilinear; the fully consistent radial return (docs/theory.md §4). The parameter vectors are made here; the law
itself has one home, fepen/laws/materials_kernel.c, which the C step includes and the numba code calls
(yield_stress, radial_return). Deviatoric stress ``s`` is stored as 6 Voigt components (xx, yy, zz, xy, yz, xz),
tension positive.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np

from fepen import native

#: fast-math flags that keep IEEE NaN/inf semantics (inverted or NaN elements must still be detected)
_FAST = {"nsz", "arcp", "contract", "afn", "reassoc"}

# Layout of the parameter vector handed to compiled code, and the kinds: read from materials_kernel.h's enums
# (declared once, in C; a member the header lacks stops the import, naming it)
_HEADER = Path(__file__).with_name("materials_kernel.h")
KIND, E_, NU, RHO, A_, B_, N_, C_, M_, TMELT, TROOM, EPS0, CP, BETA, RATE_ON, THERMAL_ON, H_ = native.enum_values(
    _HEADER, "KIND", "E_", "NU", "RHO", "A_", "B_", "N_", "C_", "M_", "TMELT", "TROOM", "EPS0", "CP", "BETA",
    "RATE_ON", "THERMAL_ON", "H_")
(N_PARAMS,) = native.enum_values(_HEADER, "N_PARAMS")
ELASTIC, JOHNSON_COOK, BILINEAR = native.enum_values(_HEADER, "ELASTIC", "JOHNSON_COOK", "BILINEAR")


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
# The law itself: fepen/laws/materials_kernel.c, its one home, called by name from compiled numba code (the
# library loaded into the process once, so that the numba kernels that call it stay cached on disk)
# ---------------------------------------------------------------------------------------------------------
def _law_library() -> None:
    """Load materials_kernel.c's library into the process for numba's calls by symbol (fepen.native)."""
    import llvmlite.binding as llvm

    from fepen import native

    native.kernel("materials")
    llvm.load_library_permanently(native.library_path("materials"))


#: numba's type of each ctypes type fepen.native reads from a prototype
_NUMBA = {ctypes.c_double: numba.types.double, ctypes.c_int32: numba.types.int32, ctypes.c_void_p: numba.types.voidptr}


def _external(name: str) -> numba.types.ExternalFunction:
    """materials_kernel.h's function ``name`` for numba, its signature read from the header's prototype."""
    args, result = native.c_prototypes(_HEADER)[name]
    return numba.types.ExternalFunction(name, _NUMBA[result](*[_NUMBA[a] for a in args]))


_law_library()
_RETURN = _external("material_radial_return")
_FLOW = _external("material_yield_stress")


@numba.njit(cache=True, error_model="numpy")
def yield_stress(eps_p, rate, T, p):
    """Flow stress (Pa) at plastic strain eps_p, plastic strain rate ``rate`` (1/s), temperature T (K): the
    C law's (materials_kernel.c)."""
    return _FLOW(eps_p, rate, T, p.ctypes.data)


@numba.njit(cache=True, error_model="numpy")
def radial_return(q_trial, eps_p, T, dt, G, p):
    """Solve q_trial - 3 G d - sigma_y(eps_p + d, d/dt, T(d)) = 0 for the plastic increment d >= 0 (the C law's
    safeguarded Newton, materials_kernel.c).

    Args:
        q_trial: von Mises stress of the elastic trial state (Pa).
        eps_p, T: equivalent plastic strain and temperature (K) at the start of the step.
        dt: time step (s), for the strain rate d/dt.
        G: shear modulus (Pa).
        p: material parameter vector (contiguous float64).

    Returns:
        (d, sigma_y, T_new): plastic strain increment, flow stress, temperature after the step. d = 0 when
        the trial state is elastic.
    """
    out = np.empty(2)
    d = _RETURN(q_trial, eps_p, T, dt, G, p.ctypes.data, out.ctypes.data)
    return d, out[0], out[1]
