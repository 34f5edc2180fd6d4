"""The uncertainty study's result and outputs (fepen.studies.uncertainty): the samples' depths and perforations
from their records, the probabilities with their Wilson and systematic intervals, uncertainty.json's content, the
lines the command prints and uncertainty.md."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from fepen.stats.sampling import conditional_probability, depth_quantiles, designer_flags, wilson
from fepen.studies.resistance import LAMBDA_BOUNDS

__all__ = ["results", "depths", "fans", "lines", "report", "B_LEVELS", "PATHS"]

#: the points of b's distribution of the systematic band
B_LEVELS = (0.1, 0.9)
#: the path and attitude figures whose 10, 50 and 90 % points the study reports (Hz_mm, Tz_mm: across the plane
#: of fire)
PATHS = ("final_axis_angle_deg", "nose_offset_mm", "Hx_mm", "Hy_mm", "Tx_mm", "Ty_mm", "Hz_mm", "Tz_mm")


def _records(out: Path, n: int) -> list:
    from fepen.studies import engine

    recs = engine.read_records(out)
    return [recs.get(i) for i in range(n)]


def _sample_result(records: list, thickness: float | None, layers: list | None,
                   beyond_deg: float = 10.0) -> dict:
    """Depths (mm), perforation flags (slab and per layer), the designer's flags (designer_flags), the path
    figures (PATHS) and statuses of a sample's records."""
    statuses, depth, perf, per_layer, summaries = {}, [], [], [], []
    for r in records:
        statuses[r["status"]] = statuses.get(r["status"], 0) + 1
        s = r.get("summary") if r["status"] == "ok" else None
        summaries.append(s)
        depth.append((np.inf if s["outcome"] == "perforated" else s["depth_mm"]) if s else np.nan)
        perf.append(float(s["outcome"] == "perforated") if s else np.nan)
        if layers:
            ls = (s or {}).get("layers") or []
            per_layer.append([float(j < len(ls) and ls[j].get("exit_speed_m_s") is not None) if s else np.nan
                              for j in range(len(layers))])
    paths = {q: np.array([(s.get(q, np.nan) if s else np.nan) for s in summaries], float) for q in PATHS}
    return {"statuses": statuses, "depth_mm": np.array(depth), "perforated": np.array(perf),
            "layers": np.array(per_layer) if layers else None, "flags": designer_flags(summaries, beyond_deg),
            "paths": paths}


def _probability(flags, draws=None, model=None, word: str = "perforated") -> dict:
    """P, its Wilson interval and (with the draws) the systematic band, of the finite 0/1 flags (word: the key of
    their count)."""
    ok = np.isfinite(flags)
    x, n = int(flags[ok].sum()), int(ok.sum())
    if n == 0:
        return {"shots": 0}
    lo, hi = wilson(x, n)
    out = {word: x, "shots": n, "probability": x / n, "wilson95": [lo, hi]}
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


def fans(out: Path, combined, inputs) -> dict:
    """{sample name: one (Hx, Hy, Tx, Ty, Hz, Tz) in mm per shot with a result}: the fan of final bodies."""
    d = {}
    for name, rows in (("combined", combined), ("inputs", inputs)):
        if rows is not None:
            p = _sample_result(_records(out / name, len(rows)), None, None)["paths"]
            f = np.column_stack([p[q] for q in ("Hx_mm", "Hy_mm", "Tx_mm", "Ty_mm", "Hz_mm", "Tz_mm")])
            d[name] = f[np.isfinite(f[:, :4]).all(axis=1)]
    return d


def depths(out: Path, combined, inputs) -> dict:
    """The depth (mm) arrays of the figure, by sample name."""
    d = {}
    for name, rows in (("combined", combined), ("inputs", inputs)):
        if rows is not None:
            d[name] = _sample_result(_records(out / name, len(rows)), None, None)["depth_mm"]
    return d


def _test(shot) -> dict | None:
    """The Table 1 test's depth and path figures (PATHS it measured), or None."""
    if shot is None:
        return None
    from fepen.studies.bands import test_values

    t = test_values(shot.name)
    return {"shot": shot.name, "depth_mm": shot.Hy_mm, **{q: t[q] for q in PATHS if q in t}}


