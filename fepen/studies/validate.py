"""``fepen validate``: the eight Table 1 shots with one parameter set, compared with the experiments; a Study
(fepen.studies.study) of one round on the one executor (``fepen validate`` without mpirun runs its deformable shots
side by side under ``mpirun -n CORES``, one rank each).

Writes to DIR: one results directory per shot (DIR/C1 ...), validation.csv, validation.md (Table 1 with the
simulated values and errors), validation.png (simulated against measured nose and tail positions, and
the trajectories) and paths.png (the nose and tail paths of the oblique shots against the straight line and
the test's final projectile, fepen.post.paths; ``python -m fepen.post.paths`` puts several DIRs on one figure).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fepen import scene as fscene
from fepen.data import SHOTS
from fepen.errors import InputError
from fepen.studies.products import Picture, Table
from fepen.studies.study import Round, Study, register

__all__ = ["Validate", "validate", "table", "FIELDS"]

FIELDS = ["shot", "v0_m_s", "obliquity_deg", "attack_deg", "Hx_mm", "Hy_mm", "Tx_mm", "Ty_mm", "Hx_exp_mm",
          "Hy_exp_mm", "Tx_exp_mm", "Ty_exp_mm", "nose_error", "tail_error", "axis_deg", "axis_exp_deg",
          "axis_error_deg", "nose_offset_mm", "nose_offset_exp_mm", "outcome", "wall_s"]


@dataclass
class ValidatePlan:
    """The eight shots' scenes, by name."""

    scenes: dict


@register
class Validate(Study):
    """``fepen validate``: Table 1's shots, each in its own folder (DIR/C1 ...), against the tests."""

    name = "validate"
    command = "validate"
    help = "the Table 1 sweep: validation.csv, validation.md, figures"
    names = (*SHOTS, "shots.jsonl", "validation.csv", "validation.md", "validation.png", "paths.png",
             "hazard_maps.png")
    out = "results/validation"

    def plan(self, scene_path=None, sets=()) -> ValidatePlan:
        from fepen.runs import setup

        base = [s for s in sets if not s.startswith("impact.")]
        for s in sets:
            if s.startswith("impact."):
                raise InputError(s.split("=")[0], "validate sets impact.* from Table 1; drop this --set")
        scenes = {name: fscene.load(scene_path, [*base, f'impact.shot="{name}"']) for name in SHOTS}
        for sc in scenes.values():
            setup.check_supported(sc)
        return ValidatePlan(scenes)

    def rounds(self, plan: ValidatePlan):
        names = list(plan.scenes)
        yield Round(list(plan.scenes.values()), keep=lambda sc: True, shot_folder=lambda out, i: out / names[i],
                    batch=False, label="")

    def result(self, plan: ValidatePlan, records: list, info) -> dict:
        rows = []
        for i, name in enumerate(plan.scenes):
            rec = records[0][i]
            if rec["status"] != "ok":
                raise InputError("validate", f"shot {name} did not finish ({rec['status']}: {rec['message']})")
            s, e = rec["summary"], SHOTS[name]
            rows.append({"shot": name, "v0_m_s": e.v0, "obliquity_deg": e.obliquity_deg, "attack_deg": e.attack_deg,
                         "Hx_mm": s["Hx_mm"], "Hy_mm": s["Hy_mm"], "Tx_mm": s["Tx_mm"], "Ty_mm": s["Ty_mm"],
                         "Hx_exp_mm": e.Hx_mm, "Hy_exp_mm": e.Hy_mm, "Tx_exp_mm": e.Tx_mm, "Ty_exp_mm": e.Ty_mm,
                         "nose_error": s["experiment"]["nose_error"], "tail_error": s["experiment"]["tail_error"],
                         "axis_deg": s["final_axis_angle_deg"],
                         "axis_exp_deg": s["experiment"]["final_axis_angle_deg"],
                         "axis_error_deg": s["experiment"]["axis_error_deg"], "nose_offset_mm": s["nose_offset_mm"],
                         "nose_offset_exp_mm": s["experiment"]["nose_offset_mm"],
                         "outcome": s["outcome"], "wall_s": s["wall_s"]})
        return {"rows": rows}

    def document(self, plan: ValidatePlan, result: dict, info) -> None:
        return None

    def tables(self, plan: ValidatePlan, result: dict, info) -> list:
        return [Table("validation.csv", FIELDS, result["rows"])]

    def texts(self, plan: ValidatePlan, result: dict, info) -> dict:
        return {"validation.md": table(result["rows"], plan.scenes["C1"])}

    def pictures(self, plan: ValidatePlan, result: dict, info) -> list:
        from fepen.post import paths, study_figures

        rows, out = result["rows"], info.out
        hazards = all((out / r["shot"] / "hazard.csv").is_file() for r in rows)
        return [Picture("validation.png", study_figures.VALIDATION_SIZE,
                        lambda fig: study_figures.validation(fig, rows, out), 110),
                Picture("paths.png", paths.size(),
                        lambda fig: paths.draw(fig, {plan.scenes["C1"].effects.fidelity: out})),
                Picture("hazard_maps.png", (12, 3.8),
                        lambda fig: study_figures.hazard_maps(fig, out) if hazards else False, 110)]

    def lines(self, result: dict) -> list[str]:
        return [f"{r['shot']}: Hx {r['Hx_mm']:.1f}/{r['Hx_exp_mm']:g} Hy {r['Hy_mm']:.1f}/{r['Hy_exp_mm']:g} "
                f"Tx {r['Tx_mm']:.1f}/{r['Tx_exp_mm']:g} Ty {r['Ty_mm']:.1f}/{r['Ty_exp_mm']:g} mm  nose error "
                f"{100 * r['nose_error']:.1f} %  tail error {100 * r['tail_error']:.1f} %  {r['outcome']}"
                for r in result["rows"]]


