"""Nose wear on plain arrays (docs/theory.md §14): the interface heat of the sliding target, and the mass it
melts off the projectile's surface.

The heat: every loaded surface point slides past the target at |v_t| under the normal stress σ_n; the
interface dissipates q = μ σ_n |v_t| per unit area (μ the interface's friction coefficient, whether or not
the friction force itself is applied: the calibrated σ_s already holds the interface's resistance, the
heat is there all the same). The mass: a fraction η of that heat melts a thin surface layer that the flow
carries away (Jones, Foster, Wang et al. 2002; Silling and Forrestal 2007: mass loss in proportion to the
frictional work), each kilogram taking h = c_p (T_melt − T_room) + L_f to heat and melt.

Where the mass leaves (docs/theory.md §14.3): by default the nose keeps its own shape family and shortens
along its axis (the nose-evolution assumption of the mass-abrasion models, which let the worn nose keep its
kind and its shank and lose length): the solid nose zone ahead of y_c (the shoulder, or the front of a
cavity) is contracted toward y_c by a factor λ, the volume it loses being the melted volume. The tip,
which the heat μ σ_n |v_t| barely reaches, recedes the most; the length lost per kilogram follows from the
nose's own volume, ΔL/Δm = y_c/(ρ V_zone).
"""

from __future__ import annotations

import numpy as np

__all__ = ["LATENT_HEAT_STEEL", "MIN_CONTRACTION", "contract_points", "contraction_after", "heat_rate", "heat_rates",
           "melt_enthalpy", "melted_mass", "recession_depth", "zone_volume"]

#: latent heat of fusion of carbon and low-alloy steels, J/kg (about 2.7e5; e.g. Smithells Metals Reference
#: Book: about 250–280 kJ/kg for iron and plain carbon steels)
LATENT_HEAT_STEEL = 2.7e5


def melt_enthalpy(specific_heat: float, melt_temperature: float, room_temperature: float,
                  latent_heat: float = LATENT_HEAT_STEEL) -> float:
    """Heat to bring one kilogram of the surface from room temperature to melted, h = c_p (T_m − T_0) + L_f.

    Args:
        specific_heat: c_p (J/(kg K)). melt_temperature, room_temperature: T_m, T_0 (K).
        latent_heat: L_f (J/kg).

    Returns:
        h (J/kg).
    """
    return specific_heat * (melt_temperature - room_temperature) + latent_heat


_JIT: dict = {}


def heat_rates(force: np.ndarray, n: np.ndarray, v: np.ndarray, mu: float) -> np.ndarray:
    """_heat_rates compiled by numba on its first call (cached on disk): a run without wear does not import
    numba for it (a rigid shot's start-up)."""
    fn = _JIT.get("heat_rates")
    if fn is None:
        import numba

        fn = _JIT["heat_rates"] = numba.njit(cache=True)(_heat_rates)
    return fn(force, n, v, mu)


def _heat_rates(force: np.ndarray, n: np.ndarray, v: np.ndarray, mu: float) -> np.ndarray:
    """Each point's interface heat per unit time (W), the formula's one home: μ σ_n A |v_t|, with σ_n A =
    max(−f·n, 0) from the target's force on the point (the normal part; a friction force is tangential and
    drops out). The rigid run sums it (heat_rate), the deformable one spreads it to the facets' nodes
    (fepen.solver.recession).

    Args:
        force: the target's forces on the points (k, 3) (N). n: outward unit normals (k, 3). v: velocities
            (k, 3) (m/s). mu: the interface's friction coefficient.

    Returns:
        (k,) heat rates (W), ≥ 0 (0 where the point is not pressed).
    """
    out = np.zeros(force.shape[0])
    for i in range(force.shape[0]):
        fn = -(force[i, 0] * n[i, 0] + force[i, 1] * n[i, 1] + force[i, 2] * n[i, 2])
        if fn <= 0.0:
            continue
        vn = v[i, 0] * n[i, 0] + v[i, 1] * n[i, 1] + v[i, 2] * n[i, 2]
        t0 = v[i, 0] - vn * n[i, 0]
        t1 = v[i, 1] - vn * n[i, 1]
        t2 = v[i, 2] - vn * n[i, 2]
        out[i] = mu * fn * np.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
    return out