def results(p, sc, out, m, why, response, draws, combined, inputs, verdict, wall, ranks, k) -> dict:
    """uncertainty.json's content."""
    thickness, layers = sc.get("target.thickness"), sc.get("target.layers")
    res = {"scene": {"label": p.label, "fidelity": sc.effects.fidelity, "base": p.base,
                     "test": _test(p.shot)},
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
        s = _sample_result(_records(out / name, len(rows)), thickness, layers, p.axis_beyond_deg)
        entry = {"shots": len(rows), "statuses": s["statuses"], "depth": depth_quantiles(s["depth_mm"])}
        model = (draws, m) if name == "combined" else (None, None)
        entry["paths"] = {q: ({f"P{c}": float(np.percentile(v[np.isfinite(v)], c)) for c in (10, 50, 90)}
                              if np.isfinite(v).any() else None) for q, v in s["paths"].items()}
        entry["ricochet"] = _probability(s["flags"]["ricochet"], *model, word="ricochets")
        entry["axis_beyond"] = {"angle_deg": p.axis_beyond_deg,
                                **_probability(s["flags"]["axis_beyond"], *model, word="beyond")}
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
def _count(e: dict) -> int:
    """The count of a probability's entry (perforated, ricochets or beyond)."""
    return next(e[k] for k in ("perforated", "ricochets", "beyond") if k in e)


def _fmt_p(e: dict) -> str:
    lo, hi = e["wilson95"]
    text = f"{e['probability']:.3f} ({_count(e)}/{e['shots']}; Wilson 95 % {lo:.3f}-{hi:.3f})"
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
    for name, what in (("combined", "inputs and model"), ("inputs", "inputs alone")):
        e = res["samples"].get(name)
        if e is None or not e.get("paths") or not e["paths"].get("final_axis_angle_deg"):
            continue
        a, o = e["paths"]["final_axis_angle_deg"], e["paths"]["nose_offset_mm"]
        out_lines.append(f"final axis ({what}): P10 {a['P10']:.1f}, P50 {a['P50']:.1f}, P90 {a['P90']:.1f} deg; "
                         f"nose offset P10 {o['P10']:.0f}, P50 {o['P50']:.0f}, P90 {o['P90']:.0f} mm")
    if res["scene"]["test"]:
        t = res["scene"]["test"]
        out_lines.append(f"the test {t['shot']}: {t['depth_mm']:.1f} mm"
                         + (f", final axis {t['final_axis_angle_deg']:.1f} deg, nose offset "
                            f"{t['nose_offset_mm']:.0f} mm" if "final_axis_angle_deg" in t else ""))
    for name, what in (("combined", "inputs and model"), ("inputs", "inputs alone")):
        e = res["samples"].get(name)
        if e is None:
            continue
        if e.get("ricochet", {}).get("shots"):
            out_lines.append(f"P(ricochet, {what}) {_fmt_p(e['ricochet'])}")
        if e.get("axis_beyond", {}).get("shots"):
            out_lines.append(f"P(|final axis| > {e['axis_beyond']['angle_deg']:g} deg, {what}) "
                             f"{_fmt_p(e['axis_beyond'])}")
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
    return out_lines


def _paths_table(res: dict) -> list[str]:
    """uncertainty.md's table of the paths' and attitudes' 10, 50 and 90 % points."""
    sc, L = res["scene"], []
    paths = [(name, e) for name, e in res["samples"].items() if name != "note" and e.get("paths")]
    if paths:
        t = sc["test"] or {}
        L += ["", "Paths and attitudes (10, 50 and 90 % of the shots; Hz, Tz: the nose and the tail across the "
                  "plane of fire):", "", "| sample | figure | P10 | P50 | P90 | test |", "|---|---|---|---|---|---|"]
        for name, e in paths:
            for q, v in e["paths"].items():
                if v is not None:
                    L.append(f"| {name} | `{q}` | {v['P10']:.1f} | {v['P50']:.1f} | {v['P90']:.1f} | "
                             + (f"{t[q]:.1f} |" if q in t else "– |"))
    return L


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
    L += _paths_table(res)
    probs = [(name, "perforation of the target", e["perforation"]) for name, e in res["samples"].items()
             if name != "note" and "perforation" in e]
    probs += [(name, f"perforation of layer {lay['layer']}", lay) for name, e in res["samples"].items()
              if name != "note" for lay in e.get("layers", [])]
    probs += [(name, "ricochet", e["ricochet"]) for name, e in res["samples"].items()
              if name != "note" and "ricochet" in e]
    probs += [(name, f"final axis beyond {e['axis_beyond']['angle_deg']:g}°", e["axis_beyond"])
              for name, e in res["samples"].items() if name != "note" and "axis_beyond" in e]
    if probs:
        L += ["", "| sample | what | P | Wilson 95 % | P at b's 10 % | P at b's 90 % |",
              "|---|---|---|---|---|---|"]
        for name, what, e in probs:
            if not e.get("shots"):
                continue
            band = e.get("systematic", {}).get("probability")
            L.append(f"| {name} | {what} | {e['probability']:.3f} ({_count(e)}/{e['shots']}) | "
                     f"{e['wilson95'][0]:.3f}-{e['wilson95'][1]:.3f} | "
                     + (f"{band[0]:.3f} | {band[1]:.3f} |" if band else "– | – |"))
        L += ["", "Wilson 95 %: the score interval of the sampling (Wilson 1927). The systematic band: P(event "
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
