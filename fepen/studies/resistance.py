"""The depth's response to the target's resistance (fepen study uncertainty, docs/uncertainty.md): a few rigid shots
of the base scene into a semi-infinite target at resistance factors lambda (target.resistance_factor) give
g(lambda) = P(lambda) / P(1), monotone in lambda, interpolated in logs; its inverse maps fepen's drawn error on the
depth onto the factor each sample runs with."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fepen import scene as fscene
from fepen.errors import SimulationError

__all__ = ["Response", "calibrate", "response_scenes", "response_of", "calibration_scene_keys", "LAMBDA_GRID",
           "LAMBDA_BOUNDS", "RESISTANCE"]

#: the resistance factors of the response g: 13 log-spaced from 0.2 to 5, the middle one exactly 1
LAMBDA_GRID = tuple(1.0 if j == 6 else float(math.exp(math.log(0.2) + j * math.log(25.0) / 12)) for j in range(13))
#: the schema's range of target.resistance_factor: lambda is clipped to it
LAMBDA_BOUNDS = (0.05, 20.0)
RESISTANCE = "target.resistance_factor"


@dataclass(frozen=True)
class Response:
    """The depth's response to the resistance factor, g(lambda) = P(lambda) / P(1), of the base shot into a
    semi-infinite target: a monotone cubic (PCHIP) in (ln lambda, ln g) through the calibration shots, continued
    by straight lines in logs beyond them.

    Attributes:
        lambdas: the calibration's resistance factors (increasing, 1 among them). ratios: P(lambda) / P(1)
            (decreasing). depth_m: P(1).
    """

    lambdas: tuple
    ratios: tuple
    depth_m: float

    def _spline(self):
        from scipy.interpolate import PchipInterpolator

        return PchipInterpolator(np.log(self.lambdas), np.log(self.ratios), extrapolate=False)

    def g(self, lam):
        """P(lambda) / P(1) at the factors lam (array or float)."""
        x = np.log(np.asarray(lam, float))
        xs, ys = np.log(self.lambdas), np.log(self.ratios)
        f = self._spline()(np.clip(x, xs[0], xs[-1]))
        lo_slope, hi_slope = (ys[1] - ys[0]) / (xs[1] - xs[0]), (ys[-1] - ys[-2]) / (xs[-1] - xs[-2])
        f = np.where(x < xs[0], ys[0] + lo_slope * (x - xs[0]),
                     np.where(x > xs[-1], ys[-1] + hi_slope * (x - xs[-1]), f))
        out = np.exp(f)
        return float(out) if np.ndim(lam) == 0 else out

    def inverse(self, ratio):
        """The lambda with g(lambda) = ratio (array or float), by bisection in ln lambda within LAMBDA_BOUNDS
        (a ratio beyond g's values there gives the bound)."""
        r = np.log(np.atleast_1d(np.asarray(ratio, float)))
        lo = np.full(r.shape, math.log(LAMBDA_BOUNDS[0]))
        hi = np.full(r.shape, math.log(LAMBDA_BOUNDS[1]))
        for _ in range(60):  # 60 halvings of ln(400): far below a double's resolution of lambda
            mid = 0.5 * (lo + hi)
            deeper = np.log(self.g(np.exp(mid))) > r  # g decreases: the root lies above mid
            lo, hi = np.where(deeper, mid, lo), np.where(deeper, hi, mid)
        out = np.exp(0.5 * (lo + hi))
        return float(out[0]) if np.ndim(ratio) == 0 else out


def calibration_scene_keys(base: dict) -> dict:
    """The base scene's keys for the response: rigid, target.thickness and target.layers removed."""
    keys = {k: v for k, v in base.items() if k not in ("target.thickness", "target.layers", RESISTANCE)}
    keys["effects.fidelity"] = "rigid"
    return keys


def calibrate(base: dict, comm=None, lambdas=LAMBDA_GRID) -> Response:
    """The Response of the base scene, from one rigid shot per factor (run together, fepen.runs.batch).

    Args:
        base: the base scene's keys. comm: the communicator of the shots (None: COMM_SELF).
        lambdas: the factors (increasing, 1 among them).

    Returns:
        The Response over the factors whose shots stop in the target (the embedded ones about lambda = 1).

    Raises:
        SimulationError: when the base shot at lambda = 1 does not stop in the target, or the depth is not
            monotone in lambda (the model's error cannot then be carried by the resistance).
    """
    from mpi4py import MPI

    from fepen.studies import engine

    comm = MPI.COMM_SELF if comm is None else comm
    scenes = response_scenes(base, lambdas)
    done, _, _ = engine.execute(len(scenes), lambda i: scenes[i], None, comm, keep=lambda sc: False,
                                batch=engine.BATCH, progress=False)  # the records in memory: a second to run again
    return response_of(done, lambdas)


def response_scenes(base: dict, lambdas=LAMBDA_GRID) -> list:
    """The calibration shots of the Response: the base scene's (calibration_scene_keys) at each factor."""
    keys = calibration_scene_keys(base)
    return [fscene.Scene({**keys, RESISTANCE: float(lam)}) for lam in lambdas]


def response_of(done: dict, lambdas=LAMBDA_GRID) -> Response:
    """The Response from the records of the response_scenes' shots ({index: record}; as ``calibrate``).

    Raises:
        SimulationError: as ``calibrate``.
    """
    records = [done[i] for i in range(len(lambdas))]
    one = list(lambdas).index(1.0)
    ok = [r["status"] == "ok" and r["summary"]["outcome"] == "embedded" for r in records]
    if not ok[one]:
        what = records[one]["summary"]["outcome"] if records[one]["summary"] else records[one]["message"]
        raise SimulationError(f"the base shot into a semi-infinite target does not stop in it ({what}): fepen's "
                              "error on the depth does not apply (--no-model-scatter runs the input scatter alone)")
    lo, hi = one, one
    while lo > 0 and ok[lo - 1]:
        lo -= 1
    while hi < len(ok) - 1 and ok[hi + 1]:
        hi += 1
    lam = [float(x) for x in lambdas[lo:hi + 1]]
    depth = np.array([records[i]["summary"]["depth_mm"] * 1e-3 for i in range(lo, hi + 1)])
    if len(lam) < 3 or not np.all(np.diff(depth) < 0):
        raise SimulationError("the base shot's depth is not monotone in target.resistance_factor over "
                              f"{lam[0]:g}-{lam[-1]:g} ({', '.join(f'{1e3 * d:.4g}' for d in depth)} mm): fepen's "
                              "error cannot be carried by the resistance (--no-model-scatter)")
    d1 = float(depth[one - lo])
    return Response(tuple(lam), tuple(float(d / d1) for d in depth), d1)
