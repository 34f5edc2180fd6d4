"""fepen.stats.sampling: the Wilson interval against published values, the importance reweighting against a
conditional probability known in closed form, the model's draws against the model's moments, the quantiles."""

import math

import numpy as np
import pytest
from scipy.special import ndtr

from fepen.stats import interval, sampling


@pytest.mark.parametrize("x, n, low, high", [(81, 263, 0.2553, 0.3662), (15, 148, 0.0624, 0.1605),
                                             (0, 20, 0.0, 0.1611), (1, 29, 0.0061, 0.1718)])
def test_wilson_interval_matches_newcombe(x, n, low, high):
    """Newcombe (1998), Statistics in Medicine 17:857, Table I, method 3 (Wilson's score interval)."""
    lo, hi = sampling.wilson(x, n)
    assert lo == pytest.approx(low, abs=6e-5) and hi == pytest.approx(high, abs=6e-5)


def test_wilson_interval_is_symmetric_and_shrinks_as_one_over_root_n():
    lo, hi = sampling.wilson(50, 100)
    assert lo + hi == pytest.approx(1.0, abs=1e-12)
    w1 = np.subtract(*sampling.wilson(500, 1000)[::-1])
    w2 = np.subtract(*sampling.wilson(2000, 4000)[::-1])
    assert w1 / w2 == pytest.approx(2.0, rel=0.01)


def test_reweighting_recovers_a_known_conditional_probability():
    """A slab perforated when eps + x > c (x: an independent input's effect): P(perforation | b) = 1 -
    Phi((c - mu - b) / sqrt(sigma^2 + s_x^2)), recovered from one sample drawn over b."""
    rng = np.random.default_rng(5)
    n, mu, tau_p, sigma, s_x, c = 400_000, -0.07, 0.17, 0.125, 0.1, 0.05
    b = tau_p * rng.standard_normal(n)
    eps = mu + b + sigma * rng.standard_normal(n)
    hit = (eps + s_x * rng.standard_normal(n) > c).astype(float)
    for b_star in (-0.2, 0.0, 0.2):
        p, ess = sampling.conditional_probability(hit, eps, mu, tau_p, sigma, b_star)
        exact = 1.0 - ndtr((c - mu - b_star) / math.hypot(sigma, s_x))
        assert p == pytest.approx(exact, abs=0.01), (b_star, p, exact)
        assert 0.1 * n < ess <= n
    # no systematic spread: no reweighting
    assert sampling.conditional_probability(hit, eps, mu, 0.0, sigma, 0.3)[0] == pytest.approx(hit.mean())


def test_model_draws_have_the_models_moments():
    """eps = mu + b + e: its mean mu and its spread m.sd(V) in each speed regime; b and e independent."""
    m = interval.model("depth", "scaled-S", "rigid")
    speeds = np.r_[np.full(100_000, 600.0), np.full(100_000, 1200.0)]
    d = sampling.draw_model_errors(m, speeds, seed=3)
    for sl, v in ((slice(0, 100_000), 600.0), (slice(100_000, None), 1200.0)):
        eps = d["eps"][sl]
        sd = m.sd(v)
        assert eps.mean() == pytest.approx(m.mu, abs=4 * sd / math.sqrt(len(eps)))
        assert eps.std() == pytest.approx(sd, rel=0.01)
        assert np.allclose(d["sd"][sl], sd)
    assert d["b"].std() == pytest.approx(m.tau * math.sqrt(1 + 1 / m.sets), rel=0.01)
    assert abs(np.corrcoef(d["b"], d["e"])[0, 1]) < 0.01
    again = sampling.draw_model_errors(m, speeds[:10], seed=3)
    assert np.array_equal(again["eps"], d["eps"][:10])  # seeded: the same draws
    assert not np.array_equal(sampling.draw_model_errors(m, speeds[:10], seed=4)["eps"], again["eps"])


def test_depth_quantiles():
    q = sampling.depth_quantiles(np.r_[np.arange(1.0, 102.0), np.nan])
    assert (q["P10_mm"], q["P50_mm"], q["P90_mm"], q["mean_mm"], q["shots"]) == (11.0, 51.0, 91.0, 51.0, 101)


def test_depth_quantiles_of_a_slab_say_through_beyond_the_stopped_shots():
    """30 of 100 shots perforate (+inf): P10 and P50 are depths, P90 lies among the perforations."""
    d = np.r_[np.arange(1.0, 71.0), np.full(30, np.inf)]
    q = sampling.depth_quantiles(d)
    assert q["P10_mm"] == pytest.approx(np.percentile(d[:70], 10 * 99 / 69)) and q["P90_mm"] is None
    assert q["P50_mm"] == pytest.approx(50.5) and q["mean_mm"] == pytest.approx(35.5)
    assert (q["shots"], q["stopped"]) == (100, 70)


def test_designer_flags_count_perforation_ricochet_and_a_turned_axis():
    """The flags of the probabilities a designer asks, shot by shot (a shot without a result: NaN, left out of
    its proportion), and their proportion with the Wilson interval of wilson()."""
    from fepen.stats.sampling import designer_flags, proportion

    shots = [{"outcome": "perforated", "final_axis_angle_deg": 3.0}, {"outcome": "ricochet",
                                                                       "final_axis_angle_deg": -35.0},
             {"outcome": "embedded", "final_axis_angle_deg": 10.5}, None,
             {"outcome": "embedded", "final_axis_angle_deg": 9.9}]
    f = designer_flags(shots, 10.0)
    assert list(f["perforation"][[0, 1, 2, 4]]) == [1, 0, 0, 0] and np.isnan(f["perforation"][3])
    assert list(f["ricochet"][[0, 1, 2, 4]]) == [0, 1, 0, 0]
    assert list(f["axis_beyond"][[0, 1, 2, 4]]) == [0, 1, 1, 0]  # |−35| and 10.5 beyond 10
    p = proportion(f["axis_beyond"])
    assert (p["count"], p["shots"], p["probability"]) == (2, 4, 0.5)
    assert p["wilson95"] == list(sampling.wilson(2, 4))
    assert proportion([np.nan]) == {"shots": 0}
