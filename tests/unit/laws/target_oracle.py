"""An independent numpy oracle of the target law (docs/theory.md §8), for the tests only: the law's one home
is target_kernel.c (fepen.laws.target.point_forces). This is the law written again, array-wise and from the
equations, so that the compiled text is checked against a second formulation on random states
(test_target_kernel.py); the physics tests (test_target.py) check the compiled law itself. Also the
SurfaceState those tests build, and ``forces``/``compiled_stress`` that hand one to the compiled law."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from fepen.laws import target as tg
from fepen.laws.target import TargetLaw, quasi_static_stress

SIN_TOL = 1e-9  # v̂·n below this counts as zero (a surface parallel to the motion is not loaded)


def forces(law: TargetLaw, s: SurfaceState):
    """The compiled law's (forces (k, 3), σ_n (k,)) on a SurfaceState."""
    return tg.normal_stress(law, s.x, s.v, s.n, s.area, s.radius, s.R_meridian, s.sin_phi0, s.axis)


def compiled_stress(law: TargetLaw, s: SurfaceState):
    """The compiled law's (σ_n (k,), inside (k,), v·n (k,)) on a SurfaceState, as normal_stress returns them."""
    _, sig = forces(law, s)
    return sig, immersion(law, s.x, s.area) > 0.0, np.einsum("ij,ij->i", s.v, s.n)


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
    sig = np.where(loaded, tunnel_stress(law, vn, sigma_s), 0.0) * frac
    if law.crater == "energy":
        shallow = loaded & (-s.x[:, 1] < law.k * law.D)
        if np.any(shallow):
            idx = np.flatnonzero(shallow)
            out = crater_energy_ejects(law, vn[idx], L_e[idx], s.radius[idx], s.R_meridian[idx], s.sin_phi0[idx])
            sig[idx[out]] = 0.0
    return sig, ins, vn


def oracle_forces(law: TargetLaw, s: SurfaceState):
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


def point_forces(law: TargetLaw, x, v, n, area, radius, R_meridian, sin_phi0, axis):
    """The law's forces on every point (k, 3) (zero where not immersed) and their sums (force (3), loaded
    points, loaded area), before any crater scaling: numpy, the reference of the C kernel."""
    f = np.zeros_like(x)
    idx = np.flatnonzero(immersion(law, x, area) > 0.0)
    sig = np.zeros(0)
    if len(idx):
        st = SurfaceState(x[idx], v[idx], n[idx], area[idx], radius[idx], R_meridian[idx], sin_phi0[idx], axis)
        f[idx], sig = oracle_forces(law, st)
    loaded = sig > 0.0
    sums = np.array([*f.sum(axis=0), float(loaded.sum()), float(area[idx][loaded].sum()) if len(idx) else 0.0])
    return f, sums


