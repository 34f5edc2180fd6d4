"""`make docs`: every figure the docs quote from a fepen command, made again by that command and written back
into the page (issue 46: docs that cannot drift).

A generated part of a page sits between two comments that name it,

    <!-- make docs: NAME -->
    ...
    <!-- /make docs: NAME -->

and BLOCKS says which command makes it. `python tools/make_docs.py` runs them all (about 12 minutes on 2
cores: the plastic Table 1 takes 5); `--only NAME ...` the named ones; `--list` lists them with their cost.
`tests/system/test_docs_figures.py` re-runs the cheap ones (the studies' limit and ricochet table, Table 1's
rigid means) and fails when a figure printed on a page moves. A page's prose around a block says what the
figures mean; when a regeneration changes a conclusion, the prose is the author's to change.

Each generator takes a scratch directory and returns the block's text (Markdown, no trailing newline).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
PY = sys.executable
RIGID = ["--set", "effects.fidelity=rigid"]


def fepen(*args, ranks: int = 1) -> float:
    """Run a fepen command from the project root; its wall time (s). A failing command stops make docs."""
    cmd = [PY, "-m", "fepen", *args]
    if ranks > 1:
        cmd = ["mpirun", "-n", str(ranks), *cmd]
    t0 = time.perf_counter()
    r = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"make docs: {' '.join(args[:2])} failed (exit {r.returncode}):\n{r.stdout[-2000:]}\n"
                         f"{r.stderr[-2000:]}")
    return time.perf_counter() - t0


def figure(src: Path, name: str) -> None:
    """A study's picture into docs/img/NAME (atomically), where its page shows it."""
    if src.is_file():
        dst = ROOT / "docs" / "img" / name
        tmp = dst.with_suffix(".png.tmp")
        tmp.write_bytes(src.read_bytes())
        os.replace(tmp, dst)


def version() -> str:
    from fepen.version import __version__

    return __version__


# ---- Table 1 (docs/validation.md) ---------------------------------------------------------------------------
def read_validation(path: Path) -> dict[str, dict]:
    """validation.csv's rows by shot."""
    with open(path, newline="") as f:
        return {r["shot"]: r for r in csv.DictReader(f)}


def within(sim: float, test: float) -> bool:
    """A nose offset within 25 mm or 25 % of the test's."""
    return abs(sim - test) <= max(25.0, 0.25 * abs(test))


def means_line(label: str, rows: dict[str, dict]) -> str:
    """The summary line of one fidelity's Table 1: mean nose and tail errors, the worst, the final axes'
    mean and largest error, how many within 10°, the nose offsets within 25 mm or 25 %."""
    nose = [float(r["nose_error"]) * 100 for r in rows.values()]
    tail = [float(r["tail_error"]) * 100 for r in rows.values()]
    axis = [abs(float(r["axis_error_deg"])) for r in rows.values()]
    off = [within(float(r["nose_offset_mm"]), float(r["nose_offset_exp_mm"])) for r in rows.values()]
    n = len(rows)
    return (f"{label}: mean nose error {np.mean(nose):.1f} %, mean tail error {np.mean(tail):.1f} %, worst "
            f"{max(nose + tail):.1f} %; final axis mean error {np.mean(axis):.1f}°, largest {max(axis):.1f}° "
            f"({sum(a <= 10.0 for a in axis)} of {n} within 10°); nose offset within 25 mm or 25 % on "
            f"{sum(off)} of {n}")


def _g(v: str, digits: int = 1) -> str:
    return f"{float(v):.{digits}f}"


def _t(v: str) -> str:
    """A test's figure as Table 1 prints it."""
    return f"{float(v):g}"


def table1_block(rigid: dict, plastic: dict) -> str:
    head = ("| shot | α (°) | Hx rigid / plastic / test (mm) | Hy rigid / plastic / test | Tx rigid / plastic / test "
            "| Ty rigid / plastic / test | nose error rigid / plastic | tail error rigid / plastic | final axis "
            "rigid / plastic / test (°) | nose offset rigid / plastic / test (mm) |\n"
            "|---|---|---|---|---|---|---|---|---|---|")
    lines = [head]
    for shot, r in rigid.items():
        p = plastic[shot]
        cols = [shot, _t(r["obliquity_deg"])]
        for q in ("Hx", "Hy", "Tx", "Ty"):
            cols.append(f"{_g(r[q + '_mm'])} / {_g(p[q + '_mm'])} / {_t(r[q + '_exp_mm'])}")
        cols.append(f"{float(r['nose_error']) * 100:.1f} / {float(p['nose_error']) * 100:.1f} %")
        cols.append(f"{float(r['tail_error']) * 100:.1f} / {float(p['tail_error']) * 100:.1f} %")
        cols.append(f"{_g(r['axis_deg'])} / {_g(p['axis_deg'])} / {_g(r['axis_exp_deg'])}")
        cols.append(f"{float(r['nose_offset_mm']):.0f} / {float(p['nose_offset_mm']):.0f} / "
                    f"{float(r['nose_offset_exp_mm']):.0f}")
        lines.append("| " + " | ".join(cols) + " |")
    return "\n".join(lines) + "\n\n" + means_line("rigid", rigid) + "\n\n" + means_line("plastic", plastic)


