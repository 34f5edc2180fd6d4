"""The seeded sample of a sweep's [monte_carlo] table (fepen.studies.spec): each varied key's distribution
(normal, uniform, truncated normal; the mean the base scene's value unless given), checked as scene keys are, and
drawn by inverse CDF from numpy's default_rng(seed), optionally stratified (Latin hypercube)."""

from __future__ import annotations

import math

import numpy as np

from fepen.errors import InputError
from fepen.scene.keys import Key

__all__ = ["DISTRIBUTIONS", "distribution", "monte_carlo", "FINITE", "POSITIVE"]

#: distribution name: its parameters (mean absent: the base scene's value)
DISTRIBUTIONS = {"normal": ("mean", "std"), "uniform": ("low", "high"),
                 "truncated-normal": ("mean", "std", "low", "high")}
#: summary entries that describe the machine or the run's cost, not the shot (costs.csv holds some)
#: the checks of the spec's own numbers, as the scene's keys are checked (fepen.scene.keys.Key)
FINITE = Key(float, None)
POSITIVE = Key(float, None, lo=0.0, lo_open=True)


def _number(where: str, value, positive: bool = False) -> float:
    """A finite number (a positive one), checked as a scene key is: InputError naming ``where``."""
    return (POSITIVE if positive else FINITE).check(where, value)


def distribution(name: str, spec, base_value) -> tuple:
    """(kind, parameters) of one Monte Carlo key, checked."""
    where = f"monte_carlo.vary.{name}"
    if not isinstance(spec, dict) or spec.get("distribution") not in DISTRIBUTIONS:
        raise InputError(f"{where}.distribution", f"one of {', '.join(map(repr, DISTRIBUTIONS))}")
    kind = spec["distribution"]
    allowed = {"distribution", *DISTRIBUTIONS[kind], *(("std_percent",) if "std" in DISTRIBUTIONS[kind] else ())}
    unknown = sorted(set(spec) - allowed)
    if unknown:
        raise InputError(f"{where}.{unknown[0]}", f"not a parameter of {kind!r}; allowed: {', '.join(sorted(allowed))}")
    p = {}
    if kind == "uniform":
        for k in ("low", "high"):
            if k not in spec:
                raise InputError(f"{where}.{k}", "required by 'uniform'")
            p[k] = _number(f"{where}.{k}", spec[k])
        if not p["low"] < p["high"]:
            raise InputError(f"{where}.high", f"must be above low = {p['low']:g}")
        return kind, p
    mean = spec.get("mean", base_value)
    if mean is None:
        raise InputError(f"{where}.mean", "required: the base scene gives this key no value")
    p["mean"] = _number(f"{where}.mean", mean)
    if ("std" in spec) == ("std_percent" in spec):
        raise InputError(f"{where}.std", "give one of std (in the key's unit) and std_percent (of the mean)")
    p["std"] = (_number(f"{where}.std", spec["std"], positive=True) if "std" in spec
                else abs(p["mean"]) * _number(f"{where}.std_percent", spec["std_percent"], positive=True) / 100)
    if kind == "truncated-normal":
        p["low"] = _number(f"{where}.low", spec.get("low", -math.inf)) if "low" in spec else -math.inf
        p["high"] = _number(f"{where}.high", spec["high"]) if "high" in spec else math.inf
        if not p["low"] < p["high"]:
            raise InputError(f"{where}.high", f"must be above low = {p['low']:g}")
    return kind, p


def _quantile(kind: str, p: dict, u: np.ndarray) -> np.ndarray:
    """The distribution's values at probabilities u (inverse CDF: the same u gives the same value)."""
    from scipy.special import ndtr, ndtri

    if kind == "uniform":
        return p["low"] + (p["high"] - p["low"]) * u
    if kind == "normal":
        return p["mean"] + p["std"] * ndtri(u)
    a, b = ndtr((p["low"] - p["mean"]) / p["std"]), ndtr((p["high"] - p["mean"]) / p["std"])
    return p["mean"] + p["std"] * ndtri(a + u * (b - a))


def monte_carlo(distributions: dict, samples: int, seed: int, latin_hypercube: bool) -> list[dict]:
    """The sample: one {key: value} per shot, from numpy's default_rng(seed), keys in the given order.

    Args:
        distributions: {key: (kind, parameters)} (distribution).
        samples: number of shots. seed: the generator's seed.
        latin_hypercube: stratify each key's probabilities into `samples` equal bins, in a random order.

    Returns:
        The shots' values.
    """
    rng = np.random.default_rng(seed)
    keys = list(distributions)
    if latin_hypercube:
        u = np.stack([(rng.permutation(samples) + rng.random(samples)) / samples for _ in keys], axis=1)
    else:
        u = rng.random((samples, len(keys)))
    u = np.clip(u, 1e-12, 1.0 - 1e-12)
    cols = [_quantile(*distributions[k], u[:, j]) for j, k in enumerate(keys)]
    return [{k: float(cols[j][i]) for j, k in enumerate(keys)} for i in range(samples)]
