"""Cell kernels on plain arrays: shape-function gradients, objectivity, patch tests, nodal pressure."""

import numpy as np
import pytest

from fepen.laws import materials as M
from fepen.solver import ckernel
from fepen.solver import kernels as K

#: the stress update's two implementations: the numba reference and the C trial pass + numba return
KERNELS = ["numba", pytest.param("C", marks=pytest.mark.skipif(ckernel.library() is None,
                                                                 reason=str(ckernel.why_not())))]


def tets(seed=0, n=20):
    """n well-shaped random tetrahedra sharing nothing (4 n nodes)."""
    rng = np.random.default_rng(seed)
    base = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    X = np.concatenate([base + 0.1 * rng.standard_normal((4, 3)) + 3 * i for i in range(n)])
    dofs = np.arange(4 * n, dtype=np.int64).reshape(n, 4)
    return X, dofs


def rot(axis, angle):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    Kx = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * Kx + (1 - np.cos(angle)) * Kx @ Kx


def voigt_to_mat(s):
    return np.array([[s[0], s[3], s[5]], [s[3], s[1], s[4]], [s[5], s[4], s[2]]])


def test_gradients_reproduce_linear_fields():
    X, dofs = tets()
    g, v0, orient = K.reference_gradients(X, dofs)
    assert np.allclose(g.sum(axis=1), 0.0, atol=1e-12)
    F = np.einsum("eai,eaj->eij", X[dofs], g)
    assert np.allclose(F, np.eye(3), atol=1e-12)
    assert np.all(v0 > 0)


#: a grid so fine that rounding to it changes nothing (the plain sums, for comparisons with the references)
FINE = 2.0 ** -200


@pytest.mark.skipif(ckernel.library() is None, reason=str(ckernel.why_not()))
def test_grid_sums_do_not_depend_on_the_order_of_the_cells():
    """Terms rounded to a power-of-two grid sum exactly: the nodal forces and volumes of the cells in reverse
    order are the same bits, in C and in numba alike, and within half a quantum per term of the plain sums;
    on the finest grid they are the plain sums."""
    rng = np.random.default_rng(11)
    n_nodes, n = 300, 2000
    dofs = np.array([rng.choice(n_nodes, 4, replace=False) for _ in range(n)], dtype=np.int64)
    mat = rng.integers(0, 2, n).astype(np.int64)
    mat[:7] = -1
    Fc = rng.standard_normal((n, 4, 3)) * 10.0 ** rng.integers(-2, 4, (n, 1, 1))
    Fc[mat < 0] = 0.0
    cvol = rng.random(n) * 1e-9
    cvol[mat < 0] = 0.0
    q_f, q_v = 2.0 ** -30, 2.0 ** -80
    nodes = ckernel.NodePasses()
    back = np.arange(n)[::-1].copy()
    out = {}
    for name, order in (("forward", np.arange(n)), ("back", back)):
        d32 = np.ascontiguousarray(dofs[order], dtype=np.int32)
        f_c, v_c = np.zeros((n_nodes, 3)), np.zeros((n_nodes, 2))
        nodes.scatter_forces(d32, np.ascontiguousarray(Fc[order]), q_f, f_c)
        nodes.scatter_volumes(d32, np.ascontiguousarray(mat[order]), np.ascontiguousarray(cvol[order]), q_v, v_c)
        f_n, v_n = np.zeros((n_nodes, 3)), np.zeros((n_nodes, 2))
        K.grid_scatter(dofs[order], mat[order], np.ascontiguousarray(Fc[order]), True, q_f, f_n)
        K.grid_scatter(dofs[order], mat[order], cvol[order].reshape(-1, 1, 1), False, q_v, v_n)
        assert np.array_equal(f_c, f_n) and np.array_equal(v_c, v_n)
        out[name] = (f_c, v_c)
    assert np.array_equal(out["forward"][0], out["back"][0]) and np.array_equal(out["forward"][1], out["back"][1])
    plain = np.zeros((n_nodes, 3))
    np.add.at(plain, dofs.ravel(), Fc.reshape(-1, 3))
    terms = np.bincount(dofs.ravel(), minlength=n_nodes)[:, None]
    assert np.all(np.abs(out["forward"][0] - plain) <= 0.5 * q_f * terms + 1e-15 * np.abs(Fc).max())
    fine = np.zeros((n_nodes, 3))
    nodes.scatter_forces(np.ascontiguousarray(dofs, dtype=np.int32), Fc, FINE, fine)
    ref = np.zeros((n_nodes, 3))
    for e in range(n):
        for a in range(4):
            ref[dofs[e, a]] += Fc[e, a]
    assert np.array_equal(fine, ref)