def table1(tmp: Path) -> str:
    fepen("validate", *RIGID, "--out", str(tmp / "R"))
    fepen("validate", "--set", "run.fields=false", "--out", str(tmp / "P"))
    return table1_block(read_validation(tmp / "R" / "validation.csv"), read_validation(tmp / "P" / "validation.csv"))


# ---- the studies (docs/studies.md) --------------------------------------------------------------------------
LIMIT_SETS = ["effects.fidelity=rigid", "target.thickness=0.15", "impact.obliquity_deg=0", "impact.attack_deg=0"]
RICOCHET_SETS = ["effects.fidelity=rigid", "impact.attack_deg=0"]


def _sets(sets: list[str]) -> list[str]:
    return [a for s in sets for a in ("--set", s)]


def limit_block(res: dict, seconds: float, ranks: int) -> str:
    lo, hi = res["bracket_m_s"]
    tol, check = res["tol_m_s"], res["check"]
    speeds = [c["v_m_s"] for c in res["curve"]]
    shots = len(res["bisection"]) + 2 + len(res["curve"])
    out = [f"The result (fepen {version()}):", "",
           f"- **Limit:** v_bl = {res['v_bl_m_s']:.1f} m/s, bracket {lo:.2f}–{hi:.2f} m/s after "
           f"{len(res['bisection'])} bisections.",
           f"- **Direct check:** {res['v_bl_m_s'] - tol:.1f} m/s "
           f"{check['below']['outcome'].replace('embedded', 'embeds')}; {res['v_bl_m_s'] + tol:.1f} m/s "
           f"{check['above']['outcome'].replace('perforated', 'perforates')}, "
           f"leaving at {check['above']['residual_speed_m_s']:.1f} m/s."]
    if "a" in res:
        out.append(f"- **Recht–Ipson fit:** a = {res['a']:.3f}, p = {res['p']:.2f}, rms error {res['rms_m_s']:.1f} m/s "
                   f"over the {len(speeds)} shots from {min(speeds):.0f} to {max(speeds):.0f} m/s.")
    out.append(f"- **Cost:** {shots} rigid shots, {seconds:.0f} s on {ranks} rank{'s' if ranks > 1 else ''}.")
    return "\n".join(out)


def ballistic_limit(tmp: Path) -> str:
    s = fepen("study", "ballistic-limit", *_sets(LIMIT_SETS), "--tol", "1", "--out", str(tmp / "bl"), ranks=2)
    figure(tmp / "bl" / "ballistic_limit.png", "ballistic-limit.png")
    return limit_block(json.loads((tmp / "bl" / "ballistic_limit.json").read_text()), s, 2)


def ricochet_rows(res: dict) -> str:
    lines = ["| v0 (m/s) | critical obliquity (deg) | bracket (deg) |", "|---|---|---|"]
    for v, c, b in zip(res["speeds_m_s"], res["critical_obliquity_deg"], res["brackets"]):
        lines.append(f"| {v:g} | {c:.1f} | {b[0]:.2f}–{b[1]:.2f} |")
    return "\n".join(lines)


def ricochet(tmp: Path) -> str:
    s = fepen("study", "ricochet", *_sets(RICOCHET_SETS), "--out", str(tmp / "ric"), ranks=2)
    res = json.loads((tmp / "ric" / "ricochet.json").read_text())
    figure(tmp / "ric" / "ricochet.png", "ricochet.png")
    return (ricochet_rows(res) + f"\n\nThe map and the bisections took {s:.0f} s on 2 ranks (fepen {version()}).")


