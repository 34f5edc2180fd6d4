"""The concrete target as a resistance law on plain arrays of projectile surface points (docs/theory.md §8,
docs/paper.md §4): cavity-expansion σ_s, tunnel stress, wake, separation, free surface, both craters,
friction, and the load on a set of points. The target face is the plane y = 0, the target y < 0.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fepen import native

#: fepen's calibrated "scaled-S" strength model (docs/validation-depth.md: one fit, rigid fidelity, on the
#: calibration sets listed there); S = coefficient (f_c/MPa)^-exponent / sqrt(1 + D/size)
SCALED_S_COEFFICIENT = 134.1
SCALED_S_EXPONENT = 0.544
SCALED_S_SIZE = 0.05404
#: the same fit with the calibrated nose wear on (effects.wear; docs/wear.md §2: fepen.studies.wear_calibration)
SCALED_S_WEAR = (124.6, SCALED_S_EXPONENT, 0.06292)


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
    """Quasi-static radial stress at the cavity wall (Pa), compression positive (§4.1), from target_kernel.c's
    cavity_wall_stress (the formula's one home, which the law's free-surface rule also calls):

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
    wall = native.kernel("target").cavity_wall_stress
    if c_over_a is None:
        return wall(float(Y), float(lam), cavity_ratio(Y, E, T))
    ca = np.asarray(c_over_a, dtype=float)
    out = np.array([wall(float(Y), float(lam), float(c)) for c in ca.ravel()]).reshape(ca.shape)
    return out if out.ndim else float(out)


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
        wall_shear2: the tunnel wall's elastic reload modulus "2G" (Pa): its stiffness under a sideways push is
            wall_shear2 / a (a the wall's radius; wall_modulus); 0: the wall carries nothing.
        reload: the tunnel wall's reload strength, the fraction of σ_s that re-expands it (reload_fraction).
        field_sigma, field_modes: the concrete's random field on σ_s (§8.8; strength_field): the standard
            deviation of the factor's logarithm and its modes (kx, ky, kz, phase) flattened (random_field_modes);
            () without a field.
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
    top: float = 0.0
    bottom: float | None = None
    surface_range: float = 1.0
    wall_shear2: float = 0.0
    reload: float = 1.0
    field_sigma: float = 0.0
    field_modes: tuple = ()

    @property
    def lower(self) -> float | None:
        """Depth of the material's rear face below the face y = 0 (m): ``bottom`` (a layer inside a block of
        touching layers), else ``thickness``; None: semi-infinite."""
        return self.thickness if self.bottom is None else self.bottom

    def point_forces(self, kernel, x, v, n, area, radius, R_meridian, sin_phi0, axis, tunnel=None, body_xi=None):
        """The law on every point: forces (k, 3) and their sums, as fepen.laws.target.point_forces returns them
        (the one signature of every target law's point_forces; fepen.laws.layers.Layered's goes layer by layer).

        Args:
            kernel: fepen.laws.target.point_forces. x ... axis, tunnel, body_xi: as it takes them.

        Returns:
            (forces (k, 3), sums (the header's SUM_ layout)).
        """
        return kernel(self, x, v, n, area, radius, R_meridian, sin_phi0, axis, tunnel, body_xi)


#: Poisson's ratio of the tunnel's wall: concrete's, rock's and soil's 0.2 (EN 1992-1-1 §3.1.3: uncracked
#: concrete), a metal's 0.33 (aluminium's; a steel's 0.29 makes its wall 3 % stiffer)
WALL_POISSON = {"metal": 0.33}
WALL_POISSON_DEFAULT = 0.2


def wall_modulus(E: float, nu: float, cracked: float) -> float:
    """The tunnel wall's elastic reload modulus "2G_eff" (Pa): a cylindrical cavity of radius a in an elastic
    medium takes p = 2G u / a (Lamé; Timoshenko and Goodier, thick cylinder of infinite outer radius); with the
    wall radially cracked out to b = ``cracked`` a (the cracks carry no hoop stress, so the cracked ring is a
    stack of radial struts, u = p a ln(b/a) / E across it), p = 2G u / [a (1 + ln(b/a) / (1 + ν))].

    Args:
        E: Young's modulus (Pa). nu: Poisson's ratio. cracked: b/a, the radially cracked ring's outer radius over
            the cavity's (the cavity expansion's c/a; 1: not cracked).

    Returns:
        2G / (1 + ln(b/a) / (1 + ν)) (Pa); the wall's stiffness is it over a.
    """
    G2 = E / (1.0 + nu)
    return G2 / (1.0 + math.log(max(cracked, 1.0)) / (1.0 + nu))


def reload_fraction(Y: float, lam: float, c_over_a: float) -> float:
    """The tunnel wall's reload strength, the fraction of the intact cavity-expansion stress that re-expands it
    (docs/theory.md §8.7): the comminuted ring the nose left (a < r < c) has lost its cohesion and keeps its
    friction, the cracked and elastic concrete beyond c unchanged; then Forrestal and Tzou's (1997) equilibrium
    in the ring with the cohesion τ0 removed gives σ_r(a) = Y (c/a)^(αλ), α = 6/(3 + 2λ), against the intact
    σ_s (cavity_wall_stress). 0.52 for the paper's concrete (λ 0.67, c/a 5.45); 0.45–0.59 over λ 0.5–0.8, c/a 4–6.

    Args:
        Y: unconfined compressive strength (Pa). lam: λ. c_over_a: the plastic zone's c/a.

    Returns:
        The fraction (1 when λ = 0: a Tresca medium's cohesion is its strength, nothing to lose but that).
    """
    if lam <= 0.0:
        return 1.0
    alpha = 6.0 / (3.0 + 2.0 * lam)
    return float(Y * c_over_a ** (alpha * lam) / quasi_static_stress(Y, 1.0, 1.0, lam, c_over_a))


@functools.lru_cache(maxsize=8)
def _gauss_legendre(n: int):
    """Gauss-Legendre nodes and weights on [-1, 1] (computed once: an eigenvalue problem)."""
    return np.polynomial.legendre.leggauss(n)


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
                   tip_depth: float = 0.0, reduce=None, tunnel=None, body_xi=None) -> PointLoad:
    """The target's forces on surface points: immersion, the law on the immersed points, the linear crater.

    The one implementation for the rigid and the deformable projectile (they differ only in where their
    points come from and in ``reduce``). The point forces are the law's one home, target_kernel.c
    (:func:`point_forces`).

    Args:
        law: the TargetLaw. x, v, n, area, radius, R_meridian, sin_phi0, axis: as point_forces, over all of
            this process's points.
        crater: a ForrestalCrater (the "linear" crater) or None. tip_depth: the nose tip's depth (m).
        reduce: the totals over the processes that share the points (a distributed surface), as
            ``reduce(f, sums)`` -> sums (5,), from this process's point forces f (k, 3) and its sums (force
            (3), loaded points, loaded area); None when this process holds them all.
        tunnel: the run's fepen.laws.tunnel.Tunnel (its shoulder set for this state), or None: no tunnel.
        body_xi: each point's distance behind the tip in the body frame (m), (k,), with a tunnel.

    Returns:
        The PointLoad.
    """
    f, sums = law.point_forces(point_forces, x, v, n, area, radius, R_meridian, sin_phi0, axis, tunnel, body_xi)
    if reduce is not None:
        sums = reduce(f, sums)
    total = sums[SUM_FORCE:SUM_FORCE + 3]
    if crater is not None:
        scale = crater.scale(tip_depth, -float(total @ axis))
        f *= scale
        total = total * scale
    return PointLoad(f, total, int(sums[SUM_LOADED]), float(sums[SUM_AREA]))


