"""The concrete target as a resistance law on plain arrays of projectile surface points (docs/theory.md §8,
docs/paper.md §4): cavity-expansion σ_s, tunnel stress, wake, separation, free surface, both craters,
friction, and the load on a set of points. The target face is the plane y = 0, the target y < 0.
"""

from __future__ import annotations

import functools
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

SIN_TOL = 1e-9  # v̂·n below this counts as zero (a surface parallel to the motion is not loaded)

#: fepen's calibrated "scaled-S" strength model (docs/validation-depth.md: one fit, rigid fidelity, on the
#: calibration sets listed there); S = coefficient (f_c/MPa)^-exponent / sqrt(1 + D/size)
SCALED_S_COEFFICIENT = 132.1
SCALED_S_EXPONENT = 0.544
SCALED_S_SIZE = 0.05631
#: the same fit with the calibrated nose wear on (effects.wear; docs/wear.md §2: fepen.studies.wear_calibration)
SCALED_S_WEAR = (124.6, SCALED_S_EXPONENT, 0.06291)


# ---------------------------------------------------------------------------------------------------------
# §4.1 quasi-static cavity expansion
# ---------------------------------------------------------------------------------------------------------
def a_over_c_cubed(Y: float, E: float, T: float) -> float:
    """(a/c)^3 = (9Y/(4E)) (Y/(2T))^(1/2) of the elastic–cracked–plastic cavity expansion: below 1 when the
    plastic zone is wider than the cavity (the scene refuses the constants otherwise)."""
    return 9.0 * Y / (4.0 * E) * math.sqrt(Y / (2.0 * T))


def cavity_ratio(Y: float, E: float, T: float) -> float:
    """c/a of the elastic–cracked–plastic cavity expansion: (a/c)^3 = (9Y/(4E)) (Y/(2T))^(1/2)."""
    return a_over_c_cubed(Y, E, T) ** (-1.0 / 3.0)


def quasi_static_stress(Y, E, T, lam, c_over_a=None):
    """Quasi-static radial stress at the cavity wall (Pa), compression positive (§4.1):

        σ_s = (Y/λ) [(2/α)(c/a)^(αλ) − (3 − λ)/3],   α = 6/(3 + 2λ)

    written as Y [(2/α) expm1(αλ ln(c/a))/λ + 1], which tends to the Tresca value Y [1 + 2 ln(c/a)] as
    λ → 0 without dividing by zero.

    Args:
        Y: unconfined compressive strength (Pa); E: Young's modulus (Pa); T: tensile strength (Pa).
        lam: pressure-hardening coefficient λ (0 <= λ < 3).
        c_over_a: plastic-zone radius over cavity radius (array allowed); default from cavity_ratio.

    Returns:
        σ_s (Pa), scalar or array like c_over_a.
    """
    ca = cavity_ratio(Y, E, T) if c_over_a is None else np.asarray(c_over_a, dtype=float)
    alpha = 6.0 / (3.0 + 2.0 * lam)
    L = np.log(ca)
    if lam == 0.0:
        g = alpha * L
    else:
        g = np.expm1(alpha * lam * L) / lam
    return Y * ((2.0 / alpha) * g + 1.0)


def strength_S(fc_pa: float, diameter: float, coefficient: float, exponent: float, size: float) -> float:
    """Empirical strength factor S of σ_s = S f_c (docs/theory.md §8.1):

        S = coefficient (f_c / 1 MPa)^(−exponent) / √(1 + D / size)

    Forrestal's power law in f_c (Frew et al. 1998) times Bažant's size-effect law (1984) in the projectile
    diameter D; size = inf gives no size effect.

    Args:
        fc_pa: unconfined compressive strength (Pa). diameter: projectile diameter D (m).
        coefficient, exponent: the power law's constants. size: Bažant's transitional size D0 (m).

    Returns:
        S (dimensionless).
    """
    return coefficient * (fc_pa / 1e6) ** -exponent / math.sqrt(1.0 + diameter / size)  # D/inf = 0


