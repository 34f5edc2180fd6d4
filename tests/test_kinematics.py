"""Cell kernels on plain arrays: shape-function gradients, objectivity, patch tests, nodal pressure."""

import numpy as np
import pytest

from fepen import kinematics as K, materials as M


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


def run_motion(X, dofs, positions, dt, s0, material, nodal=True):
    """Drive the stress kernel through a prescribed sequence of node positions."""
    g, v0, orient = K.reference_gradients(X, dofs)
    n = len(dofs)
    mat = np.zeros(n, dtype=np.int64)
    params = material.params[None]
    s = np.tile(s0, (n, 1))
    ep, T = np.zeros(n), np.full(n, 294.0)
    sy0 = np.empty(n)
    K.static_flow_stress(mat, params, ep, T, sy0)
    P = np.zeros((n, 9))
    tot = np.zeros(4)
    nv, nv0, npres = np.zeros((len(X), 1)), np.zeros((len(X), 1)), np.zeros((len(X), 1))
    speed = np.array([6000.0])
    K.volumes_and_step(X, dofs, orient, v0, mat, speed, nv0)
    for a, b in zip(positions[:-1], positions[1:]):
        v = (b - a) / dt
        K.volumes_and_step(b, dofs, orient, v0, mat, speed, nv)
        K.nodal_pressures(nv, nv0, np.array([material.bulk_modulus]), npres)
        K.stress_update(b, v, dt, dofs, g, v0, mat, params, npres, nodal, s, ep, T, sy0, P, tot)
    return s, P, ep


@pytest.mark.parametrize("steps", [7, 200])
def test_rigid_rotation_rotates_the_stress(steps):
    """Acceptance: a 90 degree rigid rotation of a pre-stressed body keeps the rotated stress within 1e-6."""
    X, dofs = tets()
    s0 = np.array([300e6, -100e6, -200e6, 80e6, -50e6, 120e6])  # deviatoric (trace 0)
    axis = [1.0, 2.0, 0.5]
    path = [X @ rot(axis, t).T for t in np.linspace(0, np.pi / 2, steps + 1)]
    s, P, ep = run_motion(X, dofs, path, 1e-7, s0, M.elastic(210e9, 0.3, 7850.0))
    R = rot(axis, np.pi / 2)
    want = R @ voigt_to_mat(s0) @ R.T
    for e in range(len(dofs)):
        assert np.max(np.abs(voigt_to_mat(s[e]) - want)) < 1e-6 * np.abs(want).max()
    # P = J sigma F^-T with F = R, J = 1: P = sigma R
    assert np.allclose(P[0].reshape(3, 3), want @ R, rtol=0, atol=1e-6 * np.abs(want).max())
    assert np.all(ep == 0)


def test_uniform_stretch_patch():
    """A homogeneous uniaxial stretch gives the same stress in every cell: hypoelastic Hencky in the small."""
    X, dofs = tets(1, 10)
    mat = M.elastic(200e9, 0.25, 7800.0)
    eps = 1e-4
    Fs = [np.diag([1 + eps * k / 50, 1, 1]) for k in range(51)]
    s, P, _ = run_motion(X, dofs, [X @ F.T for F in Fs], 1e-7, np.zeros(6), mat)
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
