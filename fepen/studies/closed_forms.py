"""Closed forms fepen is checked against (docs/theory.md §16, §17), as plain functions of numbers: the rigid
depth of a nose into a cavity-expansion target with the nose entering, and a thin slab's residual speed."""

from __future__ import annotations

import math

__all__ = ["depth_with_nose_entry", "slab_residual_speed"]


def depth_with_nose_entry(r, slope, nose_length, mass, density, B, sigma_s, N, v0) -> float:
    """Nose-tip depth (m) of a rigid nose of radius r(z) entering a semi-infinite target of σ_n = σ_s + B ρ (v·n)²
    at v0, normal: while the nose enters (0 < z < ℓ) the force is σ_s π r(z)² + B ρ V² K(z) with
    K(z) = ∫_0^z 2π r r'³/(1 + r'²) dζ, an ODE in V² solved to 1e-10; beyond, Forrestal and Warren's
    P = ℓ + m/(2π a² ρ N* B) ln(1 + N* B ρ V1²/σ_s).

    Args:
        r, slope: the nose radius r(z) and r'(z) (m, -) for 0 <= z <= nose_length. mass (kg), density ρ
        (kg/m³), B, sigma_s (Pa), N: the nose factor N*, v0 (m/s).
    """
    from scipy import integrate

    a = r(nose_length)

    def K(z):
        return integrate.quad(lambda t: 2 * math.pi * r(t) * slope(t) ** 3 / (1 + slope(t) ** 2), 0.0, z)[0]

    sol = integrate.solve_ivp(lambda z, w: [-(2 / mass) * (sigma_s * math.pi * r(z) ** 2 + B * density * K(z) * w[0])],
                              (0.0, nose_length), [v0 * v0], rtol=1e-10, atol=1e-6)
    v1_sq = sol.y[0, -1]
    return nose_length + mass / (2 * math.pi * a * a * density * N * B) * math.log(
        1 + N * B * density * v1_sq / sigma_s)


def tangent_ogive(radius: float, crh: float):
    """r(z), r'(z) and the length of a tangent ogive of base radius a and CRH ψ."""
    s = 2.0 * crh * radius
    ln = radius * math.sqrt(4.0 * crh - 1.0)

    def r(z):
        return math.sqrt(max(s * s - (ln - z) ** 2, 0.0)) - (s - radius)

    def slope(z):
        return (ln - z) / math.sqrt(max(s * s - (ln - z) ** 2, 1e-300))

    return r, slope, ln


def slab_residual_speed(v0, thickness, radius, mass, density, sigma_s, N) -> float:
    """Residual speed (m/s) of a rigid nose through a slab of σ_n = σ_s + ρ (v·n)², the full nose force over
    the thickness h: v_r² = (v0² + σ_s/(N* ρ)) exp(−2π a² N* ρ h / m) − σ_s/(N* ρ) (0 if it stops)."""
    k = math.pi * radius**2 * N * density / mass
    c = sigma_s / (N * density)
    return math.sqrt(max((v0 * v0 + c) * math.exp(-2 * k * thickness) - c, 0.0))