def nodal_volumes(x, dofs, orient, v0, mat, speed, out, with_step=True, cell_dt=None):
    """The nodal volumes per material Σ V_e / 4 (out (n_nodes, n_materials)) from volumes_and_step's cell
    volumes (a plain scatter); returns volumes_and_step's results."""
    cvol = np.empty(len(dofs))
    kin = K.volumes_and_step(x, dofs, orient, v0, mat, speed, cvol, with_step, cell_dt)
    out[:] = 0.0
    live = mat >= 0
    np.add.at(out, (dofs[live].ravel(), np.repeat(mat[live], 4)), np.repeat(0.25 * cvol[live], 4))
    return kin


def run_motion(X, dofs, positions, dt, s0, material, nodal=True, kernel="numba", full=False):
    """Drive the stress update through a prescribed sequence of node positions.

    kernel: "numba" (kernels.stress_update) or "C" (the fused C cell pass of fepen.solver.ckernel).
    Returns (s, P, eps_p), or with full=True also (T, plastic work summed over the steps); for "C", P is
    recovered from the pass's per-cell nodal forces (fused_P)."""
    g, v0, orient = K.reference_gradients(X, dofs)
    n = len(dofs)
    mat = np.zeros(n, dtype=np.int64)
    params = material.params[None]
    sT = np.ascontiguousarray(np.tile(s0, (n, 1)).T)
    s = sT.T
    ep, T = np.zeros(n), np.full(n, 294.0)
    sy0 = np.empty(n)
    K.static_flow_stress(mat, params, ep, T, sy0)
    P = np.zeros((n, 9))
    tot = np.zeros(4)
    work = 0.0
    nv, nv0, npres = np.zeros((len(X), 1)), np.zeros((len(X), 1)), np.zeros((len(X), 1))
    speed = np.array([6000.0])
    nodal_volumes(X, dofs, orient, v0, mat, speed, nv0)
    xb, vb = np.empty_like(X), np.empty_like(X)
    if kernel == "C":
        Fc = np.zeros((n, 4, 3))
        cells = ckernel.CellPasses(xb, vb, dofs, mat, orient, v0, speed, params,
                                   np.array([material.shear_modulus]), npres, sT, ep, T, sy0, np.zeros(n),
                                   np.full(n, np.inf), Fc, tot)
    for a, b in zip(positions[:-1], positions[1:]):
        xb[:] = b
        vb[:] = (b - a) / dt
        nodal_volumes(xb, dofs, orient, v0, mat, speed, nv)
        K.nodal_pressures(nv, nv0, np.array([material.bulk_modulus]), npres)
        if kernel == "C":
            cells.cells(dt)
        else:
            K.stress_update(xb, vb, dt, dofs, g, v0, mat, params, npres, nodal, s, ep, T, sy0, P, tot)
        work += tot[0]
    if kernel == "C":
        P = fused_P(Fc, g, v0)
    return (s, P, ep, T, work) if full else (s, P, ep)


def fused_P(Fc, grad0, vol0):
    """P of each cell back from its nodal forces F_j = V0 P g_j (j = 1..3, g_j = grad0[:, j], the rows of
    R^-1 with R the reference edge matrix): the columns [F_1 F_2 F_3] = V0 P (R^-1)^T, so P = [F] R^T / V0."""
    R = np.linalg.inv(grad0[:, 1:, :])
    Fm = np.swapaxes(Fc[:, 1:, :], 1, 2) / vol0[:, None, None]
    return (Fm @ np.swapaxes(R, 1, 2)).reshape(-1, 9)


