"""Nose wear on plain arrays (docs/theory.md §14): the interface heat of the sliding target, and the mass it
melts off the projectile's surface.

The heat: every loaded surface point slides past the target at |v_t| under the normal stress σ_n; the
interface dissipates q = μ σ_n |v_t| per unit area (μ the interface's friction coefficient, whether or not
the friction force itself is applied: the calibrated σ_s already holds the interface's resistance, the
heat is there all the same). The mass: a fraction η of that heat melts a thin surface layer that the flow
carries away (Jones, Foster, Wang et al. 2002; Silling and Forrestal 2007: mass loss in proportion to the
frictional work), each kilogram taking h = c_p (T_melt − T_room) + L_f to heat and melt.
"""

from __future__ import annotations

import numpy as np

__all__ = ["LATENT_HEAT_STEEL", "heat_rate", "heat_rates", "melt_enthalpy", "melted_mass", "recession_depth"]

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


def heat_rates(force: np.ndarray, n: np.ndarray, v: np.ndarray, mu: float) -> np.ndarray:
    """Each point's interface heat per unit time (W): μ σ_n A |v_t| (see heat_rate), (k,)."""
    normal = np.maximum(-np.einsum("ij,ij->i", force, n), 0.0)
    vn = np.einsum("ij,ij->i", v, n)
    vt = np.linalg.norm(v - vn[:, None] * n, axis=1)
    return mu * normal * vt


def recession_depth(heat: np.ndarray, area: np.ndarray, efficiency: float, enthalpy: float,
                    density: float) -> np.ndarray:
    """Depth (m) by which a surface recedes when the heat (J) it took over its area (m²) melts its mass off:
    d = η Q / (h ρ A); 0 where the area is 0."""
    return np.where(area > 0.0, efficiency * heat / (enthalpy * density * np.where(area > 0.0, area, 1.0)), 0.0)


def heat_rate(force: np.ndarray, n: np.ndarray, v: np.ndarray, mu: float) -> float:
    """Interface heat per unit time (W) over surface points: Σ μ σ_n A |v_t|, with σ_n A = −f·n taken from the
    target's forces on the points (the normal part; a friction force is tangential and drops out).

    Args:
        force: the target's forces on the points (k, 3) (N). n: outward unit normals (k, 3). v: velocities
            (k, 3) (m/s). mu: the interface's friction coefficient.

    Returns:
        The heat rate (W), ≥ 0.
    """
    normal = np.maximum(-np.einsum("ij,ij->i", force, n), 0.0)
    vn = np.einsum("ij,ij->i", v, n)
    vt = np.linalg.norm(v - vn[:, None] * n, axis=1)
    return float(mu * normal @ vt)


def melted_mass(heat: float, efficiency: float, enthalpy: float) -> float:
    """Mass (kg) melted off by the interface heat (J): η Q / h."""
    return efficiency * heat / enthalpy
