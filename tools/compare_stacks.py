"""The same shots on two software stacks (dolfinx 0.5.2 on Debian, the current dolfinx from PyPI): how far apart
their numbers are, shot by shot (issue 34; docs/install.md "The same numbers").

    python tools/compare_stacks.py A B        # two `fepen validate` directories (one folder per shot)
    python tools/compare_stacks.py --run      # run Table 1 rigid and at 4 mm deformable with both stacks first

For each shot: the depth on each stack, the largest relative difference over summary.json's numbers (what
measures the machine left out: times, memory, versions) and over history.csv's (each column on its own scale),
and the summary figures that differ in the 6 significant digits fepen prints. Exit 1 when a figure differs in
its printed digits.
"""

from __future__ import annotations

import argparse
import math
import re
import subprocess
import sys
from pathlib import Path

from fepen.io import results

ROOT = Path(__file__).resolve().parents[1]
#: the two stacks' interpreters (make setup, make setup-current)
STACKS = {"debian": ROOT / ".venv/bin/python", "current": ROOT / ".venv-current/bin/python"}
#: summary keys that measure the machine or the software, not the shot
VOLATILE = {"wall_s", "time_split_s", "peak_memory_bytes", "versions", "mesh_s", "interval", "communication"}


def numbers(d, prefix: str = "") -> dict[str, float]:
    """The numbers of a summary (nested keys joined by dots, list items by index; booleans and text left out)."""
    out = {}
    items = d.items() if isinstance(d, dict) else enumerate(d)
    for k, v in items:
        key = f"{prefix}{k}"
        if str(k) in VOLATILE:
            continue
        if isinstance(v, (dict, list)):
            out.update(numbers(v, key + "."))
        elif isinstance(v, (int, float)) and not isinstance(v, bool):
            out[key] = float(v)
    return out


#: figures that are small differences of large ones, judged on the scale of those (in the key's unit): the tip's
#: recession and the length change (0.011 mm for C1 at 4 mm) are the length less the tip's distance from the
#: tail, 144 mm less 143.99 mm, the stacks' positions agreeing to 4e-9 of the length; an embedded shot's residual
#: speed (1.5 m/s of C1's 700, the body's ringing when it stops) is a difference of nodal velocities of the
#: striking speed's size
SCALE = {"nose_profile.tip_recession_mm": 100.0, "length_change_mm": 100.0, "residual_speed_m_s": 100.0,
         "energy_error": 1.0,  # and the energy balance's error, a fraction of the striking energy (1e-5 of it)
         "yaw_deg": 1.0, "axis_angle_deg": 1.0,  # and angles of a nearly normal shot, hundredths of a degree
         "Hz_mm": 100.0, "Tz_mm": 100.0}  # and the body across the plane of an in-plane shot: round-off of 100 mm


def rel(a: float, b: float, scale: float = 0.0) -> float:
    """|a - b| over the larger magnitude, or over ``scale`` when larger (0 when equal)."""
    if a == b or (math.isnan(a) and math.isnan(b)):
        return 0.0
    return abs(a - b) / max(abs(a), abs(b), scale)


def printed(x: float) -> str:
    """A figure as fepen prints it (6 significant digits)."""
    return f"{x:.6g}"


def history(run: Path) -> tuple[list[str], list[list[float]]]:
    columns, rows = results.read(run).history_text()
    return columns, [[float(x) if x not in ("", "nan") else math.nan for x in r] for r in rows]


def compare_shot(a: Path, b: Path) -> dict:
    """One shot's run directories on the two stacks: their depths, the largest relative differences (summary,
    history) with where they are, and the figures whose printed digits differ."""
    sa, sb = (results.read(d).summary() for d in (a, b))
    na, nb = numbers(sa), numbers(sb)
    keys = sorted(set(na) & set(nb))
    worst_s = max(((rel(na[k], nb[k], SCALE.get(k, 0.0)), k) for k in keys), default=(0.0, ""))
    digits = [k for k in keys if printed(na[k]) != printed(nb[k])]
    missing = sorted(set(na) ^ set(nb))
    out = {"shot": a.name, "depth_a": sa.get("depth_mm"), "depth_b": sb.get("depth_mm"),
           "outcome": (sa.get("outcome"), sb.get("outcome")), "summary_rel": worst_s[0], "summary_key": worst_s[1],
           "printed_differ": digits, "missing": missing, "history_rel": 0.0, "history_col": "", "rows": None,
           "state_rows": []}
    if (a / "history.csv").is_file() and (b / "history.csv").is_file():
        (ca, ra), (cb, rb) = history(a), history(b)
        out["rows"] = (len(ra), len(rb))
        if ca != cb or len(ra) != len(rb):
            out["history_rel"], out["history_col"] = math.inf, "columns or rows differ"
        else:
            out["history_rel"], out["history_col"] = history_difference(ca, ra, rb)
            out["state_rows"] = state_rows(ca, ra, rb)
    return out