#: the "scaled-S" constants refitted by the same procedure with friction on (the paper's Coulomb μ = 0.1 on
#: the whole surface; docs/validation-depth.md): the empirical σ_s must not count the interface twice
SCALED_S_FRICTION = (62.59, 0.544, 0.06558)
SCALED_S_FRICTION_MU = 0.1

#: strength models of σ_s = S f_c: (coefficient, exponent, size (m)). "forrestal-S" is Frew et al.'s (1998)
#: fit to Sandia data; "scaled-S" is fepen's, calibrated once (docs/validation-depth.md)
S_MODELS = {"forrestal-S": (82.6, 0.544, math.inf), "scaled-S": (SCALED_S_COEFFICIENT, SCALED_S_EXPONENT,
                                                                 SCALED_S_SIZE)}


def forrestal_S(fc_pa: float) -> float:
    """Forrestal's empirical S = 82.6 fc^−0.544 (fc in MPa): σ_s = S fc."""
    return strength_S(fc_pa, 0.0, *S_MODELS["forrestal-S"])


def youngs_modulus_aci(fc_pa: float) -> float:
    """Young's modulus of normal-weight concrete from its cylinder strength, E = 4700 √(f_c / 1 MPa) MPa
    (ACI 318-19 §19.2.2.1), in Pa."""
    return 4.7e9 * math.sqrt(fc_pa / 1e6)


#: Eurocode 2 (EN 1992-1-1:2004, Table 3.1): the strength classes C f_ck / f_ck,cube, in MPa
EC2_CYLINDER_MPA = (12.0, 16.0, 20.0, 25.0, 30.0, 35.0, 40.0, 45.0, 50.0, 55.0, 60.0, 70.0, 80.0, 90.0)
EC2_CUBE_MPA = (15.0, 20.0, 25.0, 30.0, 37.0, 45.0, 50.0, 55.0, 60.0, 67.0, 75.0, 85.0, 95.0, 105.0)
STRENGTH_BASES = ("cylinder", "cube")


def cylinder_strength(fc_pa: float, basis: str = "cylinder") -> float:
    """The cylinder strength f_c (Pa) of a concrete whose compressive strength ``fc_pa`` (Pa) was measured on
    ``basis`` "cylinder" (returned as is) or "cube" (150 mm cubes, as Chinese GB 50010 grades such as C40 are
    quoted): converted by Eurocode 2's pairs of cylinder and cube strengths (EN 1992-1-1 Table 3.1),
    interpolated linearly between the classes and at the end classes' ratios outside them (0.80 below C12/15,
    0.857 above C90/105) (docs/theory.md §8.1)."""
    if basis == "cylinder":
        return fc_pa
    if basis != "cube":
        raise ValueError(f"strength basis {basis!r}: one of {', '.join(STRENGTH_BASES)}")
    cube = fc_pa / 1e6
    lo, hi = EC2_CUBE_MPA[0], EC2_CUBE_MPA[-1]
    if cube <= lo:
        return fc_pa * EC2_CYLINDER_MPA[0] / lo
    if cube >= hi:
        return fc_pa * EC2_CYLINDER_MPA[-1] / hi
    return float(np.interp(cube, EC2_CUBE_MPA, EC2_CYLINDER_MPA)) * 1e6


def metal_cavity_stress(E: float, Y: float, n: float) -> float:
    """Quasi-static radial stress of a spherical cavity expanded in an incompressible elastic, power-law
    strain-hardening metal (σ = E ε, then σ = Y (E ε / Y)^n) (Luk, Forrestal & Amos 1991; the σ_s of
    Forrestal and Warren's metal-target equations; docs/theory.md §16):

        σ_s / Y = (2/3) [1 + (2E/(3Y))^n ∫_0^(1 − 3Y/(2E)) (−ln x)^n / (1 − x) dx]

    computed as (2/3)[1 + (2E/(3Y))^n |ln β| ∫_0^1 (−ln(1 − β^t))^n dt] with β = 3Y/(2E) (x = 1 − β^t). For
    n = 0 it is Hill's (2Y/3)(1 + ln(2E/(3Y))).

    Args:
        E: Young's modulus (Pa). Y: yield stress (Pa). n: hardening exponent (0 <= n < 1).

    Returns:
        σ_s (Pa).
    """
    from scipy import integrate

    beta = 1.5 * Y / E
    if not 0.0 < beta < 1.0:
        raise ValueError(f"3Y/(2E) = {beta:g} must be in (0, 1)")
    lb = -math.log(beta)
    if n == 0.0:
        integral = lb
    else:
        val, _ = integrate.quad(lambda t: (-math.log1p(-beta**t)) ** n, 0.0, 1.0, limit=200, epsabs=0.0,
                                epsrel=1e-12)
        integral = lb * val
    return Y * (2.0 / 3.0) * (1.0 + (1.0 / beta) ** n * integral)


