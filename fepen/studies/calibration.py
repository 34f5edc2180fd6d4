"""The one calibration of the concrete law's open constants (docs/validation-depth.md, docs/validation.md):
the separation angle φ_min, the energy crater's crush strain ε, the free face's reach on σ_s, and the
"scaled-S" strength σ_s = a (f_c/MPa)^−b f_c / √(1 + D/D0), chosen together, once, by one procedure, on
Table 1's nose and tail positions and on the public depth sets of CALIBRATION_SETS, with the rigid fidelity
and everything else at fepen's defaults.

The procedure:
  1. every combination ("node") of the open constants' values in OPEN;
  2. for every node and every calibration shot, the rigid fidelity at the S = σ_s/f_c values S_SPAN times
     Forrestal's published S of the shot's strength (given through target.quasi_static_stress: the law is
     then the "scaled-S" law at that S exactly): Table 1's shots give their final nose and tail positions
     (Hx, Hy, Tx, Ty), the depth sets' shots their depth;
  3. each result interpolated in ln S between those runs (linearly; ln depth for the depth sets);
  4. at every node, b held at the published EXPONENT and (ln a, ln D0) minimising the objective: the mean over
     the groups of each group's mean error, so that each group counts once however many shots it has. Table
     1's error of a shot is the mean of its nose and tail errors |H − H_exp|/|H_exp| and its final axis's error
     (AXIS_WEIGHT_PER_DEG per degree; docs/validation.md);
     a depth set's is |ln(P_pred/P_meas)|. A grid, then Nelder–Mead;
  5. while the best node lies at the edge of the values searched in one of the open constants, the node one
     STEP beyond it in that constant (within LIMITS) is run and fitted too (a pattern search);
  6. the node with the smallest fitted objective, with its a and D0, is the calibration.

    .venv/bin/fepen study calibration [--data DIR] [--out DIR] [--set K=V]     (mpirun -n N: on N ranks)

Runs in about 10^4 rigid runs (docs/validation-depth.md gives the time), batched on the one executor; the runs'
records stay in OUT/rounds, so that the fit (seconds) is repeated from them when the study runs again.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fepen.io import results
from fepen.laws import target as tg
from fepen.studies import depth
from fepen.studies.study import Round, Study, register, set_option

__all__ = ["CALIBRATION_SETS", "OPEN", "STEP", "LIMITS", "S_SPAN", "EXPONENT", "nodes", "jobs", "job_scene",
           "table_of", "curves", "predicted", "group_errors", "objective", "fit", "calibrate", "shipped_node",
           "Calibration", "positions", "cylinder", "ok_summary"]

#: the calibration groups (file stems of fepen/data/depth; "table1" is the paper's Table 1, by its positions)
#: and what each informs
CALIBRATION_SETS = {
    "table1": "the paper's 8 shots, C40, 23.6 mm, 517-893 m/s, 0.4-20 deg: the nose and tail positions, the "
              "turning of the oblique paths (phi_min, crater, free face) and S at one size",
    "forrestal1994_d26.9mm": "f_c 32-108 MPa at one size (26.9 mm): S against f_c",
    "oneil1999": "f_c 155-163 MPa at 26.9 mm: S at very high strength",
    "forrestal1994_d76.2mm": "76.2 mm, 13 kg into 23 and 39 MPa: the size D0",
    "wu2020": "geometrically scaled 10-203 mm at one f_c and speed: the size D0",
}
#: the exponent b of f_c, held at Frew, Hanchak, Green and Forrestal's (1998) published value: the
#: calibration sets have no small-calibre shot below 32 MPa, where b matters most
EXPONENT = tg.S_MODELS["forrestal-S"][1]
#: the open constants and the values searched: the scene key -> values
OPEN = {
    "target.separation_angle_deg": (0.0, 4.0, 8.0, 12.0),
    "target.crush_strain": (0.094, 0.188, 0.376),
    "target.free_surface_range": (1.0, 2.0, 3.0),
}
#: the step of the pattern search in each open constant (step 5; "x2" multiplies or divides) and its limits
STEP = {"target.separation_angle_deg": 4.0, "target.crush_strain": "x2", "target.free_surface_range": 1.0}
LIMITS = {"target.separation_angle_deg": (0.0, 30.0), "target.crush_strain": (0.003, 0.4),
          "target.free_surface_range": (1.0, 8.0)}
#: S = σ_s/f_c of the runs, as multiples of Forrestal's S = 82.6 (f_c/MPa)^−0.544 of the shot's strength
S_SPAN = np.geomspace(0.4, 2.5, 7)


def nodes(open_=None) -> list[dict]:
    """Every combination of the open constants' values: a list of {scene key: value}."""
    open_ = OPEN if open_ is None else open_
    return [dict(zip(open_, values)) for values in itertools.product(*open_.values())]


