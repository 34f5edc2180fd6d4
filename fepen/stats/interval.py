"""Prediction intervals from fepen's own errors on public data (docs/uncertainty.md).

The model. For a shot j of data set s, the log error of the prediction P against the measurement M,

    r = ln(M / P) = mu + b_s + e_j,     b_s ~ N(0, tau^2),  e_j ~ N(0, sigma_g^2),

is a systematic error b_s shared by the shots of one set (one laboratory's concrete, projectiles, strength
measurement) and a shot-to-shot error e_j whose spread depends on the regime g of the striking speed (below
SPEED_REGIME_M_S, and from it up, where the noses of the public shots erode and a rigid law cannot follow).
Each set counts once, whatever its size: mu is the mean of the set means; tau^2 their variance less the part the
shot errors explain (the method of moments of DerSimonian and Laird 1986, floored at 0); sigma_g^2 the pooled
variance of the shots about their set's mean, over the shots of regime g. A new shot of a new set then has

    r ~ N(mu, tau^2 (1 + 1/k) + sigma_g^2)       (k sets; tau^2/k: mu is itself estimated),

and the interval at the probabilities LEVELS is P exp(mu + z_p sd). The sideways travel (one set, Table 1) has
no set term: a Student t interval of its few shots' errors.

Everything is computed from fepen/data/prediction_errors.csv (fepen.studies.prediction_errors) when asked: no
number of the model is typed in.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from statistics import NormalDist

import numpy as np

__all__ = ["LEVELS", "SPEED_REGIME_M_S", "DEPTH_OUTCOMES", "ErrorModel", "regime", "fit", "fit_small", "model",
           "coverage", "predict", "model_markdown", "coverage_markdown",
           "lateral_coverage", "interval", "quantile_z", "quantile_t"]

#: the interval's probabilities: 10 % and 90 %
LEVELS = (0.1, 0.9)
#: the striking speed (m/s) from which the shot errors are counted apart: the limit up to which a rigid-body
#: law is held to describe steel projectiles in concrete (nose erosion beyond; Forrestal et al. 1996, Frew et
#: al. 2006). Set before the errors were looked at; 900-1200 m/s give the same coverage (docs/uncertainty.md)
SPEED_REGIME_M_S = 1000.0


def regime(speed_m_s: float) -> str:
    """The speed regime's name: "below 1000 m/s" or "1000 m/s and above"."""
    return f"below {SPEED_REGIME_M_S:g} m/s" if speed_m_s < SPEED_REGIME_M_S else f"{SPEED_REGIME_M_S:g} m/s and above"


def quantile_z(p: float) -> float:
    """The standard normal's quantile at p (Python's own, Wichura's AS 241: a rigid run's process does not load
    scipy for two numbers)."""
    return NormalDist().inv_cdf(p)


