"""``fepen study uncertainty``: the scatter of a shot's inputs and fepen's own error together (docs/studies.md,
docs/uncertainty.md).

The inputs. A sweep file's ``[monte_carlo]`` (``--scatter``; fepen.studies.sweep.monte_carlo) draws the striking
speed, the angles, the concrete strength... of each sample, exactly as ``fepen sweep`` would.

fepen's own error. fepen.stats.interval's random-effects model of the depth's log error on the public data,

    eps = ln(measured / predicted) = mu + b + e,   b ~ N(0, tau^2 (1 + 1/k)),  e ~ N(0, sigma_g^2),

is drawn once per sample from its own generator (seeded from the study's seed; g: the sample's speed regime).
It acts through the scene key ``target.resistance_factor`` (lambda: the target's whole normal stress times
lambda): a few rigid shots of the base scene into a semi-infinite target (target.thickness and target.layers
removed) give the response g(lambda) = P(lambda) / P(1) of the depth, monotone in lambda, interpolated in logs
(Response); each sample then runs with lambda = g^-1(exp(eps)). The depth of the base shot thus carries exactly
the statistical model's error, and a slab's perforation follows from fepen's own physics of the weaker or
stronger target.

The runs. The samples run as a ``[table]`` sweep (fepen.studies.sweep.run: MPI groups, resumable, --ranks-per-shot)
in OUT/combined; for the rigid fidelity the same inputs also run with lambda = 1 in OUT/inputs, the input scatter
alone. The tables written to OUT (combined.csv, inputs.csv, model_draws.csv) are the record of what was drawn.

The results. Depth quantiles; the probability of perforation of the slab (target.thickness) and of each layer
(target.layers) with the Wilson (1927) score interval of the sampling; and the systematic band: P(perforation
| b) at the 10 % and 90 % points of b's distribution, by self-normalised importance reweighting of the drawn
samples (conditional_probability): how far the probability moves if fepen is systematically off for this
concrete as it is for the public sets. OUT/uncertainty.json, uncertainty.md and uncertainty.png.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fepen import scene as fscene
from fepen.errors import InputError, SimulationError
from fepen.stats.sampling import Z95, conditional_probability, depth_quantiles, draw_model_errors, wilson

__all__ = ["Response", "Plan", "LAMBDA_GRID", "Z95", "B_LEVELS", "wilson", "draw_model_errors",
           "conditional_probability", "calibrate", "plan", "study", "depth_quantiles"]

#: the resistance factors of the response g: 13 log-spaced from 0.2 to 5, the middle one exactly 1
LAMBDA_GRID = tuple(1.0 if j == 6 else float(math.exp(math.log(0.2) + j * math.log(25.0) / 12)) for j in range(13))
#: the schema's range of target.resistance_factor: lambda is clipped to it
LAMBDA_BOUNDS = (0.05, 20.0)
#: the points of b's distribution of the systematic band
B_LEVELS = (0.1, 0.9)
RESISTANCE = "target.resistance_factor"


# ------------------------------------------------------------------------------------------------- response
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
    keys = calibration_scene_keys(base)
    scenes = [fscene.Scene({**keys, RESISTANCE: float(lam)}) for lam in lambdas]
    records = engine.run_shots(list(range(len(scenes))), lambda i: scenes[i], None, comm, keep=lambda sc: False)
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


# ------------------------------------------------------------------------------------------------- the plan
@dataclass
class Plan:
    """What the study runs, read and checked before any shot.

    Attributes:
        base: the base scene's keys (flat). label: the shot's name in titles. shot: the Table 1 shot the base
            scene is (fepen.data.Shot) or None. keys: the varied input keys. inputs: one {key: value} per
            sample. samples, seed, latin_hypercube: the sample's. distributions: {key: (kind, parameters)}.
            model_scatter: whether fepen's own error is drawn. scatter: the --scatter file or None.
    """

    base: dict
    label: str
    shot: object
    keys: list
    inputs: list
    samples: int
    seed: int
    latin_hypercube: bool
    distributions: dict
    model_scatter: bool
    scatter: str | None

    @property
    def scene(self) -> fscene.Scene:
        """The base scene, resolved."""
        return fscene.Scene(self.base)

    @property
    def rigid(self) -> bool:
        return self.scene.effects.fidelity == "rigid"


def _expand_shot(base: dict) -> dict:
    """The base with impact.shot replaced by its speed and angles (so that a --set or a varied key may change
    them), as fepen.studies.sweep.read does."""
    from fepen.studies.sweep import IMPACT

    if "impact.shot" not in base:
        return base
    resolved = fscene.Scene(base)
    out = {k: v for k, v in base.items() if k != "impact.shot"}
    for k in IMPACT:
        out.setdefault(k, resolved.get(k))
    return out


def plan(scene_path=None, scatter=None, sets=(), samples: int | None = None, seed: int | None = None,
         model_scatter: bool = True) -> Plan:
    """Read and check the study's input: every error here, in one line, before anything runs.

    Args:
        scene_path: the base scene file, or None (the scatter file's scene and [base], else the default scene).
        scatter: a sweep file with a [monte_carlo] section (its distributions, samples, seed), or None (no
            input scatter). sets: --set KEY=VALUE over the base. samples, seed: override the file's (None: the
            file's; without a file, 1000 and 0). model_scatter: draw fepen's own error.

    Returns:
        The Plan.

    Raises:
        InputError: naming the option or key.
    """
    from types import SimpleNamespace

    from fepen.studies import sweep, sweep_figures

    if samples is not None and (isinstance(samples, bool) or not isinstance(samples, int) or not 2 <= samples
                                <= sweep.MAX_SHOTS):
        raise InputError("--samples", f"an integer in [2, {sweep.MAX_SHOTS}], got {samples!r}")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int) or seed < 0):
        raise InputError("--seed", f"a non-negative integer, got {seed!r}")
    spec, path = {}, None
    if scatter is not None:
        path = Path(scatter)
        try:
            spec = sweep._load(path)
        except InputError as err:
            raise InputError("--scatter", err.message) from None
        if "monte_carlo" not in spec or "grid" in spec or "table" in spec:
            raise InputError("--scatter", f"{path} must hold a [monte_carlo] section (and no [grid] or [table])")
    if scene_path is not None:
        base = fscene.read_toml(scene_path)
    elif path is not None:
        base = sweep._base_keys(path, {k: spec[k] for k in ("scene", "base") if k in spec}, ())
    else:
        base = {}
    given = [fscene.parse_set(item) for item in sets]
    for k, _ in given:
        if k not in fscene.SCHEMA:
            raise fscene.unknown_key(k)
    if RESISTANCE in base or any(k == RESISTANCE for k, _ in given):
        raise InputError(RESISTANCE, "the study draws it (fepen's own error); leave it out, or give "
                                     "--no-model-scatter and scale the law otherwise")
    if any(k in sweep.IMPACT for k, _ in given):
        base = _expand_shot(base)
    for k, v in given:
        base[k] = v
    resolved = fscene.Scene(base)
    if spec:
        mc = dict(spec["monte_carlo"])
        if samples is not None:
            mc["samples"] = samples
        if seed is not None:
            mc["seed"] = seed
        keys, inputs = sweep._monte_carlo(mc, resolved)
        if RESISTANCE in keys:
            raise InputError(f"monte_carlo.vary.{RESISTANCE}", "the study draws it (fepen's own error)")
        specs = sweep._flat_leaves(mc["vary"], lambda d: "distribution" in d)
        dists = {k: sweep._distribution(k, specs[k], resolved.get(k)) for k in keys}
        n, sd, lhs = mc["samples"], mc.get("seed", 0), mc.get("latin_hypercube", False)
    else:
        n, sd, lhs = (samples if samples is not None else 1000), (seed if seed is not None else 0), False
        keys, inputs, dists = [], [{} for _ in range(n)], {}
    shot = sweep_figures.measured_shot(SimpleNamespace(base=base, keys=[]))
    if "target.compressive_strength" in keys and "target.strength_basis" not in base and not base.get(
            "target.layers"):
        # a given strength is read on cylinders unless its basis is given (fepen.scene): the drawn strengths
        # keep the basis of the base scene's value, about which they scatter (the default's 40 MPa is on cubes)
        base["target.strength_basis"] = resolved.get("target.strength_basis")
    label = _label(resolved, scene_path, path, spec)
    p = Plan(base, label, shot, keys, inputs, n, sd, lhs, dists, model_scatter,
             str(path.resolve()) if path is not None else None)
    if not p.rigid and not model_scatter and not keys:
        raise InputError("--no-model-scatter", "with no --scatter nothing would vary")
    return p


def _label(sc: fscene.Scene, scene_path, scatter_path, spec) -> str:
    """The shot's name in titles: the Table 1 shot or the scene file, the slab, the speed."""
    name = sc.get("impact.shot")
    if name is None:
        src = scene_path or (spec.get("scene") if spec else None)
        name = Path(src).name if src else "default scene"
    parts = [name]
    if sc.get("target.thickness") is not None:
        parts.append(f"{1e3 * sc.get('target.thickness'):.4g} mm slab")
    if sc.get("target.layers"):
        parts.append(f"{len(sc.get('target.layers'))} layers")
    parts.append(f"{sc.impact.velocity:.4g} m/s")
    return ", ".join(parts)


def model_of(sc: fscene.Scene):
    """(the ErrorModel of the scene's concrete and law, or None; why not, or None)."""
    from fepen.stats import interval

    if sc.target.kind != "concrete" and not sc.get("target.layers"):
        return None, f"no errors on public data for target.material = {sc.target.material!r}"
    m = interval.model("depth", sc.target.strength_model, "rigid")
    if m is None:
        return None, f"no errors on public data for target.strength_model = {sc.target.strength_model!r}"
    return m, None


# ------------------------------------------------------------------------------------------------- tables
def _csv(rows: list, cols: list) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(cols)
    for r in rows:
        w.writerow([repr(float(r[c])) if isinstance(r[c], float) else r[c] for c in cols])
    return buf.getvalue()


def _records(out: Path, n: int) -> list:
    from fepen.studies import engine

    recs = engine.read_records(out)
    return [recs.get(i) for i in range(n)]


def _sample_result(records: list, thickness: float | None, layers: list | None) -> dict:
    """Depths (mm), perforation flags (slab and per layer) and statuses of a sample's records."""
    statuses, depth, perf, per_layer = {}, [], [], []
    for r in records:
        statuses[r["status"]] = statuses.get(r["status"], 0) + 1
        s = r.get("summary") if r["status"] == "ok" else None
        depth.append((np.inf if s["outcome"] == "perforated" else s["depth_mm"]) if s else np.nan)
        perf.append(float(s["outcome"] == "perforated") if s else np.nan)
        if layers:
            ls = (s or {}).get("layers") or []
            per_layer.append([float(j < len(ls) and ls[j].get("exit_speed_m_s") is not None) if s else np.nan
                              for j in range(len(layers))])
    return {"statuses": statuses, "depth_mm": np.array(depth), "perforated": np.array(perf),
            "layers": np.array(per_layer) if layers else None}


def _probability(flags, draws=None, model=None) -> dict:
    """P, its Wilson interval and (with the draws) the systematic band, of the finite 0/1 flags."""
    ok = np.isfinite(flags)
    x, n = int(flags[ok].sum()), int(ok.sum())
    if n == 0:
        return {"shots": 0}
    lo, hi = wilson(x, n)
    out = {"perforated": x, "shots": n, "probability": x / n, "wilson95": [lo, hi]}
    if draws is not None:
        from fepen.stats.interval import quantile_z

        band, ess = [], []
        for level in B_LEVELS:
            b = quantile_z(level) * draws["tau_predictive"]
            pr, e = conditional_probability(flags[ok], draws["eps"][ok], model.mu, draws["tau_predictive"],
                                            draws["sigma"][ok], b)
            band.append(pr)
            ess.append(e)
        out["systematic"] = {"b_levels": list(B_LEVELS),
                             "b": [quantile_z(v) * draws["tau_predictive"] for v in B_LEVELS],
                             "probability": band, "effective_samples": ess}
    return out


# ------------------------------------------------------------------------------------------------- the study
def study(p: Plan, out, comm=None, ranks_per_shot: int = 1, fresh: bool = False, say=print,
          progress: bool = True) -> dict:
    """Run the study of a Plan and write OUT/uncertainty.json, uncertainty.md, uncertainty.png.

    Args:
        p: the Plan (plan). out: the results directory. comm: the communicator (None: COMM_WORLD).
        ranks_per_shot: ranks of each shot's group. fresh: run every shot again. say: prints lines (rank 0).
        progress: the shots' progress bar (rank 0).

    Returns:
        The content of uncertainty.json (every rank).
    """
    from mpi4py import MPI

    from fepen.runs import setup
    from fepen.stats import envelope
    from fepen.studies import engine

    comm = MPI.COMM_WORLD if comm is None else comm
    t0 = time.perf_counter()
    engine.check_ranks_per_shot(ranks_per_shot, comm.size)
    sc = p.scene
    facts = setup.envelope_facts(sc, setup.check_supported(sc))
    verdict = envelope.verdict(facts)
    verdict["line"] = envelope.line(verdict)
    m, why, response, draws = _model_draws(p, sc, comm)
    combined = [{**s, RESISTANCE: float(draws["lambda"][i])} for i, s in enumerate(p.inputs)] if m is not None \
        else None
    run_inputs = m is None or p.rigid
    inputs = (p.inputs if p.keys else [{}]) if run_inputs else None
    digest = hashlib.sha256(json.dumps([p.base, combined, inputs], sort_keys=True, default=str).encode()).hexdigest()
    out = Path(out)
    err = None
    if comm.rank == 0:
        err = _check_out(out, digest, fresh)
    err = comm.bcast(err, root=0)
    if err:
        raise InputError(*err)
    from fepen.io import rundir

    with rundir.study_directory(out, comm, fresh, "uncertainty", UNCERTAINTY_NAMES):
        return _study(p, sc, out, comm, ranks_per_shot, fresh, say, progress, t0, verdict,
                      (m, why, response, draws, combined, inputs, digest))


#: what the uncertainty study writes into its folder (fepen.io.rundir.study_directory)
UNCERTAINTY_NAMES = ("uncertainty_input.json", "combined.csv", "model_draws.csv", "inputs.csv", "combined", "inputs",
                     "uncertainty.json", "uncertainty.md", "uncertainty.png")


def _study(p: Plan, sc, out: Path, comm, ranks_per_shot: int, fresh: bool, say, progress: bool, t0: float, verdict,
           drawn: tuple) -> dict:
    """study's body, in its claimed folder."""
    from mpi4py import MPI

    from fepen.io import files
    from fepen.studies import sweep

    m, why, response, draws, combined, inputs, digest = drawn
    out = files.prepare(out, comm)
    if comm.rank == 0:
        _write_tables(out, p, digest, combined, inputs, draws)
    comm.barrier()
    for name, rows, table in (("combined", combined, "combined.csv"), ("inputs", inputs, "inputs.csv")):
        if rows is None:
            continue
        spec = ({"base": dict(p.base), "table": {"file": str((out / table).resolve())}} if p.keys or name ==
                "combined" else {"base": dict(p.base), "grid": {RESISTANCE: [1.0]}})
        sweep.run(spec, out / name, comm, ranks_per_shot, fresh=fresh, progress=progress,
                  say=lambda *ls, name=name: say(*(f"{name}: {x}" for x in ls)))
    wall = time.perf_counter() - t0
    result = None
    if comm.rank == 0:
        result = _results(p, sc, out, m, why, response, draws, combined, inputs, verdict, wall, comm.size,
                          ranks_per_shot)
        files.write_json(out / "uncertainty.json", result, MPI.COMM_SELF)
        files.write_text(out / "uncertainty.md", report(result), MPI.COMM_SELF)
        figure(result, out, _depths(out, combined, inputs, sc))
        say(*lines(result, out))
    return comm.bcast(result, root=0)


def _model_draws(p: Plan, sc, comm) -> tuple:
    """(the ErrorModel or None, why none or None, the Response, the draws with their "lambda") of the study:
    the response calibrated on rank 0 (its error raised on every rank), the draws the same on every rank."""
    m, why = model_of(sc) if p.model_scatter else (None, "--no-model-scatter")
    if m is None:
        return None, why, None, None
    res = None
    if comm.rank == 0:
        try:
            res = calibrate(p.base)
        except SimulationError as err:
            res = err
    res = comm.bcast(res, root=0)
    if isinstance(res, SimulationError):
        raise res
    speeds = [s.get("impact.velocity", sc.impact.velocity) for s in p.inputs]
    draws = draw_model_errors(m, speeds, p.seed)
    draws["speed_m_s"] = np.array(speeds, float)
    draws["lambda"] = np.clip(res.inverse(np.exp(draws["eps"])), *LAMBDA_BOUNDS)
    return m, None, res, draws


def _write_tables(out: Path, p: Plan, digest: str, combined, inputs, draws) -> None:
    """uncertainty_input.json (the study's digest), combined.csv, model_draws.csv, inputs.csv (rank 0)."""
    from mpi4py import MPI

    from fepen.io import files

    files.write_json(out / "uncertainty_input.json", {"digest": digest, "scatter": p.scatter, "samples": p.samples,
                                                      "seed": p.seed}, MPI.COMM_SELF)
    if combined is not None:
        files.write_text(out / "combined.csv", _csv(combined, [*p.keys, RESISTANCE]), MPI.COMM_SELF)
        rows = [{"shot": i, "speed_m_s": float(draws["speed_m_s"][i]), "b": float(draws["b"][i]),
                 "e": float(draws["e"][i]), "eps": float(draws["eps"][i]), "sigma": float(draws["sigma"][i]),
                 RESISTANCE: float(draws["lambda"][i])} for i in range(len(combined))]
        files.write_text(out / "model_draws.csv", _csv(rows, list(rows[0])), MPI.COMM_SELF)
    if inputs is not None and p.keys:
        files.write_text(out / "inputs.csv", _csv(inputs, p.keys), MPI.COMM_SELF)


def _check_out(out: Path, digest: str, fresh: bool):
    """None when OUT is new, holds this study (resumable) or fresh; else (key, message) of an InputError."""
    if out.exists() and not out.is_dir():
        return ("--out", f"{out} is a file, not a results directory")
    if fresh:
        return None
    from fepen.studies import engine

    return engine.other_study(out, out / "uncertainty_input.json", digest, "uncertainty study")


def _depths(out: Path, combined, inputs, sc) -> dict:
    """The depth (mm) arrays of the figure, by sample name."""
    d = {}
    for name, rows in (("combined", combined), ("inputs", inputs)):
        if rows is not None:
            d[name] = _sample_result(_records(out / name, len(rows)), None, None)["depth_mm"]
    return d


def _results(p, sc, out, m, why, response, draws, combined, inputs, verdict, wall, ranks, k) -> dict:
    """uncertainty.json's content."""
    thickness, layers = sc.get("target.thickness"), sc.get("target.layers")
    res = {"scene": {"label": p.label, "fidelity": sc.effects.fidelity, "base": p.base,
                     "test": ({"shot": p.shot.name, "depth_mm": p.shot.Hy_mm} if p.shot else None)},
           "scatter": {"file": p.scatter, "samples": p.samples, "seed": p.seed, "latin_hypercube": p.latin_hypercube,
                       "vary": {k2: {"distribution": kind, **prm} for k2, (kind, prm) in p.distributions.items()}},
           "model_scatter": None, "envelope": verdict, "target": {"thickness_m": thickness,
                                                                 "layers": len(layers) if layers else 0},
           "samples": {}, "wall_s": wall, "ranks": ranks, "ranks_per_shot": k}
    if m is not None:
        lam = draws["lambda"]
        res["model_scatter"] = {
            "law": m.law, "mu": m.mu, "tau": m.tau, "tau_predictive": draws["tau_predictive"], "sets": m.sets,
            "sigma_by_regime": dict(m.sigma), "basis": m.basis(sc.impact.velocity),
            "response": {"resistance_factor": list(response.lambdas), "depth_ratio": list(response.ratios),
                         "depth_at_1_mm": 1e3 * response.depth_m},
            "resistance_factor": {"P10": float(np.percentile(lam, 10)), "P50": float(np.percentile(lam, 50)),
                                  "P90": float(np.percentile(lam, 90)),
                                  "clipped": int(np.sum((lam <= LAMBDA_BOUNDS[0]) | (lam >= LAMBDA_BOUNDS[1])))}}
    else:
        res["model_scatter"] = {"none": why}
    for name, rows in (("combined", combined), ("inputs", inputs)):
        if rows is None:
            continue
        s = _sample_result(_records(out / name, len(rows)), thickness, layers)
        entry = {"shots": len(rows), "statuses": s["statuses"], "depth": depth_quantiles(s["depth_mm"])}
        model = (draws, m) if name == "combined" else (None, None)
        if thickness is not None or layers:
            entry["perforation"] = _probability(s["perforated"], *model)
        if layers:
            entry["layers"] = [{"layer": j, "material": (layers[j].get("material") or "concrete"),
                                "thickness_m": layers[j].get("thickness"),
                                **_probability(s["layers"][:, j], *model)} for j in range(len(layers))]
        res["samples"][name] = entry
    if combined is None:
        res["samples"]["note"] = "the input scatter alone: " + str(why)
    elif inputs is None:
        res["samples"]["note"] = (f"{sc.effects.fidelity} fidelity: the combined sample alone (the inputs-only one is "
                                  "run for the rigid fidelity)")
    return res


# ------------------------------------------------------------------------------------------------- outputs
def _fmt_p(e: dict) -> str:
    lo, hi = e["wilson95"]
    text = f"{e['probability']:.3f} ({e['perforated']}/{e['shots']}; Wilson 95 % {lo:.3f}-{hi:.3f})"
    if "systematic" in e:
        a, b = e["systematic"]["probability"]
        text += f"; systematic band {a:.3f}-{b:.3f} (b at its 10 % and 90 %)"
    return text


def _mm(v) -> str:
    """A depth in mm, or "through" (a quantile among the shots that perforated)."""
    return "through" if v is None else f"{v:.1f} mm"


def lines(res: dict, out) -> list[str]:
    """The few lines the command prints."""
    out_lines = []
    for name, what in (("combined", "inputs and model"), ("inputs", "inputs alone")):
        e = res["samples"].get(name)
        if e is None or not e["depth"].get("shots"):
            continue
        q = e["depth"]
        out_lines.append(f"depth ({what}, {q['shots']} shots): P10 {_mm(q['P10_mm'])}, P50 {_mm(q['P50_mm'])}, "
                         f"P90 {_mm(q['P90_mm'])}, mean {_mm(q['mean_mm'])}"
                         + (f" (of the {q['stopped']} that stopped)" if q["stopped"] < q["shots"] else ""))
    if res["scene"]["test"]:
        t = res["scene"]["test"]
        out_lines.append(f"the test {t['shot']}: {t['depth_mm']:.1f} mm")
    for name, what in (("combined", "inputs and model"), ("inputs", "inputs alone")):
        e = res["samples"].get(name)
        if e is None:
            continue
        if "perforation" in e and e["perforation"].get("shots"):
            th = res["target"]["thickness_m"]
            target = f"the {1e3 * th:.4g} mm slab" if th is not None else "the target"
            out_lines.append(f"P(perforation of {target}, {what}) {_fmt_p(e['perforation'])}")
        for lay in e.get("layers", []):
            if lay.get("shots"):
                out_lines.append(f"P(layer {lay['layer']} perforated, {what}) {_fmt_p(lay)}")
    ms = res["model_scatter"]
    if "none" in ms:
        out_lines.append(f"no model scatter: {ms['none']}")
    if "note" in res["samples"]:
        out_lines.append(res["samples"]["note"])
    out_lines.append(res["envelope"]["line"])
    out_lines.append(f"wall {res['wall_s']:.1f} s ({res['ranks']} rank{'s' if res['ranks'] > 1 else ''})")
    out_lines.append(f"written: {out}/uncertainty.json, uncertainty.md, uncertainty.png")
    return out_lines


def report(res: dict) -> str:
    """uncertainty.md: what was drawn, the depth quantiles, the probabilities, the envelope."""
    sc = res["scene"]
    L = [f"# Uncertainty study: {sc['label']}, {sc['fidelity']} fidelity", ""]
    sct = res["scatter"]
    if sct["vary"]:
        L.append(f"Input scatter from `{sct['file']}`: {sct['samples']} samples, seed {sct['seed']}"
                 + (", Latin hypercube" if sct["latin_hypercube"] else "") + "; "
                 + "; ".join(f"`{k}` {v['distribution']} ("
                             + ", ".join(f"{a} {b:.4g}" for a, b in v.items() if a != "distribution") + ")"
                             for k, v in sct["vary"].items()) + ".")
    else:
        L.append(f"No input scatter: {sct['samples']} samples of the base scene's inputs, seed {sct['seed']}.")
    ms = res["model_scatter"]
    if "none" in ms:
        L += ["", f"No model scatter: {ms['none']}."]
    else:
        r = ms["response"]
        L += ["", f"fepen's own error (fepen.stats.interval, {ms['basis']}): ln(M/P) = mu + b + e, mu = "
                  f"{ms['mu']:.4f}, b ~ N(0, {ms['tau_predictive']:.4f}^2) (tau {ms['tau']:.4f}, {ms['sets']} sets), "
                  "e ~ N(0, sigma_g^2) with " + ", ".join(f"sigma = {v:.4f} {g}" for g, v in
                                                         ms["sigma_by_regime"].items()) + ".",
              f"Carried by target.resistance_factor through the base shot's semi-infinite response (depth "
              f"{r['depth_at_1_mm']:.1f} mm at factor 1): " + ", ".join(
                  f"{lam:.3g}: {g:.3f}" for lam, g in zip(r["resistance_factor"], r["depth_ratio"]))
              + f". Drawn factors: P10 {ms['resistance_factor']['P10']:.3f}, P50 "
                f"{ms['resistance_factor']['P50']:.3f}, P90 {ms['resistance_factor']['P90']:.3f}"
                f" ({ms['resistance_factor']['clipped']} clipped to the key's range)."]
    L += ["", "| sample | shots | P10 (mm) | P50 (mm) | P90 (mm) | mean (mm) | statuses |",
          "|---|---|---|---|---|---|---|"]
    for name, e in res["samples"].items():
        if name == "note":
            continue
        q = e["depth"]
        st = ", ".join(f"{k} {v}" for k, v in sorted(e["statuses"].items()))
        if q.get("shots"):
            L.append(f"| {name} | {e['shots']} | " + " | ".join(_mm(q[c]).replace(" mm", "") for c in (
                "P10_mm", "P50_mm", "P90_mm", "mean_mm")) + f" | {st} |")
    if res["target"]["thickness_m"] is not None or res["target"]["layers"]:
        L += ["", "A shot through the target has no depth: \"through\" is a quantile among them; the mean is of the "
                  "shots that stopped."]
    if sc["test"]:
        L += ["", f"The test {sc['test']['shot']}: {sc['test']['depth_mm']:.1f} mm."]
    probs = [(name, "target", e["perforation"]) for name, e in res["samples"].items()
             if name != "note" and "perforation" in e]
    probs += [(name, f"layer {lay['layer']}", lay) for name, e in res["samples"].items() if name != "note"
              for lay in e.get("layers", [])]
    if probs:
        L += ["", "| sample | what | P(perforation) | Wilson 95 % | P at b's 10 % | P at b's 90 % |",
              "|---|---|---|---|---|---|"]
        for name, what, e in probs:
            if not e.get("shots"):
                continue
            band = e.get("systematic", {}).get("probability")
            L.append(f"| {name} | {what} | {e['probability']:.3f} ({e['perforated']}/{e['shots']}) | "
                     f"{e['wilson95'][0]:.3f}-{e['wilson95'][1]:.3f} | "
                     + (f"{band[0]:.3f} | {band[1]:.3f} |" if band else "– | – |"))
        L += ["", "Wilson 95 %: the score interval of the sampling (Wilson 1927). The systematic band: P(perforation "
                  "| b) with b at the 10 % and 90 % points of its distribution, by self-normalised importance "
                  "reweighting of the drawn samples: how far the probability moves if fepen is systematically off "
                  "for this concrete as it is for the public sets."]
    if "note" in res["samples"]:
        L += ["", res["samples"]["note"] + "."]
    L += ["", f"Envelope: {res['envelope']['line']}.", "",
          f"Wall time {res['wall_s']:.1f} s on {res['ranks']} rank(s), {res['ranks_per_shot']} per shot.", "",
          "Files: uncertainty.json (every figure), combined.csv and inputs.csv (the samples' scene keys), "
          "model_draws.csv (b, e, eps and the factor of each sample), combined/ and inputs/ (the sweeps: sweep.csv, "
          "shots.jsonl), uncertainty.png.", ""]
    return "\n".join(L)


def figure(res: dict, out, depths: dict) -> Path:
    """uncertainty.png: the depth histograms of both samples with their P10 and P90, the slab and the test; and
    P(perforation) with its intervals (a finite target) or the depth's CDF."""
    from fepen.post.figures import new_figure, save_figure

    fig = new_figure((12, 4.8))
    ax, ax2 = fig.subplots(1, 2)
    colours = {"combined": "tab:blue", "inputs": "tab:orange"}
    names = {"combined": "inputs and model", "inputs": "inputs alone"}
    finite = [d[np.isfinite(d)] for d in depths.values()]
    allv = np.concatenate(finite) if finite else np.array([])
    bins = np.linspace(allv.min(), allv.max(), 41) if len(allv) and allv.max() > allv.min() else 20
    for name, d in depths.items():
        d = d[np.isfinite(d)]
        if not len(d):
            continue
        q = res["samples"][name]["depth"]
        through = q["shots"] - q["stopped"]
        ax.hist(d, bins=bins, alpha=0.45, color=colours[name], label=f"{names[name]} ({len(d)} stopped"
                + (f", {through} through)" if through else ")"))
        for p in ("P10_mm", "P90_mm"):
            if q[p] is not None:
                ax.axvline(q[p], color=colours[name], ls="--", lw=1.2)
    th = res["target"]["thickness_m"]
    if th is not None:
        ax.axvline(1e3 * th, color="k", lw=2, label=f"slab {1e3 * th:.4g} mm")
    if res["scene"]["test"]:
        t = res["scene"]["test"]
        ax.axvline(t["depth_mm"], color="tab:red", lw=2, label=f"test {t['shot']} {t['depth_mm']:.1f} mm")
    ax.set_xlabel("depth of penetration (mm)")
    ax.set_ylabel("samples")
    ax.set_title("depth; dashed: P10 and P90")
    ax.legend(fontsize=8)
    probs = []
    for name in ("combined", "inputs"):
        e = res["samples"].get(name)
        if e is None:
            continue
        if "perforation" in e and e["perforation"].get("shots"):
            probs.append((name, "target", e["perforation"]))
        for lay in e.get("layers", []):
            if lay.get("shots"):
                probs.append((name, f"layer {lay['layer']}", lay))
    if probs:
        for j, (name, what, e) in enumerate(probs):
            lo, hi = e["wilson95"]
            ax2.errorbar([j], [e["probability"]], yerr=[[e["probability"] - lo], [hi - e["probability"]]],
                         fmt="o", color=colours[name], capsize=6, label=f"{names[name]}: Wilson 95 %"
                         if what in ("target", "layer 0") else None)
            if "systematic" in e:
                a, b = e["systematic"]["probability"]
                ax2.fill_between([j - 0.25, j + 0.25], [a, a], [b, b], color=colours[name], alpha=0.2,
                                 label="systematic band (b at 10 %, 90 %)" if what in ("target", "layer 0") else None)
        ax2.set_xticks(range(len(probs)), [f"{what}\n{names[name]}" for name, what, _ in probs], fontsize=8)
        ax2.set_xlim(-0.6, len(probs) - 0.4)
        ax2.set_ylim(-0.02, 1.02)
        ax2.set_ylabel("probability of perforation (−)")
        ax2.set_title("P(perforation)")
        ax2.legend(fontsize=8)
    else:
        for name, d in depths.items():
            d = np.sort(d[np.isfinite(d)])
            if len(d):
                ax2.plot(d, (np.arange(len(d)) + 1) / len(d), color=colours[name], label=names[name])
        if res["scene"]["test"]:
            ax2.axvline(res["scene"]["test"]["depth_mm"], color="tab:red", lw=2, label="test")
        ms = res["model_scatter"]
        if "response" in ms:
            ax2.axvline(ms["response"]["depth_at_1_mm"], color="k", ls=":", label="fepen at the nominal inputs")
        ax2.set_xlabel("depth of penetration (mm)")
        ax2.set_ylabel("cumulative probability (−)")
        ax2.set_title("depth's distribution")
        ax2.grid(alpha=0.3)
        ax2.legend(fontsize=8)
    sc = res["scene"]
    fig.suptitle(f"Uncertainty: {sc['label']}, {sc['fidelity']} fidelity, {res['scatter']['samples']} samples")
    fig.tight_layout()
    return save_figure(fig, Path(out) / "uncertainty.png")