def point_forces(law: TargetLaw, x, v, n, area, radius, R_meridian, sin_phi0, axis, tunnel=None, body_xi=None):
    """The law on every point (docs/theory.md §8), before any linear-crater scaling: target_kernel.c's
    point_forces, the law's one home, through fepen.native.

    Args:
        law: the TargetLaw.
        x, v, n: the points' positions (m), velocities (m/s) and outward unit normals, (k, 3) each.
        area: each point's patch area (m^2); radius: its distance from the axis (m); R_meridian: the meridian's
            radius of curvature there (m, inf where straight); sin_phi0: sin of the surface's angle to the
            axis, (k,) each.
        axis: the unit axis, tail to nose (3,), or None (no wake rule).
        tunnel: a fepen.laws.tunnel.Tunnel, or None (§8.7); body_xi: the points' distances behind the tip
            in the body frame (m), (k,), with a tunnel.

    Returns:
        (forces (k, 3) (N, zero where not loaded), sums (5,): force (3) (N), loaded points, loaded area (m^2)).
    """
    f, sig, sums = _kernel()(law, x, v, n, area, radius, R_meridian, sin_phi0, axis, tunnel, body_xi)
    return f, sums


def normal_stress(law: TargetLaw, x, v, n, area, radius, R_meridian, sin_phi0, axis=None, tunnel=None,
                  body_xi=None):
    """(forces (k, 3) (N), σ_n (k,) (Pa, weighted by the immersed fraction, zero where not loaded)) on the
    points, with the same arguments as point_forces."""
    f, sig, _ = _kernel()(law, x, v, n, area, radius, R_meridian, sin_phi0, axis, tunnel, body_xi)
    return f, sig