def _forrestal_S(row) -> float:
    return tg.forrestal_S(row.fc)


def _scene_sets(name: str, row) -> list[str]:
    """The rigid scene of one calibration shot: Table 1's shots as fepen runs them (the paper's projectile and
    target), the depth sets' by fepen.studies.depth.scene_sets."""
    if name == "table1":
        return ["effects.fidelity=rigid", f'impact.shot="{row.name}"']
    return depth.scene_sets(row)


def job_scene(job):
    """The rigid scene of one run of step 2: (group, row, S, node, extra)."""
    from fepen import scene

    name, row, S, node, extra = job
    return scene.load(None, [*_scene_sets(name, row), scene.set_item("target.quasi_static_stress", S * cylinder(row)),
                             *[scene.set_item(k, v) for k, v in node.items()], *extra])


def positions(summary: dict) -> tuple:
    """(Hx, Hy, Tx, Ty) (m) of one rigid run's summary."""
    return tuple(summary[k] / 1e3 for k in ("Hx_mm", "Hy_mm", "Tx_mm", "Ty_mm"))


def cylinder(row) -> float:
    """The shot's cylinder strength (Pa): the row's strength on its basis (the paper's Table 1: C40 cube)."""
    return row.fc_cylinder


def jobs(sets: dict, node_list: list[dict], extra=()) -> list[tuple]:
    """The runs of step 2, shot by shot (all nodes and S of one shot together): (group, row, S, node, extra)."""
    return [(name, row, Sr * _forrestal_S(_Row(row)), node, tuple(extra))
            for name, rows in sets.items() for row in rows for node in node_list for Sr in S_SPAN]


def table_of(sets: dict, node_list: list[dict], positions: list) -> np.ndarray:
    """The runs' (Hx, Hy, Tx, Ty) (in jobs()' order) as an object array [node][group] of arrays (shots,
    len(S_SPAN), 4) (m)."""
    res = np.array(positions).reshape(-1, len(node_list), len(S_SPAN), 4)
    table = np.empty((len(node_list), len(sets)), dtype=object)
    k = 0
    for j, rows in enumerate(sets.values()):
        for i in range(len(node_list)):
            table[i, j] = res[k:k + len(rows), i]
        k += len(rows)
    return table


def curves(sets: dict, node_list: list[dict], extra=(), comm=None) -> np.ndarray:
    """The runs of step 2 here and now (fepen.studies.engine.summaries: batched on the one executor), as
    table_of's array."""
    from fepen.studies import engine

    found = engine.summaries([job_scene(j) for j in jobs(sets, node_list, extra)], comm)
    return table_of(sets, node_list, [positions(s) for s in found])


class _Row:
    """A row seen with its cylinder strength (Forrestal's S and the scaled-S law take the cylinder f_c)."""

    def __init__(self, row):
        self.fc, self.D = cylinder(row), row.D


def strength_S(row, a: float, D0: float, b: float = EXPONENT) -> float:
    """S of the scaled-S law for this shot (its cylinder strength, its diameter)."""
    r = _Row(row)
    return tg.strength_S(r.fc, r.D, a, b, D0)


def predicted(rows, table: np.ndarray, a: float, D0: float, b: float = EXPONENT) -> np.ndarray:
    """(Hx, Hy, Tx, Ty) (m) of the shots under the scaled-S constants, interpolated in ln S (step 3): (shots, 4)."""
    out = np.empty((len(rows), 4))
    for i, row in enumerate(rows):
        grid = np.log(S_SPAN * _forrestal_S(_Row(row)))
        s = math.log(strength_S(row, a, D0, b))
        for q in range(4):
            c = table[i, :, q]
            out[i, q] = math.exp(np.interp(s, grid, np.log(c))) if q == 1 else np.interp(s, grid, c)
    return out


#: Table 1's final axis enters a shot's error at this weight per degree: one degree counts as 1 % of a
#: position (about 3 mm of Table 1's 300 mm), so a degree and a few millimetres count alike
AXIS_WEIGHT_PER_DEG = 0.01