def recession_depth(heat: np.ndarray, area: np.ndarray, efficiency: float, enthalpy: float,
                    density: float) -> np.ndarray:
    """Depth (m) by which a surface recedes when the heat (J) it took over its area (m²) melts its mass off:
    d = η Q / (h ρ A); 0 where the area is 0."""
    return np.where(area > 0.0, efficiency * heat / (enthalpy * density * np.where(area > 0.0, area, 1.0)), 0.0)


def heat_rate(force: np.ndarray, n: np.ndarray, v: np.ndarray, mu: float) -> float:
    """Interface heat per unit time (W) over surface points: the sum of heat_rates, ≥ 0."""
    return float(heat_rates(np.ascontiguousarray(force, dtype=float), np.ascontiguousarray(n, dtype=float),
                            np.ascontiguousarray(v, dtype=float), float(mu)).sum())


def melted_mass(heat: float, efficiency: float, enthalpy: float) -> float:
    """Mass (kg) melted off by the interface heat (J): η Q / h."""
    return efficiency * heat / enthalpy


#: the nose zone is never contracted below this fraction of its length (the mass beyond it still leaves,
#: uniformly: a nose worn that far is outside the model, docs/theory.md §14.3)
MIN_CONTRACTION = 0.05


def zone_volume(X: np.ndarray, N: np.ndarray, area: np.ndarray, y_c: float, radius_c: float) -> float:
    """Volume (m³) of a solid body of revolution ahead of the plane y = y_c (axis +y, tip at y = 0) from
    surface points on it, by the divergence theorem: V = (1/3) (Σ_{y < y_c} (X·N) A + y_c π r_c²), the last
    term the closing disc at y_c of radius r_c.

    Args:
        X: surface points (k, 3) (m), the axis through the origin along +y. N: outward unit normals (k, 3).
        area: their areas (k,) (m²). y_c: the zone's end (m). radius_c: the body's radius at y_c (m).

    Returns:
        The volume (m³).
    """
    zone = X[:, 1] < y_c
    return float((np.einsum("ij,ij->i", X[zone], N[zone]) @ area[zone] + y_c * np.pi * radius_c**2) / 3.0)


def contraction_after(contraction: float, volume: float, zone0: float) -> float:
    """The nose zone's length factor λ after ``volume`` (m³) more has melted off a zone of original volume
    ``zone0`` (m³): λ − volume/zone0 (the zone's volume is λ zone0), never below MIN_CONTRACTION."""
    return max(contraction - volume / zone0, MIN_CONTRACTION)


def contract_points(X: np.ndarray, N: np.ndarray, area: np.ndarray, R_meridian: np.ndarray, y_c: float,
                    contraction: float) -> tuple[np.ndarray, ...]:
    """Surface points of a nose contracted along its axis toward y = y_c by λ: y' = y_c − λ (y_c − y) for
    y < y_c (the map diag(1, λ, 1)); normals by its inverse transpose, areas by λ |A^-T N|, the meridian's
    radius of curvature by R λ² (n_r/n_r')³ (the curvature of r(y) under y → λ y), the sine of the surface's
    angle to the axis as |N'_y|. Points behind y_c are returned unchanged.

    Args:
        X, N, area, R_meridian: the original points (k, 3), unit normals (k, 3), areas (k,) (m²) and meridian
            radii of curvature (k,) (m, inf where flat). y_c: the zone's end (m). contraction: λ in (0, 1].

    Returns:
        (X', N', area', sin_phi0', R_meridian') of all the points.
    """
    lam = float(contraction)
    zone = X[:, 1] < y_c
    X2, N2, A2, R2 = X.copy(), N.copy(), area.copy(), R_meridian.copy()
    sin_phi = np.abs(N[:, 1]).copy()
    if lam == 1.0 or not zone.any():
        return X2, N2, A2, sin_phi, R2
    X2[zone, 1] = y_c - lam * (y_c - X[zone, 1])
    m = N[zone] * np.array([lam, 1.0, lam])
    norm = np.linalg.norm(m, axis=1)
    N2[zone] = m / norm[:, None]
    A2[zone] = area[zone] * norm
    nr0 = np.hypot(N[zone, 0], N[zone, 2])
    nr1 = np.hypot(N2[zone, 0], N2[zone, 2])
    with np.errstate(divide="ignore", invalid="ignore"):
        R2[zone] = np.where(nr1 > 0.0, R_meridian[zone] * lam * lam * (nr0 / nr1) ** 3, R_meridian[zone])
    sin_phi[zone] = np.abs(N2[zone, 1])
    return X2, N2, A2, sin_phi, R2
