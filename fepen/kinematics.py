"""Cell kernels of the explicit solver on plain arrays (numba): kinematics, nodal volumes, stress update.

Element: the linear tetrahedron with averaged nodal pressure (Bonet & Burton 1998). Each node carries the
volume Σ V_e/4 of its cells (per material); its volume ratio J_a = V_a / V0_a defines a nodal pressure
p_a = K ln(J_a) / J_a, the derivative of the volumetric energy K/2 (ln J_a)^2 stored at the node; a cell's
mean stress is the average of its four nodes' pressures. The cell's deviatoric stress is its own. With
``nodal = False`` each cell uses its own J (the plain, locking-prone element).

Deviatoric stress: hypoelastic with the Hughes–Winget incremental rotation. The increment of the
displacement gradient at the mid-step configuration, ΔL = (∂Δu/∂X) F_{n+1/2}^{-1}, gives ΔD = sym ΔL and
ΔW = skew ΔL; the stress is rotated by Q = (I − ΔW/2)^{-1}(I + ΔW/2), which is exactly orthogonal and, for a
rigid rotation, exactly the rotation of the step; then s += 2 G dev(ΔD) and the radial return of
fepen.materials. The first Piola–Kirchhoff stress handed to the force form is P = J σ F^{-T}.

Arrays: x (n_nodes, 3) current positions; dofs (n_cells, 4) node indices; grad0 (n_cells, 4, 3) reference
shape-function gradients; vol0 (n_cells,) reference volumes; mat (n_cells,) material index into params
(n_materials, N_PARAMS); s (n_cells, 6) deviatoric Cauchy stress (xx, yy, zz, xy, yz, xz).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from fepen import materials as M

#: fast-math flags that keep IEEE NaN/inf semantics (inverted or NaN elements must still be detected)
_FAST = {"nsz", "arcp", "contract", "afn", "reassoc"}


def reference_gradients(X: np.ndarray, dofs: np.ndarray):
    """Shape-function gradients, volumes and orientation signs of the reference cells.

    Args:
        X: reference node coordinates (n_nodes, 3).
        dofs: cell node indices (n_cells, 4).

    Returns:
        (grad0 (n_cells, 4, 3), vol0 (n_cells,) > 0 whatever the node ordering, orient (n_cells,) ±1).
    """
    p = X[dofs]
    Jm = np.stack([p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]], axis=2)  # columns
    inv = np.linalg.inv(Jm)  # rows: gradients of phi_1..3
    grad0 = np.empty((len(dofs), 4, 3))
    grad0[:, 1:] = inv
    grad0[:, 0] = -inv.sum(axis=1)
    det = np.linalg.det(Jm)
    return grad0, np.abs(det) / 6.0, np.sign(det)


@numba.njit(cache=True, inline="always", fastmath=_FAST, error_model="numpy")
def _six_volume(x, dofs, e):
    """det(x1 - x0, x2 - x0, x3 - x0) of cell e: six times its signed volume."""
    n0, n1, n2, n3 = dofs[e, 0], dofs[e, 1], dofs[e, 2], dofs[e, 3]
    ax, ay, az = x[n1, 0] - x[n0, 0], x[n1, 1] - x[n0, 1], x[n1, 2] - x[n0, 2]
    bx, by, bz = x[n2, 0] - x[n0, 0], x[n2, 1] - x[n0, 1], x[n2, 2] - x[n0, 2]
    cx, cy, cz = x[n3, 0] - x[n0, 0], x[n3, 1] - x[n0, 1], x[n3, 2] - x[n0, 2]
    return ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def volumes_and_step(x, dofs, orient, vol0, mat, speed, nodal_vol, with_step=True):
    """Current cell volumes into nodal volumes; the smallest J; the stable step of the current mesh.

    Args:
        x: current positions (n_nodes, 3).
        dofs, vol0, mat: see module docstring. orient: +1 or −1 per cell, the sign of the reference
            det(X1 − X0, X2 − X0, X3 − X0) (so that J > 0 for an uninverted cell whatever the node order).
        speed: dilatational wave speed per material (m/s).
        nodal_vol: (n_nodes, n_materials) output, zeroed and filled with Σ V_e / 4.
        with_step: also compute the shortest altitudes (else the third result is inf).

    Returns:
        (min J, cell of min J, min over cells of shortest altitude / wave speed, cell of that minimum).
    """
    nodal_vol[:] = 0.0
    jmin = np.inf
    worst = -1
    dtmin = np.inf
    dtcell = -1
    for e in range(dofs.shape[0]):
        # J = det(x1 - x0, x2 - x0, x3 - x0) / (6 V0): needs the positions only, not the gradients
        J = _six_volume(x, dofs, e) / (6.0 * vol0[e]) * orient[e]
        if not (J > jmin):
            if not (J >= jmin):  # also catches NaN
                jmin = J
                worst = e
        V = J * vol0[e]
        m = mat[e]
        for a in range(4):
            nodal_vol[dofs[e, a], m] += 0.25 * V
        if not with_step:
            continue
        # shortest altitude = 3 V / largest face area
        amax = 0.0
        for f in range(4):
            i0 = dofs[e, (f + 1) % 4]
            i1 = dofs[e, (f + 2) % 4]
            i2 = dofs[e, (f + 3) % 4]
            ax = x[i1, 0] - x[i0, 0]
            ay = x[i1, 1] - x[i0, 1]
            az = x[i1, 2] - x[i0, 2]
            bx = x[i2, 0] - x[i0, 0]
            by = x[i2, 1] - x[i0, 1]
            bz = x[i2, 2] - x[i0, 2]
            cx = ay * bz - az * by
            cy = az * bx - ax * bz
            cz = ax * by - ay * bx
            area2 = cx * cx + cy * cy + cz * cz
            if area2 > amax:
                amax = area2
        if amax > 0.0 and V > 0.0:
            h = 3.0 * V / (0.5 * math.sqrt(amax))
            t = h / speed[m]
            if t < dtmin:
                dtmin = t
                dtcell = e
    return jmin, worst, dtmin, dtcell


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def cell_jacobians(x, dofs, orient, vol0, out):
    """J = V / V0 of every cell into out (for the energies; the same formula as volumes_and_step)."""
    for e in range(dofs.shape[0]):
        out[e] = _six_volume(x, dofs, e) / (6.0 * vol0[e]) * orient[e]


@numba.njit(cache=True, inline="always", fastmath=_FAST, error_model="numpy")
def _cofactor(a00, a01, a02, a10, a11, a12, a20, a21, a22):
    """Cofactor matrix (J A^-T) of a 3x3 matrix given by its entries, as a 9-tuple, row-major."""
    return (a11 * a22 - a12 * a21, a12 * a20 - a10 * a22, a10 * a21 - a11 * a20,
            a02 * a21 - a01 * a22, a00 * a22 - a02 * a20, a01 * a20 - a00 * a21,
            a01 * a12 - a02 * a11, a02 * a10 - a00 * a12, a00 * a11 - a01 * a10)


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def nodal_pressures(nodal_vol, nodal_vol0, bulk, out):
    """Nodal mean stress p_a = K ln(J_a) / J_a per material (Pa), J_a = V_a / V0_a; 0 where no volume."""
    for n in range(nodal_vol.shape[0]):
        for m in range(nodal_vol.shape[1]):
            v0 = nodal_vol0[n, m]
            if v0 > 0.0:
                Ja = nodal_vol[n, m] / v0
                out[n, m] = bulk[m] * math.log(Ja) / Ja
            else:
                out[n, m] = 0.0


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def stress_update(x, v, dt, dofs, grad0, vol0, mat, params, nodal_p, nodal, s, eps_p, temp, sy0, P_out,
                  totals):
    """Advance every cell's stress over one step and write P = J σ F^{-T} (row-major) into P_out.

    Written with scalars rather than 3x3 temporaries (twice as fast under numba).

    Args:
        x: positions at the end of the step (n_nodes, 3); v: velocities over the step (n_nodes, 3).
        dt: the step (s).
        params: material parameters (n_materials, N_PARAMS).
        nodal_p: nodal mean stress per material (n_nodes, n_materials), from nodal_pressures.
        nodal: True for the averaged nodal pressure, False for the plain element (own J).
        s, eps_p, temp: deviatoric stress (n, 6), plastic strain (n,), temperature (n,); updated in place.
        sy0: static flow stress σ_y(ε_p, T) of each cell (n,) (inf for elastic cells); updated in place.
        P_out: (n_cells_packed, 9) output, first n_cells rows written.
        totals: (4,) output: plastic work, heat, (unused), largest plastic increment.
    """
    nmat = params.shape[0]
    G_m = np.empty(nmat)
    K_m = np.empty(nmat)
    for m in range(nmat):
        G_m[m] = params[m, M.E_] / (2.0 * (1.0 + params[m, M.NU]))
        K_m[m] = params[m, M.E_] / (3.0 * (1.0 - 2.0 * params[m, M.NU]))
    de = np.empty(6)
    se = np.empty(6)
    totals[:] = 0.0
    for e in range(dofs.shape[0]):
        m = mat[e]
        G = G_m[m]
        # F = sum_a x_a (x) grad0_a and the increment D = sum_a (v_a dt) (x) grad0_a
        F00 = F01 = F02 = F10 = F11 = F12 = F20 = F21 = F22 = 0.0
        D00 = D01 = D02 = D10 = D11 = D12 = D20 = D21 = D22 = 0.0
        for a in range(4):
            nd = dofs[e, a]
            g0 = grad0[e, a, 0]
            g1 = grad0[e, a, 1]
            g2 = grad0[e, a, 2]
            x0 = x[nd, 0]
            x1 = x[nd, 1]
            x2 = x[nd, 2]
            u0 = v[nd, 0] * dt
            u1 = v[nd, 1] * dt
            u2 = v[nd, 2] * dt
            F00 += x0 * g0
            F01 += x0 * g1
            F02 += x0 * g2
            F10 += x1 * g0
            F11 += x1 * g1
            F12 += x1 * g2
            F20 += x2 * g0
            F21 += x2 * g1
            F22 += x2 * g2
            D00 += u0 * g0
            D01 += u0 * g1
            D02 += u0 * g2
            D10 += u1 * g0
            D11 += u1 * g1
            D12 += u1 * g2
            D20 += u2 * g0
            D21 += u2 * g1
            D22 += u2 * g2
        # mid-step configuration F_m = F - D/2 and L = D F_m^-1 (through the cofactor of F_m)
        a00 = F00 - 0.5 * D00
        a01 = F01 - 0.5 * D01
        a02 = F02 - 0.5 * D02
        a10 = F10 - 0.5 * D10
        a11 = F11 - 0.5 * D11
        a12 = F12 - 0.5 * D12
        a20 = F20 - 0.5 * D20
        a21 = F21 - 0.5 * D21
        a22 = F22 - 0.5 * D22
        c00, c01, c02, c10, c11, c12, c20, c21, c22 = _cofactor(a00, a01, a02, a10, a11, a12, a20, a21, a22)
        idet = 1.0 / (a00 * c00 + a01 * c01 + a02 * c02)
        L00 = (D00 * c00 + D01 * c01 + D02 * c02) * idet
        L01 = (D00 * c10 + D01 * c11 + D02 * c12) * idet
        L02 = (D00 * c20 + D01 * c21 + D02 * c22) * idet
        L10 = (D10 * c00 + D11 * c01 + D12 * c02) * idet
        L11 = (D10 * c10 + D11 * c11 + D12 * c12) * idet
        L12 = (D10 * c20 + D11 * c21 + D12 * c22) * idet
        L20 = (D20 * c00 + D21 * c01 + D22 * c02) * idet
        L21 = (D20 * c10 + D21 * c11 + D22 * c12) * idet
        L22 = (D20 * c20 + D21 * c21 + D22 * c22) * idet
        # Hughes-Winget rotation Q = (I - W/2)^-1 (I + W/2), W = skew(L), in closed form (Cayley):
        # with w the axial vector of W/2, Q = I + 2 (W/2 + (W/2)^2) / (1 + |w|^2)
        w0 = 0.25 * (L21 - L12)
        w1 = 0.25 * (L02 - L20)
        w2 = 0.25 * (L10 - L01)
        c = 2.0 / (1.0 + w0 * w0 + w1 * w1 + w2 * w2)
        Q00 = 1.0 - c * (w1 * w1 + w2 * w2)
        Q11 = 1.0 - c * (w0 * w0 + w2 * w2)
        Q22 = 1.0 - c * (w0 * w0 + w1 * w1)
        Q01 = c * (-w2 + w0 * w1)
        Q10 = c * (w2 + w0 * w1)
        Q02 = c * (w1 + w0 * w2)
        Q20 = c * (-w1 + w0 * w2)
        Q12 = c * (-w0 + w1 * w2)
        Q21 = c * (w0 + w1 * w2)
        # rotated deviatoric stress Q S Q^T
        S00 = s[e, 0]
        S11 = s[e, 1]
        S22 = s[e, 2]
        S01 = s[e, 3]
        S12 = s[e, 4]
        S02 = s[e, 5]
        T00 = Q00 * S00 + Q01 * S01 + Q02 * S02
        T01 = Q00 * S01 + Q01 * S11 + Q02 * S12
        T02 = Q00 * S02 + Q01 * S12 + Q02 * S22
        T10 = Q10 * S00 + Q11 * S01 + Q12 * S02
        T11 = Q10 * S01 + Q11 * S11 + Q12 * S12
        T12 = Q10 * S02 + Q11 * S12 + Q12 * S22
        T20 = Q20 * S00 + Q21 * S01 + Q22 * S02
        T21 = Q20 * S01 + Q21 * S11 + Q22 * S12
        T22 = Q20 * S02 + Q21 * S12 + Q22 * S22
        se[0] = T00 * Q00 + T01 * Q01 + T02 * Q02
        se[1] = T10 * Q10 + T11 * Q11 + T12 * Q12
        se[2] = T20 * Q20 + T21 * Q21 + T22 * Q22
        se[3] = T00 * Q10 + T01 * Q11 + T02 * Q12
        se[4] = T10 * Q20 + T11 * Q21 + T12 * Q22
        se[5] = T00 * Q20 + T01 * Q21 + T02 * Q22
        tr = (L00 + L11 + L22) / 3.0
        de[0] = L00 - tr
        de[1] = L11 - tr
        de[2] = L22 - tr
        de[3] = 0.5 * (L01 + L10)
        de[4] = 0.5 * (L12 + L21)
        de[5] = 0.5 * (L02 + L20)
        # cofactor C = J F^-T of the end-of-step F, so that P = J sigma F^-T = sigma C
        C00, C01, C02, C10, C11, C12, C20, C21, C22 = _cofactor(F00, F01, F02, F10, F11, F12, F20, F21, F22)
        J = F00 * C00 + F01 * C01 + F02 * C02
        V = J * vol0[e]
        for i in range(6):
            se[i] += 2.0 * G * de[i]
        if params[m, M.KIND] != M.ELASTIC:
            # yield check against the cell's current static flow stress (kept in sy0, refreshed only
            # when the cell yields): elastic cells pay no flow-stress evaluation
            q = math.sqrt(1.5 * (se[0] ** 2 + se[1] ** 2 + se[2] ** 2
                                 + 2.0 * (se[3] ** 2 + se[4] ** 2 + se[5] ** 2)))
            if q > sy0[e]:
                p = params[m]
                d, sy, T_new = M.radial_return(q, eps_p[e], temp[e], dt, G, p)
                if d > 0.0:
                    scale = sy / q
                    for i in range(6):
                        se[i] *= scale
                    eps_p[e] += d
                    temp[e] = T_new
                    sy0[e] = M.yield_stress(eps_p[e], 0.0, T_new, p)
                    totals[0] += sy * d * V
                    if p[M.THERMAL_ON] > 0.0:
                        totals[1] += p[M.BETA] * sy * d * V
                    if d > totals[3]:
                        totals[3] = d
        s0 = se[0]
        s1 = se[1]
        s2 = se[2]
        s3 = se[3]
        s4 = se[4]
        s5 = se[5]
        s[e, 0] = s0
        s[e, 1] = s1
        s[e, 2] = s2
        s[e, 3] = s3
        s[e, 4] = s4
        s[e, 5] = s5
        if nodal:
            pm = 0.25 * (nodal_p[dofs[e, 0], m] + nodal_p[dofs[e, 1], m] + nodal_p[dofs[e, 2], m]
                         + nodal_p[dofs[e, 3], m])
        else:
            pm = K_m[m] * math.log(J) / J
        p00 = s0 + pm
        p11 = s1 + pm
        p22 = s2 + pm
        # P_ij = sum_k sigma_ik C_kj
        P_out[e, 0] = p00 * C00 + s3 * C10 + s5 * C20
        P_out[e, 1] = p00 * C01 + s3 * C11 + s5 * C21
        P_out[e, 2] = p00 * C02 + s3 * C12 + s5 * C22
        P_out[e, 3] = s3 * C00 + p11 * C10 + s4 * C20
        P_out[e, 4] = s3 * C01 + p11 * C11 + s4 * C21
        P_out[e, 5] = s3 * C02 + p11 * C12 + s4 * C22
        P_out[e, 6] = s5 * C00 + s4 * C10 + p22 * C20
        P_out[e, 7] = s5 * C01 + s4 * C11 + p22 * C21
        P_out[e, 8] = s5 * C02 + s4 * C12 + p22 * C22


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def plastic_pass(x, dt, dofs, grad0, vol0, mat, params, s, eps_p, temp, sy0, P_out, cells, totals):
    """Radial return of the cells whose elastic trial state (from the C trial pass, fepen.ckernel) exceeds
    their static flow stress: their s, eps_p, temp, sy0 and P corrected in place, as stress_update does in
    its own loop.

    Args:
        cells: indices of the cells over their flow stress (from the trial pass).
        totals: (4,) output: plastic work, heat, (unused), largest plastic increment.
        others: see stress_update.
    """
    totals[:] = 0.0
    for e in cells:
        m = mat[e]
        p = params[m]
        G = p[M.E_] / (2.0 * (1.0 + p[M.NU]))
        s0, s1, s2, s3, s4, s5 = s[e, 0], s[e, 1], s[e, 2], s[e, 3], s[e, 4], s[e, 5]
        q = math.sqrt(1.5 * (s0 * s0 + s1 * s1 + s2 * s2 + 2.0 * (s3 * s3 + s4 * s4 + s5 * s5)))
        d, sy, T_new = M.radial_return(q, eps_p[e], temp[e], dt, G, p)
        if not (d > 0.0):
            continue
        scale = sy / q
        for i in range(6):
            s[e, i] *= scale
        eps_p[e] += d
        temp[e] = T_new
        sy0[e] = M.yield_stress(eps_p[e], 0.0, T_new, p)
        # P = (s + p I) C changes by (scale - 1) s C; C = cof F and J again (a few cells only)
        F00 = F01 = F02 = F10 = F11 = F12 = F20 = F21 = F22 = 0.0
        for a in range(4):
            nd = dofs[e, a]
            g0 = grad0[e, a, 0]
            g1 = grad0[e, a, 1]
            g2 = grad0[e, a, 2]
            F00 += x[nd, 0] * g0
            F01 += x[nd, 0] * g1
            F02 += x[nd, 0] * g2
            F10 += x[nd, 1] * g0
            F11 += x[nd, 1] * g1
            F12 += x[nd, 1] * g2
            F20 += x[nd, 2] * g0
            F21 += x[nd, 2] * g1
            F22 += x[nd, 2] * g2
        C00, C01, C02, C10, C11, C12, C20, C21, C22 = _cofactor(F00, F01, F02, F10, F11, F12, F20, F21, F22)
        V = (F00 * C00 + F01 * C01 + F02 * C02) * vol0[e]
        f = scale - 1.0
        s0 *= f
        s1 *= f
        s2 *= f
        s3 *= f
        s4 *= f
        s5 *= f
        P_out[e, 0] += s0 * C00 + s3 * C10 + s5 * C20
        P_out[e, 1] += s0 * C01 + s3 * C11 + s5 * C21
        P_out[e, 2] += s0 * C02 + s3 * C12 + s5 * C22
        P_out[e, 3] += s3 * C00 + s1 * C10 + s4 * C20
        P_out[e, 4] += s3 * C01 + s1 * C11 + s4 * C21
        P_out[e, 5] += s3 * C02 + s1 * C12 + s4 * C22
        P_out[e, 6] += s5 * C00 + s4 * C10 + s2 * C20
        P_out[e, 7] += s5 * C01 + s4 * C11 + s2 * C21
        P_out[e, 8] += s5 * C02 + s4 * C12 + s2 * C22
        totals[0] += sy * d * V
        if p[M.THERMAL_ON] > 0.0:
            totals[1] += p[M.BETA] * sy * d * V
        if d > totals[3]:
            totals[3] = d


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def static_flow_stress(mat, params, eps_p, temp, out):
    """σ_y(ε_p, ε̇ = 0, T) of every cell into out (inf for elastic materials)."""
    for e in range(len(mat)):
        out[e] = M.yield_stress(eps_p[e], 0.0, temp[e], params[mat[e]])


def deviatoric_energy(s: np.ndarray, J: np.ndarray, vol0: np.ndarray, G: np.ndarray) -> float:
    """Σ V s:s / (4G) over cells (J): the stored deviatoric elastic energy."""
    ss = s[:, 0] ** 2 + s[:, 1] ** 2 + s[:, 2] ** 2 + 2.0 * (s[:, 3] ** 2 + s[:, 4] ** 2 + s[:, 5] ** 2)
    return float(np.sum(J * vol0 * ss / (4.0 * G)))


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def volumetric_energy(nodal_vol, nodal_vol0, bulk, n_owned):
    """Σ over owned nodes and materials of V0_a K/2 (ln J_a)^2 (J)."""
    total = 0.0
    for n in range(n_owned):
        for m in range(nodal_vol.shape[1]):
            v0 = nodal_vol0[n, m]
            if v0 > 0.0:
                lj = math.log(nodal_vol[n, m] / v0)
                total += v0 * 0.5 * bulk[m] * lj * lj
    return total
