"""Rigid shots in batches (fepen.runs.batch, fepen/laws/rigid_batch.c) against the single path
(RigidRun.run, the reference): every reported figure of every shot within 1e-12 (bitwise in practice), on
random speeds, angles, strengths and targets (hypothesis), and the automatic fallback where the batch does not
go."""

import ctypes
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mpi4py import MPI

from fepen import native, scene
from fepen.errors import InputError, SimulationError
from fepen.laws import target as tg
from fepen.laws.rigid_body import RigidState
from fepen.runs import batch
from fepen.runs.rigid import RigidRun
from fepen.studies import engine

KERNEL = batch.kernel()
pytestmark = pytest.mark.skipif(KERNEL is None, reason=str(native.why_not("rigid_batch")))
#: the summary keys of the machine, not of the shot
MACHINE = ("wall_s", "time_split_s", "peak_memory_bytes", "versions")


def rigid(*sets):
    """A rigid scene of the default projectile with the given keys (impact.shot dropped)."""
    flat = dict(scene.read_toml("scenes/default.toml"))
    flat.pop("impact.shot", None)
    flat["effects.fidelity"] = "rigid"
    for item in sets:
        k, v = scene.parse_set(item)
        flat[k] = v
    return scene.Scene(flat)


#: absolute tolerances of the figures that are small differences of large ones, known to the precision of what
#: they are taken from, not to 1e-12 of themselves: the energy error (a 1e-6 balance over KE_0: 1e-14 of KE_0)
#: and the residual speed (a few cm/s left of hundreds of m/s: 1e-10 m/s). Bitwise on Debian's numpy 1.24;
#: numpy 2's SIMD exp and sin (a last bit off libm's, which rigid_batch.c calls) move them by ~1e-16 of their
#: sources; likewise a sideways travel of a few nm left by a 1e-5 deg yaw (a position of 1e2 mm known to 1e-13 of
#: itself: 1e-10 mm).
#: figures that vanish at normal incidence, where round-off is all they hold (the axis from Hx - Tx over the
#: body's length: 1e-10 mm in 144 mm is 4e-11 deg)
ABS_TOL = {"energy_error": 1e-14, "residual_speed_m_s": 1e-10, "Hx_mm": 1e-10, "Tx_mm": 1e-10, "Hz_mm": 1e-10,
           "Tz_mm": 1e-10, "final_axis_angle_deg": 1e-9, "axis_error_deg": 1e-9, "nose_offset_mm": 1e-10}


def assert_same(ref: dict, got: dict, rtol: float = 1e-12):
    """Every figure of the single path's summary in the batch's, numbers within rtol (lists item by item)."""
    for k, v in ref.items():
        if k in MACHINE:
            continue
        w = got[k]
        if isinstance(v, dict):
            assert_same(v, w, rtol)
        elif isinstance(v, list) and v and all(isinstance(x, float) for x in v):
            assert len(w) == len(v) and all(math.isclose(a, b, rel_tol=rtol) for a, b in zip(w, v)), \
                f"{k}: {w!r} against {v!r}"
        elif isinstance(v, float) and not isinstance(v, bool):
            atol = ABS_TOL.get(k, 0.0)
            assert math.isclose(w, v, rel_tol=rtol, abs_tol=atol) or w == v, f"{k}: {w!r} against {v!r}"
        else:
            assert w == v, f"{k}: {w!r} against {v!r}"


def single(sc, history=True):
    try:
        return RigidRun(sc, None, MPI.COMM_SELF, history=history).run()
    except (InputError, SimulationError) as err:
        return err


def test_the_kernel_builds():
    """The batch's C builds here (a machine where it does not would silently take the single path)."""
    assert KERNEL is not None


def test_the_batch_law_is_point_forces_bitwise():
    """rigid_batch.c's copy of the law (with its shortcuts) gives point_forces' forces and sums to the bit, on
    random states of the default body in and out of the target."""
    lib, _, gauss = KERNEL
    run = RigidRun(rigid(), None, MPI.COMM_SELF)
    g, k = run.pts, len(run.pts["area0"])
    rng = np.random.default_rng(7)
    for _ in range(200):
        s = run.state
        c = s.c.copy()
        c[1] = rng.uniform(-0.4, 0.05)
        q = s.q + rng.normal(0.0, 0.05, 4)
        st_ = RigidState(c, q / np.linalg.norm(q), s.V * rng.uniform(0.05, 1.5), rng.normal(0.0, 0.05, 3))
        x, v, n, _arm = run.body.points(st_)
        axis = np.ascontiguousarray(-run.body.at(st_)[1][:, 1])
        f0, sums0 = tg.point_forces(run.law, x, v, n, g["area0"], g["radius"], g["R_meridian"], g["sin_phi0"],
                                       axis)
        f, sums = np.zeros((k, 3)), np.zeros(5)
        arrays = [np.ascontiguousarray(a, dtype=float) for a in (
            x, v, n, g["area0"], np.sqrt(g["area0"]), g["radius"], g["R_meridian"], g["sin_phi0"], axis,
            tg._law_numbers(run.law))]
        lib.batch_law(k, *[a.ctypes.data for a in arrays], gauss.ctypes.data, len(gauss) // 2,
                      f.ctypes.data_as(ctypes.c_void_p), sums.ctypes.data_as(ctypes.c_void_p))
        assert np.array_equal(f, f0) and np.array_equal(sums, sums0)


