"""``fepen validate --samples N [--seed S]``: Table 1's shots as the distributions they are (issue 59). Each shot
runs N members whose unmeasured inputs are drawn from their declared distributions (fepen.stats.striking: the yaw
out of the plane of fire, the recorded attack's reading error, the angular rates, the speed and obliquity errors,
the concrete's random field); the members are rigid shots batched on the one executor, or deformable ones (--set
effects.fidelity=plastic, on a subset of the shots with --shots) one per rank. For each shot and
quantity the 10, 50 and 90 % points of its members, the test's value and whether it lies inside.

Writes to DIR: bands.csv (shot, quantity, p10, p50, p90, test, inside), bands.md (the table, coverage and the
bands' widths) and bands.png (each shot's fan of final nose and tail positions with the test's marked).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fepen import scene as fscene
from fepen.data import SHOTS
from fepen.errors import InputError
from fepen.stats import striking
from fepen.studies.products import Picture, Table
from fepen.studies.study import Round, Study, register

__all__ = ["Bands", "QUANTITIES", "FIELDS", "STRIKING_KEYS", "band_rows", "test_values", "striking_inputs",
           "median_errors"]

#: the quantities banded, each with the test's value (test_values)
QUANTITIES = ("Hx_mm", "Hy_mm", "Tx_mm", "Ty_mm", "final_axis_angle_deg", "nose_offset_mm", "depth_mm")
#: bands.csv's columns
FIELDS = ("shot", "quantity", "p10", "p50", "p90", "test", "inside")
#: the most members a shot's ensemble may have
MAX_SAMPLES = 10000


@dataclass
class BandsPlan:
    """The base scene's --set lines, the members' scenes by shot, the prior, the seed."""

    sets: tuple
    members: dict
    prior: striking.StrikingPrior
    seed: int


#: the keys the striking draw sets besides the speed and the angles a scatter file may vary
STRIKING_KEYS = ("impact.attack_plane_deg", "impact.pitch_rate_rad_s", "impact.yaw_rate_rad_s",
                 "target.heterogeneity_cv", "target.heterogeneity_length", "target.heterogeneity_seed")


def striking_inputs(resolved: fscene.Scene, keys: list, inputs: list, seed: int) -> tuple[list, list]:
    """Each sample's inputs with the unmeasured striking state and the concrete's field drawn on top
    (fepen.stats.striking: the sample's speed, obliquity and attack are its recorded values; generator
    member_rng(seed, "striking", i), apart from the scatter's).

    Returns:
        (keys, inputs) with the drawn keys.
    """

    from fepen.stats import striking as fstriking

    clash = [k for k in keys if k in STRIKING_KEYS]
    if clash:
        raise InputError("--striking", f"draws {clash[0]} itself; leave it out of the --scatter file's vary")
    from fepen.runs import targets

    prior = targets.of(resolved).striking_prior(fstriking.PRIOR)  # the field lives in one concrete
    out = []
    for i, s in enumerate(inputs):
        v, ob, at = (s[k] if k in s else resolved.get(k) for k in ("impact.velocity", "impact.obliquity_deg",
                                                                     "impact.attack_deg"))
        d = fstriking.draw(prior, v, ob, at, fstriking.member_rng(seed, "striking", i))
        out.append({**s, **d})
    return list(dict.fromkeys([*keys, *out[0]])) if out else keys, out


def test_values(name: str) -> dict:
    """Table 1's values of QUANTITIES for one shot (its final axis atan2(Hx − Tx, Hy − Ty), its nose offset from
    the line of fire, its depth the nose's Hy)."""
    from fepen.io.results import final_axis_deg, nose_offset_mm

    e = SHOTS[name]
    return {"Hx_mm": e.Hx_mm, "Hy_mm": e.Hy_mm, "Tx_mm": e.Tx_mm, "Ty_mm": e.Ty_mm,
            "final_axis_angle_deg": float(final_axis_deg(e.Hx_mm, e.Hy_mm, e.Tx_mm, e.Ty_mm)),
            "nose_offset_mm": nose_offset_mm(e.Hx_mm, e.Hy_mm, e.obliquity_deg), "depth_mm": e.Hy_mm}


def band_rows(values: dict, tests: dict) -> list[dict]:
    """bands.csv's rows of one shot: {quantity: members' values} and {quantity: the test's} in, FIELDS out."""
    rows = []
    for q in QUANTITIES:
        p10, p50, p90 = (float(v) for v in np.percentile(np.asarray(values[q], dtype=float), [10.0, 50.0, 90.0]))
        t = tests[q]
        rows.append({"p10": p10, "p50": p50, "p90": p90, "test": t, "inside": bool(p10 <= t <= p90), "quantity": q})
    return rows


@register
class Bands(Study):
    """Table 1's shots as ensembles over their unmeasured inputs (module docstring)."""

    name = "validate-bands"
    command = ""  # fepen validate --samples N
    help = "Table 1's shots as ensembles: bands.csv, bands.md, bands.png"
    names = ("shots.jsonl", "shots", "bands.csv", "bands.md", "bands.png")
    out = "results/validation-bands"

    def plan(self, scene_path=None, sets=(), samples: int = 200, seed: int = 0,
             prior: striking.StrikingPrior = striking.PRIOR, shots=None) -> BandsPlan:
        """The members' scenes of each shot (all of Table 1, or ``shots``: names), rigid unless --set
        effects.fidelity says otherwise; InputError before anything runs."""
        if not 1 <= samples <= MAX_SAMPLES:
            raise InputError("--samples", f"got {samples}, expected an integer in [1, {MAX_SAMPLES}]")
        if not 0 <= seed < 2**32:
            raise InputError("--seed", f"got {seed}, expected an integer in [0, 2^32)")
        for s in sets:
            key = s.split("=")[0].strip()
            if key.startswith("impact.") or key.startswith("target.heterogeneity_"):
                raise InputError(key, "validate --samples draws impact.* and target.heterogeneity_* for each member "
                                      "(docs/uncertainty.md); drop this --set")
        names = list(SHOTS) if not shots else list(dict.fromkeys(shots))
        for name in names:
            if name not in SHOTS:
                raise InputError("--shots", f"got {name!r}, expected names of Table 1's shots ({', '.join(SHOTS)})")
        base = fscene.load(scene_path, ["effects.fidelity=rigid", *sets])  # a bad --set here, once
        # a deformable member keeps its folder (shots/NNNNN: its summary, history and log), not its fields
        quiet = [] if base.effects.fidelity == "rigid" else ["run.fields=false", "run.figures=false"]
        members = {}
        for name in names:
            e = SHOTS[name]
            members[name] = [fscene.load(scene_path, [
                "effects.fidelity=rigid", *quiet, *sets, *[f"{k}={v!r}" for k, v in striking.draw(
                    prior, e.v0, e.obliquity_deg, e.attack_deg, striking.member_rng(seed, name, i)).items()]])
                for i in range(samples)]
        return BandsPlan(tuple(sets), members, prior, seed)

    def fidelity(self, plan: BandsPlan) -> str:
        """The members' fidelity."""
        return next(iter(plan.members.values()))[0].effects.fidelity

    def digest(self, plan: BandsPlan) -> str:
        from fepen.studies.record import canonical_digest

        return canonical_digest(plan.sets, plan.prior, plan.seed, {k: len(v) for k, v in plan.members.items()})

    def rounds(self, plan: BandsPlan):
        scenes = [sc for shots in plan.members.values() for sc in shots]
        yield Round(scenes, keep=lambda sc: sc.effects.fidelity != "rigid", label="members")

    def result(self, plan: BandsPlan, records: list, info) -> dict:
        rows, fans, i = [], {}, 0
        for name, shots in plan.members.items():
            values = {q: [] for q in QUANTITIES}
            fan = []
            for _ in shots:
                rec = records[0][i]
                i += 1
                if rec["status"] != "ok":
                    raise InputError("validate", f"a member of {name} did not finish ({rec['status']}: "
                                                 f"{rec['message']})")
                s = rec["summary"]
                for q in QUANTITIES:
                    values[q].append(s[q])
                fan.append((s["Hx_mm"], s["Hy_mm"], s["Tx_mm"], s["Ty_mm"], s.get("Hz_mm", 0.0), s.get("Tz_mm", 0.0)))
            rows += [{"shot": name, **r} for r in band_rows(values, test_values(name))]
            fans[name] = fan
        return {"rows": rows, "samples": len(next(iter(plan.members.values()))), "seed": plan.seed,
                "prior": plan.prior.__dict__, "fidelity": self.fidelity(plan), "_fans": fans}

    def document(self, plan: BandsPlan, result: dict, info) -> None:
        return None

    def tables(self, plan: BandsPlan, result: dict, info) -> list:
        return [Table("bands.csv", FIELDS, result["rows"])]

    def texts(self, plan: BandsPlan, result: dict, info) -> dict:
        return {"bands.md": report(result)}

    def pictures(self, plan: BandsPlan, result: dict, info) -> list:
        from fepen.post import study_figures

        fans = result["_fans"]
        return [Picture("bands.png", (15, 6.5),
                        lambda fig: study_figures.fans(fig, fans, {n: test_values(n) for n in fans}), 110)]

    def lines(self, result: dict) -> list[str]:
        return summary_lines(result)


def coverage(rows: list[dict]) -> dict:
    """{quantity: (shots inside their band, shots)}."""
    out = {}
    for q in QUANTITIES:
        qs = [r for r in rows if r["quantity"] == q]
        out[q] = (sum(bool(r["inside"]) for r in qs), len(qs))
    return out


def median_errors(rows: list[dict]) -> dict:
    """{shot: (nose error, tail error)} of the members' medians (p50 of Hx, Hy, Tx, Ty) against the test, as
    fepen.io.results.comparison measures a run's: |H − H_test| / |H_test|."""
    out = {}
    for name in dict.fromkeys(r["shot"] for r in rows):
        v = {r["quantity"]: r for r in rows if r["shot"] == name}
        e = []
        for a, b in (("Hx_mm", "Hy_mm"), ("Tx_mm", "Ty_mm")):
            got = np.array([v[a]["p50"], v[b]["p50"]])
            want = np.array([v[a]["test"], v[b]["test"]])
            e.append(float(np.linalg.norm(got - want) / np.linalg.norm(want)))
        out[name] = tuple(e)
    return out


def summary_lines(result: dict) -> list[str]:
    rows = result["rows"]
    cov = coverage(rows)
    width = {r["shot"]: r["p90"] - r["p10"] for r in rows if r["quantity"] == "final_axis_angle_deg"}
    med = np.array(list(median_errors(rows).values()))
    return [f"{result['samples']} members per shot (seed {result['seed']}): the test inside its 10-90 % band on "
            + ", ".join(f"{q} {a} of {b}" for q, (a, b) in cov.items()),
            "final axis band widths: " + ", ".join(f"{k} {v:.1f}" for k, v in width.items())
            + f" deg (mean {np.mean(list(width.values())):.1f})",
            f"the members' medians: mean nose error {100 * med[:, 0].mean():.1f} %, mean tail error "
            f"{100 * med[:, 1].mean():.1f} %"]


def report(result: dict) -> str:
    """bands.md: the bands per shot and quantity, the coverage and the widths."""
    p = result["prior"]
    lines = [f"# Table 1 as distributions: {result['samples']} {result.get('fidelity', 'rigid')} members per shot, "
             f"seed {result['seed']}", "",
             f"Drawn per member (docs/uncertainty.md): yaw out of the plane of fire N(0, {p['yaw_deg']:g}°); the "
             f"recorded in-plane attack's error N(0, {p['attack_error_deg']:g}°); pitch and yaw rates "
             f"N(0, {p['rate_rad_s']:g} rad/s); the speed's error {100 * p['speed_fraction']:g} %; the "
             f"obliquity's error N(0, {p['obliquity_error_deg']:g}°); the concrete's random field on σ_s, cv "
             f"{p['concrete_cv']:g}, correlation length {1e3 * p['concrete_length_m']:g} mm, a seed per member.", "",
             "| shot | quantity | 10 % | 50 % | 90 % | test | inside |", "|---|---|---|---|---|---|---|"]
    for r in result["rows"]:
        lines.append(f"| {r['shot']} | {r['quantity']} | {r['p10']:.1f} | {r['p50']:.1f} | {r['p90']:.1f} | "
                     f"{r['test']:.1f} | {'yes' if r['inside'] else 'no'} |")
    lines += ["", *summary_lines(result), ""]
    return "\n".join(lines)