@pytest.mark.parametrize("kernel", KERNELS)
@pytest.mark.parametrize("steps", [7, 200])
def test_rigid_rotation_rotates_the_stress(steps, kernel):
    """Acceptance: a 90 degree rigid rotation of a pre-stressed body keeps the rotated stress within 1e-6."""
    X, dofs = tets()
    s0 = np.array([300e6, -100e6, -200e6, 80e6, -50e6, 120e6])  # deviatoric (trace 0)
    axis = [1.0, 2.0, 0.5]
    path = [X @ rot(axis, t).T for t in np.linspace(0, np.pi / 2, steps + 1)]
    s, P, ep = run_motion(X, dofs, path, 1e-7, s0, M.elastic(210e9, 0.3, 7850.0), kernel=kernel)
    R = rot(axis, np.pi / 2)
    want = R @ voigt_to_mat(s0) @ R.T
    for e in range(len(dofs)):
        assert np.max(np.abs(voigt_to_mat(s[e]) - want)) < 1e-6 * np.abs(want).max()
    # P = J sigma F^-T with F = R, J = 1: P = sigma R
    assert np.allclose(P[0].reshape(3, 3), want @ R, rtol=0, atol=1e-6 * np.abs(want).max())
    assert np.all(ep == 0)


@pytest.mark.parametrize("kernel", KERNELS)
def test_uniform_stretch_patch(kernel):
    """A homogeneous uniaxial stretch gives the same stress in every cell: hypoelastic Hencky in the small."""
    X, dofs = tets(1, 10)
    mat = M.elastic(200e9, 0.25, 7800.0)
    eps = 1e-4
    Fs = [np.diag([1 + eps * k / 50, 1, 1]) for k in range(51)]
    s, P, _ = run_motion(X, dofs, [X @ F.T for F in Fs], 1e-7, np.zeros(6), mat, kernel=kernel)
    G, Kb = mat.shear_modulus, mat.bulk_modulus
    e = np.log(1 + eps)
    assert np.allclose(s[:, 0], 2 * G * 2 * e / 3, rtol=1e-4)
    assert np.allclose(s[:, 1], -2 * G * e / 3, rtol=1e-4)
    J = 1 + eps
    sxx = s[0, 0] + Kb * np.log(J) / J
    assert np.allclose(P[:, 0], J * sxx / (1 + eps), rtol=1e-4)  # P_xx = J sigma_xx / F_xx


def test_nodal_pressure_of_a_uniform_compression_is_exact():
    X, dofs = tets(2, 5)
    mat = M.elastic(200e9, 0.3, 7800.0)
    J = 0.97
    path = [X * (1 + (J ** (1 / 3) - 1) * k / 20) for k in range(21)]
    for nodal in (True, False):
        s, P, _ = run_motion(X, dofs, path, 1e-7, np.zeros(6), mat, nodal=nodal)
        assert np.allclose(s, 0.0, atol=1e-3)  # no deviatoric stress
        p = mat.bulk_modulus * np.log(J) / J
        F = J ** (1 / 3)
        assert np.allclose(P[:, 0], J * p / F, rtol=1e-10)


@pytest.mark.skipif(ckernel.library() is None, reason=str(ckernel.why_not()))
def test_c_trial_pass_matches_the_numba_kernel():
    """The C trial pass + plastic_pass gives the numba kernel's stresses, plastic strains, temperatures and
    plastic work to round-off, through a large random motion (stretch, shear, rotation) in which every
    cell yields repeatedly (Johnson-Cook with rate and heating)."""
    X, dofs = tets(3, 40)
    rng = np.random.default_rng(7)
    mat = M.johnson_cook(200e9, 0.29, 7850.0, 792e6, 510e6, 0.26, 0.014, 1.03, 1793.0, 294.0, 1.0,
                         477.0, 0.9, strain_rate=True, thermal=True)
    path, F = [X], np.eye(3)
    for k in range(120):
        F = (np.eye(3) + 2e-3 * rng.standard_normal((3, 3))) @ F
        path.append(X @ (rot([1.0, -0.3, 0.7], 0.01 * k) @ F).T + 1e-4 * rng.standard_normal(X.shape))
    ref = run_motion(X, dofs, path, 1e-7, np.zeros(6), mat, kernel="numba", full=True)
    got = run_motion(X, dofs, path, 1e-7, np.zeros(6), mat, kernel="C", full=True)
    assert np.all(ref[2] > 0.02)  # every cell yielded
    for a, b in zip(ref[:4], got[:4]):
        assert np.max(np.abs(a - b)) <= 1e-11 * np.max(np.abs(a))
    assert abs(ref[4] - got[4]) <= 1e-11 * abs(ref[4])