def _t_cdf(t: float, dof: int) -> float:
    """Student's t distribution's CDF at t for a whole number of degrees of freedom: the finite series of
    Abramowitz and Stegun 26.7.3 (odd) and 26.7.4 (even) in theta = atan(t / sqrt(dof))."""
    theta = math.atan(t / math.sqrt(dof))
    s, c = math.sin(theta), math.cos(theta)
    if dof % 2:  # odd: (2/pi) [theta + sin cos (1 + 2/3 cos^2 + 2 4/(3 5) cos^4 + ...)], the sum to cos^(dof-3)
        term, total = 1.0, 1.0 if dof > 1 else 0.0
        for j in range(1, (dof - 1) // 2):
            term *= (2.0 * j) / (2.0 * j + 1.0) * c * c
            total += term
        a = 2.0 / math.pi * (theta + (s * c * total if dof > 1 else 0.0))
    else:  # even: sin (1 + 1/2 cos^2 + 1 3/(2 4) cos^4 + ...), the sum to cos^(dof-2)
        term = total = 1.0
        for j in range(1, dof // 2):
            term *= (2.0 * j - 1.0) / (2.0 * j) * c * c
            total += term
        a = s * total
    return 0.5 + 0.5 * a


def quantile_t(p: float, dof: int) -> float:
    """Student's t quantile at p for a whole number of degrees of freedom (>= 1): Newton's method on _t_cdf from the
    normal quantile, to the last few bits (tests/unit/stats: against scipy's stdtrit)."""
    if dof < 1 or dof != int(dof):
        raise ValueError(f"degrees of freedom: a whole number >= 1, got {dof!r}")
    dof = int(dof)
    if p == 0.5:
        return 0.0
    log_norm = math.lgamma((dof + 1) / 2.0) - math.lgamma(dof / 2.0) - 0.5 * math.log(dof * math.pi)
    t = quantile_z(p)
    for _ in range(100):
        density = math.exp(log_norm - 0.5 * (dof + 1) * math.log1p(t * t / dof))
        step = (_t_cdf(t, dof) - p) / density
        t -= step
        if abs(step) <= 1e-15 * max(1.0, abs(t)):
            break
    return t


@dataclass(frozen=True)
class ErrorModel:
    """The fitted error model of one quantity, law and fidelity.

    Attributes:
        quantity: "depth" or "lateral". law: target.strength_model. fidelity: "rigid" or "plastic".
        mu: the mean log error ln(M/P). tau: the spread of the sets' systematic errors. sigma: the shot errors'
            spread by regime name. shots: shots by regime. sets: number of sets k. t_dof: None (normal) or the
            degrees of freedom of a Student t (the small-sample lateral model).
    """

    quantity: str
    law: str
    fidelity: str
    mu: float
    tau: float
    sigma: dict
    shots: dict
    sets: int
    t_dof: int | None = None
    set_names: tuple = field(default=())

    def sd(self, speed_m_s: float) -> float:
        """The predictive standard deviation of ln(M/P) at this striking speed."""
        s = self.sigma.get(regime(speed_m_s), self.sigma.get("all"))
        k = max(self.sets, 1)
        return math.sqrt(self.tau**2 * (1.0 + 1.0 / k) + s**2)

    def z(self, p: float) -> float:
        if self.t_dof is None:
            return quantile_z(p)
        n = self.shots["all"]
        return quantile_t(p, self.t_dof) * math.sqrt(1.0 + 1.0 / n)

    def log_bounds(self, speed_m_s: float, levels=LEVELS) -> tuple:
        """ln(M/P) at the probabilities ``levels``."""
        sd = self.sd(speed_m_s)
        return tuple(self.mu + self.z(p) * sd for p in levels)

    def basis(self, speed_m_s: float) -> str:
        """Where the interval comes from, in a few words."""
        if self.t_dof is not None:
            return (f"{self.shots['all']} shots of one set ({', '.join(self.set_names)}), {self.fidelity} fidelity: "
                    f"Student t, {self.t_dof} degrees of freedom")
        g = regime(speed_m_s)
        return (f"{sum(self.shots.values())} shots in {self.sets} public sets, {self.law} law, rigid fidelity; "
                f"shot scatter from the {self.shots.get(g, 0)} shots {g}")


def fit(rows: list[dict], quantity: str = "depth", law: str = "scaled-S", fidelity: str = "rigid") -> ErrorModel:
    """The random-effects model (module docstring) of the rows of one quantity, law and fidelity.

    Args:
        rows: prediction-error rows (fepen.studies.prediction_errors.read), filtered here.

    Returns:
        The ErrorModel (needs at least two sets).
    """
    rows = [r for r in rows if r["quantity"] == quantity and r["law"] == law and r["fidelity"] == fidelity]
    by_set: dict[str, list] = {}
    for r in rows:
        by_set.setdefault(r["set"], []).append(r)
    if len(by_set) < 2:
        raise ValueError(f"{quantity}/{law}/{fidelity}: {len(by_set)} set(s); the set term needs two or more")
    means, counts, pooled_ss, pooled_dof, within = [], [], 0.0, 0, {}
    for shots in by_set.values():
        e = np.array([math.log(r["measured_m"] / r["predicted_m"]) for r in shots])
        means.append(e.mean())
        counts.append(len(e))
        pooled_ss += float(((e - e.mean()) ** 2).sum())
        pooled_dof += len(e) - 1
        for g in sorted({regime(r["V_m_s"]) for r in shots}):  # about the set's mean in that regime
            eg = np.array([x for x, r in zip(e, shots) if regime(r["V_m_s"]) == g])
            ss, dof = within.get(g, (0.0, 0))
            within[g] = (ss + float(((eg - eg.mean()) ** 2).sum()), dof + len(eg) - 1)
    means, counts = np.array(means), np.array(counts)
    sigma = {g: math.sqrt(ss / dof) if dof > 0 else 0.0 for g, (ss, dof) in within.items()}
    s2 = pooled_ss / pooled_dof if pooled_dof > 0 else 0.0
    tau2 = max(float(means.var(ddof=1)) - float(np.mean(s2 / counts)), 0.0)
    shots = {g: sum(regime(r["V_m_s"]) == g for r in rows) for g in sigma}
    return ErrorModel(quantity, law, fidelity, float(means.mean()), math.sqrt(tau2), sigma, shots, len(by_set),
                      None, tuple(by_set))


def fit_small(rows: list[dict], quantity: str = "lateral", law: str = "scaled-S",
              fidelity: str = "rigid") -> ErrorModel:
    """The small-sample model of one set's few shots (the sideways travel): ln(M/P) ~ mu + s t_{n-1} sqrt(1+1/n)."""
    rows = [r for r in rows if r["quantity"] == quantity and r["law"] == law and r["fidelity"] == fidelity]
    if len(rows) < 3:
        raise ValueError(f"{quantity}/{law}/{fidelity}: {len(rows)} shots; a t interval needs three or more")
    e = np.array([math.log(r["measured_m"] / r["predicted_m"]) for r in rows])
    return ErrorModel(quantity, law, fidelity, float(e.mean()), 0.0, {"all": float(e.std(ddof=1))},
                      {"all": len(e)}, 1, len(e) - 1, tuple(sorted({r["set"] for r in rows})))


@functools.lru_cache(maxsize=16)
def model(quantity: str = "depth", law: str = "scaled-S", fidelity: str = "rigid") -> ErrorModel | None:
    """The ErrorModel of the shipped table (None when it has no rows of that quantity, law and fidelity)."""
    from fepen.data import prediction_errors

    rows = prediction_errors.read()
    try:
        return fit(rows, quantity, law, fidelity) if quantity == "depth" else fit_small(rows, quantity, law, fidelity)
    except ValueError:
        return None


def interval(m: ErrorModel, predicted: float, speed_m_s: float, levels=LEVELS) -> tuple:
    """The interval of the measurement at ``levels``, for a prediction (any unit: the interval's)."""
    return tuple(predicted * math.exp(b) for b in m.log_bounds(speed_m_s, levels))


def coverage(rows: list[dict], law: str = "scaled-S", levels=LEVELS) -> list[dict]:
    """Leave-one-set-out coverage of the depth interval: each set's shots against the model fitted on the
    other sets alone. One dict per set: set, role, shots, inside, below, above, and the set's bias."""
    rows = [r for r in rows if r["quantity"] == "depth" and r["law"] == law and r["fidelity"] == "rigid"]
    out = []
    for name in sorted({r["set"] for r in rows}):
        test = [r for r in rows if r["set"] == name]
        m = fit([r for r in rows if r["set"] != name], "depth", law, "rigid")
        below = above = 0
        for r in test:
            lo, hi = interval(m, r["predicted_m"], r["V_m_s"], levels)
            below += r["measured_m"] < lo
            above += r["measured_m"] > hi
        bias = float(np.mean([r["predicted_m"] / r["measured_m"] - 1.0 for r in test]))
        out.append({"set": name, "role": test[0]["role"], "shots": len(test), "inside": len(test) - below - above,
                    "below": below, "above": above, "bias": bias})
    return out


def lateral_coverage(rows: list[dict], fidelity: str = "rigid", levels=LEVELS) -> list[dict]:
    """Leave-one-shot-out coverage of the sideways-travel interval (one set: no set to leave out)."""
    rows = [r for r in rows if r["quantity"] == "lateral" and r["fidelity"] == fidelity]
    out = []
    for i, r in enumerate(rows):
        m = fit_small(rows[:i] + rows[i + 1:], "lateral", r["law"], fidelity)
        lo, hi = interval(m, r["predicted_m"], r["V_m_s"], levels)
        out.append({"shot": r["shot"], "predicted_m": r["predicted_m"], "measured_m": r["measured_m"],
                    "low_m": lo, "high_m": hi, "inside": lo <= r["measured_m"] <= hi})
    return out


#: outcomes whose final depth is a depth of penetration (a perforation, a ricochet or a run that ended while
#: the projectile still moved has none to bound)
DEPTH_OUTCOMES = ("embedded",)


def _lateral_span(fidelity: str) -> dict | None:
    """The obliquity (deg) and speed (m/s) ranges of the lateral rows of this fidelity (None: no rows)."""
    from fepen.data import prediction_errors

    rows = [r for r in prediction_errors.read() if r["quantity"] == "lateral" and r["fidelity"] == fidelity]
    if not rows:
        return None
    return {c: (min(r[c] for r in rows), max(r[c] for r in rows)) for c in ("obliquity_deg", "V_m_s")}


def predict(facts: dict, verdict: dict, outcome: str, depth_m: float, lateral_m: float) -> dict:
    """The summary's intervals of one finished shot.

    Args:
        facts: fepen.runs.setup.envelope_facts. verdict: fepen.stats.envelope.verdict of them.
        outcome: the run's outcome. depth_m: the nose's greatest depth. lateral_m: the nose's final sideways
            travel Hx.

    Returns:
        {"depth_interval_mm": [low, high] or None, "lateral_interval_mm": [low, high] or None, "interval":
        {"levels", "depth", "lateral", "extrapolated"}}: each of "depth" and "lateral" says where its interval
        comes from, or why there is none.
    """
    law, speed, fid = facts["law"], facts["values"]["V_m_s"], facts["fidelity"]
    out = {"depth_interval_mm": None, "lateral_interval_mm": None,
           "interval": {"levels": list(LEVELS), "extrapolated": not verdict["inside"]}}
    m = model("depth", law, "rigid") if facts["target"] == "concrete" else None
    if m is None:
        out["interval"]["depth"] = "none: no errors on public data for this target and law"
    elif outcome not in DEPTH_OUTCOMES:
        out["interval"]["depth"] = f"none: the shot's outcome is {outcome}, the data are of shots that stopped"
    else:
        out["depth_interval_mm"] = [1e3 * v for v in interval(m, depth_m, speed)]
        out["interval"]["depth"] = m.basis(speed) + ("" if fid == "rigid" else
                                                     "; applied to this fidelity's depth")
    lat_fid = "rigid" if fid == "rigid" else "plastic"
    lm = model("lateral", law, lat_fid) if facts["target"] == "concrete" else None
    span = _lateral_span(lat_fid)
    ob = facts["values"]["obliquity_deg"]
    if lm is None or span is None:
        out["interval"]["lateral"] = "none: no errors on public data for this target, law and fidelity"
    elif not span["obliquity_deg"][0] <= ob <= span["obliquity_deg"][1]:
        lo, hi = span["obliquity_deg"]
        out["interval"]["lateral"] = f"none: obliquity {ob:.3g} deg outside the {lo:.3g}-{hi:.3g} deg of Table 1's " \
                                     "oblique shots"
    elif not span["V_m_s"][0] <= speed <= span["V_m_s"][1]:
        lo, hi = span["V_m_s"]
        out["interval"]["lateral"] = f"none: striking speed {speed:.4g} m/s outside the {lo:.4g}-{hi:.4g} m/s of " \
                                     "Table 1's oblique shots"
    elif outcome not in DEPTH_OUTCOMES:
        out["interval"]["lateral"] = f"none: the shot's outcome is {outcome}"
    else:
        lo, hi = interval(lm, abs(lateral_m), speed)
        sign = 1.0 if lateral_m >= 0 else -1.0
        out["lateral_interval_mm"] = sorted([1e3 * sign * lo, 1e3 * sign * hi])
        out["interval"]["lateral"] = lm.basis(speed)
    return out


def model_markdown(models) -> str:
    """Fitted models as one Markdown table: mu, tau, each regime's sigma and shots, and the interval's factors."""
    lines = ["| quantity, law, fidelity | mu | tau | regime | sigma | shots | sets | 10 % factor | 90 % factor |",
             "|---|---|---|---|---|---|---|---|---|"]
    for m in models:
        for g, s in m.sigma.items():
            speed = 0.5 * SPEED_REGIME_M_S if g.startswith("below") or g == "all" else 2.0 * SPEED_REGIME_M_S
            lo, hi = (math.exp(b) for b in m.log_bounds(speed))
            lines.append(f"| {m.quantity}, {m.law}, {m.fidelity} | {m.mu:+.3f} | {m.tau:.3f} | {g} | {s:.3f} | "
                         f"{m.shots[g]} | {m.sets} | {lo:.3f} | {hi:.3f} |")
    return "\n".join(lines) + "\n"


def coverage_markdown(table: list[dict]) -> str:
    """The leave-one-set-out coverage table (coverage) as Markdown, with the pooled rows."""
    lines = ["| set | role | shots | inside | below | above | coverage | bias of fepen |",
             "|---|---|---|---|---|---|---|---|"]
    for r in table:
        lines.append(f"| {r['set']} | {r['role']} | {r['shots']} | {r['inside']} | {r['below']} | {r['above']} | "
                     f"{100 * r['inside'] / r['shots']:.0f} % | {100 * r['bias']:+.1f} % |")
    for label, rows in (("pooled, held-out sets", [r for r in table if r["role"] == "held-out"]),
                        ("pooled, calibration sets", [r for r in table if r["role"] == "calibration"]),
                        ("pooled, all sets", table)):
        n, i = sum(r["shots"] for r in rows), sum(r["inside"] for r in rows)
        b, a = sum(r["below"] for r in rows), sum(r["above"] for r in rows)
        lines.append(f"| **{label}** | | {n} | {i} | {b} | {a} | **{100 * i / n:.1f} %** | |")
    return "\n".join(lines) + "\n"