def metal_cavity_ratio(E: float, Y: float) -> float:
    """c/a of the incompressible elastic–plastic spherical cavity, (2E/(3Y))^(1/3): the plastic zone the
    free-surface rule cuts (docs/theory.md §16)."""
    return (2.0 * E / (3.0 * Y)) ** (1.0 / 3.0)


def ogive_nose_factor(crh: float) -> float:
    """N* = (8ψ − 1)/(24ψ²) of a tangent ogive (frictionless)."""
    return (8.0 * crh - 1.0) / (24.0 * crh * crh)


# ---------------------------------------------------------------------------------------------------------
# The law
# ---------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class TargetLaw:
    """Parameters of the resistance law (SI units).

    Attributes:
        density: ρ0 (kg/m^3). Y, E, T, lam: strength, modulus, tensile strength, λ (§4.1).
        sigma_s: the quasi-static stress used (Pa) (computed or given).
        B: inertial factor. thickness: None for semi-infinite.
        crater: "none", "linear" or "energy"; k: crater depth factor; D: projectile diameter (m).
        separation, phi_min: switch and minimum separation angle (rad).
        free_surface: switch the plastic-zone truncation by the face; surface_range: how far from the face it
            acts, in plastic-zone widths (c/a → min(c/a, 1 + L_e/(surface_range ρ))).
        friction, mu: friction switch and (static) coefficient; mu_dynamic (None: mu) and mu_decay (s/m):
            the velocity-dependent sliding law (sliding_friction).
        lock_density: Q1 of the energy crater (kg/m^3); crush_strain: ε of the energy crater.
        c_over_a: plastic-zone ratio of the cavity expansion.
        top, bottom: depths of this material's own faces below y = 0 when it is one layer of a block of
            touching layers (fepen.laws.layers): it loads only points between them, while the free faces of
            the crater, the free-surface rule and the perforation stay those of the block (0, thickness).
            bottom None: thickness.
    """

    density: float
    Y: float
    E: float
    T: float
    lam: float
    sigma_s: float
    B: float = 1.0
    thickness: float | None = None
    crater: str = "none"
    k: float = 2.37
    D: float = 0.0236
    separation: bool = False
    phi_min: float = 0.0
    free_surface: bool = False
    friction: bool = False
    mu: float = 0.0
    mu_dynamic: float | None = None
    mu_decay: float = 0.0
    lock_density: float = 2650.0
    crush_strain: float = 0.094
    c_over_a: float = 1.0
    given_sigma_s: bool = False
    onset: float = 0.0
    top: float = 0.0
    bottom: float | None = None
    surface_range: float = 1.0

    @property
    def lower(self) -> float | None:
        """Depth of the material's rear face below the face y = 0 (m): ``bottom`` (a layer inside a block of
        touching layers), else ``thickness``; None: semi-infinite."""
        return self.thickness if self.bottom is None else self.bottom


@dataclass
class SurfaceState:
    """Surface points as the law sees them (all arrays over the points).

    Attributes:
        x, v, n: position, velocity, outward unit normal (k, 3). area: tributary area (k,).
        radius: distance of the point from the projectile axis (k,) (the local cavity radius).
        R_meridian: meridional radius of curvature of the surface at the point (k,), inf where flat.
        sin_phi0: sine of the angle between the surface and the axis at the point (k,) (0 on the shank).
        axis: unit vector of the projectile axis, tail to nose (3,), or None (no wake rule).
    """

    x: np.ndarray
    v: np.ndarray
    n: np.ndarray
    area: np.ndarray
    radius: np.ndarray
    R_meridian: np.ndarray
    sin_phi0: np.ndarray
    axis: np.ndarray | None = None