def validate(scene_path, sets, out, comm=None, say=None) -> list[dict]:
    """Run all shots (same scene, same --set overrides, only impact.shot changes); one dict per shot with the
    FIELDS."""
    from fepen.studies import study

    st = Validate()
    return study.run(st, st.plan(scene_path, sets), out, comm, say=say or (lambda *ls: None))["rows"]


def table(rows, sc) -> str:
    """Markdown Table 1 with the simulated values and the errors."""
    lines = [f"Fidelity: {sc.effects.fidelity}; crater: {sc.effects.crater}; separation: {sc.effects.separation}"
             f" (phi_min {sc.target.separation_angle_deg:g} deg); free surface: {sc.effects.free_surface}; "
             f"friction: {sc.effects.friction}; mesh {sc.mesh.size * 1e3:g} mm.", "",
             "| shot | v0 (m/s) | α (°) | ϑ (°) | Hx sim / test (mm) | Hy sim / test (mm) | Tx sim / test (mm) | "
             "Ty sim / test (mm) | nose error | tail error | final axis sim / test (°) | nose offset sim / test (mm) | "
             "outcome |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(
            f"| {r['shot']} | {r['v0_m_s']:g} | {r['obliquity_deg']:g} | {r['attack_deg']:g} | "
            f"{r['Hx_mm']:.1f} / {r['Hx_exp_mm']:g} | {r['Hy_mm']:.1f} / {r['Hy_exp_mm']:g} | "
            f"{r['Tx_mm']:.1f} / {r['Tx_exp_mm']:g} | {r['Ty_mm']:.1f} / {r['Ty_exp_mm']:g} | "
            f"{100 * r['nose_error']:.1f} % | {100 * r['tail_error']:.1f} % | "
            f"{r['axis_deg']:.1f} / {r['axis_exp_deg']:.1f} | "
            f"{r['nose_offset_mm']:.0f} / {r['nose_offset_exp_mm']:.0f} | "
            f"{r['outcome']} |")
    ne = np.array([r["nose_error"] for r in rows])
    te = np.array([r["tail_error"] for r in rows])
    ae = np.abs([r["axis_error_deg"] for r in rows])
    lines += ["", f"Mean nose error {100 * ne.mean():.1f} %, largest {100 * ne.max():.1f} %; mean tail error "
                  f"{100 * te.mean():.1f} %, largest {100 * te.max():.1f} %. Errors: |H_sim − H_test| / |H_test| "
                  "with H = (Hx, Hy), likewise T.",
              "", f"Final axis atan2(Hx − Tx, Hy − Ty): mean error {ae.mean():.1f}°, largest {ae.max():.1f}°; "
                  "nose offset from the line of fire "
                  "(the nose's distance from the line through the impact point along the striking velocity).", ""]
    return "\n".join(lines)