@pytest.mark.skipif(ckernel.library() is None, reason=str(ckernel.why_not()))
@pytest.mark.parametrize("seed", [0, 1])
def test_fused_pass_matches_the_numba_kernels_on_mixed_cells(seed):
    """One step of random deformation of pre-stressed cells of two materials (Johnson-Cook, bilinear), some
    yielding and some not, some eroded (material -1): the C kinematics and fused cell pass give the numba
    kernels' volumes, smallest J, h/c, stresses, plastic strains, temperatures, flow stresses, plastic work,
    heat and nodal forces (kernels.internal_force of their P) to round-off."""
    X, dofs = tets(10 + seed, 60)
    rng = np.random.default_rng(seed)
    n = len(dofs)
    g, v0, orient = K.reference_gradients(X, dofs)
    jc = M.johnson_cook(200e9, 0.29, 7850.0, 792e6, 510e6, 0.26, 0.014, 1.03, 1793.0, 294.0, 1.0, 477.0, 0.9)
    bl = M.bilinear(70e9, 0.33, 2700.0, 300e6, 1e9)
    mats = [jc, bl]
    params = np.stack([m.params for m in mats])
    G_m = np.array([m.shear_modulus for m in mats])
    bulk = np.array([m.bulk_modulus for m in mats])
    speed = np.array([5900.0, 6300.0])
    mat = rng.integers(0, 2, n).astype(np.int64)
    mat[rng.choice(n, 6, replace=False)] = -1
    live = mat >= 0
    dt = 1e-7
    x = X @ (np.eye(3) + 4e-3 * rng.standard_normal((3, 3))).T + 2e-3 * rng.standard_normal(X.shape)
    v = 50.0 * rng.standard_normal(X.shape)
    s0 = rng.standard_normal((n, 6)) * 250e6
    s0[:, :3] -= s0[:, :3].mean(axis=1, keepdims=True)
    s0[~live] = 0.0
    ep0 = np.where(rng.random(n) < 0.5, 0.0, 0.05 * rng.random(n))
    T0 = 294.0 + 200.0 * rng.random(n)

    def state():
        sT = np.ascontiguousarray(s0.T.copy())
        ep, T = ep0.copy(), T0.copy()
        sy0 = np.empty(n)
        K.static_flow_stress(mat, params, ep, T, sy0)
        return sT, ep, T, sy0

    nv0, nv, npres = np.zeros((len(X), 2)), np.zeros((len(X), 2)), np.zeros((len(X), 2))
    nodal_volumes(X, dofs, orient, v0, mat, speed, nv0)
    cdt_ref = np.full(n, np.inf)
    kin_ref = nodal_volumes(x, dofs, orient, v0, mat, speed, nv, True, cdt_ref)
    K.nodal_pressures(nv, nv0, bulk, npres)
    # the numba reference
    sT, ep, T, sy0 = state()
    P = np.zeros((n, 9))
    tot_ref = np.zeros(4)
    K.stress_update(x, v, dt, dofs, g, v0, mat, params, npres, True, sT.T, ep, T, sy0, P, tot_ref)
    f_ref = np.zeros_like(X)
    K.internal_force(P, dofs, g, v0, f_ref)
    ref = (sT, ep, T, sy0)
    # the C passes
    sT, ep, T, sy0 = state()
    cvol, cdt, Fc, tot = np.zeros(n), np.full(n, np.inf), np.zeros((n, 4, 3)), np.zeros(4)
    cells = ckernel.CellPasses(x, v, dofs, mat, orient, v0, speed, params, G_m, npres, sT, ep, T, sy0, cvol,
                               cdt, Fc, tot)
    kin = cells.kinematics(True)
    nodes = ckernel.NodePasses()
    nv_c, np_c = np.zeros_like(nv), np.zeros_like(npres)
    nodes.scatter_volumes(cells.dofs32, mat, cvol, FINE, nv_c)
    nodes.nodal_pressure(nv_c, nv0, bulk, np_c)
    assert np.allclose(nv_c, nv, rtol=1e-13, atol=0) and np.allclose(np_c, npres, rtol=1e-11, atol=1e-3)
    assert kin[1] == kin_ref[1] and kin[3] == kin_ref[3]
    assert kin[0] == pytest.approx(kin_ref[0], rel=1e-13) and kin[2] == pytest.approx(kin_ref[2], rel=1e-13)
    assert np.allclose(cdt, cdt_ref, rtol=1e-13) and np.all(cvol[~live] == 0.0)
    yielded = cells.cells(dt)
    assert 5 < yielded < live.sum() - 5  # both kinds of cells
    got = (sT, ep, T, sy0)
    for a, b in zip(ref, got):
        assert np.all(np.isfinite(a) == np.isfinite(b))
        ok = np.isfinite(a)
        assert np.max(np.abs(a[ok] - b[ok])) <= 1e-11 * np.max(np.abs(a[ok]))
    assert np.allclose(tot, tot_ref, rtol=1e-11, atol=0)
    assert np.all(Fc[~live] == 0.0) and np.all(sT[:, ~live] == 0.0)
    f = np.zeros_like(X)
    nodes.scatter_forces(cells.dofs32, Fc, FINE, f)
    assert np.max(np.abs(f - f_ref)) <= 1e-11 * np.max(np.abs(f_ref))
    assert np.allclose(Fc.sum(axis=1), 0.0, atol=1e-12 * np.abs(Fc).max())  # each cell's forces balance
    # the step's own passes sum the nodal volumes and forces in their blocks, without Fc: the same bits as the
    # passes apart (stale values in the outputs are overwritten)
    sT, ep, T, sy0 = state()
    nv_f, f_f = np.full_like(nv, np.nan), np.full_like(X, np.nan)
    fused = ckernel.CellPasses(x, v, dofs, mat, orient, v0, speed, params, G_m, npres, sT, ep, T, sy0, np.zeros(n),
                               np.full(n, np.inf), None, np.zeros(4), nvol=nv_f, fint=f_f)
    assert fused.kinematics(True, FINE) == kin
    assert np.array_equal(nv_f, nv_c)
    assert fused.cells(dt, FINE) == yielded
    assert np.array_equal(f_f, f)
    assert all(np.array_equal(a, b) for a, b in zip(got, (sT, ep, T, sy0)))


