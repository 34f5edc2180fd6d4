"""The shell-charge contact law on node pairs (numba): kinematic normal force, Coulomb friction, and
their work. The algorithm and its energy accounting: docs/theory.md §13.
"""

from __future__ import annotations

import math

import numba


@numba.njit(cache=True, error_model="numpy")
def pair_forces(x, vel, acc, mass, pa, pb, normal, dt, dt_avg, mu, force, fn, state):
    """The kinematic contact forces of node pairs (module docstring).

    Args:
        x, vel, acc: current positions, v^{n−1/2}, a^n without contact (n_nodes, 3).
        mass: lumped nodal masses (n_nodes,). pa, pb: shell and charge node of each pair (k,).
        normal: unit normal of each pair, out of the charge (k, 3).
        dt: Δt_{n+1/2}; dt_avg: (Δt_{n−1/2} + Δt_{n+1/2}) / 2; mu: Coulomb friction coefficient (≥ 0).
        force: (k, 3) output, the force on a (−force on b). fn: (k,) output, F_N.
        state: (k,) output, 0 open, 1 stuck, 2 sliding.
    """
    for i in range(len(pa)):
        a, b = pa[i], pb[i]
        inv = 1.0 / mass[a] + 1.0 / mass[b]
        nx, ny, nz = normal[i, 0], normal[i, 1], normal[i, 2]
        rx = vel[a, 0] + dt_avg * acc[a, 0] - vel[b, 0] - dt_avg * acc[b, 0]
        ry = vel[a, 1] + dt_avg * acc[a, 1] - vel[b, 1] - dt_avg * acc[b, 1]
        rz = vel[a, 2] + dt_avg * acc[a, 2] - vel[b, 2] - dt_avg * acc[b, 2]
        rn = rx * nx + ry * ny + rz * nz
        g = (x[a, 0] - x[b, 0]) * nx + (x[a, 1] - x[b, 1]) * ny + (x[a, 2] - x[b, 2]) * nz
        gp = g + dt * rn
        if gp >= 0.0:
            force[i, 0] = force[i, 1] = force[i, 2] = 0.0
            fn[i] = 0.0
            state[i] = 0
            continue
        f_n = -gp / (dt * dt_avg * inv)
        tx, ty, tz = rx - rn * nx, ry - rn * ny, rz - rn * nz
        sx, sy, sz = -tx / (dt_avg * inv), -ty / (dt_avg * inv), -tz / (dt_avg * inv)
        s = math.sqrt(sx * sx + sy * sy + sz * sz)
        cap = mu * f_n
        if s <= cap:
            state[i] = 1
        else:
            k = cap / s
            sx, sy, sz = k * sx, k * sy, k * sz
            state[i] = 2
        force[i, 0] = f_n * nx + sx
        force[i, 1] = f_n * ny + sy
        force[i, 2] = f_n * nz + sz
        fn[i] = f_n


@numba.njit(cache=True, error_model="numpy")
def pair_work(vel, acc, mass, pa, pb, normal, force, fn, dt_prev, dt, dt_avg, count, out):
    """Add the pairs' normal and tangential work over the two half steps around this force to out[0:2]
    (pairs with count False skipped: another rank counts them).

    vel, acc: v^{n−1/2} and a^n before the contact forces were added."""
    for i in range(len(pa)):
        if not count[i] or (fn[i] == 0.0 and force[i, 0] == 0.0 and force[i, 1] == 0.0 and force[i, 2] == 0.0):
            continue
        a, b = pa[i], pb[i]
        inv = 1.0 / mass[a] + 1.0 / mass[b]
        wn = 0.0
        wt = 0.0
        for k in range(3):
            before = dt_prev * (vel[a, k] - vel[b, k])
            after = dt * (vel[a, k] + dt_avg * acc[a, k] - vel[b, k] - dt_avg * acc[b, k]
                          + dt_avg * inv * force[i, k])
            d = 0.5 * (before + after)
            fnk = fn[i] * normal[i, k]
            wn += fnk * d
            wt += (force[i, k] - fnk) * d
        out[0] += wn
        out[1] += wt


@numba.njit(cache=True, error_model="numpy")
def wall_normals(x, tri, out):
    """Area vectors of the wall facets (oriented out of the charge), a third to each node, into out."""
    for i in range(tri.shape[0]):
        i0, i1, i2 = tri[i, 0], tri[i, 1], tri[i, 2]
        ax, ay, az = x[i1, 0] - x[i0, 0], x[i1, 1] - x[i0, 1], x[i1, 2] - x[i0, 2]
        bx, by, bz = x[i2, 0] - x[i0, 0], x[i2, 1] - x[i0, 1], x[i2, 2] - x[i0, 2]
        cx, cy, cz = (ay * bz - az * by) / 6.0, (az * bx - ax * bz) / 6.0, (ax * by - ay * bx) / 6.0
        for j in range(3):
            out[tri[i, j], 0] += cx
            out[tri[i, j], 1] += cy
            out[tri[i, j], 2] += cz


@numba.njit(cache=True, error_model="numpy")
def wall_facet_normals(x, tri, out):
    """Each wall facet's area vector over 6 (oriented out of the charge), into out (f, 3): the term
    wall_normals adds to each of its three nodes."""
    for i in range(tri.shape[0]):
        i0, i1, i2 = tri[i, 0], tri[i, 1], tri[i, 2]
        ax, ay, az = x[i1, 0] - x[i0, 0], x[i1, 1] - x[i0, 1], x[i1, 2] - x[i0, 2]
        bx, by, bz = x[i2, 0] - x[i0, 0], x[i2, 1] - x[i0, 1], x[i2, 2] - x[i0, 2]
        out[i, 0] = (ay * bz - az * by) / 6.0
        out[i, 1] = (az * bx - ax * bz) / 6.0
        out[i, 2] = (ax * by - ay * bx) / 6.0