def is_state(column: str) -> bool:
    """A column that counts discrete states (the shell-charge pairs free, sticking or sliding): a pair whose gap or
    slip is round-off while the wall carries no load may take either state, so these are compared apart."""
    return column.endswith("_fraction")


def state_rows(columns: list[str], ra: list[list[float]], rb: list[list[float]]) -> list[int]:
    """The rows where a state column (is_state) differs."""
    js = [j for j, c in enumerate(columns) if is_state(c)]
    return [i for i, (r1, r2) in enumerate(zip(ra, rb)) if any(r1[j] != r2[j] for j in js)]


def family(name: str) -> str:
    """A vector's components share a scale: nose_x_mm, nose_y_mm, nose_z_mm -> nose_*_mm; vx_m_s -> v*_m_s;
    moment_y_N_m -> moment_*_N_m (a planar shot's out-of-plane moment is round-off on the in-plane one's scale)."""
    name = re.sub(r"(^|_)[xyz](?=_)", r"\1*", name)
    return re.sub(r"^v[xyz]_", "v*_", name)


def history_difference(columns: list[str], ra: list[list[float]], rb: list[list[float]]) -> tuple[float, str]:
    """The largest difference of two histories' numbers relative to their column's largest magnitude (a column
    that starts at zero, as the work done, is judged on its scale, not on its first rows), and its column; the
    state columns (is_state) left out."""
    worst = (0.0, "")
    scales: dict[str, float] = {}
    for j, name in enumerate(columns):
        vals = [abs(r[j]) for rows in (ra, rb) for r in rows if not math.isnan(r[j])]
        scales[family(name)] = max(scales.get(family(name), 0.0), max(vals, default=0.0))
    for j, name in enumerate(columns):
        if is_state(name):
            continue
        a = [r[j] for r in ra if not math.isnan(r[j])]
        b = [r[j] for r in rb if not math.isnan(r[j])]
        scale = max(scales[family(name)], SCALE.get(name, 0.0))
        if len(a) != len(b):
            return math.inf, name
        if scale > 0.0:
            worst = max(worst, (max(abs(x - y) for x, y in zip(a, b)) / scale, name))
    return worst


def compare(a: Path, b: Path) -> list[dict]:
    """Every shot folder (holding summary.json) that both directories have."""
    shots = sorted(p.name for p in a.iterdir() if (p / "summary.json").is_file() and (b / p.name / "summary.json")
                   .is_file())
    return [compare_shot(a / s, b / s) for s in shots]


def table(rows: list[dict], label: str) -> str:
    lines = [f"{label}", "| shot | depth A (mm) | depth B (mm) | summary: largest rel. diff (key) | history.csv: "
             "largest diff. over the column's scale (column) | printed digits differ |", "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['shot']} | {r['depth_a']:.6g} | {r['depth_b']:.6g} | {r['summary_rel']:.2g} "
                     f"({r['summary_key']}) | {r['history_rel']:.2g} ({r['history_col']}) | "
                     f"{', '.join(r['printed_differ']) or 'none'} |")
    return "\n".join(lines)


def run_both(out: Path, size_mm: int = 4) -> list[tuple[str, Path, Path]]:
    """Table 1 rigid and deformable at ``size_mm`` (fields off) with each stack's fepen validate; the deformable
    case is named plastic-{size_mm}mm."""
    cases = {"rigid": ["--set", "effects.fidelity=rigid"],
             f"plastic-{size_mm}mm": ["--set", f"mesh.size={size_mm}e-3", "--set", "run.fields=false"]}
    done = []
    for case, sets in cases.items():
        dirs = [out / f"{stack}-{case}" for stack in STACKS]
        cmds = [[str(py), "-m", "fepen", "validate", "--out", str(d), *sets] for py, d in zip(STACKS.values(), dirs)]
        if case == "rigid":  # one process each (a rigid validate runs its shots in its own process): both at once
            procs = [subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.DEVNULL) for cmd in cmds]
            codes = [p.wait() for p in procs]
            for cmd, code in zip(cmds, codes):
                if code:
                    raise subprocess.CalledProcessError(code, cmd)
        else:  # the deformable shots take every core (one worker per core): one stack after the other
            for cmd in cmds:
                subprocess.run(cmd, cwd=ROOT, check=True, stdout=subprocess.DEVNULL)
        done.append((case, *dirs))
    return done


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dirs", nargs="*", type=Path, help="two fepen validate directories (A B)")
    ap.add_argument("--run", action="store_true", help="run Table 1 with both stacks first")
    ap.add_argument("--out", type=Path, default=ROOT / "results/stacks", help="where --run writes")
    args = ap.parse_args(argv)
    pairs = run_both(args.out) if args.run else [("A against B", *args.dirs)]
    bad = 0
    for label, a, b in pairs:
        rows = compare(a, b)
        print(table(rows, f"{label}: A = {a}, B = {b}"))
        bad += sum(bool(r["printed_differ"] or r["missing"]) for r in rows)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
