"""fepen.studies.uncertainty's pieces: the resistance response and its inverse, and bad options answered in one
line with exit 2 before any shot (its statistics: tests/unit/stats/test_sampling.py)."""

import math

import numpy as np
import pytest

from fepen import cli
from fepen.studies import uncertainty as unc

DEMO = unc.Path(__file__).resolve().parents[3] / "demos" / "studies" / "c3_scatter.toml"


def power_response(exponent=-0.8):
    lam = np.array(unc.LAMBDA_GRID)
    return unc.Response(tuple(lam), tuple(lam**exponent), 0.35)


def test_lambda_grid_is_log_spaced_with_one_in_it():
    lam = np.array(unc.LAMBDA_GRID)
    assert lam[0] == pytest.approx(0.2) and lam[-1] == pytest.approx(5.0) and 1.0 in unc.LAMBDA_GRID
    assert np.allclose(np.diff(np.log(lam)), math.log(25.0) / 12, rtol=1e-12)


def test_response_inverse_is_the_inverse():
    """g(g^-1(x)) = x across and beyond the grid, and g^-1(g(lambda)) = lambda."""
    r = unc.Response(tuple(unc.LAMBDA_GRID), (3.54, 2.95, 2.43, 1.97, 1.58, 1.25, 1.0, 0.795, 0.636, 0.512, 0.418,
                                              0.345, 0.289), 0.3476)  # C3's, rounded
    x = np.geomspace(0.2, 4.0, 201)  # 0.2 and 4 lie beyond g(5) = 0.289 and g(0.2) = 3.54: the straight ends
    assert np.allclose(r.g(r.inverse(x)), x, rtol=1e-12)
    lam = np.geomspace(0.1, 10.0, 101)
    assert np.allclose(r.inverse(r.g(lam)), lam, rtol=1e-12)
    assert r.g(1.0) == pytest.approx(1.0, abs=1e-15) and r.inverse(1.0) == pytest.approx(1.0, rel=1e-12)
    assert np.all(np.diff(r.g(lam)) < 0)  # monotone between the nodes too (PCHIP)
    assert np.allclose(r.g(np.array(unc.LAMBDA_GRID)), r.ratios, rtol=1e-13)  # through the nodes


def test_a_power_law_response_inverts_exactly():
    """ln g linear in ln lambda: PCHIP and the straight ends reproduce it, so g^-1(x) = x^(1/exponent)."""
    r = power_response(-0.8)
    x = np.geomspace(0.15, 5.0, 50)
    assert np.allclose(r.inverse(x), x ** (-1.25), rtol=1e-10)


def test_inverse_is_clipped_to_the_keys_range():
    r = power_response(-0.8)
    assert r.inverse(1e-6) == pytest.approx(unc.LAMBDA_BOUNDS[1]) and r.inverse(1e6) == pytest.approx(
        unc.LAMBDA_BOUNDS[0])


GRID = "[base]\neffects.fidelity = 'rigid'\n[grid]\n'impact.velocity' = [500.0]\n"
BAD_VARY = "[monte_carlo]\nsamples = 10\n[monte_carlo.vary]\n'impact.speed' = { distribution = 'normal', std = 1.0 }\n"
UNC = ["study", "uncertainty", "--out", "out", "--set", "effects.fidelity=rigid"]


@pytest.mark.parametrize("argv, text, key, words", [
    (UNC + ["--samples", "1"], None, "--samples", r"an integer in \[2, 200000\], got 1"),
    (UNC + ["--seed", "-3"], None, "--seed", r"a non-negative integer, got -3"),
    (UNC + ["--samples", "many"], None, "command line", r"invalid int value: 'many'"),
    (UNC + ["--scatter", "nowhere.toml"], None, "--scatter", r"cannot read nowhere.toml"),
    (UNC + ["--scatter", "SWEEP"], GRID, "--scatter", r"must hold a \[monte_carlo\] section"),
    (UNC + ["--scatter", "SWEEP"], BAD_VARY, "monte_carlo.vary.impact.speed", r"not a scene key"),
    (UNC + ["--set", "target.resistance_factor=2"], None, "target.resistance_factor", r"the study draws it"),
    (UNC + ["--set", "impact.velocity=-5"], None, "impact.velocity", r"got -5"),
    (UNC + ["--ranks-per-shot", "2"], None, "--ranks-per-shot", r"must divide the number of ranks \(1\)"),
    (UNC + ["--speeds", "1,2"], None, "command line", r"unrecognized arguments: --speeds"),
    (UNC + ["--axis-beyond", "95"], None, "--axis-beyond", r"an angle in \(0, 90\) degrees, got 95"),
    (UNC + ["--striking", "--scatter", "SWEEP"], "[monte_carlo]\nsamples = 4\n[monte_carlo.vary]\n"
     "'impact.attack_plane_deg' = { distribution = 'normal', std = 10.0 }\n", "--striking",
     r"draws impact.attack_plane_deg itself"),
    (["study", "uncertainty", "--set", "effects.fidelity=plastic", "--no-model-scatter"], None,
     "--no-model-scatter", r"nothing would vary"),
])
def test_bad_options_are_one_line_and_exit_2(tmp_path, monkeypatch, capsys, bad_input_line, argv, text, key, words):
    from fepen.studies import engine

    def ran(*args, **kwargs):
        raise RuntimeError("the bad input got as far as running a shot")

    monkeypatch.setattr(engine, "run_shots", ran)
    monkeypatch.setattr(engine, "execute", ran)
    monkeypatch.chdir(tmp_path)
    if text is not None:
        (tmp_path / "sweep.toml").write_text(text)
    code = cli.main([str(tmp_path / "sweep.toml") if a == "SWEEP" else a for a in argv])
    bad_input_line(code, capsys.readouterr().err, key, words)
    assert not (tmp_path / "out").exists()