def group_errors(name: str, rows, pred: np.ndarray) -> np.ndarray:
    """Each shot's error (step 4): Table 1's mean of its nose error, tail error and final-axis error (the axis
    AXIS_WEIGHT_PER_DEG per degree), a depth set's |ln(P_pred/P_meas)|."""
    if name == "table1":
        from fepen.data import SHOTS

        e = [SHOTS[r.name] for r in rows]
        H = np.array([(x.Hx_mm, x.Hy_mm) for x in e]) / 1e3
        T = np.array([(x.Tx_mm, x.Ty_mm) for x in e]) / 1e3
        P = np.abs(pred)
        nose = np.linalg.norm(P[:, :2] - H, axis=1) / np.linalg.norm(H, axis=1)
        tail = np.linalg.norm(P[:, 2:] - T, axis=1) / np.linalg.norm(T, axis=1)
        axis = np.abs(results.final_axis_deg(*P.T) - results.final_axis_deg(H[:, 0], H[:, 1], T[:, 0], T[:, 1]))
        return (nose + tail + AXIS_WEIGHT_PER_DEG * axis) / 3.0
    return np.abs(np.log(pred[:, 1] / np.array([r.depth for r in rows])))


def objective(theta, sets: dict, tables) -> float:
    """Mean over the groups of each group's mean error, at (ln a, ln D0) = theta; tables: [group] arrays."""
    a, D0 = math.exp(theta[0]), math.exp(theta[1])
    return float(np.mean([group_errors(name, rows, predicted(rows, t, a, D0)).mean()
                          for (name, rows), t in zip(sets.items(), tables)]))


def fit(sets: dict, tables) -> tuple[float, float, float]:
    """(a, D0 (m), objective) minimising objective() at one node: a grid over (ln a, ln D0), then Nelder–Mead."""
    from scipy.optimize import minimize

    grid = [(la, lD) for la in np.linspace(math.log(20.0), math.log(400.0), 31)
            for lD in np.linspace(math.log(0.005), math.log(10.0), 19)]
    start = np.array(min(grid, key=lambda x: objective(x, sets, tables)))
    simplex = np.vstack([start, start + [0.1, 0.0], start + [0.0, 0.3]])
    best = minimize(lambda x: objective(x, sets, tables), start, method="Nelder-Mead",
                    options={"initial_simplex": simplex, "xatol": 1e-6, "fatol": 1e-9, "maxiter": 4000})
    return math.exp(best.x[0]), math.exp(best.x[1]), float(best.fun)


def calibrate(sets: dict, table: np.ndarray, node_list: list[dict]) -> list[tuple]:
    """Step 4 at every node and step 5: [(objective, node, a, D0)] best first."""
    out = []
    for i, node in enumerate(node_list):
        a, D0, obj = fit(sets, list(table[i]))
        out.append((obj, node, a, D0))
    return sorted(out, key=lambda r: r[0])


def _key(node: dict) -> str:
    """A node as text (the .npz keeps it): JSON of its sorted items."""
    import json

    return json.dumps(sorted(node.items()))


def _node(key: str) -> dict:
    import json

    return dict(json.loads(key))


def _beyond(node: dict, seen: list[dict]) -> list[dict]:
    """Step 5: the nodes one STEP beyond ``node`` in each constant where it is at the edge of ``seen``."""
    out = []
    for k, step in STEP.items():
        values = sorted({n[k] for n in seen})
        lo, hi = LIMITS[k]
        for edge, sign in ((values[-1], 1), (values[0], -1)):
            if node[k] != edge:
                continue
            v = (node[k] * 2.0 ** sign) if step == "x2" else node[k] + sign * step
            if lo <= v <= hi:
                out.append({**node, k: round(v, 9)})
    return out


def shipped_node() -> dict:
    """The open constants as fepen ships them (the scene's defaults for the paper's concrete)."""
    from fepen import scene

    sc = scene.load(None, ["effects.fidelity=rigid"])
    from fepen.runs import setup

    law = setup.target_law(sc)
    return {"target.separation_angle_deg": round(math.degrees(law.phi_min), 9),
            "target.crush_strain": law.crush_strain, "target.free_surface_range": law.surface_range}


def load_sets(folder=None) -> dict[str, list]:
    """The calibration groups: table1 from fepen, the others from fepen/data/depth (or ``folder``)."""
    folder = Path(folder) if folder else Path(depth.shipped_sets()["wu2020"]).parent
    return {name: depth.table1_set() if name == "table1" else depth.read_set(folder / f"{name}.csv")
            for name in CALIBRATION_SETS}


