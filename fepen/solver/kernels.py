"""Cell kernels of the explicit solver on plain arrays (numba): kinematics, nodal volumes and the stress update
of the averaged-nodal-pressure tetrahedron (Hughes–Winget rotation, radial return, P = J σ F^{-T}).
Theory: docs/theory.md §3–§4.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from fepen.laws import materials as M

#: fast-math flags that keep IEEE NaN/inf semantics (inverted or NaN elements must still be detected)
_FAST = {"nsz", "arcp", "contract", "afn", "reassoc"}

# The small helpers below are plain numba functions, called, not inlined at numba's IR level (inline="always"):
# IR inlining made stress_update take 38 s and plastic_pass 7.5 s to compile on a machine's first run (fresh
# clone, empty numba cache), against 5.2 s and 2.7 s now; LLVM still inlines what pays. The runs give the same
# bits (history.csv of a worn, eroding C7 and of the soft hard case: the same SHA-256); the numba reference
# stress_update runs 7-15 % slower per cell (the fused C pass, the default, does not use it).


def reference_gradients(X: np.ndarray, dofs: np.ndarray):
    """Shape-function gradients, volumes and orientation signs of the reference cells.

    Args:
        X: reference node coordinates (n_nodes, 3).
        dofs: cell node indices (n_cells, 4).

    Returns:
        (grad0 (n_cells, 4, 3), vol0 (n_cells,) > 0 whatever the node ordering, orient (n_cells,) ±1).
    """
    grad0 = np.empty((len(dofs), 4, 3))
    vol0 = np.empty(len(dofs))
    orient = np.empty(len(dofs))
    _reference_gradients(np.ascontiguousarray(X), np.ascontiguousarray(dofs, dtype=np.int64), grad0, vol0, orient)
    return grad0, vol0, orient


@numba.njit(cache=True, error_model="numpy")
def _reference_gradients(X, dofs, grad0, vol0, orient):
    """reference_gradients in one pass: with the edges a, b, c from node 0 as the columns of J, the rows of
    J^{-1} (the gradients of phi_1..3) are (b×c, c×a, a×b) / det J, det J = a·(b×c)."""
    for e in range(dofs.shape[0]):
        p0 = dofs[e, 0]
        a = np.empty(3)
        b = np.empty(3)
        c = np.empty(3)
        for k in range(3):
            a[k] = X[dofs[e, 1], k] - X[p0, k]
            b[k] = X[dofs[e, 2], k] - X[p0, k]
            c[k] = X[dofs[e, 3], k] - X[p0, k]
        bc = np.array([b[1] * c[2] - b[2] * c[1], b[2] * c[0] - b[0] * c[2], b[0] * c[1] - b[1] * c[0]])
        ca = np.array([c[1] * a[2] - c[2] * a[1], c[2] * a[0] - c[0] * a[2], c[0] * a[1] - c[1] * a[0]])
        ab = np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])
        det = a[0] * bc[0] + a[1] * bc[1] + a[2] * bc[2]
        for k in range(3):
            grad0[e, 1, k] = bc[k] / det
            grad0[e, 2, k] = ca[k] / det
            grad0[e, 3, k] = ab[k] / det
            grad0[e, 0, k] = -(grad0[e, 1, k] + grad0[e, 2, k] + grad0[e, 3, k])
        vol0[e] = abs(det) / 6.0
        orient[e] = 1.0 if det > 0.0 else (-1.0 if det < 0.0 else 0.0)


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def _six_volume(x, dofs, e):
    """det(x1 - x0, x2 - x0, x3 - x0) of cell e: six times its signed volume."""
    n0, n1, n2, n3 = dofs[e, 0], dofs[e, 1], dofs[e, 2], dofs[e, 3]
    ax, ay, az = x[n1, 0] - x[n0, 0], x[n1, 1] - x[n0, 1], x[n1, 2] - x[n0, 2]
    bx, by, bz = x[n2, 0] - x[n0, 0], x[n2, 1] - x[n0, 1], x[n2, 2] - x[n0, 2]
    cx, cy, cz = x[n3, 0] - x[n0, 0], x[n3, 1] - x[n0, 1], x[n3, 2] - x[n0, 2]
    return ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def volumes_and_step(x, dofs, orient, vol0, mat, speed, cvol, with_step=True, cell_dt=None):
    """Current cell volumes; the smallest J; the stable step of the current mesh.
    Eroded cells (material −1) are skipped: no volume, no J, no step.

    Args:
        x: current positions (n_nodes, 3).
        dofs, vol0, mat: see stress_update. orient: +1 or −1 per cell, the sign of the reference
            det(X1 − X0, X2 − X0, X3 − X0) (so that J > 0 for an uninverted cell whatever the node order).
        speed: dilatational wave speed per material (m/s).
        cvol: (n_cells,) output, each cell's current volume (0 for eroded cells); the nodal volumes are their
            sums (fepen.solver.assembly.NodalSum, in a partition-independent order).
        with_step: also compute the shortest altitudes (else the third result is inf).
        cell_dt: None, or (n_cells,) output of each live cell's altitude / wave speed (with_step only).

    Returns:
        (min J, cell of min J, min over cells of shortest altitude / wave speed, cell of that minimum).
    """
    jmin = np.inf
    worst = -1
    dtmin = np.inf
    dtcell = -1
    for e in range(dofs.shape[0]):
        m = mat[e]
        if m < 0:
            cvol[e] = 0.0
            continue
        # J = det(x1 - x0, x2 - x0, x3 - x0) / (6 V0): needs the positions only, not the gradients
        J = _six_volume(x, dofs, e) / (6.0 * vol0[e]) * orient[e]
        if not (J >= jmin) and jmin == jmin:  # smaller, or the first NaN (kept: a later cell must not hide it)
            jmin = J
            worst = e
        V = J * vol0[e]
        cvol[e] = V
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
            if cell_dt is not None:
                cell_dt[e] = t
            if t < dtmin:
                dtmin = t
                dtcell = e
    return jmin, worst, dtmin, dtcell


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def cell_jacobians(x, dofs, orient, vol0, mat, out):
    """J = V / V0 of every cell into out (for the energies; the same formula as volumes_and_step); 1 for
    eroded cells (material −1)."""
    for e in range(dofs.shape[0]):
        out[e] = _six_volume(x, dofs, e) / (6.0 * vol0[e]) * orient[e] if mat[e] >= 0 else 1.0


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def _cofactor(A):
    """Cofactor matrix (det A · A^-T) and determinant of a 3x3 matrix A given as a 9-tuple, row-major.

    Returns:
        (cofactor as a 9-tuple, row-major; det A).
    """
    a00, a01, a02, a10, a11, a12, a20, a21, a22 = A
    c00, c01, c02 = a11 * a22 - a12 * a21, a12 * a20 - a10 * a22, a10 * a21 - a11 * a20
    C = (c00, c01, c02,
         a02 * a21 - a01 * a22, a00 * a22 - a02 * a20, a01 * a20 - a00 * a21,
         a01 * a12 - a02 * a11, a02 * a10 - a00 * a12, a00 * a11 - a01 * a10)
    return C, a00 * c00 + a01 * c01 + a02 * c02


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
def _moduli(p):
    """(G, K): shear and bulk moduli of the material parameter vector p."""
    return p[M.E_] / (2.0 * (1.0 + p[M.NU])), p[M.E_] / (3.0 * (1.0 - 2.0 * p[M.NU]))


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def _gradient(y, f, dofs, grad0, e):
    """Σ_a (f y_a) ⊗ grad0_a over the nodes of cell e, a 9-tuple, row-major: F for (x, 1), ΔF for (v, dt)."""
    G00 = G01 = G02 = G10 = G11 = G12 = G20 = G21 = G22 = 0.0
    for a in range(4):
        nd = dofs[e, a]
        g0, g1, g2 = grad0[e, a, 0], grad0[e, a, 1], grad0[e, a, 2]
        y0, y1, y2 = y[nd, 0] * f, y[nd, 1] * f, y[nd, 2] * f
        G00 += y0 * g0
        G01 += y0 * g1
        G02 += y0 * g2
        G10 += y1 * g0
        G11 += y1 * g1
        G12 += y1 * g2
        G20 += y2 * g0
        G21 += y2 * g1
        G22 += y2 * g2
    return G00, G01, G02, G10, G11, G12, G20, G21, G22


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def _velocity_gradient(F, D):
    """ΔL = ΔF F_m^-1 at the mid-step configuration F_m = F − ΔF/2 (through the cofactor of F_m), a 9-tuple.

    Args:
        F: end-of-step deformation gradient; D: its increment over the step ΔF (9-tuples, row-major).
    """
    D00, D01, D02, D10, D11, D12, D20, D21, D22 = D
    c, det = _cofactor((F[0] - 0.5 * D00, F[1] - 0.5 * D01, F[2] - 0.5 * D02,
                        F[3] - 0.5 * D10, F[4] - 0.5 * D11, F[5] - 0.5 * D12,
                        F[6] - 0.5 * D20, F[7] - 0.5 * D21, F[8] - 0.5 * D22))
    c00, c01, c02, c10, c11, c12, c20, c21, c22 = c
    idet = 1.0 / det
    return ((D00 * c00 + D01 * c01 + D02 * c02) * idet, (D00 * c10 + D01 * c11 + D02 * c12) * idet,
            (D00 * c20 + D01 * c21 + D02 * c22) * idet, (D10 * c00 + D11 * c01 + D12 * c02) * idet,
            (D10 * c10 + D11 * c11 + D12 * c12) * idet, (D10 * c20 + D11 * c21 + D12 * c22) * idet,
            (D20 * c00 + D21 * c01 + D22 * c02) * idet, (D20 * c10 + D21 * c11 + D22 * c12) * idet,
            (D20 * c20 + D21 * c21 + D22 * c22) * idet)


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def _hughes_winget(L, s, e):
    """Q s_e Q^T, the deviatoric stress of cell e (Voigt 6-tuple) rotated by Q = (I − W/2)^-1 (I + W/2),
    W = skew(L), in closed form (Cayley): with w the axial vector of W/2, Q = I + 2 (W/2 + (W/2)^2) / (1 + |w|^2).
    """
    w0, w1, w2 = 0.25 * (L[7] - L[5]), 0.25 * (L[2] - L[6]), 0.25 * (L[3] - L[1])
    c = 2.0 / (1.0 + w0 * w0 + w1 * w1 + w2 * w2)
    Q00 = 1.0 - c * (w1 * w1 + w2 * w2)
    Q11 = 1.0 - c * (w0 * w0 + w2 * w2)
    Q22 = 1.0 - c * (w0 * w0 + w1 * w1)
    Q01, Q10 = c * (-w2 + w0 * w1), c * (w2 + w0 * w1)
    Q02, Q20 = c * (w1 + w0 * w2), c * (-w1 + w0 * w2)
    Q12, Q21 = c * (-w0 + w1 * w2), c * (w0 + w1 * w2)
    S00, S11, S22, S01, S12, S02 = s[e, 0], s[e, 1], s[e, 2], s[e, 3], s[e, 4], s[e, 5]
    T00 = Q00 * S00 + Q01 * S01 + Q02 * S02
    T01 = Q00 * S01 + Q01 * S11 + Q02 * S12
    T02 = Q00 * S02 + Q01 * S12 + Q02 * S22
    T10 = Q10 * S00 + Q11 * S01 + Q12 * S02
    T11 = Q10 * S01 + Q11 * S11 + Q12 * S12
    T12 = Q10 * S02 + Q11 * S12 + Q12 * S22
    T20 = Q20 * S00 + Q21 * S01 + Q22 * S02
    T21 = Q20 * S01 + Q21 * S11 + Q22 * S12
    T22 = Q20 * S02 + Q21 * S12 + Q22 * S22
    return (T00 * Q00 + T01 * Q01 + T02 * Q02, T10 * Q10 + T11 * Q11 + T12 * Q12,
            T20 * Q20 + T21 * Q21 + T22 * Q22, T00 * Q10 + T01 * Q11 + T02 * Q12,
            T10 * Q20 + T11 * Q21 + T12 * Q22, T00 * Q20 + T01 * Q21 + T02 * Q22)


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def _trial_stress(L, s, e, G, se, de):
    """Elastic trial deviatoric stress of cell e into se (6,): the rotated s_e + 2 G dev(sym L).

    de (6,) is scratch: forming the sum through the two arrays fixes how fastmath may associate it (the
    floating-point results are kept bit for bit).
    """
    se[0], se[1], se[2], se[3], se[4], se[5] = _hughes_winget(L, s, e)
    L00, L01, L02, L10, L11, L12, L20, L21, L22 = L
    tr = (L00 + L11 + L22) / 3.0
    de[0], de[1], de[2] = L00 - tr, L11 - tr, L22 - tr
    de[3], de[4], de[5] = 0.5 * (L01 + L10), 0.5 * (L12 + L21), 0.5 * (L02 + L20)
    for i in range(6):
        se[i] += 2.0 * G * de[i]


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def _mises(S):
    """von Mises stress √(3/2 s:s) of a deviatoric stress S, a 6-tuple in Voigt order."""
    s0, s1, s2, s3, s4, s5 = S
    return math.sqrt(1.5 * (s0 * s0 + s1 * s1 + s2 * s2 + 2.0 * (s3 * s3 + s4 * s4 + s5 * s5)))


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def _piola(P_out, e, add, s00, s11, s22, s01, s12, s02, C):
    """P_ij = Σ_k σ_ik C_kj of the symmetric σ (given by its six entries) and the 9-tuple C, row-major, into
    row e of P_out: written, or added to it if add."""
    C00, C01, C02, C10, C11, C12, C20, C21, C22 = C
    P = (s00 * C00 + s01 * C10 + s02 * C20, s00 * C01 + s01 * C11 + s02 * C21, s00 * C02 + s01 * C12 + s02 * C22,
         s01 * C00 + s11 * C10 + s12 * C20, s01 * C01 + s11 * C11 + s12 * C21, s01 * C02 + s11 * C12 + s12 * C22,
         s02 * C00 + s12 * C10 + s22 * C20, s02 * C01 + s12 * C11 + s22 * C21, s02 * C02 + s12 * C12 + s22 * C22)
    for i in range(9):
        if add:
            P_out[e, i] += P[i]
        else:
            P_out[e, i] = P[i]


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def _yielded(e, d, sy, T_new, scale, p, V, eps_p, temp, sy0, totals, se):
    """Bookkeeping of the radial return of a cell e that yields: its deviatoric stress se (6,) scaled from the
    trial state to the flow stress, its eps_p, temp and static flow stress sy0 updated, its plastic work, heat
    and increment added to totals (see stress_update).

    Args:
        d, sy, T_new: plastic increment (> 0), flow stress and temperature from fepen.laws.materials.radial_return.
        scale: σ_y / q_trial. p: material parameter vector. V: current cell volume.
        se: the cell's trial deviatoric stress (6,), scaled in place.
        others: see stress_update.
    """
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


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def stress_update(x, v, dt, dofs, grad0, vol0, mat, params, nodal_p, nodal, s, eps_p, temp, sy0, P_out,
                  totals):
    """Advance every cell's stress over one step and write P = J σ F^{-T} (row-major) into P_out.

    Written with scalars rather than 3x3 temporaries (twice as fast under numba).

    Args:
        x: positions at the end of the step (n_nodes, 3); v: velocities over the step (n_nodes, 3).
        dt: the step (s).
        dofs: cell node indices (n_cells, 4); grad0: reference shape-function gradients (n_cells, 4, 3);
            vol0: reference volumes (n_cells,); mat: material index of each cell into params (n_cells,).
        params: material parameters (n_materials, N_PARAMS).
        nodal_p: nodal mean stress per material (n_nodes, n_materials), from nodal_pressures.
        nodal: True for the averaged nodal pressure, False for the plain element (own J).
        s, eps_p, temp: deviatoric Cauchy stress (n, 6) as (xx, yy, zz, xy, yz, xz), plastic strain (n,),
            temperature (n,); updated in place.
        sy0: static flow stress σ_y(ε_p, T) of each cell (n,) (inf for elastic cells); updated in place.
        P_out: (n_cells_packed, 9) output, first n_cells rows written.
        totals: (4,) output: plastic work, heat, (unused), largest plastic increment.
    """
    nmat = params.shape[0]
    G_m = np.empty(nmat)
    K_m = np.empty(nmat)
    for m in range(nmat):
        G_m[m], K_m[m] = _moduli(params[m])
    se = np.empty(6)  # the cell's trial, then final, deviatoric stress
    de = np.empty(6)  # scratch of _trial_stress
    totals[:] = 0.0
    for e in range(dofs.shape[0]):
        m = mat[e]
        if m < 0:  # eroded: its P row was zeroed when it was removed
            continue
        G = G_m[m]
        F = _gradient(x, 1.0, dofs, grad0, e)
        _trial_stress(_velocity_gradient(F, _gradient(v, dt, dofs, grad0, e)), s, e, G, se, de)
        C, J = _cofactor(F)  # C = J F^-T of the end-of-step F, so that P = J σ F^-T = σ C
        if params[m, M.KIND] != M.ELASTIC:
            # yield check against the cell's current static flow stress (kept in sy0, refreshed only
            # when the cell yields): elastic cells pay no flow-stress evaluation
            q = _mises((se[0], se[1], se[2], se[3], se[4], se[5]))
            if q > sy0[e]:
                p = params[m]
                d, sy, T_new = M.radial_return(q, eps_p[e], temp[e], dt, G, p)
                if d > 0.0:
                    _yielded(e, d, sy, T_new, sy / q, p, J * vol0[e], eps_p, temp, sy0, totals, se)
        s0, s1, s2, s3, s4, s5 = se[0], se[1], se[2], se[3], se[4], se[5]
        s[e, 0], s[e, 1], s[e, 2], s[e, 3], s[e, 4], s[e, 5] = s0, s1, s2, s3, s4, s5
        if nodal:
            pm = 0.25 * (nodal_p[dofs[e, 0], m] + nodal_p[dofs[e, 1], m] + nodal_p[dofs[e, 2], m]
                         + nodal_p[dofs[e, 3], m])
        else:
            pm = K_m[m] * math.log(J) / J
        _piola(P_out, e, False, s0 + pm, s1 + pm, s2 + pm, s3, s4, s5, C)


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def plastic_pass(x, dt, dofs, grad0, vol0, mat, params, s, eps_p, temp, sy0, P_out, cells, totals):
    """Radial return of the cells whose elastic trial state (from the C trial pass, fepen.solver.ckernel) exceeds
    their static flow stress: their s, eps_p, temp, sy0 and P corrected in place, as stress_update does in
    its own loop.

    Args:
        cells: indices of the cells over their flow stress (from the trial pass).
        totals: (4,) output: plastic work, heat, (unused), largest plastic increment.
        others: see stress_update.
    """
    totals[:] = 0.0
    for e in cells:
        p = params[mat[e]]
        s0, s1, s2, s3, s4, s5 = s[e, 0], s[e, 1], s[e, 2], s[e, 3], s[e, 4], s[e, 5]
        q = _mises((s0, s1, s2, s3, s4, s5))
        d, sy, T_new = M.radial_return(q, eps_p[e], temp[e], dt, _moduli(p)[0], p)
        if d > 0.0:
            C, J = _cofactor(_gradient(x, 1.0, dofs, grad0, e))
            scale = sy / q
            _yielded(e, d, sy, T_new, scale, p, J * vol0[e], eps_p, temp, sy0, totals, s[e])
            f = scale - 1.0  # P = (s + p I) C changes by (scale - 1) s C
            _piola(P_out, e, True, s0 * f, s1 * f, s2 * f, s3 * f, s4 * f, s5 * f, C)


@numba.njit(cache=True, error_model="numpy")
def internal_force(P, dofs, grad0, vol0, f):
    """The internal nodal forces f_a = Σ_e V0_e P_e grad0_{e,a} (the form ∫ P : ∇_X w dX of one-point P1
    cells), added into f (n_nodes, 3) over the cells of dofs (rows of P beyond them are not read)."""
    for e in range(dofs.shape[0]):
        v = vol0[e]
        P00, P01, P02 = v * P[e, 0], v * P[e, 1], v * P[e, 2]
        P10, P11, P12 = v * P[e, 3], v * P[e, 4], v * P[e, 5]
        P20, P21, P22 = v * P[e, 6], v * P[e, 7], v * P[e, 8]
        for a in range(4):
            nd = dofs[e, a]
            g0, g1, g2 = grad0[e, a, 0], grad0[e, a, 1], grad0[e, a, 2]
            f[nd, 0] += P00 * g0 + P01 * g1 + P02 * g2
            f[nd, 1] += P10 * g0 + P11 * g1 + P12 * g2
            f[nd, 2] += P20 * g0 + P21 * g1 + P22 * g2


@numba.njit(cache=True, error_model="numpy")
def internal_force_cells(P, dofs, grad0, vol0, Fc):
    """Each cell's internal forces on its four nodes, V0_e P_e grad0_{e,a}, into Fc (n_cells, 4, 3) (the
    terms internal_force adds; their nodal sums are taken in a partition-independent order by
    fepen.solver.assembly.NodalSum)."""
    for e in range(dofs.shape[0]):
        v = vol0[e]
        P00, P01, P02 = v * P[e, 0], v * P[e, 1], v * P[e, 2]
        P10, P11, P12 = v * P[e, 3], v * P[e, 4], v * P[e, 5]
        P20, P21, P22 = v * P[e, 6], v * P[e, 7], v * P[e, 8]
        for a in range(4):
            g0, g1, g2 = grad0[e, a, 0], grad0[e, a, 1], grad0[e, a, 2]
            Fc[e, a, 0] = P00 * g0 + P01 * g1 + P02 * g2
            Fc[e, a, 1] = P10 * g0 + P11 * g1 + P12 * g2
            Fc[e, a, 2] = P20 * g0 + P21 * g1 + P22 * g2


@numba.njit(cache=True, error_model="numpy")
def grid_scatter(dofs, mat, values, per_node, quantum, out):
    """out = 0, then each live cell's value at each of its nodes added, rounded to a multiple of quantum (a
    power of two), so that the sums are exact (while below 2^53 quantum): the same in any order and on any
    partition (docs/theory.md §3.4). values (n_cells, 4, bs) per node if per_node (into out (n, bs)), else
    (n_cells,) per cell, into its material's column of out (n, n_materials). The arithmetic of the C
    kernel's scatter_forces and scatter_volumes."""
    out[:] = 0.0
    iq = 1.0 / quantum
    for e in range(dofs.shape[0]):
        m = mat[e]
        if m < 0:
            continue
        if per_node:
            for a in range(4):
                nd = dofs[e, a]
                for k in range(values.shape[2]):
                    out[nd, k] += np.rint(values[e, a, k] * iq) * quantum
        else:
            c = np.rint(0.25 * values[e, 0, 0] * iq) * quantum
            for a in range(4):
                out[dofs[e, a], m] += c


@numba.njit(cache=True, error_model="numpy")
def work_halves(du, f, g, n, work):
    """Half of each owned node's work over a step, du·f / 2 and du·g / 2 for the internal forces f and the
    external forces g, added into work (n_nodes, 2): called with the old forces and again with the new ones
    (the trapezoidal rule; the arithmetic of the C node passes), each node's running sum the same on any
    partition (their sum: diagnostics.work_sums)."""
    for a in range(n):
        work[a, 0] += 0.5 * (du[a, 0] * f[a, 0] + du[a, 1] * f[a, 1] + du[a, 2] * f[a, 2])
        work[a, 1] += 0.5 * (du[a, 0] * g[a, 0] + du[a, 1] * g[a, 1] + du[a, 2] * g[a, 2])


@numba.njit(cache=True, fastmath=_FAST, error_model="numpy")
def static_flow_stress(mat, params, eps_p, temp, out):
    """σ_y(ε_p, ε̇ = 0, T) of every cell into out (inf for elastic materials and eroded cells)."""
    for e in range(len(mat)):
        out[e] = M.yield_stress(eps_p[e], 0.0, temp[e], params[mat[e]]) if mat[e] >= 0 else np.inf


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