@pytest.mark.skipif(ckernel.library() is None, reason=str(ckernel.why_not()))
def test_c_kinematics_reports_inverted_and_nan_cells():
    """The kinematics passes (C and numba) find an inverted cell's negative J, and a NaN position's NaN J
    (no fast-math), even when later cells are sound."""
    X, dofs = tets(4, 8)
    g, v0, orient = K.reference_gradients(X, dofs)
    n = len(dofs)
    mat = np.zeros(n, dtype=np.int64)
    args = (np.zeros((6, n)), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n),
            np.zeros((n, 4, 3)), np.zeros(4))
    for bad, check in ((-1.0, lambda J: J < 0.0), (np.nan, np.isnan)):
        x = X.copy()
        p = dofs[3]
        x[p[0]] = x[p[1:]].mean(axis=0) + bad * (X[p[0]] - X[p[1:]].mean(axis=0))  # mirrored, or NaN
        cells = ckernel.CellPasses(x, np.zeros_like(x), dofs, mat, orient, v0, np.array([6000.0]),
                                   M.elastic(2e11, 0.3, 7800.0).params[None], np.array([8e10]),
                                   np.zeros((len(X), 1)), *args)
        J, worst, _, _ = cells.kinematics(False)
        assert check(J) and worst == 3
        J, worst, _, _ = K.volumes_and_step(x, dofs, orient, v0, mat, np.array([6000.0]), np.zeros(n))
        assert check(J) and worst == 3