def inside(law: TargetLaw, x: np.ndarray) -> np.ndarray:
    """Points inside the target material: −lower < y < −top."""
    y = x[:, 1]
    mask = y < -law.top
    if law.lower is not None:
        mask &= y > -law.lower
    return mask


def immersion(law: TargetLaw, x: np.ndarray, area: np.ndarray) -> np.ndarray:
    """Immersed fraction of each load point's patch, clip(½ − y/ℓ, 0, 1) with ℓ = √A (and likewise at the
    rear face): a patch crossing the face is loaded in proportion to the part of it inside the target, so
    the force grows continuously as the projectile enters instead of jumping point by point."""
    ell = np.sqrt(area)
    y = x[:, 1]
    w = np.clip(0.5 - (y + law.top) / ell, 0.0, 1.0)
    if law.lower is not None:
        w *= np.clip(0.5 + (y + law.lower) / ell, 0.0, 1.0)
    return w


def escape_length(law: TargetLaw, x: np.ndarray) -> np.ndarray:
    """Distance L_e from each point to the nearest free face of the target (m): the shortest distance to
    the front face y = 0 and, for a slab or a block of layers, to its rear face y = −thickness
    (docs/theory.md §8.3). Finite at every incidence: the depth of the point below the face for a
    semi-infinite target, so that the crater and the free-surface rule act at normal incidence too."""
    depth = np.maximum(-x[:, 1], 0.0)
    if law.thickness is None:
        return depth
    return np.minimum(depth, np.maximum(law.thickness - depth, 0.0))


def tunnel_stress(law: TargetLaw, vn: np.ndarray, sigma_s) -> np.ndarray:
    """σ_s + B ρ0 (v·n)² where v·n > 0, else 0 (Pa)."""
    return np.where(vn > 0.0, sigma_s + law.B * law.density * vn * vn, 0.0)


@functools.lru_cache(maxsize=8)
def _gauss_legendre(n: int):
    """Gauss-Legendre nodes and weights on [-1, 1] (computed once: an eigenvalue problem)."""
    return np.polynomial.legendre.leggauss(n)


def crater_energy_ejects(law: TargetLaw, vn, L_e, radius, R_meridian, sin_phi0, n_gauss: int = 8):
    """The splash-streamline energy balance per unit surface area (docs/theory.md §8.3).

        E_kin      = ½ Q1 v_n² ∫_0^l (1 + w/R)(1 + w sinφ/ρ) (ρ/(ρ + w))^4 dw,   l = (c/a − 1) ρ
        E_strength = ε σ_cf (2ρ L_e + L_e²) / ρ
    The medium is thrown out (no load) where E_kin − E_strength >= 0.

    Returns:
        Boolean array: True where the medium is ejected.
    """
    rho = np.maximum(radius, 1e-12)
    l = (law.c_over_a - 1.0) * rho
    xg, wg = _gauss_legendre(n_gauss)
    integral = np.zeros_like(rho)
    for xi, wi in zip(xg, wg):
        w = 0.5 * l * (xi + 1.0)
        growth = (1.0 + w / R_meridian) * (1.0 + w * sin_phi0 / rho)
        integral += 0.5 * l * wi * growth * (rho / (rho + w)) ** 4
    e_kin = 0.5 * law.lock_density * vn * vn * integral
    e_str = law.crush_strain * law.Y * (2.0 * rho * L_e + L_e**2) / rho
    return e_kin - e_str >= 0.0