def monte_carlo(tmp: Path) -> str:
    s = fepen("sweep", "demos/studies/c3_scatter.toml", "--out", str(tmp / "mc"), ranks=2)
    figure(tmp / "mc" / "histograms.png", "mc-c3-histograms.png")
    figure(tmp / "mc" / "sweep.png", "mc-c3-sweep.png")
    with open(tmp / "mc" / "sweep.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    depth = np.array([float(r["Hy_mm"]) for r in rows])
    hx = np.array([float(r["Hx_mm"]) for r in rows])
    keys = ["impact.velocity", "target.compressive_strength", "impact.obliquity_deg", "impact.attack_deg"]
    X = np.array([[float(r[k]) for k in keys] for r in rows])
    X[:, 1] *= 1e-6  # MPa
    A = np.column_stack([X, np.ones(len(X))])
    rate = np.linalg.lstsq(A, depth, rcond=None)[0]
    rate_hx = np.linalg.lstsq(A, hx, rcond=None)[0]
    embedded = sum(r["outcome"] == "embedded" for r in rows)

    def stats(a):
        return (f"{a.mean():.1f} | {a.std(ddof=1):.1f} | {np.percentile(a, 5):.1f} | {np.percentile(a, 50):.1f} | "
                f"{np.percentile(a, 95):.1f}")

    single = read_validation_row_c3(tmp)
    pct = 100.0 * np.mean(depth < 349.6)
    return "\n".join([
        f"{embedded} of the {len(rows)} shots embed ({s:.1f} s on 2 ranks, fepen {version()}).", "",
        "| figure | mean | std | P5 | P50 | P95 |", "|---|---|---|---|---|---|",
        f"| depth (mm) | {stats(depth)} |", f"| nose's sideways travel Hx (mm) | {stats(hx)} |", "",
        f"The single C3 shot (rigid) goes {single:.1f} mm; the test's own depth, 349.6 mm, lies at the "
        f"{pct:.0f}th percentile of this scatter. A least-squares plane through the {len(rows)} shots gives the "
        "rates:", "",
        f"- speed: {rate[0]:+.2f} mm per m/s;", f"- strength: {rate[1]:+.1f} mm per MPa (cube);",
        f"- obliquity: {rate[2]:+.1f} mm per degree;", f"- yaw: {rate[3]:+.1f} mm per degree.", "",
        f"At the scatter given (one standard deviation: 20 m/s, 4 MPa, 1°, 0.5°) the speed, the strength, the "
        f"obliquity and the yaw move the depth by about {abs(rate[0]) * 20:.0f}, {abs(rate[1]) * 4:.0f}, "
        f"{abs(rate[2]):.0f} and {abs(rate[3]) * 0.5:.0f} mm; the depth's spread is ±"
        f"{100 * depth.std(ddof=1) / depth.mean():.1f} % at one standard deviation. The sideways travel Hx: "
        f"{rate_hx[3]:+.1f} mm per degree of yaw, {rate_hx[2]:+.1f} mm per degree of obliquity."])


def read_validation_row_c3(tmp: Path) -> float:
    fepen("run", "scenes/default.toml", *RIGID, "--out", str(tmp / "c3"))
    return float(json.loads((tmp / "c3" / "summary.json").read_text())["Hy_mm"])


def _q(v) -> str:
    return "through" if v is None else f"{v:.1f}"


def _unc_table(res: dict, perforation: bool) -> str:
    names = {"combined": "inputs and model", "inputs": "inputs alone"}
    if perforation:
        lines = ["| sample | P(perforation) | Wilson 95 % | systematic band (b at 10 %, 90 %) |", "|---|---|---|---|"]
        for k, label in names.items():
            e = res["samples"][k]["perforation"]
            band = e.get("systematic", {}).get("probability")
            lines.append(f"| {label} | {e['probability']:.3f} ({e['perforated']}/{e['shots']}) | "
                         f"{e['wilson95'][0]:.3f}–{e['wilson95'][1]:.3f} | "
                         + (f"{band[0]:.3f}–{band[1]:.3f} |" if band else "– |"))
        return "\n".join(lines)
    lines = ["| sample | P10 (mm) | P50 (mm) | P90 (mm) | mean (mm) |", "|---|---|---|---|---|"]
    for k, label in names.items():
        d = res["samples"][k]["depth"]
        lines.append(f"| {label} | {_q(d.get('P10_mm'))} | {_q(d.get('P50_mm'))} | {_q(d.get('P90_mm'))} | "
                     f"{_q(d.get('mean_mm'))} |")
    return "\n".join(lines)


def uncertainty_c3(tmp: Path) -> str:
    s = fepen("study", "uncertainty", "--scatter", "demos/studies/c3_scatter.toml", "--out", str(tmp / "u"), ranks=2)
    res = json.loads((tmp / "u" / "uncertainty.json").read_text())
    figure(tmp / "u" / "uncertainty.png", "uncertainty-c3.png")
    ms = res["model_scatter"]
    with open(tmp / "u" / "inputs" / "sweep.csv", newline="") as f:
        inputs = np.array([float(r["Hy_mm"]) for r in csv.DictReader(f)])
    test = res["scene"]["test"]["depth_mm"]
    c, i = res["samples"]["combined"]["depth"], res["samples"]["inputs"]["depth"]
    nominal = ms["response"]["depth_at_1_mm"]
    inside = c["P10_mm"] <= test <= c["P90_mm"]
    shift = 100.0 * (c["P50_mm"] / nominal - 1.0)
    shots = res["samples"]["combined"]["shots"] + res["samples"]["inputs"]["shots"]
    return "\n".join([
        _unc_table(res, False), "",
        f"The test's {test:g} mm lies at the {100 * np.mean(inputs < test):.0f}th percentile of the input scatter "
        f"and {'inside' if inside else 'outside'} the combined P10–P90. fepen's own error widens the 10–90 % range "
        f"from {i['P90_mm'] - i['P10_mm']:.0f} mm to {c['P90_mm'] - c['P10_mm']:.0f} mm. The combined median lies "
        f"{abs(shift):.0f} % {'below' if shift < 0 else 'above'} the nominal prediction ({nominal:.1f} mm): the "
        f"model's mean error μ = {ms['mu']:+.3f} (τ = {ms['tau']:.3f}; fepen predicts the public sets' depths "
        f"{100 * abs(np.expm1(ms['mu'])):.1f} % {'deep' if ms['mu'] < 0 else 'shallow'} on average). {shots} rigid "
        f"shots and {len(ms['response']['resistance_factor'])} for the response: {s:.0f} s on 2 ranks "
        f"(fepen {version()})."])


def uncertainty_slab(tmp: Path) -> str:
    sets = ["effects.fidelity=rigid", "target.thickness=0.15"]
    fepen("study", "ballistic-limit", *_sets(sets), "--tol", "1", "--out", str(tmp / "bl"), ranks=2)
    v = json.loads((tmp / "bl" / "ballistic_limit.json").read_text())["v_bl_m_s"]
    s = fepen("study", "uncertainty", "--scatter", "demos/studies/c3_scatter.toml", "--set", "target.thickness=0.15",
              "--set", f"impact.velocity={v:.1f}", "--out", str(tmp / "u"), ranks=2)
    res = json.loads((tmp / "u" / "uncertainty.json").read_text())
    figure(tmp / "u" / "uncertainty.png", "uncertainty-slab.png")
    alone = res["samples"]["inputs"]["perforation"]["probability"]
    both = res["samples"]["combined"]["perforation"]["probability"]
    band = res["samples"]["combined"]["perforation"]["systematic"]["probability"]
    shots = res["samples"]["combined"]["shots"] + res["samples"]["inputs"]["shots"]
    return "\n".join([
        "**A 150 mm slab at its ballistic limit** (the limit of the default projectile and concrete, rigid, at C3's",
        "angles: `fepen study ballistic-limit --set target.thickness=0.15 --set effects.fidelity=rigid --tol 1` gives "
        f"{v:.1f} m/s):", "", "```sh",
        ".venv/bin/fepen study uncertainty --scatter demos/studies/c3_scatter.toml --set target.thickness=0.15 \\",
        f"    --set impact.velocity={v:.1f} --out results/unc-slab", "```", "", _unc_table(res, True), "",
        f"At its limit the slab stops {100 * (1 - alone):.0f} % of the shots of the test's scatter; with fepen's "
        f"error, {100 * (1 - both):.0f} %. The systematic band is the message: whether fepen is right for this "
        f"concrete moves the probability of perforation from {100 * band[0]:.0f} % to {100 * band[1]:.0f} %. The "
        f"shot is outside the validated envelope (a slab; the depth data are of thick targets). {shots} rigid slab "
        f"shots took {s:.0f} s on 2 ranks (fepen {version()})."])


# ---- a run's interval (docs/uncertainty.md) ------------------------------------------------------------------
def _run_lines(tmp: Path, name: str, *sets: str) -> tuple[list[str], dict]:
    """A rigid run's printed interval and envelope lines, and its summary."""
    cmd = [PY, "-m", "fepen", "run", *RIGID, *_sets(list(sets)), "--out", str(tmp / name)]
    r = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"make docs: fepen run {' '.join(sets)} failed:\n{r.stderr[-2000:]}")
    text = r.stdout + r.stderr
    lines = [ln.removeprefix("fepen: ") for ln in text.splitlines()
             if ln.startswith(("depth_interval_mm", "lateral_interval_mm")) or "validated envelope" in ln]
    return lines, json.loads((tmp / name / "summary.json").read_text())


