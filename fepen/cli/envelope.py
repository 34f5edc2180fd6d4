"""``fepen envelope [SCENE.toml] [--set KEY=VALUE ...]``: the validated envelope of fepen's concrete laws, the
statistical model of their errors and its leave-one-set-out coverage (docs/uncertainty.md); with a scene, its
verdict and the interval it would get, before anything is run."""

from __future__ import annotations

import math

from fepen.cli.common import say, set_argument

HELP = "the validated envelope, the error model and its coverage; with a scene: its verdict (docs/uncertainty.md)"


def add_arguments(parser) -> None:
    parser.add_argument("scene", nargs="?", help="a scene to judge (absent, and no --set: the tables)")
    set_argument(parser, "override a scene key of the scene judged")


def run(args) -> int:
    """Print the tables, or one scene's verdict and interval factors."""
    if args.scene is None and not args.sets:
        say(tables())
        return 0
    from fepen import scene as fscene
    from fepen.runs import setup
    from fepen.stats import envelope, interval

    sc = fscene.load(args.scene, args.sets)
    built = setup.check_supported(sc, meshes=False)  # judges the scene, meshes nothing: no mesh budget
    facts = setup.envelope_facts(sc, built)
    v = envelope.verdict(facts)
    lines = [envelope.line(v)]
    m = interval.model("depth", facts["law"], "rigid") if facts["target"] == "concrete" else None
    if m is not None:
        speed = facts["values"]["V_m_s"]
        lo, hi = (f"{100 * (math.exp(b) - 1):+.0f} %" for b in m.log_bounds(speed))
        lines.append(f"depth interval (10-90 %): the predicted depth {lo} to {hi} ({m.basis(speed)})")
    else:
        lines.append("depth interval: none (no errors on public data for this target and law)")
    say(*lines)
    return 0


def tables() -> str:
    """The envelope of each law, the error models and the coverage tables (Markdown): what docs/uncertainty.md
    shows between its ``fepen envelope`` markers."""
    from fepen.data import prediction_errors
    from fepen.stats import envelope, interval

    rows = prediction_errors.read()
    laws = [law for law in envelope.LAWS if envelope.ranges(law)]
    same = all(envelope.ranges(law) == envelope.ranges(laws[0]) for law in laws)
    parts = ["### The validated envelope", ""]
    parts += [envelope.markdown(laws[0], laws if same else None)] if same else [envelope.markdown(law) for law in laws]
    models = [interval.model("depth", law, "rigid") for law in laws]
    models += [m for m in (interval.model("lateral", "scaled-S", f) for f in ("rigid", "plastic")) if m is not None]
    parts += ["### The error model", "", interval.model_markdown(models)]
    for law in envelope.LAWS:
        parts += [f"### Leave-one-set-out coverage of the depth interval, {law} law", "",
                  interval.coverage_markdown(interval.coverage(rows, law))]
    for fid in ("rigid", "plastic"):
        cov = interval.lateral_coverage(rows, fid)
        if cov:
            parts += [f"### Leave-one-shot-out coverage of the sideways-travel interval, {fid} fidelity", "",
                      "| shot | predicted Hx (mm) | measured (mm) | interval (mm) | inside |", "|---|---|---|---|---|"]
            parts += [f"| {c['shot']} | {1e3 * c['predicted_m']:.1f} | {1e3 * c['measured_m']:.1f} | "
                      f"{1e3 * c['low_m']:.1f} to {1e3 * c['high_m']:.1f} | {'yes' if c['inside'] else 'no'} |"
                      for c in cov]
            parts += [f"| **pooled** | | | | **{sum(c['inside'] for c in cov)} of {len(cov)}** |", ""]
    return "\n".join(parts).rstrip("\n") + "\n"
