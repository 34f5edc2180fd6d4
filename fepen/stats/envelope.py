"""The validated envelope: the ranges of the public shots fepen's laws were checked on (docs/uncertainty.md),
and whether a scene lies inside them.

The ranges are read from fepen/data/prediction_errors.csv (fepen.studies.prediction_errors): for the depth, the
shots of every shipped public set and Table 1, per concrete strength law. A scene is inside when every
dimension of DIMENSIONS lies within the range of the shots of its law and every condition of ``_conditions``
holds (a concrete target of one material, an ogive nose, a law with errors, no layers, no slab of finite
thickness, the projectile's steel of Table 1 for a deformable fidelity). Outside, the verdict names each
dimension, its value and how far it lies beyond the range.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

__all__ = ["Dimension", "DIMENSIONS", "KEYS", "LAWS", "ranges", "verdict", "line", "markdown"]


@dataclass(frozen=True)
class Dimension:
    """One dimension of the envelope.

    Attributes:
        name: what it is, in words. column: the prediction-error table's column. unit: the unit shown.
        scale: the table's SI value times scale is in ``unit``. relative: distances beyond the range as a
        percentage of the range's end (False: in ``unit``, for ranges that start at 0).
    """

    name: str
    column: str
    unit: str
    scale: float = 1.0
    relative: bool = True


DIMENSIONS = (
    Dimension("calibre", "D_m", "mm", 1e3),
    Dimension("length over calibre", "L_over_D", ""),
    Dimension("ogive CRH", "crh", ""),
    Dimension("projectile mass", "mass_kg", "kg"),
    Dimension("striking speed", "V_m_s", "m/s"),
    Dimension("concrete strength f_c (cylinder)", "fc_cylinder_Pa", "MPa", 1e-6),
    Dimension("concrete density", "rho_kg_m3", "kg/m^3"),
    Dimension("obliquity", "obliquity_deg", "deg", relative=False),
    Dimension("angle of attack", "attack_deg", "deg", relative=False),
)


@functools.lru_cache(maxsize=8)
def ranges(law: str = "scaled-S", quantity: str = "depth") -> dict:
    """{column: (low, high)} in SI over the shots with errors of this law, plus "shots" and "sets"."""
    from fepen.data import prediction_errors

    rows = [r for r in prediction_errors.read() if r["law"] == law and r["quantity"] == quantity
            and r["fidelity"] == "rigid"]
    if not rows:
        return {}
    out = {d.column: (min(r[d.column] for r in rows), max(r[d.column] for r in rows)) for d in DIMENSIONS}
    out["shots"], out["sets"] = len(rows), len({r["set"] for r in rows})
    return out


def _beyond(d: Dimension, value: float, lo: float, hi: float) -> str | None:
    """How far value lies beyond [lo, hi], in words (None inside; a relative tolerance of 1e-9)."""
    tol = 1e-9 * max(abs(lo), abs(hi), 1e-30)
    if lo - tol <= value <= hi + tol:
        return None
    side, end = ("above", hi) if value > hi else ("below", lo)
    if d.relative and end != 0.0:
        return f"{100.0 * abs(value / end - 1.0):.3g} % {side}"
    return f"{abs(value - end) * d.scale:.3g} {d.unit} {side}".replace("  ", " ")


def _fmt(d: Dimension, v: float) -> str:
    return f"{v * d.scale:.4g}"


def _conditions(facts: dict) -> list[dict]:
    """What lies outside for a reason other than a range: the target, the nose, the law, the fidelity's steel."""
    out = []
    law = facts["law"]
    if facts["target"] != "concrete":
        out.append({"dimension": "target", "key": "target.material", "value": facts["target"],
                    "range": "one concrete block", "by": "no public depth data"})
    elif not ranges(law):
        out.append({"dimension": "strength law", "key": "target.strength_model", "value": law,
                    "range": ", ".join(LAWS), "by": "no errors on public data"})
    if facts["nose"] != "ogive":
        out.append({"dimension": "nose", "key": "projectile.nose", "value": facts["nose"],
                    "range": "tangent ogive", "by": "every public shot has an ogive nose"})
    if facts["thickness_m"] is not None:
        out.append({"dimension": "target thickness", "key": "target.thickness",
                    "value": f"{1e3 * facts['thickness_m']:.4g} mm", "range": "thick targets",
                    "by": "the depth data are of targets the shots did not perforate"})
    A, A0 = facts["steel_A_Pa"], facts["reference_A_Pa"]
    if facts["fidelity"] != "rigid" and abs(A / A0 - 1.0) > 1e-9:
        out.append({"dimension": "steel yield stress A (deformable fidelity)", "key": "projectile.material.A",
                    "value": f"{A * 1e-6:.4g} MPa", "range": f"{A0 * 1e-6:.4g} MPa (Table 1's steel)",
                    "by": f"{100.0 * abs(A / A0 - 1.0):.3g} % {'above' if A > A0 else 'below'}"})
    return out