def normal_stress(law: TargetLaw, s: SurfaceState, vhat_tol: float = SIN_TOL):
    """Normal stress σ_n on every surface point (Pa), with the crater ("energy"), separation and
    free-surface effects that the law switches on; the "linear" crater is applied to forces by
    :func:`forces` because it is a statement about the total force.

    Returns:
        (σ_n (k,) (already weighted by the immersed fraction), inside mask (k,), v·n (k,)).
    """
    frac = immersion(law, s.x, s.area)
    ins = frac > 0.0
    vn = np.einsum("ij,ij->i", s.v, s.n)
    speed = np.linalg.norm(s.v, axis=1)
    sin_phi = np.where(speed > 0.0, vn / np.maximum(speed, 1e-300), 0.0)
    loaded = ins & (sin_phi > vhat_tol)
    if s.axis is not None:  # the wake: moving backward, a point meets the open tunnel, not concrete
        loaded &= s.v @ s.axis > 0.0
    if law.separation:
        loaded &= sin_phi > math.sin(law.phi_min)
    sigma_s = np.full(len(vn), law.sigma_s)
    need_L = law.free_surface or law.crater == "energy"
    L_e = escape_length(law, s.x) if need_L else None
    if law.free_surface:
        ca = np.minimum(law.c_over_a, 1.0 + L_e / (law.surface_range * np.maximum(s.radius, 1e-12)))
    if law.free_surface and not law.given_sigma_s:
        sigma_s = quasi_static_stress(law.Y, law.E, law.T, law.lam, ca)
    elif law.free_surface:  # σ_s given: scale it like the cavity-expansion value
        sigma_s = law.sigma_s * quasi_static_stress(law.Y, law.E, law.T, law.lam, ca) / quasi_static_stress(
            law.Y, law.E, law.T, law.lam, law.c_over_a)
    if law.onset > 0.0:  # σ_s develops over the first `onset` of surface angle (grazing: no expansion)
        sigma_s = sigma_s * np.minimum(sin_phi / math.sin(law.onset), 1.0)
    sig = np.where(loaded, tunnel_stress(law, vn, sigma_s), 0.0) * frac
    if law.crater == "energy":
        shallow = loaded & (-s.x[:, 1] < law.k * law.D)
        if np.any(shallow):
            idx = np.flatnonzero(shallow)
            out = crater_energy_ejects(law, vn[idx], L_e[idx], s.radius[idx], s.R_meridian[idx], s.sin_phi0[idx])
            sig[idx[out]] = 0.0
    return sig, ins, vn


def forces(law: TargetLaw, s: SurfaceState):
    """Nodal forces of the target on the surface points (N), shape (k, 3).

    Args:
        law: the TargetLaw.
        s: the surface state.

    Returns:
        (forces (k, 3), σ_n (k,)).
    """
    sig, ins, vn = normal_stress(law, s)
    f = -(sig * s.area)[:, None] * s.n
    if law.friction and law.mu > 0.0:
        vt = s.v - vn[:, None] * s.n
        speed_t = np.linalg.norm(vt, axis=1)
        slide = speed_t > 1e-9
        mu = sliding_friction(law, speed_t[slide])
        f[slide] -= (mu * sig[slide] * s.area[slide] / speed_t[slide])[:, None] * vt[slide]
    return f, sig


def sliding_friction(law: TargetLaw, speed_t):
    """The friction coefficient at tangential sliding speed |v_t| (m/s): μ_d + (μ_s − μ_d) e^(−c |v_t|),
    LS-DYNA's FS, FD, DC form (docs/theory.md §8.4), with μ_s = law.mu, μ_d = law.mu_dynamic, c =
    law.mu_decay; the constant Coulomb coefficient law.mu when c = 0 or μ_d = μ_s."""
    mu_d = law.mu if law.mu_dynamic is None else law.mu_dynamic
    if law.mu_decay == 0.0 or mu_d == law.mu:
        return law.mu
    return mu_d + (law.mu - mu_d) * np.exp(-law.mu_decay * np.asarray(speed_t))


@dataclass
class PointLoad:
    """The target's load on a set of surface points (fepen.laws.target.load_on_points).

    Attributes:
        force: force on every point (k, 3) (N), zero where not immersed.
        total: total force (3,) (N); loaded: points under a positive stress; area: their area (m^2);
            each summed over all ranks when the caller's ``reduce`` does so.
    """

    force: np.ndarray
    total: np.ndarray
    loaded: int
    area: float