def crater_gauss() -> np.ndarray:
    """The energy crater's Gauss-Legendre rule as the kernel takes it: 8 nodes then 8 weights on [-1, 1]."""
    return _kernel().gauss


#: the modes of the concrete's random field (§8.8): its marginal is a sum of FIELD_MODES cosines, Gaussian to
#: within a few per cent in its tails
FIELD_MODES = 32


def random_field_modes(seed: int, correlation_length: float, modes: int = FIELD_MODES) -> tuple:
    """The modes of a Gaussian random field of unit variance with the covariance exp(−r²/(2 ℓ²)), ℓ the
    correlation length (m), by the spectral representation (docs/theory.md §8.8): wave vectors drawn from the
    covariance's spectrum, N(0, I/ℓ²), and phases uniform on [0, 2π), from numpy's PCG64 with ``seed``.

    Returns:
        (kx, ky, kz, phase) per mode, flattened: TargetLaw.field_modes.
    """
    rng = np.random.Generator(np.random.PCG64(int(seed)))
    k = rng.standard_normal((modes, 3)) / correlation_length
    phase = rng.uniform(0.0, 2.0 * np.pi, modes)
    return tuple(float(v) for v in np.column_stack([k, phase]).ravel())


def field_log_sigma(cv: float) -> float:
    """The standard deviation of the logarithm of a lognormal factor of mean 1 and coefficient of variation cv:
    sqrt(ln(1 + cv²))."""
    return math.sqrt(math.log1p(cv * cv))


def strength_field(law: TargetLaw, x: np.ndarray) -> np.ndarray:
    """The law's strength factor on σ_s at target points x (k, 3) (m; 1 without a field): target_kernel.c's
    field_factor, the factor the law applies there."""
    x = np.ascontiguousarray(x, dtype=float).reshape(-1, 3)
    p = _law_numbers(law)
    out = np.empty(len(x))
    lib = native.kernel("target")
    assert lib.strength_field(len(x), x.ctypes.data, p.ctypes.data, out.ctypes.data) == len(p)
    return out


_KERNEL: dict = {}


def _kernel():
    """point_forces in C (target_kernel.c, fepen.native's "target"), bound once."""
    if "fn" not in _KERNEL:
        _KERNEL["fn"] = _bind(native.kernel("target"))
    return _KERNEL["fn"]