def run_interval(tmp: Path) -> str:
    from fepen.data import experiments

    lines, c3 = _run_lines(tmp, "c3")
    _, c7 = _run_lines(tmp, "c7", "impact.shot=C7")
    t3, t7 = experiments.shot("C3"), experiments.shot("C7")
    d3, l3 = c3["depth_interval_mm"], c3["lateral_interval_mm"]
    d7, l7 = c7["depth_interval_mm"], c7["lateral_interval_mm"]
    short = 100 * (1 - c7["Hy_mm"] / t7.Hy_mm)
    side = 100 * (1 - c7["Hx_mm"] / t7.Hx_mm)

    def inside(v, iv):
        return "inside" if iv[0] <= v <= iv[1] else "outside"

    return "\n".join(["```", *lines, "```", "",
                      f"The test measured {t3.Hy_mm:g} mm deep and {t3.Hx_mm:g} mm sideways (fepen: {c3['Hy_mm']:.1f} "
                      f"and {c3['Hx_mm']:.1f} mm, rigid; fepen {version()}). C7 (`--set impact.shot=C7`), where "
                      f"fepen's depth is {abs(short):.0f} % {'short' if short > 0 else 'deep'} and its sideways travel "
                      f"{abs(side):.0f} % {'short' if side > 0 else 'long'}: {c7['Hy_mm']:.1f} mm, interval "
                      f"{d7[0]:.1f}-{d7[1]:.1f} mm; the test's {t7.Hy_mm:g} mm lies {inside(t7.Hy_mm, d7)}, and its "
                      f"{t7.Hx_mm:g} mm sideways {inside(t7.Hx_mm, l7)} {l7[0]:.1f}-{l7[1]:.1f} mm. C3's own: "
                      f"{d3[0]:.1f}-{d3[1]:.1f} mm deep, {l3[0]:.1f}-{l3[1]:.1f} mm sideways."])


