"""The charge-safety criteria on plain arrays (docs/theory.md §20): the demands a run computes in its charge
and on the shell-charge interface, and each criterion's margin against its threshold. Pure functions; the
thresholds are plain numbers (fepen.data.explosives and the charge.safety.* keys give them).

A margin is threshold / demand: 1 at the threshold, above 1 safe by that factor, below 1 beyond it; an
infinite margin where there is no demand, None where no threshold is given.

    strength         the equivalent (von Mises) stress of a charge cell against the explosive's strength:
                     the onset of damage (crystal fracture and debonding, which raise a pressed explosive's
                     sensitivity)
    tension          the largest principal stress of a charge cell (tension positive) against its tensile
                     strength
    friction_work    the friction work per unit area dissipated at an interface point so far (J/m²)
    friction_power   the friction power per unit area at an interface point, mu p v (W/m²)
    gap              the largest gap at the charge's ends (m): a gap that closes compresses its gas
    closure_speed    the speed at which an open end gap closes (m/s)
    acceleration_g   the charge's filtered peak acceleration (g); the set-forward pressure of a column of
                     length L is rho L a (reported beside it)
"""

from __future__ import annotations

import math

import numba
import numpy as np

__all__ = ["CRITERIA", "largest_principal", "von_mises", "margin", "margins", "pair_friction", "cell_demands",
           "set_forward_pressure"]

#: every criterion, in the order the summary lists them: (name, the demand's unit, what it is)
CRITERIA = (
    ("strength", "Pa", "the charge's equivalent stress against the explosive's strength"),
    ("tension", "Pa", "the charge's largest principal stress against its tensile strength"),
    ("friction_work", "J/m^2", "the friction work per unit area at the shell-charge interface"),
    ("friction_power", "W/m^2", "the friction power per unit area (mu p v) at the shell-charge interface"),
    ("gap", "m", "the largest gap at the charge's ends"),
    ("closure_speed", "m/s", "the speed at which an open end gap closes"),
    ("acceleration_g", "g", "the charge's filtered peak acceleration"),
)


def largest_principal(stress: np.ndarray) -> np.ndarray:
    """The largest principal stress of each symmetric tensor (tension positive), in closed form.

    Args:
        stress: (n, 6) Cauchy stresses in the order xx, yy, zz, xy, yz, xz (Pa).

    Returns:
        (n,) the largest eigenvalue of each (Pa): the trigonometric solution of the characteristic cubic
        (exact to round-off; a spherical tensor gives its mean).
    """
    s = np.asarray(stress, dtype=float)
    xx, yy, zz, xy, yz, xz = (s[:, k] for k in range(6))
    q = (xx + yy + zz) / 3.0
    p1 = xy * xy + yz * yz + xz * xz
    p2 = (xx - q) ** 2 + (yy - q) ** 2 + (zz - q) ** 2 + 2.0 * p1
    p = np.sqrt(p2 / 6.0)
    safe = np.where(p > 0.0, p, 1.0)
    bxx, byy, bzz = (xx - q) / safe, (yy - q) / safe, (zz - q) / safe
    bxy, byz, bxz = xy / safe, yz / safe, xz / safe
    det = bxx * (byy * bzz - byz * byz) - bxy * (bxy * bzz - byz * bxz) + bxz * (bxy * byz - byy * bxz)
    phi = np.arccos(np.clip(det / 2.0, -1.0, 1.0)) / 3.0
    return np.where(p > 0.0, q + 2.0 * p * np.cos(phi), q)


def von_mises(stress: np.ndarray) -> np.ndarray:
    """The von Mises stress of each tensor (n, 6: xx, yy, zz, xy, yz, xz; Pa)."""
    s = np.asarray(stress, dtype=float)
    q = (s[:, 0] + s[:, 1] + s[:, 2]) / 3.0
    d = s[:, :3] - q[:, None]
    return np.sqrt(1.5 * (np.sum(d * d, axis=1) + 2.0 * np.sum(s[:, 3:] ** 2, axis=1)))


def margin(threshold: float | None, demand: float) -> float | None:
    """threshold / demand: inf where there is no demand (≤ 0), None where no threshold is given."""
    if threshold is None:
        return None
    return math.inf if not demand > 0.0 else float(threshold) / float(demand)


def margins(threshold: float | None, demand: np.ndarray) -> np.ndarray | None:
    """margin() of each demand (an array); None where no threshold is given."""
    if threshold is None:
        return None
    d = np.asarray(demand, dtype=float)
    return np.divide(float(threshold), d, out=np.full(d.shape, np.inf), where=d > 0.0)