@pytest.mark.skipif(ckernel.library() is None, reason=str(ckernel.why_not()))
def test_c_update_passes_are_central_differences():
    """update_begin / update_end: v += h a, du = dt v, u += du, x = X + u; a = (f_ext - f_int) / m with fixed
    components held at 0; each owned node's two halves of the trapezoidal work."""
    rng = np.random.default_rng(3)
    nn, own = 50, 40
    a, v, u, X = (rng.standard_normal((nn, 3)) for _ in range(4))
    fi, fe = rng.standard_normal((nn, 3)), rng.standard_normal((nn, 3))
    m = 1.0 + rng.random(nn)
    x, du = np.empty((nn, 3)), np.empty((nn, 3))
    v_ref = v + 0.7 * a
    u_ref = u + 0.3 * v_ref
    nodes = ckernel.NodePasses()
    work = np.zeros((nn, 2))
    nodes.update_begin(0.7, 0.3, own, a, v, u, X, x, du, fi, fe, work)
    assert np.allclose(v, v_ref, rtol=1e-15) and np.allclose(u, u_ref, rtol=1e-15) and np.allclose(x, X + u)
    half = 0.5 * np.stack([np.sum(du * fi, axis=1), np.sum(du * fe, axis=1)], axis=1)
    assert np.allclose(work[:own], half[:own], rtol=1e-13, atol=0) and np.all(work[own:] == 0.0)
    fixed = rng.random((nn, 3)) < 0.2
    acc = np.zeros((nn, 3))
    nodes.update_end(own, fi, fe, m, fixed, du, acc, work)
    want = np.where(fixed, 0.0, (fe - fi) / m[:, None])
    assert np.allclose(acc[:own], want[:own], rtol=1e-15) and np.all(acc[own:] == 0.0)
    assert np.allclose(work[:own], 2.0 * half[:own], rtol=1e-13, atol=0)  # the same forces: twice the half


@pytest.mark.skipif(ckernel.library() is None, reason=str(ckernel.why_not()))
def test_c_facet_kinematics_is_the_numba_loop_to_the_bit():
    """Surface.kinematics's C loop (vectorised across facets) and its numba reference give the same bits on
    deformed facets, a collapsed one (zero area: NaN normal) and one turned over (1 + a.b below 1e-12)."""
    from fepen.solver.surface import _facet_kinematics

    rng = np.random.default_rng(11)
    nn, nf = 400, 900
    X = rng.standard_normal((nn, 3))
    tri = rng.integers(0, nn, (nf, 3)).astype(np.int64)
    tri[5] = [7, 7, 8]  # collapsed
    av = 0.5 * np.cross(X[tri[:, 1]] - X[tri[:, 0]], X[tri[:, 2]] - X[tri[:, 0]])
    flat0 = np.linalg.norm(av, axis=1)
    n_flat0 = av / np.maximum(flat0, 1e-300)[:, None]
    N0 = n_flat0 + 0.05 * rng.standard_normal((nf, 3))
    N0 /= np.linalg.norm(N0, axis=1)[:, None]
    area0 = flat0 * (1.0 + 0.01 * rng.random(nf))
    x = X + 0.02 * rng.standard_normal((nn, 3))
    x[tri[9]] = X[tri[9][[0, 2, 1]]]  # turned over: its normal reversed
    v = 300.0 * rng.standard_normal((nn, 3))
    out_c = [np.empty((nf, 3)), np.empty((nf, 3)), np.empty(nf), np.empty((nf, 3))]
    out_n = [np.empty_like(a) for a in out_c]
    ckernel.library().facet_kinematics(nf, *[a.ctypes.data for a in (x, v, tri, n_flat0, N0, area0, flat0)],
                                       *[a.ctypes.data for a in out_c])
    _facet_kinematics(x, v, tri, n_flat0, N0, area0, flat0, *out_n)
    assert np.isnan(out_n[3][5]).all()
    for a, b in zip(out_c, out_n):
        assert np.array_equal(a, b, equal_nan=True)