def load_on_points(law: TargetLaw, x, v, n, area, radius, R_meridian, sin_phi0, axis, crater=None,
                   tip_depth: float = 0.0, reduce=None) -> PointLoad:
    """The target's forces on surface points: immersion, the law on the immersed points, the linear crater.

    The one implementation for the rigid and the deformable projectile (they differ only in where their
    points come from and in ``reduce``). The point forces come from the C transcription of the law
    (fepen/laws/target_kernel.c) when it builds, else from :func:`point_forces` (numpy, the reference).

    Args:
        law: the TargetLaw. x, v, n, area, radius, R_meridian, sin_phi0, axis: as SurfaceState, over all of
            this process's points.
        crater: a ForrestalCrater (the "linear" crater) or None. tip_depth: the nose tip's depth (m).
        reduce: the totals over the processes that share the points (a distributed surface), as
            ``reduce(f, sums)`` -> sums (5,), from this process's point forces f (k, 3) and its sums (force
            (3), loaded points, loaded area); None when this process holds them all.

    Returns:
        The PointLoad.
    """
    kernel = _point_kernel() or point_forces
    if getattr(law, "layered", False):  # a fepen.laws.layers.Layered target: layer by layer
        f, sums = law.point_forces(kernel, x, v, n, area, radius, R_meridian, sin_phi0, axis)
    else:
        f, sums = kernel(law, x, v, n, area, radius, R_meridian, sin_phi0, axis)
    if reduce is not None:
        sums = reduce(f, sums)
    total = sums[:3]
    if crater is not None:
        scale = crater.scale(tip_depth, -float(total @ axis))
        f *= scale
        total = total * scale
    return PointLoad(f, total, int(sums[3]), float(sums[4]))


def point_forces(law: TargetLaw, x, v, n, area, radius, R_meridian, sin_phi0, axis):
    """The law's forces on every point (k, 3) (zero where not immersed) and their sums (force (3), loaded
    points, loaded area), before any crater scaling: numpy, the reference of the C kernel."""
    f = np.zeros_like(x)
    idx = np.flatnonzero(immersion(law, x, area) > 0.0)
    sig = np.zeros(0)
    if len(idx):
        st = SurfaceState(x[idx], v[idx], n[idx], area[idx], radius[idx], R_meridian[idx], sin_phi0[idx], axis)
        f[idx], sig = forces(law, st)
    loaded = sig > 0.0
    sums = np.array([*f.sum(axis=0), float(loaded.sum()), float(area[idx][loaded].sum()) if len(idx) else 0.0])
    return f, sums


_KERNEL = {}


def _point_kernel():
    """point_forces in C (fepen/laws/target_kernel.c), or None when it does not build or FEPEN_KERNEL=numpy
    (the numpy reference) is set."""
    if "fn" not in _KERNEL:
        _KERNEL["fn"] = None
        if os.environ.get("FEPEN_KERNEL", "").lower() not in ("numpy", "numba"):
            from fepen import native

            lib, _KERNEL["why_not"] = native.load(Path(__file__).with_name("target_kernel.c"))
            if lib is not None:
                _KERNEL["fn"] = _bind(lib)
    return _KERNEL["fn"]


@functools.lru_cache(maxsize=16)
def _law_numbers(law: TargetLaw) -> np.ndarray:
    """The law as the C kernel's parameter array (the order of its enum)."""
    return np.array([law.density, law.Y, law.E, law.T, law.lam, law.sigma_s, law.B,
                     -1.0 if law.thickness is None else law.thickness,
                     {"none": 0.0, "linear": 1.0, "energy": 2.0}[law.crater], law.k, law.D, float(law.separation),
                     law.phi_min, float(law.free_surface), float(law.friction), law.mu,
                     law.mu if law.mu_dynamic is None else law.mu_dynamic, law.mu_decay, law.lock_density,
                     law.crush_strain, law.c_over_a, float(law.given_sigma_s), law.onset, law.top,
                     -1.0 if law.lower is None else law.lower, law.surface_range])


