"""Statistics of a sample of shots (fepen study uncertainty, docs/uncertainty.md): the Wilson (1927) score
interval of a proportion, the flags a designer asks the probability of (perforation, ricochet, a final axis beyond
an angle), fepen's own error drawn from the random-effects model of fepen.stats.interval, the
probability of perforation conditioned on a systematic error by self-normalised importance weights, and the
depth's quantiles with shots through the target among them."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["Z95", "MODEL_STREAM", "AXIS_BEYOND_DEG", "wilson", "draw_model_errors", "conditional_probability",
           "depth_quantiles", "designer_flags", "proportion"]

#: the final axis angle (deg) beyond which a shot counts in P(|final axis| > angle), unless a study is told
#: otherwise: a body turned by 10° no longer strikes a layer behind the first as it was aimed
AXIS_BEYOND_DEG = 10.0

#: the standard normal's 97.5 % quantile (the 95 % interval)
Z95 = 1.959963984540054
#: the model's generator: numpy's default_rng([seed, MODEL_STREAM]), apart from the inputs' default_rng(seed)
MODEL_STREAM = 33


def wilson(successes: int, n: int, z: float = Z95) -> tuple[float, float]:
    """The Wilson (1927) score interval of a binomial proportion.

    Args:
        successes: the count x. n: the trials (> 0). z: the normal quantile (1.96: 95 %).

    Returns:
        (low, high) of the proportion.
    """
    if n <= 0:
        raise ValueError("wilson: n must be positive")
    p = successes / n
    d = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / d
    half = z / d * math.sqrt(p * (1.0 - p) / n + z * z / (4 * n * n))
    return max(0.0, centre - half), min(1.0, centre + half)


def draw_model_errors(m, speeds_m_s, seed: int) -> dict:
    """fepen's own error for each sample: eps = mu + b + e, b ~ N(0, tau^2 (1 + 1/k)), e ~ N(0, sigma_g^2)
    (fepen.stats.interval's random-effects model; g: the sample's speed regime).

    Args:
        m: the fepen.stats.interval.ErrorModel. speeds_m_s: each sample's striking speed (its regime's sigma).
        seed: the study's seed (the generator is default_rng([seed, MODEL_STREAM])).

    Returns:
        {"b", "e", "eps", "sigma", "sd"} arrays, one value per sample; "tau_predictive" (float): the spread of b,
        tau sqrt(1 + 1/k).
    """
    from fepen.stats.interval import regime

    speeds = np.asarray(speeds_m_s, float)
    rng = np.random.default_rng([seed, MODEL_STREAM])
    z = rng.standard_normal((len(speeds), 2))
    tau_p = m.tau * math.sqrt(1.0 + 1.0 / max(m.sets, 1))
    sigma = np.array([m.sigma.get(regime(v), m.sigma.get("all", 0.0)) for v in speeds], float)
    b, e = tau_p * z[:, 0], sigma * z[:, 1]
    return {"b": b, "e": e, "eps": m.mu + b + e, "sigma": sigma, "sd": np.sqrt(tau_p**2 + sigma**2),
            "tau_predictive": tau_p}


def conditional_probability(hit, eps, mu: float, tau_p: float, sigma, b_star: float) -> tuple[float, float]:
    """P(hit | b = b_star) from a sample drawn with eps ~ N(mu, tau_p^2 + sigma^2), by self-normalised importance
    weights w = phi((eps - mu - b_star) / sigma) / sigma over phi((eps - mu) / sd) / sd (the inputs, drawn
    independently of eps, keep their distribution).

    Args:
        hit: 0/1 per sample (perforated). eps: the drawn log errors. mu, tau_p: the model's mean and b's spread.
        sigma: each sample's shot-to-shot spread. b_star: the systematic error conditioned on.

    Returns:
        (the probability, the weights' effective sample size (sum w)^2 / sum w^2).
    """
    hit, eps = np.asarray(hit, float), np.asarray(eps, float)
    sigma = np.broadcast_to(np.asarray(sigma, float), eps.shape)
    if tau_p <= 0.0:
        return float(hit.mean()), float(len(hit))
    sd = np.sqrt(tau_p**2 + sigma**2)
    logw = (-0.5 * ((eps - mu - b_star) / sigma) ** 2 - np.log(sigma)) - (-0.5 * ((eps - mu) / sd) ** 2 - np.log(sd))
    w = np.exp(logw - logw.max())
    return float((w * hit).sum() / w.sum()), float(w.sum() ** 2 / (w**2).sum())


def depth_quantiles(depth_mm) -> dict:
    """The depth's quantiles (numpy's linear interpolation) and mean, in mm.

    Args:
        depth_mm: the shots' depths; NaN: no result (left out); +inf: a shot through the target (its depth lies
            beyond it: a quantile that falls among those is None).

    Returns:
        {"P10_mm", "P50_mm", "P90_mm", "mean_mm" (of the shots that stopped), "shots", "stopped"}.
    """
    d = np.sort(np.asarray(depth_mm, float))
    d = d[~np.isnan(d)]
    if not len(d):
        return {"shots": 0}
    out = {}
    for name, q in (("P10_mm", 0.1), ("P50_mm", 0.5), ("P90_mm", 0.9)):
        h = (len(d) - 1) * q
        lo = int(math.floor(h))
        hi = min(lo + 1, len(d) - 1)
        f = h - lo
        out[name] = None if not np.isfinite(d[lo]) or (f > 0 and not np.isfinite(d[hi])) else float(
            d[lo] + f * (d[hi] - d[lo]) if f > 0 else d[lo])
    stopped = d[np.isfinite(d)]
    out["mean_mm"] = float(stopped.mean()) if len(stopped) else None
    out["shots"], out["stopped"] = int(len(d)), int(len(stopped))
    return out


def designer_flags(summaries, beyond_deg: float = AXIS_BEYOND_DEG) -> dict:
    """The 0/1 flags of the probabilities a designer asks, per shot: perforated, ricochet, |final axis| beyond
    ``beyond_deg``; NaN for a shot without a result (None).

    Args:
        summaries: the shots' summaries (dicts with "outcome" and "final_axis_angle_deg") or None.
        beyond_deg: the final axis's angle (deg).

    Returns:
        {"perforation", "ricochet", "axis_beyond"}: arrays of 0, 1 or NaN.
    """
    out = {k: [] for k in ("perforation", "ricochet", "axis_beyond")}
    for s in summaries:
        ok = s is not None
        out["perforation"].append(float(s["outcome"] == "perforated") if ok else np.nan)
        out["ricochet"].append(float(s["outcome"] == "ricochet") if ok else np.nan)
        out["axis_beyond"].append(float(abs(s["final_axis_angle_deg"]) > beyond_deg) if ok else np.nan)
    return {k: np.asarray(v, float) for k, v in out.items()}


def proportion(flags) -> dict:
    """The proportion of the finite 0/1 flags with its Wilson 95 % interval: {"count", "shots", "probability",
    "wilson95"} ({"shots": 0} without one)."""
    f = np.asarray(flags, float)
    f = f[np.isfinite(f)]
    if not len(f):
        return {"shots": 0}
    x, n = int(f.sum()), len(f)
    return {"count": x, "shots": n, "probability": x / n, "wilson95": list(wilson(x, n))}
