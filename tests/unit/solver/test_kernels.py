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


def nodal_volumes(x, dofs, orient, v0, mat, speed, out):
    """The nodal volumes Σ V_e / 4 (one material) from volumes_and_step's cell volumes."""
    cvol = np.empty(len(dofs))
    K.volumes_and_step(x, dofs, orient, v0, mat, speed, cvol)
    out[:] = 0.0
    np.add.at(out[:, 0], dofs.ravel(), np.repeat(0.25 * cvol, 4))


def run_motion(X, dofs, positions, dt, s0, material, nodal=True, kernel="numba", full=False):
    """Drive the stress update through a prescribed sequence of node positions.

    kernel: "numba" (fepen.kinematics.stress_update) or "C" (fepen.solver.ckernel trial pass + plastic_pass).
    Returns (s, P, eps_p), or with full=True also (T, plastic work summed over the steps)."""
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
        trial = ckernel.TrialPass(xb, vb, np.ascontiguousarray(X), dofs, mat, 6.0 * v0 * orient,
                                  np.array([material.shear_modulus]), npres, sT, sy0, P)
    for a, b in zip(positions[:-1], positions[1:]):
        xb[:] = b
        vb[:] = (b - a) / dt
        nodal_volumes(xb, dofs, orient, v0, mat, speed, nv)
        K.nodal_pressures(nv, nv0, np.array([material.bulk_modulus]), npres)
        if kernel == "C":
            K.plastic_pass(xb, dt, dofs, g, v0, mat, params, s, ep, T, sy0, P, trial(dt), tot)
        else:
            K.stress_update(xb, vb, dt, dofs, g, v0, mat, params, npres, nodal, s, ep, T, sy0, P, tot)
        work += tot[0]
    return (s, P, ep, T, work) if full else (s, P, ep)


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