def _bind(lib):
    import ctypes

    vp, i32 = ctypes.c_void_p, ctypes.c_int32
    lib.point_forces.argtypes = [i32, *[vp] * 10, i32, vp, vp, vp]
    lib.point_forces.restype = i32
    xg, wg = _gauss_legendre(8)
    gauss = np.ascontiguousarray(np.concatenate([xg, wg]))
    bound: dict = {}  # the addresses of the arrays a run passes every call unchanged (its points' constants)

    def constant(a, keep):
        """The address of a per-point array, taken once for a C-contiguous float64 array (whose address does
        not change; the cache holds the array, so its id is not reused while it is cached); any other array is
        converted (kept alive in ``keep`` for the call)."""
        hit = bound.get(id(a))
        if hit is not None and hit[0] is a:
            return hit[1]
        if isinstance(a, np.ndarray) and a.dtype == np.float64 and a.flags.c_contiguous:
            if len(bound) > 64:
                bound.clear()
            bound[id(a)] = (a, a.ctypes.data)
            return a.ctypes.data
        c = np.ascontiguousarray(a, dtype=float)
        keep.append(c)
        return c.ctypes.data

    gauss_at = gauss.ctypes.data  # c_point_forces.gauss below keeps the array alive

    def c_point_forces(law, x, v, n, area, radius, R_meridian, sin_phi0, axis):
        p = _law_numbers(law)
        moving = [np.ascontiguousarray(a, dtype=float) for a in (x, v, n)]
        ax = None if axis is None else np.ascontiguousarray(axis, dtype=float)
        k = len(moving[0])
        out = np.empty(4 * k + 5)
        at = out.ctypes.data
        keep: list = []
        count = lib.point_forces(k, *[a.ctypes.data for a in moving],
                                 *[constant(a, keep) for a in (area, radius, R_meridian, sin_phi0)],
                                 None if ax is None else ax.ctypes.data, p.ctypes.data, gauss_at, len(xg), at,
                                 at + 24 * k, at + 32 * k)
        assert count == len(p), "target_kernel.c and _law_numbers disagree on the parameters"
        return out[: 3 * k].reshape(k, 3), out[4 * k:]

    c_point_forces.gauss = gauss
    return c_point_forces


@dataclass
class ForrestalCrater:
    """Forrestal et al. (1994): in the crater (tip depth z < k D) the axial force is c z, with c set by
    continuity with the tunnel force at z = k D:

        V1² = (M V0² − π a² k D σ_s) / (M + N* ρ0 π a² k D),    c = π a² (σ_s + N* ρ0 V1²) / (k D)

    fepen applies it by scaling the tunnel-law stresses of all loaded points so that their force along the
    axis is c z; past k D the scale is 1.

    Args:
        law: the target law. mass: projectile mass (kg). v0: striking speed (m/s). crh: nose CRH.
        nose_factor: N* of the nose (fepen.geometry.shape.Shape.nose_factor); None: the tangent ogive's.
    """

    law: TargetLaw
    mass: float
    v0: float
    crh: float
    nose_factor: float | None = None

    def __post_init__(self):
        a = 0.5 * self.law.D
        kd = self.law.k * self.law.D
        N = self.N = self.nose_factor if self.nose_factor is not None else (
            ogive_nose_factor(self.crh) if self.crh > 0 else 1.0)
        area = math.pi * a * a
        self.v1_sq = max((self.mass * self.v0**2 - area * kd * self.law.sigma_s)
                         / (self.mass + N * self.law.density * area * kd), 0.0)
        self.c = area * (self.law.sigma_s + N * self.law.density * self.v1_sq) / kd if kd > 0 else 0.0
        self.kd = kd

    def scale(self, tip_depth: float, axial_force: float) -> float:
        """Factor on the stresses given the tunnel-law force along the axis (N) at this tip depth (m)."""
        if tip_depth >= self.kd or axial_force <= 0.0:
            return 1.0
        return max(tip_depth, 0.0) * self.c / axial_force

    def depth(self) -> float:
        """Forrestal's two-stage final depth (m): k D + M/(2π a² ρ0 N*) ln(1 + N* ρ0 V1²/σ_s)."""
        a = 0.5 * self.law.D
        N = self.N
        return self.kd + self.mass / (2 * math.pi * a * a * self.law.density * N) * math.log(
            1 + N * self.law.density * self.v1_sq / self.law.sigma_s)
