"""The target law's one home (fepen/laws/target_kernel.c, target.point_forces) against an independent numpy
oracle of its equations (target_oracle.py) on random surface states, with every switch of the law."""

import math

import numpy as np
import pytest
import target_oracle as oracle

from fepen.laws import target as tg

CA = tg.cavity_ratio(40e6, 32.5e9, 4e6)
LAWS = {
    "plain": {},
    "tresca, free surface": dict(lam=0.0, free_surface=True),
    "energy crater, free surface": dict(crater="energy", k=2.37, free_surface=True),
    "given sigma_s, free surface": dict(free_surface=True, given_sigma_s=True),
    "separation, plate": dict(separation=True, phi_min=math.radians(5.0), thickness=0.3),
    "friction mu(v)": dict(friction=True, mu=0.3, mu_dynamic=0.05, mu_decay=0.01),
    "Coulomb friction, energy crater, plate": dict(friction=True, mu=0.1, crater="energy", thickness=0.25),
    "everything": dict(crater="energy", free_surface=True, separation=True, phi_min=0.02, friction=True,
                       mu=0.2, mu_dynamic=0.1, mu_decay=0.02, thickness=0.4, given_sigma_s=True,
                       surface_range=2.5),
}


def random_state(k, seed):
    """k points around and in a face at y = 0, moving mostly into the target (−y), some backward."""
    rng = np.random.default_rng(seed)
    x = rng.uniform([-0.05, -0.5, -0.05], [0.05, 0.01, 0.05], (k, 3))
    x[: k // 10, 1] = rng.uniform(-1e-3, 1e-3, k // 10)  # crossing the face
    x[k // 10: k // 3, 1] = rng.uniform(-0.05, 0.0, k // 3 - k // 10)  # in the crater
    v = rng.normal([0.0, -600.0, 0.0], 150.0, (k, 3))
    n = rng.normal(size=(k, 3))
    n[: k // 8, 1] = 0.0  # shank-like points, parallel to the motion
    # just under the face, sliding sideways along a normal that looks up at it: the crater throws it out
    m = k // 10
    x[-m:, 1] = rng.uniform(-5e-3, -5e-4, m)
    t = rng.uniform(0.0, 2 * np.pi, m)
    n[-m:] = np.stack([np.cos(t), np.full(m, 0.2), np.sin(t)], axis=1)
    v[-m:] = np.stack([300.0 * np.cos(t), np.full(m, -600.0), 300.0 * np.sin(t)], axis=1)
    n /= np.linalg.norm(n, axis=1)[:, None]
    area = rng.uniform(1e-6, 2e-5, k)
    radius = rng.uniform(0.0, 0.012, k)
    R = np.where(rng.random(k) < 0.5, np.inf, rng.uniform(0.02, 0.1, k))
    sin_phi0 = rng.uniform(0.0, 1.0, k)
    axis = np.array([0.05, -1.0, 0.02])
    return x, v, n, area, radius, R, sin_phi0, axis / np.linalg.norm(axis)


@pytest.mark.parametrize("name", LAWS)
def test_the_compiled_law_is_the_oracle(name):
    law = tg.TargetLaw(**{**dict(density=2400.0, Y=40e6, E=32.5e9, T=4e6, lam=0.67, sigma_s=300e6, c_over_a=CA,
                                 D=0.0236), **LAWS[name]})
    for seed in range(3):
        state = random_state(400, seed)
        for axis in (state[-1], None):  # with and without the wake rule
            f_ref, s_ref = oracle.point_forces(law, *state[:-1], axis)
            f_c, s_c = tg.point_forces(law, *state[:-1], axis)
            scale = np.abs(f_ref).max()
            assert scale > 0.0 and s_ref[3] > 10  # the state loads many points
            np.testing.assert_allclose(f_c, f_ref, rtol=1e-12, atol=1e-13 * scale)
            np.testing.assert_allclose(s_c[:3], s_ref[:3], rtol=1e-11, atol=1e-12 * scale)
            assert s_c[3] == s_ref[3] and s_c[4] == pytest.approx(s_ref[4], rel=1e-13)
    if law.crater == "energy":  # the crater's branch was taken: it unloads some points
        no_crater = tg.TargetLaw(**{**law.__dict__, "crater": "none"})
        assert tg.point_forces(no_crater, *state[:-1], axis)[1][3] > s_ref[3]


def test_load_on_points_is_the_law_plus_the_linear_crater():
    """load_on_points: the law's forces and sums, scaled by the linear crater's factor at the tip's depth."""
    law = tg.TargetLaw(density=2400.0, Y=40e6, E=32.5e9, T=4e6, lam=0.67, sigma_s=300e6, c_over_a=CA, D=0.0236,
                       k=2.0)
    state = random_state(300, 7)
    f, sums = oracle.point_forces(law, *state)
    plain = tg.load_on_points(law, *state)
    np.testing.assert_allclose(plain.total, sums[:3], rtol=1e-11)
    assert plain.loaded == sums[3]
    crater = tg.ForrestalCrater(law, 0.367, 600.0, 3.0)
    scaled = tg.load_on_points(law, *state, crater=crater, tip_depth=0.01)
    factor = crater.scale(0.01, -float(plain.total @ state[-1]))
    assert 0.0 < factor < 1.0
    np.testing.assert_allclose(scaled.total, factor * plain.total, rtol=1e-14)
    np.testing.assert_allclose(scaled.force, factor * plain.force, rtol=1e-14)
