"""The scalar parts of the stress update (fepen.solver.kernels): kinematics, rotation, Piola stress, return."""

import numpy as np
import pytest
from test_kernels import rot, voigt_to_mat

from fepen.laws import materials as M
from fepen.solver import kernels as K


def one_tet(seed=0):
    rng = np.random.default_rng(seed)
    X = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float) + 0.1 * rng.standard_normal((4, 3))
    dofs = np.arange(4, dtype=np.int64)[None]
    grad0, vol0, _ = K.reference_gradients(X, dofs)
    return X, dofs, grad0, vol0


def tup(A):
    return tuple(float(a) for a in np.ravel(A))


S0 = np.array([300e6, -100e6, -200e6, 80e6, -50e6, 120e6])  # deviatoric (trace 0)


def test_cofactor_is_det_times_inverse_transpose():
    A = np.random.default_rng(1).standard_normal((3, 3)) + 2 * np.eye(3)
    C, det = K._cofactor(tup(A))
    assert det == pytest.approx(np.linalg.det(A), rel=1e-14)
    assert np.allclose(np.reshape(C, (3, 3)), det * np.linalg.inv(A).T, rtol=0, atol=1e-14 * np.abs(C).max())


def test_gradient_of_an_affine_motion_is_its_matrix():
    X, dofs, grad0, _ = one_tet()
    A = np.array([[1.1, 0.2, -0.1], [0.05, 0.9, 0.3], [0.0, -0.2, 1.2]])
    F = K._gradient(X @ A.T + [1.0, -2.0, 0.5], 1.0, dofs, grad0, 0)
    assert np.allclose(np.reshape(F, (3, 3)), A, rtol=0, atol=1e-14)
    v = np.full_like(X, 3.0) + X @ A.T  # a translation does not enter the gradient
    D = K._gradient(v, 1e-7, dofs, grad0, 0)
    assert np.allclose(np.reshape(D, (3, 3)), 1e-7 * A, rtol=0, atol=1e-20)


@pytest.mark.parametrize("angle", [1e-6, 0.01, 0.3])
def test_rigid_step_rotates_the_stress_exactly(angle):
    """Over a rigid rotation step the mid-step ΔL gives Q = the step's rotation: s is rotated, |s| is kept,
    and the trial stress has no elastic increment."""
    X, dofs, grad0, _ = one_tet(2)
    R0, R1 = rot([0.3, 1.0, -0.4], 0.2), rot([0.3, 1.0, -0.4], 0.2 + angle)
    x0, x1 = X @ R0.T, X @ R1.T
    dt = 1e-7
    F = K._gradient(x1, 1.0, dofs, grad0, 0)
    L = K._velocity_gradient(F, K._gradient((x1 - x0) / dt, dt, dofs, grad0, 0))
    s = S0[None].copy()
    rotated = np.array(K._hughes_winget(L, s, 0))
    Q = R1 @ R0.T
    want = Q @ voigt_to_mat(S0) @ Q.T
    assert np.allclose(voigt_to_mat(rotated), want, rtol=0, atol=1e-12 * np.abs(S0).max())
    assert np.linalg.norm(voigt_to_mat(rotated)) == pytest.approx(np.linalg.norm(voigt_to_mat(S0)), rel=1e-14)
    se, de = np.empty(6), np.empty(6)
    K._trial_stress(L, s, 0, 80e9, se, de)
    assert np.allclose(se, rotated, rtol=0, atol=1e-12 * np.abs(S0).max())


def test_piola_is_J_sigma_F_inverse_transpose():
    F = np.array([[1.05, 0.1, 0.0], [-0.02, 0.97, 0.04], [0.03, 0.0, 1.01]])
    C, J = K._cofactor(tup(F))
    pm = -4e7
    sigma = voigt_to_mat(S0) + pm * np.eye(3)
    P_out = np.full((2, 9), 7.0)
    K._piola(P_out, 1, False, S0[0] + pm, S0[1] + pm, S0[2] + pm, S0[3], S0[4], S0[5], C)
    assert np.all(P_out[0] == 7.0)
    want = J * sigma @ np.linalg.inv(F).T
    assert np.allclose(P_out[1].reshape(3, 3), want, rtol=0, atol=1e-13 * np.abs(want).max())
    K._piola(P_out, 1, True, S0[0] + pm, S0[1] + pm, S0[2] + pm, S0[3], S0[4], S0[5], C)
    assert np.allclose(P_out[1].reshape(3, 3), 2 * want, rtol=0, atol=1e-13 * np.abs(want).max())


@pytest.mark.parametrize("material", [M.bilinear(10.1e9, 0.3, 1850, 45e6, 600e6),
                                      M.johnson_cook(210e9, 0.3, 7850, 950e6, 725e6, 0.375, 0.015, 0.625,
                                                     1765, 294, 1, 470, 0.9, True, True)])
def test_return_lands_on_the_flow_stress_and_the_P_correction_is_exact(material):
    """The return scales the trial stress onto σ_y = q − 3 G Δε_p, the plastic work is σ_y Δε_p V, sy0 is the
    new static flow stress, and P + (scale − 1) s C (plastic_pass's correction) is the P of the returned stress."""
    p = material.params
    G = material.shear_modulus
    F = np.array([[1.02, 0.05, 0.0], [0.0, 0.99, 0.01], [0.02, 0.0, 1.0]])
    C, J = K._cofactor(tup(F))
    trial = 5.0 * S0  # well above both flow stresses
    q = K._mises(tup(trial))
    assert q == pytest.approx(np.sqrt(1.5) * np.linalg.norm(voigt_to_mat(trial)), rel=1e-14)
    eps_p, temp, sy0, totals = np.array([0.01]), np.array([300.0]), np.empty(1), np.zeros(4)
    K.static_flow_stress(np.zeros(1, np.int64), p[None], eps_p, temp, sy0)
    assert q > sy0[0]
    d, sy, T_new = M.radial_return(q, eps_p[0], temp[0], 1e-7, G, p)
    assert d > 0
    assert q - 3 * G * d == pytest.approx(sy, abs=2e-12 * q)  # consistency
    V = 2e-6
    se = trial.copy()
    K._yielded(0, d, sy, T_new, sy / q, p, V, eps_p, temp, sy0, totals, se)
    assert K._mises(tup(se)) == pytest.approx(sy, rel=1e-14)
    assert np.allclose(se, trial * (sy / q), rtol=1e-15, atol=0)
    assert eps_p[0] == 0.01 + d and temp[0] == T_new
    assert sy0[0] == M.yield_stress(eps_p[0], 0.0, T_new, p)
    assert totals[0] == pytest.approx(sy * d * V, rel=1e-15) and totals[3] == d
    assert totals[1] == pytest.approx(p[M.BETA] * sy * d * V if material.kind == M.JOHNSON_COOK else 0.0, rel=1e-15)
    pm = 3e7
    P_out, want = np.empty((1, 9)), np.empty((1, 9))
    K._piola(P_out, 0, False, trial[0] + pm, trial[1] + pm, trial[2] + pm, *trial[3:], C)  # the trial P
    f = sy / q - 1.0
    K._piola(P_out, 0, True, *(f * trial[:3]), *(f * trial[3:]), C)
    K._piola(want, 0, False, se[0] + pm, se[1] + pm, se[2] + pm, *se[3:], C)
    assert np.allclose(P_out, want, rtol=0, atol=1e-13 * np.abs(want).max())