def worked_example(tmp: Path) -> str:
    """The plastic C3 run's printed figures and how to read them."""
    cmd = [PY, "-m", "fepen", "run", "scenes/default.toml", "--set", "run.fields=false", "--out", str(tmp / "p")]
    t0 = time.perf_counter()
    r = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"make docs: the plastic C3 run failed:\n{r.stderr[-2000:]}")
    seconds = time.perf_counter() - t0
    keep = ("depth_mm =", "Hx_mm =", "depth_interval_mm", "lateral_interval_mm")
    lines = [ln.removeprefix("fepen: ") for ln in (r.stdout + r.stderr).splitlines()
             if ln.startswith(keep) or "validated envelope" in ln]
    s = json.loads((tmp / "p" / "summary.json").read_text())
    lo, hi = s["depth_interval_mm"]
    return "\n".join([
        f"plastic at the default mesh, `fepen run scenes/default.toml --set run.fields=false` ({seconds:.0f} s on "
        f"one rank, fepen {version()}):", "", "```", *lines, "```", "",
        f"The test: 349.6 mm deep, 81.4 mm sideways. How to read it: fepen's best estimate is "
        f"{s['Hy_mm']:.0f} mm; a test of this shot into a concrete that fepen has not seen would come out between "
        f"{lo:.0f} and {hi:.0f} mm four times in five."])