def report_lines(sets, tables: dict, ranked) -> list[str]:
    """Every node's fit, then each group's errors at the chosen one."""
    lines = []
    for obj, node, a, D0 in ranked:
        lines.append(f"objective {obj:.4f}  a {a:7.3f}  D0 {D0 * 1e3:9.2f} mm  " +
                     "  ".join(f"{k.split('.')[-1]} {v:g}" for k, v in node.items()))
    obj, node, a, D0 = ranked[0]
    lines.append(f"== chosen: {node}, coefficient {a:.4g}, exponent {EXPONENT}, size {D0:.4g} m "
                 f"(objective {obj:.4f})")
    for (name, rows), t in zip(sets.items(), tables[_key(node)]):
        e = group_errors(name, rows, predicted(rows, t, a, D0))
        lines.append(f"  {name:24s} n {len(rows):3d}  mean error {e.mean():.1%}  worst {e.max():.1%}")
    return lines


@dataclass
class CalibrationPlan:
    """The calibration groups, the starting nodes and the --set lines of every run."""

    sets: dict
    nodes: list
    extra: tuple


@register
class Calibration(Study):
    """The one calibration of the concrete law's open constants (module docstring): steps 2-6 as rounds of
    rigid runs on the one executor (OUT/rounds/NNN, resumable), the fits between them."""

    name = "calibration"
    help = "the calibration of the concrete law's open constants on Table 1 and the depth sets (slow)"
    names = ("rounds", "calibration.json", "calibration.md")
    out = "results/calibration"

    @classmethod
    def add_arguments(cls, parser) -> None:
        parser.add_argument("--data", default=None, help="folder of the depth sets (default: fepen/data/depth)")
        set_option(parser, "a scene key in every run")

    @classmethod
    def options(cls, args) -> dict:
        return {"data": args.data, "sets": args.sets}

    def plan(self, data=None, sets=(), nodes_=None) -> CalibrationPlan:
        from fepen import scene

        scene.load(None, ["effects.fidelity=rigid", *sets])  # bad --set here
        return CalibrationPlan(load_sets(data), list(nodes_ or nodes()), tuple(sets))

    def digest(self, plan: CalibrationPlan) -> str:
        import hashlib
        import json

        blob = json.dumps([{n: [r.__dict__ for r in rows] for n, rows in plan.sets.items()}, plan.nodes,
                           plan.extra], sort_keys=True, default=str)
        return hashlib.sha256(blob.encode()).hexdigest()[:16]

    def rounds(self, plan: CalibrationPlan):
        """Steps 2-6: the runs of the nodes not run yet, their fits, the nodes beyond the best (step 5)."""
        tables, fits, todo, r = {}, {}, list(plan.nodes), 0
        while True:
            missing = [n for n in todo if _key(n) not in tables]
            if missing:
                js = jobs(plan.sets, missing, plan.extra)
                recs = yield Round([job_scene(j) for j in js], folder=f"rounds/{r:03d}", label=f"round {r}",
                                   then=True)
                r += 1
                t = table_of(plan.sets, missing, [positions(ok_summary(recs[i])) for i in range(len(js))])
                for i, n in enumerate(missing):
                    tables[_key(n)] = list(t[i])
            for k in tables:
                if k not in fits:
                    a, D0, obj = fit(plan.sets, tables[k])
                    fits[k] = (obj, _node(k), a, D0)
            ranked = sorted(fits.values(), key=lambda x: x[0])
            todo = [n for n in _beyond(ranked[0][1], [x[1] for x in ranked]) if _key(n) not in tables]
            if not todo:
                return ranked, tables

    def result(self, plan: CalibrationPlan, records: list, info) -> dict:
        ranked, tables = info.found
        obj, node, a, D0 = ranked[0]
        return {"chosen": {"node": node, "coefficient": a, "exponent": EXPONENT, "size_m": D0, "objective": obj},
                "nodes": [{"node": n, "coefficient": aa, "size_m": dd, "objective": oo} for oo, n, aa, dd in ranked],
                "_report": "\n".join(["# The calibration of the concrete law", "", "```",
                                      *report_lines(plan.sets, tables, ranked), "```", ""])}

    def report(self, result: dict) -> str:
        return result["_report"]

    def lines(self, result: dict) -> list[str]:
        c = result["chosen"]
        return [f"== chosen: {c['node']}, coefficient {c['coefficient']:.4g}, exponent {c['exponent']}, size "
                f"{c['size_m']:.4g} m (objective {c['objective']:.4f})"]


def ok_summary(record: dict) -> dict:
    """A run's summary (a calibration run that did not finish stops the calibration)."""
    if record["status"] != "ok":
        from fepen.errors import SimulationError

        raise SimulationError(f"a calibration run did not finish ({record['status']}: {record['message']})")
    return record["summary"]