@numba.njit(cache=True, error_model="numpy")
def pair_friction(vel, acc, mass, pa, pb, normal, force, fn, dt_prev, dt, dt_avg, area, heat, work, power, peak):
    """The friction heat of each node pair over the two half steps around this force: added to heat (J) and,
    per unit area, to work (J/m², the dissipation so far); its rate per unit area written to power (W/m²) and
    kept in peak where larger.

    The dissipation is −F_t · Δ, F_t the tangential part of the pair's force on the shell node and Δ the
    pair's relative displacement over the half steps before and after the force (as fepen.laws.contact's
    pair_work, whose sum over the pairs it is): zero on a stuck pair, mu F_N |v_t| Δt on a sliding one.

    Args:
        vel, acc: v^{n−1/2} and a^n before the contact forces were added (n_nodes, 3). mass: nodal masses.
        pa, pb: shell and charge node of each pair. normal: (k, 3) unit normals out of the charge.
        force: (k, 3) the contact force on the shell node. fn: (k,) its normal part.
        dt_prev, dt, dt_avg: Δt_{n−1/2}, Δt_{n+1/2} and their mean. area: (k,) each pair's wall area (m²).
        heat: (k,) J, added to. work: (k,) J/m², added to. power: (k,) W/m², written. peak: (k,) W/m², the
            largest power so far.
    """
    for i in range(len(pa)):
        if fn[i] == 0.0 or area[i] <= 0.0:
            power[i] = 0.0
            continue
        a, b = pa[i], pb[i]
        inv = 1.0 / mass[a] + 1.0 / mass[b]
        w = 0.0
        for k in range(3):
            before = dt_prev * (vel[a, k] - vel[b, k])
            after = dt * (vel[a, k] + dt_avg * acc[a, k] - vel[b, k] - dt_avg * acc[b, k] + dt_avg * inv * force[i, k])
            w += (force[i, k] - fn[i] * normal[i, k]) * 0.5 * (before + after)
        heat[i] -= w  # the pair's share of the interface's dissipation, as pair_work sums it
        q = max(-w, 0.0)  # a step's round-off of either sign on a stuck pair: no heat to a criterion
        work[i] += q / area[i]
        power[i] = q / area[i] / max(0.5 * (dt_prev + dt), 1e-300)
        if power[i] > peak[i]:
            peak[i] = power[i]


@numba.njit(cache=True, error_model="numpy")
def cell_demands(sd, nodal_p, dofs, mat, cells, nodal, alpha, filtered, demand, peak, raw_peak):
    """The charge cells' demands of the strength and tension criteria at a history row, in one pass: each
    cell's Cauchy stress, low-passed (filtered += alpha (stress − filtered); alpha = 1: unfiltered), its von
    Mises stress and largest principal stress into demand[0] and demand[1] (0 on an eroded cell), each kept
    in peak where larger; the unfiltered von Mises stress's largest into raw_peak[0].

    Args:
        sd: the cells' stress (n, 6: xx, yy, zz, xy, yz, xz; Pa), the deviator when ``nodal`` (the mean stress
            is then the mean of the cell's nodes' nodal_p of its material). nodal_p: (n_nodes, n_materials).
        dofs: (n, 4) the cells' nodes. mat: (n,) their material (−1 eroded). cells: the charge cells (k,).
        nodal: whether the averaged-nodal-pressure element is on. alpha: the low-pass's weight (0 < alpha ≤ 1).
        filtered: (k, 6) updated. demand, peak: (2, k) written, updated. raw_peak: (1,) updated.
    """
    st = np.empty(6)
    for j in range(len(cells)):
        c = cells[j]
        if mat[c] < 0:
            demand[0, j] = 0.0
            demand[1, j] = 0.0
            continue
        pm = 0.0
        if nodal:
            for a in range(4):
                pm += nodal_p[dofs[c, a], mat[c]]
            pm *= 0.25
        for i in range(6):
            st[i] = sd[c, i]
        for i in range(3):
            st[i] += pm
        q = (st[0] + st[1] + st[2]) / 3.0
        dx, dy, dz = st[0] - q, st[1] - q, st[2] - q
        raw_peak[0] = max(raw_peak[0], math.sqrt(1.5 * (dx * dx + dy * dy + dz * dz
                                                       + 2.0 * (st[3] * st[3] + st[4] * st[4] + st[5] * st[5]))))
        for i in range(6):  # the low-passed stress
            filtered[j, i] += alpha * (st[i] - filtered[j, i])
            st[i] = filtered[j, i]
        q = (st[0] + st[1] + st[2]) / 3.0
        dx, dy, dz = st[0] - q, st[1] - q, st[2] - q
        j2 = dx * dx + dy * dy + dz * dz + 2.0 * (st[3] * st[3] + st[4] * st[4] + st[5] * st[5])
        vm = math.sqrt(1.5 * j2)
        p = math.sqrt(j2 / 6.0)
        if p > 0.0:
            bxx, byy, bzz, bxy, byz, bxz = dx / p, dy / p, dz / p, st[3] / p, st[4] / p, st[5] / p
            det = bxx * (byy * bzz - byz * byz) - bxy * (bxy * bzz - byz * bxz) + bxz * (bxy * byz - byy * bxz)
            s1 = q + 2.0 * p * math.cos(math.acos(min(max(det / 2.0, -1.0), 1.0)) / 3.0)
        else:
            s1 = q
        demand[0, j] = vm
        demand[1, j] = s1
        peak[0, j] = max(peak[0, j], vm)
        peak[1, j] = max(peak[1, j], s1)


def set_forward_pressure(density: float, length: float, acceleration: float) -> float:
    """The pressure a column of explosive exerts on the face that stops it (Pa): rho L a, the column's mass
    per unit area times its acceleration (an upper bound where the walls carry part of the load by friction).

    Args:
        density: kg/m³. length: the column's length along the acceleration (m). acceleration: m/s² (its size).
    """
    return float(density) * float(length) * abs(float(acceleration))
