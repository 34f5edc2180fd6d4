"""The C transcription of the rigid body's load-point kinematics and force sums (fepen/laws/rigid_kernel.c)
against RigidBody's numpy expressions, on a random body, state and forces."""

import numpy as np
import pytest

from fepen import native
from fepen.laws import rigid_body as rb

LIB = rb._kernel()
pytestmark = pytest.mark.skipif(LIB is None, reason=str(native.why_not("rigid_body")))


def random_body(seed, k=500):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(3, 3))
    inertia = A @ A.T + 3 * np.eye(3)
    n = rng.normal(size=(k, 3))
    n /= np.linalg.norm(n, axis=1)[:, None]
    body = rb.RigidBody(0.4, rng.normal(size=3), inertia, rng.normal(size=(k, 3)), n)
    q = rng.normal(size=4)
    s = rb.RigidState(rng.normal(size=3), q / np.linalg.norm(q), rng.normal(size=3) * 600, rng.normal(size=3))
    return body, s, rng.normal(size=(k, 3)) * 1e4


@pytest.mark.parametrize("seed", range(4))
def test_points_and_sums_are_the_numpy_expressions(seed):
    body, s, f = random_body(seed)
    got = body.points(s)
    F, M = body.force_moment(got[3], f)
    body.lib = None  # the numpy reference
    ref = body.points(s)
    F_ref, M_ref = body.force_moment(ref[3], f)
    for a, b in zip(got, ref):
        np.testing.assert_allclose(a, b, rtol=1e-13, atol=1e-12 * np.abs(b).max())
    np.testing.assert_allclose(F, F_ref, rtol=1e-11, atol=1e-11 * np.abs(f).sum())
    np.testing.assert_allclose(M, M_ref, rtol=1e-11, atol=1e-11 * np.abs(f).sum())
    # a rigid motion: v − V = ω × (x − c) at every point
    w = body.omega(s)
    np.testing.assert_allclose(got[1] - s.V, np.cross(w, got[0] - s.c), atol=1e-10 * np.abs(got[1]).max())
