"""The rigid run's one RK4 step (rigid_batch.c's rigid_step, the batch's own, which RigidRun.step calls when the C
kernels are built) against its oracle, the numpy step (fepen.laws.rigid_body.RigidBody.rk4_step with
RigidRun.force_fn): bitwise, step by step and over whole runs (the state, the force at the step's start, the work,
the angular impulse, the last stage's load, the tunnel, the wear). Bitwise on numpy 1 (Debian's 1.24, whose
expressions the C repeats); numpy 2 rounds some of its small products and sums otherwise (its SIMD loops), a last
bit that a trajectory carries on: there within 1e-9 of each number (step by step) and test_batch's tolerances
(whole runs)."""

import numpy as np
import pytest
from mpi4py import MPI
from test_batch import CASES, MACHINE, assert_same, rigid

from fepen import native
from fepen.runs import rigid as rigid_run
from fepen.runs.rigid import RigidRun

pytestmark = pytest.mark.skipif(rigid_run.kernel() is None, reason=str(native.why_not("rigid_batch")))

#: the batch's cases, and what only the single path runs: the wear (the mass alone, and the nose that moves its
#: load points)
STEP_CASES = [*CASES, ["effects.wear=true"], ["effects.wear=true", "projectile.wear.distribution=surface"]]


def pair(sets):
    """(the oracle: a RigidRun on the numpy step, the same shot on the compiled step)."""
    oracle, run = (RigidRun(rigid(*sets), None, MPI.COMM_SELF) for _ in range(2))
    assert run.compiled is not None
    oracle.compiled = None
    return oracle, run


#: numpy 1, whose expressions rigid_batch.c repeats: the two steps bitwise the same
BITWISE = np.lib.NumpyVersion(np.__version__) < "2.0.0"


def same(a, b, what: str) -> None:
    """a and b (numbers or arrays) bitwise the same (numpy 2: within 1e-9 of the largest)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if BITWISE:
        assert a.tobytes() == b.tobytes(), what
    else:
        assert np.allclose(a, b, rtol=1e-9, atol=1e-9 * float(np.abs(a).max(initial=0.0))), what


def same_step(a: RigidRun, b: RigidRun) -> None:
    """Every number a step leaves."""
    at = f"at step {a.step_count}"
    same(a.state.as_array(), b.state.as_array(), f"state {at}")
    same(a.F, b.F, f"force {at}")
    same([a.w_ext, a.loaded, a.area], [b.w_ext, b.loaded, b.area], f"work, load {at}")
    same(a.angular_impulse, b.angular_impulse, f"angular impulse {at}")
    same(a.body.angular_impulse_step, b.body.angular_impulse_step, f"angular impulse step {at}")
    if a.tunnel is not None and BITWISE:  # numpy 2: a station a last bit off may be another sector's
        same(a.tunnel.buf, b.tunnel.buf, f"tunnel {at}")
    if a.wear is not None:
        same([a.wear.heat, a.wear.mass_lost, a.body.mass], [b.wear.heat, b.wear.mass_lost, b.body.mass], f"wear {at}")
        same(a.body.r0, b.body.r0, f"worn points {at}")
        same(a.tip_arm, b.tip_arm, f"worn tip {at}")


@pytest.mark.parametrize("sets", STEP_CASES, ids=lambda s: ",".join(s) or "C3")
def test_the_compiled_step_is_the_numpy_step_bitwise(sets):
    """200 steps from the strike, each compared."""
    oracle, run = pair(sets)
    for _ in range(200):
        oracle.step()
        run.step()
        same_step(oracle, run)


@pytest.mark.parametrize("sets", [[], ["effects.crater=linear"], ["effects.wear=true"]],
                         ids=lambda s: ",".join(s) or "C3")
def test_a_run_on_the_compiled_step_is_the_oracles_run_bitwise(sets):
    """Whole runs: every history row and every figure of the summary."""
    oracle, run = pair(sets)
    ref, got = oracle.run(), run.run()
    if not BITWISE:
        assert_same(ref, got)
        return
    assert {k: v for k, v in ref.items() if k not in MACHINE} == {k: v for k, v in got.items() if k not in MACHINE}
    assert oracle.rows == run.rows


def test_the_compiled_stop_back_is_the_numpy_one_bitwise():
    """An embedded stop's interpolation back to V·a = 0 (rigid_batch.c's rigid_stop_back, the batch's): as
    RigidRun.stop_back's numpy on random pairs of states, moving forward or backward along the axis."""
    from fepen.laws.rigid_body import RigidState

    run = RigidRun(rigid(), None, MPI.COMM_SELF)
    rng = np.random.default_rng(11)
    moved = 0
    for _ in range(300):
        pair_ = []
        for _ in range(2):
            q = rng.normal(0.0, 1.0, 4)
            pair_.append(RigidState(rng.normal(0.0, 0.1, 3), q / np.linalg.norm(q), rng.normal(0.0, 300.0, 3),
                                    rng.normal(0.0, 0.1, 3)))
        got = []
        for back in (run.stop_back, lambda: run.compiled.stop_back(run)):
            run.prev, run.state = pair_
            got.append((back(), run.state.as_array()))
        (lam0, y0), (lam1, y1) = got
        assert (lam0 is None) == (lam1 is None)
        same([lam0 or 1.0, *y0], [lam1 or 1.0, *y1], "the state taken back")
        moved += lam0 is not None
    assert 50 < moved < 250


def test_what_the_compiled_step_does_not_cover_takes_the_numpy_step(monkeypatch):
    """A layered target steps in numpy; so does every shot without the C kernels (FEPEN_KERNEL=numpy)."""
    from test_batch import LAYERS

    from fepen import scene

    assert RigidRun(scene.Scene(LAYERS, sets=["effects.fidelity=rigid"]), None, MPI.COMM_SELF).compiled is None
    monkeypatch.setattr(rigid_run, "kernel", lambda: None)
    assert RigidRun(rigid(), None, MPI.COMM_SELF).compiled is None