def test_plan_of_the_shipped_scatter_takes_its_scene_and_overrides():
    """The C3 scatter: its scene (shot C3) and [base], --samples and --seed over the file's; a --set of the
    speed replaces the shot's (no conflict with impact.shot), and the scene is then no longer the test."""
    p = unc.plan(None, DEMO, samples=20, seed=7)
    assert p.samples == 20 and p.seed == 7 and len(p.inputs) == 20 and p.rigid
    assert p.keys == ["impact.velocity", "impact.obliquity_deg", "impact.attack_deg", "target.compressive_strength"]
    assert p.shot is not None and p.shot.name == "C3"
    speeds = np.array([s["impact.velocity"] for s in p.inputs])
    assert 584.3 - 20 < speeds.mean() < 584.3 + 20
    slab = unc.plan(None, DEMO, ["target.thickness=0.15", "impact.velocity=315.0"], samples=20, seed=7)
    assert slab.shot is None and slab.scene.impact.velocity == 315.0 and slab.scene.impact.obliquity_deg == 10.5
    assert np.mean([s["impact.velocity"] for s in slab.inputs]) == pytest.approx(315.0, abs=15.0)


def test_the_drawn_strengths_keep_the_base_scenes_basis():
    """The default concrete's 40 MPa is a cube strength; a given strength is read on cylinders unless its basis
    is given: the study pins the base's basis, so the strengths drawn about 40 MPa are cube strengths too."""
    p = unc.plan(None, DEMO, samples=4, seed=1)
    assert p.base["target.strength_basis"] == "cube"
    assert p.shot is not None and p.shot.name == "C3"  # still the test


def test_striking_draws_the_unrecorded_state_on_top_of_each_sample():
    """--striking: each sample of the C3 scatter also draws the yaw out of the plane of fire, the reading errors
    and the concrete's field (fepen.stats.striking.PRIOR), about the sample's own speed, obliquity and attack; the
    out-of-plane yaw's spread is the prior's (within its sampling error), the field's seeds differ, and the same
    seed draws the same samples."""
    from fepen.stats import striking

    n = 400
    p = unc.plan(None, DEMO, samples=n, seed=11, striking=True)
    again = unc.plan(None, DEMO, samples=n, seed=11, striking=True)
    assert p.inputs == again.inputs and p.striking
    for k in ("impact.attack_plane_deg", "target.heterogeneity_cv", "target.heterogeneity_seed"):
        assert k in p.keys
    assert "impact.shot" not in p.base and p.shot is not None and p.shot.name == "C3"
    plain = unc.plan(None, DEMO, samples=n, seed=11)
    out = np.array([s["impact.attack_deg"] * math.sin(math.radians(s["impact.attack_plane_deg"])) for s in p.inputs])
    inp = np.array([s["impact.attack_deg"] * math.cos(math.radians(s["impact.attack_plane_deg"])) for s in p.inputs])
    sd = math.sqrt(striking.PRIOR.yaw_deg**2)
    assert abs(out.mean()) < 3 * sd / math.sqrt(n) and abs(out.std() / sd - 1) < 3 / math.sqrt(2 * n)
    # the in-plane attack is the scatter's own draw plus its reading error
    base = np.array([s["impact.attack_deg"] for s in plain.inputs])
    err = inp - base
    assert abs(err.std() / striking.PRIOR.attack_error_deg - 1) < 3 / math.sqrt(2 * n)
    assert len({s["target.heterogeneity_seed"] for s in p.inputs}) == n
