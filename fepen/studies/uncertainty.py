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

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fepen import scene as fscene
from fepen.errors import InputError
from fepen.stats.sampling import draw_model_errors
from fepen.studies.products import Inputs, Picture, Table
from fepen.studies.resistance import LAMBDA_BOUNDS, LAMBDA_GRID, RESISTANCE, Response, calibrate
from fepen.studies.study import Round, Study, Sub, register, set_option

__all__ = ["Uncertainty", "Response", "Plan", "LAMBDA_GRID", "LAMBDA_BOUNDS", "calibrate", "plan", "study",
           "RESISTANCE"]



# ------------------------------------------------------------------------------------------------- the plan
@dataclass
class Plan:
    """What the study runs, read and checked before any shot.

    Attributes:
        base: the base scene's keys (flat). label: the shot's name in titles. shot: the Table 1 shot the base
            scene is (fepen.data.Shot) or None. keys: the varied input keys. inputs: one {key: value} per
            sample. samples, seed, latin_hypercube: the sample's. distributions: {key: (kind, parameters)}.
            model_scatter: whether fepen's own error is drawn. scatter: the --scatter file or None. striking:
            whether each sample also draws the striking state and the concrete's field nobody measured
            (fepen.stats.striking.PRIOR). axis_beyond_deg: the angle of P(|final axis| > angle).
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
    striking: bool = False
    axis_beyond_deg: float = 10.0

    @property
    def scene(self) -> fscene.Scene:
        """The base scene, resolved."""
        return fscene.Scene(self.base)

    @property
    def rigid(self) -> bool:
        return self.scene.effects.fidelity == "rigid"


def plan(scene_path=None, scatter=None, sets=(), samples: int | None = None, seed: int | None = None,
         model_scatter: bool = True, striking: bool = False, axis_beyond: float | None = None) -> Plan:
    """Read and check the study's input: every error here, in one line, before anything runs.

    Args:
        scene_path: the base scene file, or None (the scatter file's scene and [base], else the default scene).
        scatter: a sweep file with a [monte_carlo] section (its distributions, samples, seed), or None (no
            input scatter). sets: --set KEY=VALUE over the base. samples, seed: override the file's (None: the
            file's; without a file, 1000 and 0). model_scatter: draw fepen's own error. striking: each sample
            also draws the unmeasured striking state and the concrete's field (docs/uncertainty.md). axis_beyond:
            the angle (deg) of P(|final axis| > angle) (None: fepen.stats.sampling.AXIS_BEYOND_DEG).

    Returns:
        The Plan.

    Raises:
        InputError: naming the option or key.
    """
    from types import SimpleNamespace

    from fepen.studies import spec as fspec
    from fepen.studies.sweep import measured_shot

    beyond = _check_options(samples, seed, axis_beyond)
    spec, path = {}, None
    if scatter is not None:
        path = Path(scatter)
        try:
            spec = fspec.load(path)
        except InputError as err:
            raise InputError("--scatter", err.message) from None
        if "monte_carlo" not in spec or "grid" in spec or "table" in spec:
            raise InputError("--scatter", f"{path} must hold a [monte_carlo] section (and no [grid] or [table])")
    if scene_path is not None:
        base = fscene.read_toml(scene_path)
    elif path is not None:
        base = fspec.base_keys(path, {k: spec[k] for k in ("scene", "base") if k in spec}, ())
    else:
        base = {}
    given = [fscene.parse_set(item) for item in sets]
    for k, _ in given:
        if k not in fscene.SCHEMA:
            raise fscene.unknown_key(k)
    if RESISTANCE in base or any(k == RESISTANCE for k, _ in given):
        raise InputError(RESISTANCE, "the study draws it (fepen's own error); leave it out, or give "
                                     "--no-model-scatter and scale the law otherwise")
    if any(k in fspec.IMPACT for k, _ in given):
        base = fspec.expand_shot(base)
    for k, v in given:
        base[k] = v
    resolved = fscene.Scene(base)
    if spec:
        mc = dict(spec["monte_carlo"])
        if samples is not None:
            mc["samples"] = samples
        if seed is not None:
            mc["seed"] = seed
        keys, inputs = fspec.sample(mc, resolved)
        if RESISTANCE in keys:
            raise InputError(f"monte_carlo.vary.{RESISTANCE}", "the study draws it (fepen's own error)")
        specs = fspec.flat_leaves(mc["vary"], lambda d: "distribution" in d)
        dists = {k: fspec.distribution(k, specs[k], resolved.get(k)) for k in keys}
        n, sd, lhs = mc["samples"], mc.get("seed", 0), mc.get("latin_hypercube", False)
    else:
        n, sd, lhs = (samples if samples is not None else 1000), (seed if seed is not None else 0), False
        keys, inputs, dists = [], [{} for _ in range(n)], {}
    shot = measured_shot(SimpleNamespace(base=base, keys=[]))
    fspec.keep_basis(base, keys, resolved)  # the drawn strengths keep the base scene's basis
    label = _label(resolved, scene_path, path, spec)
    if striking:
        base = fspec.expand_shot(base)
        from fepen.studies.bands import striking_inputs

        keys, inputs = striking_inputs(resolved, keys, inputs, sd)
    p = Plan(base, label, shot, keys, inputs, n, sd, lhs, dists, model_scatter,
             str(path.resolve()) if path is not None else None, bool(striking), float(beyond))
    if not p.rigid and not model_scatter and not keys:
        raise InputError("--no-model-scatter", "with no --scatter nothing would vary")
    return p


def _check_options(samples, seed, axis_beyond) -> float:
    """--samples, --seed and --axis-beyond checked (InputError); the angle of P(|final axis| > angle)."""
    from fepen.stats.sampling import AXIS_BEYOND_DEG
    from fepen.studies import spec as fspec

    if samples is not None and (isinstance(samples, bool) or not isinstance(samples, int) or not 2 <= samples
                                <= fspec.MAX_SHOTS):
        raise InputError("--samples", f"an integer in [2, {fspec.MAX_SHOTS}], got {samples!r}")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int) or seed < 0):
        raise InputError("--seed", f"a non-negative integer, got {seed!r}")
    beyond = AXIS_BEYOND_DEG if axis_beyond is None else axis_beyond
    if isinstance(beyond, bool) or not isinstance(beyond, (int, float)) or not 0.0 < beyond < 90.0:
        raise InputError("--axis-beyond", f"an angle in (0, 90) degrees, got {axis_beyond!r}")
    return float(beyond)


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
    from fepen.runs import targets
    from fepen.stats import interval

    why = targets.of(sc).no_public_errors(sc)
    if why is not None:
        return None, why
    m = interval.model("depth", sc.target.strength_model, "rigid")
    if m is None:
        return None, f"no errors on public data for target.strength_model = {sc.target.strength_model!r}"
    return m, None


# ------------------------------------------------------------------------------------------------- the study
#: what the uncertainty study writes into its folder (fepen.io.rundir.study_directory)
UNCERTAINTY_NAMES = ("uncertainty_input.json", "response", "combined.csv", "model_draws.csv", "inputs.csv", "combined",
                     "inputs", "uncertainty.json", "uncertainty.md", "uncertainty.png")


@register
class Uncertainty(Study):
    """``fepen study uncertainty``: the inputs' scatter and fepen's own error drawn together (module docstring)."""

    name = "uncertainty"
    help = ("the scatter of the inputs and fepen's own error together: the depth's distribution, P(perforation) "
            "with its intervals: uncertainty.json, uncertainty.md, uncertainty.png")
    names = UNCERTAINTY_NAMES
    out = "results/uncertainty"

    @classmethod
    def add_arguments(cls, parser) -> None:
        parser.add_argument("scene", nargs="?", help="the base scene (absent: the default)")
        set_option(parser, "override a key of the base scene")
        parser.add_argument("--scatter", metavar="SWEEP.toml", help="a sweep file whose [monte_carlo] gives the "
                                                                    "inputs' distributions (absent SCENE: its scene "
                                                                    "and [base] too)")
        parser.add_argument("--samples", type=int, default=None, metavar="N", help="samples (default: the --scatter "
                                                                                   "file's; without it 1000)")
        parser.add_argument("--seed", type=int, default=None, metavar="S", help="the seed (default: the --scatter "
                                                                                "file's; without it 0)")
        parser.add_argument("--no-model-scatter", dest="model_scatter", action="store_false",
                            help="the input scatter alone (fepen's own error not drawn)")
        parser.add_argument("--striking", action="store_true",
                            help="each sample also draws what a test does not record: the yaw out of the plane of "
                                 "fire, the angles' reading errors, the rates, the concrete's field "
                                 "(docs/uncertainty.md)")
        parser.add_argument("--axis-beyond", type=float, default=None, metavar="DEG",
                            help="the angle of P(|final axis| > DEG) (default 10)")

    @classmethod
    def options(cls, args) -> dict:
        return {"scene_path": args.scene, "scatter": args.scatter, "sets": args.sets, "samples": args.samples,
                "seed": args.seed, "model_scatter": args.model_scatter, "striking": args.striking,
                "axis_beyond": args.axis_beyond}

    @classmethod
    def argv(cls, args) -> list[str]:
        """Its own options as command-line words (``fepen study uncertainty --workers W``'s relaunch under mpirun)."""
        return [*([args.scene] if args.scene else []), *[f"--set={s}" for s in args.sets],
                *[f"{o}={v}" for o, v in (("--scatter", args.scatter), ("--samples", args.samples),
                                          ("--seed", args.seed), ("--axis-beyond", args.axis_beyond)) if v is not None],
                *([] if args.model_scatter else ["--no-model-scatter"]), *(["--striking"] if args.striking else [])]

    def plan(self, **options) -> Plan:
        return plan(**options)

    def digest(self, p: Plan) -> str:
        """The base, the drawn inputs, the seed and whether fepen's error is drawn: the model's draws follow from
        them (and from the shipped errors)."""
        return hashlib.sha256(json.dumps([p.base, p.inputs, p.seed, p.model_scatter], sort_keys=True,
                                         default=str).encode()).hexdigest()

    def rounds(self, p: Plan):
        """The response's shots (a round of their own, resumable), the tables of what is drawn (written before the
        samples' sweeps read them), then the sweeps; returns what was drawn (``_drawn``)."""
        from fepen.studies import sweep
        from fepen.studies.resistance import response_scenes

        m, why = model_of(p.scene) if p.model_scatter else (None, "--no-model-scatter")
        records = (yield Round(response_scenes(p.base), folder="response", keep=lambda sc: False, label="",
                               then=True)) if m is not None else None
        drawn = _drawn(p, m, why, records)
        m, why, response, draws, combined, inputs, verdict = drawn
        out = yield Inputs(tuple(_tables(p, combined, inputs, draws)), {"uncertainty_input.json": {
            "digest": self.digest(p), "scatter": p.scatter, "samples": p.samples, "seed": p.seed}})
        for name, rows, table in (("combined", combined, "combined.csv"), ("inputs", inputs, "inputs.csv")):
            if rows is None:
                continue
            spec = ({"base": dict(p.base), "table": {"file": str((out / table).resolve())}} if p.keys or name ==
                    "combined" else {"base": dict(p.base), "grid": {RESISTANCE: [1.0]}})
            st = sweep.SweepStudy()
            yield Sub(st, st.plan(spec), name, label=name)
        return drawn

    def result(self, p: Plan, records: list, info) -> dict:
        from fepen.studies import uncertainty_report as ur

        m, why, response, draws, combined, inputs, verdict = info.found
        return {**ur.results(p, p.scene, info.out, m, why, response, draws, combined, inputs, verdict, info.wall_s,
                             info.ranks, info.ranks_per_shot), "_out": info.out}

    def report(self, result: dict) -> str:
        from fepen.studies import uncertainty_report as ur

        return ur.report(result)

    def pictures(self, p: Plan, result: dict, info) -> list:
        from fepen.post import study_figures
        from fepen.studies import uncertainty_report as ur

        combined, inputs, out = info.found[4], info.found[5], info.out
        return [Picture("uncertainty.png", (17, 4.8), lambda fig: study_figures.uncertainty(
            fig, result, ur.depths(out, combined, inputs), ur.fans(out, combined, inputs)))]

    def lines(self, result: dict) -> list[str]:
        from fepen.studies import uncertainty_report as ur

        return ur.lines(result, result["_out"])

def study(p: Plan, out, comm=None, ranks_per_shot: int = 1, fresh: bool = False, say=print,
          progress: bool = True) -> dict:
    """Run the study of a Plan (Uncertainty) and write OUT/uncertainty.json, uncertainty.md, uncertainty.png.

    Returns:
        The content of uncertainty.json (every rank).
    """
    from fepen.studies import study as fstudy

    res = fstudy.run(Uncertainty(), p, out, comm, ranks_per_shot, fresh, say, progress)
    return {k: v for k, v in res.items() if k != "ran"}


def _drawn(p: Plan, m, why, records) -> tuple:
    """What the study draws, the same on every rank: (the ErrorModel or None, why none, the Response, the draws
    with their "lambda", the combined sample's rows, the input scatter's rows, the envelope's verdict), from the
    response shots' records (None without a model)."""
    from fepen.runs import setup
    from fepen.stats import envelope
    from fepen.studies.resistance import response_of

    sc = p.scene
    verdict = envelope.verdict(setup.envelope_facts(sc, setup.check_supported(sc)))
    verdict["line"] = envelope.line(verdict)
    response = draws = None
    if m is not None:
        response = response_of(records)
        speeds = [s.get("impact.velocity", sc.impact.velocity) for s in p.inputs]
        draws = draw_model_errors(m, speeds, p.seed)
        draws["speed_m_s"] = np.array(speeds, float)
        draws["lambda"] = np.clip(response.inverse(np.exp(draws["eps"])), *LAMBDA_BOUNDS)
    combined = [{**s, RESISTANCE: float(draws["lambda"][i])} for i, s in enumerate(p.inputs)] \
        if m is not None else None
    inputs = (p.inputs if p.keys else [{}]) if (m is None or p.rigid) else None
    return m, why, response, draws, combined, inputs, verdict


def _tables(p: Plan, combined, inputs, draws) -> list:
    """combined.csv, model_draws.csv, inputs.csv: the record of what was drawn (each number the digits of its
    double)."""
    out = []
    if combined is not None:
        out.append(Table("combined.csv", [*p.keys, RESISTANCE], combined, digits=None))
        rows = [{"shot": i, "speed_m_s": float(draws["speed_m_s"][i]), "b": float(draws["b"][i]),
                 "e": float(draws["e"][i]), "eps": float(draws["eps"][i]), "sigma": float(draws["sigma"][i]),
                 RESISTANCE: float(draws["lambda"][i])} for i in range(len(combined))]
        out.append(Table("model_draws.csv", list(rows[0]), rows, digits=None))
    if inputs is not None and p.keys:
        out.append(Table("inputs.csv", p.keys, inputs, digits=None))
    return out
