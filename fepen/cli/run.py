"""``fepen run SCENE.toml [--out DIR] [--set KEY=VALUE ...] [--force] [--no-sensitivity]`` and ``fepen run --resume
DIR``: one simulation (fepen.api.run, fepen.api.resume), its summary printed, with how far its final axis moves
for the yaw a test does not record (fepen.runs.sensitivity)."""

from __future__ import annotations

from fepen.cli.common import say, scene_arguments, written_line
from fepen.errors import InputError

HELP = "one simulation: summary.json, history.csv, fields.xdmf, figures"


def add_arguments(parser) -> None:
    scene_arguments(parser, "results/run")
    parser.add_argument("--resume", metavar="DIR",
                        help="continue the killed or interrupted run in DIR from its last checkpoint (same scene, "
                             "same ranks)")
    parser.add_argument("--force", action="store_true",
                        help="when --out holds another run's results, remove them first (only what fepen writes)")
    parser.add_argument("--no-sensitivity", dest="sensitivity", action="store_false",
                        help="skip the two rigid shots at the in-plane attack -/+ the declared yaw "
                             "(summary.json's attitude_sensitivity; docs/uncertainty.md)")


def run(args) -> int:
    """Run one scene, or continue a run; print its summary."""
    from fepen import api

    if args.resume is not None:
        if args.scene is not None or args.sets or args.force or not args.sensitivity:
            raise InputError("--resume", "takes the scene of the run it continues (DIR/scene.toml): give no "
                                         "scene file, no --set and no --force")
        result = api.resume(args.resume, progress=True)
    else:
        result = api.run(api.Scene(args.scene, sets=args.sets), out=args.out, progress=True, force=args.force,
                         sensitivity=args.sensitivity)
    summary, out = result.summary, result.out
    keys = ("outcome", "depth_mm", "Hx_mm", "Hy_mm", "Tx_mm", "Ty_mm", "length_mm", "residual_speed_m_s",
            *(("max_peeq",) if summary.get("fidelity") != "rigid" else ()), "energy_error", "steps", "dt_s", "wall_s")
    keys += tuple(k for k in ("mass_loss_kg", "mass_loss_percent") if k in summary)
    say(*(f"{k} = {summary[k]:.6g}" if isinstance(summary[k], float) else f"{k} = {summary[k]}"
          for k in keys), *experiment_lines(summary), *sensitivity_lines(summary), *safety_lines(summary),
        *prediction_lines(summary),
        written_line(out))
    return 0


def experiment_lines(summary: dict) -> list[str]:
    """A Table 1 shot's errors against its test, one line (none for another shot); a run cut at its end time
    (outcome "ended") is not compared: the line says so."""
    e = summary.get("experiment")
    if not e:
        return []
    if not e.get("compared", True):
        end = summary["scene"].get("run", {}).get("end_time")
        cut = f"run.end_time = {end:g} s" if end is not None else "its longest time (run.end_time unset)"
        return [f"against Table 1 {e['shot']}: not compared: {cut} cut the run at t = {summary['end_time_s']:.6g} s, "
                "before it stopped, perforated or ricocheted (its nose and tail are not the test's final ones)"]
    return [f"against Table 1 {e['shot']}: nose error {100 * e['nose_error']:.1f} %, tail error "
            f"{100 * e['tail_error']:.1f} %, final axis {summary['final_axis_angle_deg']:.1f} deg (test "
            f"{e['final_axis_angle_deg']:.1f}), nose offset {summary['nose_offset_mm']:.0f} mm (test "
            f"{e['nose_offset_mm']:.0f})"]


def sensitivity_lines(summary: dict) -> list[str]:
    """How far the final axis moves for the unrecorded yaw, one line (fepen.runs.sensitivity)."""
    from fepen.runs.sensitivity import line

    got = line(summary)
    return [got] if got else []


def safety_lines(summary: dict) -> list[str]:
    """A charged run's charge-safety verdict, one line (docs/charge.md)."""
    if not summary.get("charge_safety"):
        return []
    from fepen.runs.charge_safety import line

    return [line(summary["charge_safety"])]


def prediction_lines(summary: dict) -> list[str]:
    """The intervals and the envelope's verdict of a summary, one line each (docs/uncertainty.md)."""
    lines = []
    info = summary.get("interval") or {}
    pct = "-".join(f"{100 * p:g}" for p in info.get("levels", ())) + " %"
    for name, quantity in (("depth_interval_mm", "depth"), ("lateral_interval_mm", "lateral")):
        iv = summary.get(name)
        if iv is None and quantity == "depth" and info.get("depth"):
            lines.append(f"{name} = {info['depth']}")  # "none: ..." and why
        if iv is not None:
            where = "; extrapolated: the shot lies outside the validated envelope" if info.get("extrapolated") else ""
            lines.append(f"{name} = {iv[0]:.4g} to {iv[1]:.4g} ({pct}: {info.get(quantity)}{where})")
    if summary.get("envelope"):
        lines.append(summary["envelope"]["line"])
    return lines