#: the law as the C kernel takes it: target_kernel.h's P_ members, in their order, and the law's number at each
#: (the random field's modes follow P_COUNT); checked against the header, member by member, when the kernel is
#: loaded (fepen.native.shares)
_LAW = (
    ("P_DENSITY", lambda law: law.density), ("P_Y", lambda law: law.Y), ("P_E", lambda law: law.E),
    ("P_T", lambda law: law.T), ("P_LAM", lambda law: law.lam), ("P_SIGMA_S", lambda law: law.sigma_s),
    ("P_B", lambda law: law.B), ("P_THICKNESS", lambda law: -1.0 if law.thickness is None else law.thickness),
    ("P_CRATER", lambda law: {"none": 0.0, "linear": 1.0, "energy": 2.0}[law.crater]), ("P_K", lambda law: law.k),
    ("P_D", lambda law: law.D), ("P_SEPARATION", lambda law: float(law.separation)),
    ("P_PHI_MIN", lambda law: law.phi_min), ("P_FREE_SURFACE", lambda law: float(law.free_surface)),
    ("P_FRICTION", lambda law: float(law.friction)), ("P_MU", lambda law: law.mu),
    ("P_MU_DYNAMIC", lambda law: law.mu if law.mu_dynamic is None else law.mu_dynamic),
    ("P_MU_DECAY", lambda law: law.mu_decay), ("P_LOCK_DENSITY", lambda law: law.lock_density),
    ("P_CRUSH_STRAIN", lambda law: law.crush_strain), ("P_C_OVER_A", lambda law: law.c_over_a),
    ("P_GIVEN_SIGMA_S", lambda law: float(law.given_sigma_s)), ("P_WALL_SHEAR2", lambda law: law.wall_shear2),
    ("P_TOP", lambda law: law.top), ("P_LOWER", lambda law: -1.0 if law.lower is None else law.lower),
    ("P_SURFACE_RANGE", lambda law: law.surface_range), ("P_RELOAD", lambda law: law.reload),
    ("P_FIELD_SIGMA", lambda law: law.field_sigma), ("P_FIELD_MODES", lambda law: len(law.field_modes) // 4))
native.shares("target", "P_", [(member, 1) for member, _ in _LAW])
#: the sums point_forces writes (target_kernel.h's SUM_ enum, all its members): the force (3), the points loaded,
#: their area; a layout shared as _LAW is
SUM_FORCE, SUM_LOADED, SUM_AREA, SUM_COUNT = native.enum_values(Path(__file__).with_name("target_kernel.h"),
                                                                "SUM_FORCE", "SUM_LOADED", "SUM_AREA", "SUM_COUNT")
native.shares("target", "SUM_", [("SUM_FORCE", 3), ("SUM_LOADED", 1), ("SUM_AREA", 1)])


@functools.lru_cache(maxsize=16)
def _law_numbers(law: TargetLaw) -> np.ndarray:
    """The law as the C kernel's parameter array (_LAW: the order of target_kernel.h's P_ enum), then its random
    field's modes."""
    return np.array([number(law) for _, number in _LAW] + list(law.field_modes))


def _bind(lib):

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

    def c_point_forces(law, x, v, n, area, radius, R_meridian, sin_phi0, axis, tunnel=None, body_xi=None):
        p = _law_numbers(law)
        moving = [np.ascontiguousarray(a, dtype=float) for a in (x, v, n)]
        ax = None if axis is None else np.ascontiguousarray(axis, dtype=float)
        k = len(moving[0])
        out = np.empty(4 * k + SUM_COUNT)
        at = out.ctypes.data
        keep: list = []
        count = lib.point_forces(k, *[a.ctypes.data for a in moving],
                                 *[constant(a, keep) for a in (area, radius, R_meridian, sin_phi0)],
                                 None if ax is None else ax.ctypes.data, p.ctypes.data, gauss_at, len(xg), at,
                                 at + 24 * k, at + 32 * k,
                                 None if tunnel is None else constant(body_xi, keep),
                                 None if tunnel is None else tunnel.buf.ctypes.data)
        assert count == len(p), "target_kernel.h and _law_numbers disagree on the parameters"
        return out[: 3 * k].reshape(k, 3), out[3 * k: 4 * k], out[4 * k:]

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
