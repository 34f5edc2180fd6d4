"""``fepen study ballistic-limit`` and ``ricochet``: the bisected ballistic limit of a slab against the closed
form of a rigid nose through a slab (no crater, no free surface), whose residual speeds are exactly a
Recht–Ipson curve with p = 2 and a = exp(−π a² N* ρ h / m); direct shots one tolerance either side of each
boundary; bad input named."""

import math

import pytest
from conftest import run_fepen
from mpi4py import MPI

from fepen import scene
from fepen.runs import setup
from fepen.studies import closed_forms, limits

SLAB = ["effects.fidelity=rigid", "impact.obliquity_deg=0", "impact.attack_deg=0", "effects.crater=none",
        "effects.free_surface=false", "target.thickness=0.1",
        "target.separation_angle_deg=0", "effects.tunnel=false"]  # the closed form


def test_ballistic_limit_is_the_slab_closed_form(tmp_path):
    tol = 1.0
    res = limits.ballistic_limit(None, SLAB, tmp_path / "bl", MPI.COMM_SELF, v_low=100.0, v_high=1500.0, tol=tol,
                                 curve=8, say=lambda *a: None)
    sc = scene.Scene(None, SLAB)
    law, shape = setup.target_law(sc), setup.projectile_shape(sc)
    mass = setup.projectile(sc).shape.mass(setup.projectile(sc).shell_density)
    N = shape.nose_factor()
    k = math.pi * shape.radius**2 * N * law.density / mass
    c = law.sigma_s / (N * law.density)
    v_bl = math.sqrt(c * (math.exp(2 * k * 0.1) - 1.0))
    assert closed_forms.slab_residual_speed(v_bl * 1.00001, 0.1, shape.radius, mass, law.density, law.sigma_s, N) < 2
    lo, hi = res["bracket_m_s"]
    assert hi - lo <= tol and lo < res["v_bl_m_s"] < hi
    assert res["v_bl_m_s"] == pytest.approx(v_bl, rel=0.01)
    # the direct check one tolerance either side
    assert res["check"]["below"]["outcome"] == "embedded"
    assert res["check"]["above"]["outcome"] == "perforated"
    # Recht–Ipson: v_r² = exp(−2kh) (v² − v_bl²), i.e. p = 2, a = exp(−kh)
    assert res["p"] == pytest.approx(2.0, abs=0.1)
    assert res["a"] == pytest.approx(math.exp(-k * 0.1), rel=0.02)
    assert (tmp_path / "bl" / "ballistic_limit.png").stat().st_size > 10_000


def test_ricochet_boundary_by_bisection(tmp_path):
    # phi_min 0: at the calibrated 12 deg the critical obliquity falls with speed (71.7 deg at 300 m/s, 68.9
    # at 900 m/s; issue 29's closing note), which this test's physics claim below does not cover
    base = ["effects.fidelity=rigid", "impact.attack_deg=0", "target.separation_angle_deg=0"]
    tol = 1.0
    res = limits.ricochet(None, base, tmp_path / "ric", MPI.COMM_SELF, speeds=(300.0, 900.0), tol=tol,
                          map_step=15.0, say=lambda *a: None)
    crit = res["critical_obliquity_deg"]
    assert 30 < crit[0] < crit[1] < 85  # faster shots bite at larger obliquities
    from fepen.runs.rigid import RigidRun

    for v, c, (lo, hi) in zip(res["speeds_m_s"], crit, res["brackets"]):
        assert hi - lo <= tol
        for ob, rico in ((c - tol, False), (c + tol, True)):
            s = RigidRun(scene.Scene(None, [*base, f"impact.velocity={v}", f"impact.obliquity_deg={ob}"]), None,
                         MPI.COMM_SELF).run()
            assert (s["outcome"] == "ricochet") == rico, (v, ob, s["outcome"])


@pytest.mark.parametrize("args, key", [
    (["ballistic-limit", "--set", "effects.fidelity=rigid"], "target.thickness"),
    (["ballistic-limit", "--set", "effects.fidelity=rigid", "--set", "target.thickness=0.15", "--speeds", "900,1000"],
     "--speeds"),
    (["ricochet", "--speeds", "300,fast"], "--speeds"),
])
def test_bad_study_input(tmp_path, args, key):
    r = run_fepen("study", *args, "--out", tmp_path / "x")
    assert r.returncode == 2, r.stderr
    assert r.stderr.startswith(f"fepen: bad input: {key}") and "Traceback" not in r.stderr