#: the scene key of each dimension (a verdict names it)
KEYS = {"D_m": "projectile.diameter", "L_over_D": "projectile.length", "crh": "projectile.crh",
        "mass_kg": "projectile.mass", "V_m_s": "impact.velocity", "fc_cylinder_Pa": "target.compressive_strength",
        "rho_kg_m3": "target.density", "obliquity_deg": "impact.obliquity_deg", "attack_deg": "impact.attack_deg"}
#: the laws with errors on public data (fepen.studies.prediction_errors.LAWS)
LAWS = ("scaled-S", "forrestal-S")


def verdict(facts: dict) -> dict:
    """Whether a shot lies inside the validated envelope of its law.

    Args:
        facts: what the envelope looks at (fepen.runs.setup.envelope_facts): "law" (target.strength_model),
            "target" ("concrete", another target.material, "layered" or "a rigid wall"), "nose", "thickness_m"
            (None: semi-infinite), "fidelity", "steel_A_Pa" and "reference_A_Pa" (Table 1's steel), and
            "values": {column of DIMENSIONS: SI value}.

    Returns:
        {"inside": bool, "law", "checked_on": "171 shots in 13 public sets", "outside": [{"dimension", "key",
        "value", "range", "by"}, ...]} (outside empty when inside).
    """
    law = facts["law"]
    outside = _conditions(facts)
    r = ranges(law)
    if r and facts["target"] == "concrete":
        for d in DIMENSIONS:
            if d.column == "crh" and facts["nose"] != "ogive":
                continue
            lo, hi = r[d.column]
            value = facts["values"].get(d.column)
            if value is None:  # not known before the body is built (a mass from a CAD body)
                continue
            by = _beyond(d, value, lo, hi)
            if by is not None:
                unit = f" {d.unit}" if d.unit else ""
                end = hi if value > hi else lo
                outside.append({"dimension": d.name, "key": KEYS[d.column], "value": f"{_fmt(d, value)}{unit}",
                                "range": f"{_fmt(d, lo)}-{_fmt(d, hi)}{unit}", "by": by,
                                "factor": abs(value / end) if end != 0.0 and value != 0.0 else math.inf})
    checked = f"{r['shots']} shots in {r['sets']} public sets" if r else "no public data"
    return {"inside": not outside, "law": law, "checked_on": checked, "outside": outside}


#: a value this many times beyond its checked range (either way) is more likely a unit slip than a design
UNIT_SLIP = 10.0


def unit_slips(v: dict) -> list[str]:
    """One warning per value UNIT_SLIP times or more beyond its checked range, naming its key: a km/s typed for
    m/s, mm for m (verdict's "outside")."""
    out = []
    for o in v["outside"]:
        f = o.get("factor")
        if f is not None and (f >= UNIT_SLIP or f <= 1.0 / UNIT_SLIP):
            times = f if f >= 1.0 else 1.0 / f
            out.append(f"{o['key']}: {o['value']} is {times:.3g} times {'above' if f >= 1.0 else 'below'} the "
                       f"{o['range']} checked: a unit slip? (scene keys are in SI: m, kg, m/s, Pa)")
    return out


def line(v: dict) -> str:
    """The verdict in one line."""
    if v["inside"]:
        return f"inside the validated envelope ({v['law']} law: {v['checked_on']})"
    parts = [f"{o['dimension']} {o['value']} is {o['by']} the {o['range']} checked" if o["by"][:1].isdigit()
             else f"{o['dimension']} {o['value']}: {o['by']} ({o['range']})" for o in v["outside"]]
    return "outside the validated envelope: " + "; ".join(parts)


def markdown(law: str = "scaled-S", laws=None) -> str:
    """The envelope of a law as a Markdown table (docs/uncertainty.md; ``fepen envelope``); ``laws``: the laws
    that share it, named in its first line."""
    r = ranges(law)
    names = " and ".join(f"`{x}`" for x in (laws or [law]))
    lines = [f"{'Laws' if laws and len(laws) > 1 else 'Law'} {names}: {r['shots']} shots in {r['sets']} public sets "
             "(fepen/data/prediction_errors.csv).", "",
             "| dimension | low | high | unit |", "|---|---|---|---|"]
    for d in DIMENSIONS:
        lo, hi = r[d.column]
        lines.append(f"| {d.name} | {_fmt(d, lo)} | {_fmt(d, hi)} | {d.unit} |")
    return "\n".join(lines) + "\n"