CASES = [
    [],  # C3 itself
    ["effects.crater=linear"],
    ["target.thickness=0.2", "impact.velocity=900"],  # perforated
    ["impact.obliquity_deg=75", "impact.velocity=400"],  # ricochet
    ["effects.friction=true", "target.S_coefficient=80", "target.S_size=0.06"],  # friction: a strength of its own
    ["run.end_time=0.0004"],  # ends at its end time
    ["effects.separation=false", "effects.free_surface=false", "effects.crater=none"],
]


@pytest.mark.parametrize("sets", CASES, ids=lambda s: ",".join(s) or "C3")
def test_a_batch_gives_the_single_paths_summaries(sets):
    sc = rigid(*sets)
    assert_same(single(sc), batch.summaries([sc])[0])


@pytest.mark.filterwarnings("ignore:overflow:RuntimeWarning", "ignore:invalid value:RuntimeWarning")
@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(shots=st.lists(st.tuples(st.floats(150.0, 1200.0), st.floats(0.0, 60.0), st.floats(-4.0, 4.0),
                                st.floats(15e6, 90e6), st.sampled_from([None, 0.15, 0.3, 0.6]),
                                st.booleans()), min_size=1, max_size=3))
def test_random_shots_in_a_batch_agree_with_the_single_path(shots):
    """Random shots of one projectile in one batch: speed, obliquity, yaw, strength, slab or not, crater
    kind; each summary as the single path's, to 1e-12 (and with history=False as rigid_depth runs them)."""
    scenes = []
    for v, ob, yaw, fc, thk, linear in shots:
        sets = [f"impact.velocity={v!r}", f"impact.obliquity_deg={ob!r}", f"impact.attack_deg={yaw!r}",
                f"target.compressive_strength={fc!r}", *([f"target.thickness={thk!r}"] if thk else []),
                *(["effects.crater=linear"] if linear else [])]
        scenes.append(rigid(*sets))
    for history in (True, False):
        got = batch.summaries(scenes, history=history)
        for sc, g in zip(scenes, got):
            ref = single(sc, history)
            if isinstance(ref, Exception):
                assert type(g) is type(ref) and str(g) == str(ref)
            else:
                assert_same(ref, g)


def test_wear_and_layers_take_the_single_path():
    """What the kernel does not cover runs by RigidRun.run, named by reason, with the same summary."""
    worn = rigid("effects.wear=true")
    assert batch.reason(RigidRun(worn, None, MPI.COMM_SELF)) == "wear"
    assert_same(single(worn), batch.summaries([worn])[0])
    layered = scene.Scene(LAYERS, sets=["effects.fidelity=rigid"])
    assert batch.reason(RigidRun(layered, None, MPI.COMM_SELF)) == "a layered target"
    assert_same(single(layered), batch.summaries([layered])[0])
    assert batch.reason(RigidRun(rigid(), None, MPI.COMM_SELF)) is None


LAYERS = """
[impact]
velocity = 800.0

[[target.layers]]
material = "concrete"
thickness = 0.1
gap = 0.2

[[target.layers]]
material = "concrete"
"""


@pytest.mark.filterwarnings("ignore:overflow:RuntimeWarning", "ignore:invalid value:RuntimeWarning")
def test_a_non_finite_state_falls_back_to_the_single_paths_error():
    """A shot whose state turns non-finite (a slow oblique shot into strong concrete under the linear crater, at
    a step that meets its glitch at 532 us: the crater's scale of the load, c z over the axial force, once the
    wall carries the body) is run again by the single path, which stops it with its own error."""
    sc = rigid("impact.velocity=183.0", "impact.obliquity_deg=50.0", "impact.attack_deg=0.0",
               "target.compressive_strength=85584548.0", "effects.crater=linear", "run.rigid_step=2e-7")
    ref, got = single(sc), batch.summaries([sc, rigid()])
    assert isinstance(ref, SimulationError) and type(got[0]) is SimulationError and str(got[0]) == str(ref)
    assert isinstance(got[1], dict)


def test_bad_input_comes_back_as_its_error():
    bad = rigid("projectile.mass=100.0")
    got = batch.summaries([bad, rigid()])
    assert isinstance(got[0], InputError)
    assert isinstance(got[1], dict) and got[1]["outcome"] == "embedded"


def test_chunks_share_the_end_between_groups():
    runs = engine.chunks(list(range(1000)), 32, 2)
    assert [i for r in runs for i in r] == list(range(1000)) and max(map(len, runs)) == 32
    assert max(map(len, engine.chunks(list(range(10)), 32, 2))) == 2
    assert engine.chunks([], 32, 2) == []


def test_a_runaway_is_stopped_not_reported(monkeypatch):
    """A rigid run whose energy balance runs away (here: the guard lowered below a stable shot's error) stops
    with a SimulationError naming the error, the time and the nose, on both paths alike."""
    from fepen.runs import rigid as rigid_run

    monkeypatch.setattr(rigid_run, "UNSTABLE_ENERGY_ERROR", 1e-9)
    sc = rigid()
    ref, got = single(sc), batch.summaries([sc])
    assert isinstance(ref, SimulationError) and "energy balance error" in str(ref) and "nose at" in str(ref)
    assert type(got[0]) is SimulationError and str(got[0]) == str(ref)