# ---- depth on public data (docs/validation-depth.md) ----------------------------------------------------------
def depth_errors(tmp: Path) -> str:
    fepen("validate-depth", "--workers", "2", "--out", str(tmp / "depth"))
    text = (tmp / "depth" / "depth.md").read_text()
    figure(tmp / "depth" / "depth.png", "validation-depth.png")
    from fepen.studies.calibration import CALIBRATION_SETS

    table = [ln for ln in text.splitlines() if ln.startswith("|")]
    with open(tmp / "depth" / "depth.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["set"] not in CALIBRATION_SETS and r["set"] != "table1"]
    err = {k: 100 * np.mean([abs(float(r[f"{k}_depth_m"]) / float(r["depth_m"]) - 1) for r in rows])
           for k in ("default", "closed_form")}
    return ("\n".join(table) + f"\n\nPooled over the {len(rows)} shots of the sets not used for any choice, mean "
            f"|error|: default law {err['default']:.1f} %, closed form {err['closed_form']:.1f} % (fepen {version()}).")


# ---- the charge-safety map (docs/charge.md) ------------------------------------------------------------------
CHARGE_SAFETY = ["demos/charge/charge_800.toml", "--speeds", "100,200,400,800,1200", "--obliquities", "0,10,20",
                 "--set", "mesh.size=0.005"]


def charge_safety(tmp: Path) -> str:
    s = fepen("study", "charge-safety", *CHARGE_SAFETY, "--out", str(tmp / "cs"), ranks=2)
    figure(tmp / "cs" / "charge_safety.png", "charge-safety-map.png")
    text = (tmp / "cs" / "charge_safety.md").read_text().split("\n", 2)[2].strip()  # without its title
    return (f"`mpirun -n 2 fepen study charge-safety {' '.join(CHARGE_SAFETY)}` ({s:.0f} s on 2 ranks, fepen "
            f"{version()}):\n\n" + text + "\n\n![the charge-safety map](img/charge-safety-map.png)")


def history_columns(tmp: Path) -> str:
    """history.csv's column tables, from their declarations (fepen.io.columns)."""
    from fepen.io import columns

    return columns.markdown()


def run_tables(tmp: Path) -> str:
    """A run's other CSV tables, from their declarations (fepen.io.columns.TABLES)."""
    from fepen.io import columns

    return columns.tables_markdown()


#: name -> (page, generator, rough cost on 2 cores)
BLOCKS = {
    "history-columns": ("docs/results.md", history_columns, "0 s"),
    "run-tables": ("docs/results.md", run_tables, "0 s"),
    "table1": ("docs/validation.md", table1, "5 min"),
    "ballistic-limit": ("docs/studies.md", ballistic_limit, "15 s"),
    "ricochet": ("docs/studies.md", ricochet, "20 s"),
    "monte-carlo": ("docs/studies.md", monte_carlo, "30 s"),
    "uncertainty-c3": ("docs/studies.md", uncertainty_c3, "45 s"),
    "uncertainty-slab": ("docs/studies.md", uncertainty_slab, "3 min"),
    "depth-errors": ("docs/validation-depth.md", depth_errors, "1 min"),
    "run-interval": ("docs/uncertainty.md", run_interval, "5 s"),
    "worked-example": ("docs/uncertainty.md", worked_example, "40 s"),
    "charge-safety": ("docs/charge.md", charge_safety, "2.5 min"),
}


def block_text(page: str, name: str) -> str:
    """The text now between the block's markers on its page."""
    text = (ROOT / page).read_text()
    m = re.search(rf"<!-- make docs: {re.escape(name)} -->\n(.*?)\n<!-- /make docs: {re.escape(name)} -->", text,
                  re.S)
    if m is None:
        raise SystemExit(f"make docs: {page} has no block {name!r} (<!-- make docs: {name} --> ... "
                         f"<!-- /make docs: {name} -->)")
    return m.group(1)


def replace_block(page: str, name: str, body: str) -> bool:
    """Write body between the block's markers (the page atomically); whether it changed."""
    path = ROOT / page
    text = path.read_text()
    old = block_text(page, name)
    if old == body:
        return False
    new = text.replace(f"<!-- make docs: {name} -->\n{old}\n<!-- /make docs: {name} -->",
                       f"<!-- make docs: {name} -->\n{body}\n<!-- /make docs: {name} -->")
    tmp = path.with_suffix(".md.tmp")
    tmp.write_text(new)
    os.replace(tmp, path)
    return True


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", nargs="+", choices=sorted(BLOCKS), help="the blocks to make (default: all)")
    ap.add_argument("--list", action="store_true", help="list the blocks, their pages and costs")
    args = ap.parse_args(argv)
    if args.list:
        for name, (page, _, cost) in BLOCKS.items():
            print(f"{name:16s} {page:28s} {cost}")
        return 0
    for name in args.only or BLOCKS:
        page, make, _ = BLOCKS[name]
        block_text(page, name)  # the markers exist before anything runs
        with tempfile.TemporaryDirectory(prefix=f"fepen-docs-{name}-") as tmp:
            t0 = time.perf_counter()
            body = make(Path(tmp))
        changed = replace_block(page, name, body)
        print(f"{name}: {page} {'changed' if changed else 'unchanged'} ({time.perf_counter() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
