"""`make docs`: every figure the docs quote from a fepen command, made again by that command and written back
into the page (issue 46: docs that cannot drift).

A generated part of a page sits between two comments that name it,

    <!-- make docs: NAME -->
    ...
    <!-- /make docs: NAME -->

and BLOCKS says which command makes it. `python tools/make_docs.py` runs them all; `--only NAME ...` the
named ones; `--list` lists them with their cost on 2 cores and the total. Each block begins with a line naming
the command that made its figures and the fepen that ran it. `tests/system/test_docs_figures.py` re-runs the
cheap ones (Block.cheap) on one rank and fails when a digit printed on a page moves (wall times masked). A
page's prose around a block says what the figures mean; when a regeneration changes a conclusion, the prose is
the author's to change.

Each generator takes a scratch directory and returns the block's text (Markdown, no trailing newline).
"""

from __future__ import annotations

import argparse
import atexit
import csv
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # the fepen of this checkout (a worktree's own), for the blocks that import it
PY = sys.executable
RIGID = ["--set", "effects.fidelity=rigid"]


#: the ranks a block's command runs on at most (MAKE_DOCS_RANKS=1: the drift test, which runs no mpirun; a
#: study's figures are the same on any rank count, its wall time is the machine's and is masked)
RANKS = int(os.environ.get("MAKE_DOCS_RANKS", "2"))


def took(seconds: float, ranks: int = 2) -> str:
    """A block's wall time as the pages print it ("12 s on 2 ranks"), on the ranks the command really ran on."""
    r = min(ranks, RANKS)
    return f"{seconds:.0f} s on {r} rank{'s' if r > 1 else ''}"


def child_env() -> dict:
    """The environment of a command make docs starts: Python's copy of this process's, passed explicitly. Without
    it a child inherits the C environment, which Open MPI's MPI_Init writes into once a block has loaded MPI in this
    process (PMIX_RANK, PMIX_SERVER_URI*, OMPI_MCA_ess=singleton, ...): the child then takes itself for a rank of
    this process's singleton job, and a relaunching command (fepen validate --workers 2) ended at once with exit
    1 and nothing said."""
    return dict(os.environ)


def fepen(*args, ranks: int = 1) -> float:
    """Run a fepen command from the project root; its wall time (s). A failing command stops make docs."""
    ranks = min(ranks, RANKS)
    cmd = [PY, "-m", "fepen", *args]
    if ranks > 1:
        cmd = ["mpirun", "-n", str(ranks), *cmd]
    for attempt in (1, 2):
        t0 = time.perf_counter()
        r = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, env=child_env())
        if r.returncode == 0:
            return time.perf_counter() - t0
        if attempt == 1 and r.returncode == 1 and not (r.stdout + r.stderr).strip():
            # Open MPI's launch here sometimes ends a job at once with exit 1 and nothing said (the same command
            # then runs): once again, and said so; a command that fails with a word stops make docs at once
            print(f"make docs: {' '.join(args[:2])} ended with exit 1 and no output; running it again",
                  file=sys.stderr)
            continue
        raise SystemExit(f"make docs: {' '.join(args[:2])} failed (exit {r.returncode}):\n{r.stdout[-2000:]}\n"
                         f"{r.stderr[-2000:]}")
    raise AssertionError("unreachable")


#: the commands already run in this make docs, by their arguments: blocks quoting the same run share it
_MADE: dict[tuple, tuple[Path, float]] = {}


def made(*args, ranks: int = 1) -> tuple[Path, float]:
    """A fepen command's output folder (its --out) and wall time (s), the command run once per make docs.

    Args:
        args: the command's arguments without --out.
        ranks: the ranks it runs on (at most RANKS).

    Returns:
        (the folder, the seconds it took the first time).
    """
    key = (args, min(ranks, RANKS))
    if key not in _MADE:
        out = Path(tempfile.mkdtemp(prefix="fepen-docs-shared-"))
        atexit.register(shutil.rmtree, out, True)
        _MADE[key] = (out / "out", fepen(*args, "--out", str(out / "out"), ranks=ranks))
    return _MADE[key]


#: whether the blocks' pictures go into docs/img (the drift test, which only compares text, sets it False)
FIGURES = True


def figure(src: Path, name: str) -> None:
    """A study's picture into docs/img/NAME (atomically), where its page shows it."""
    if FIGURES and src.is_file():
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


VALIDATE_RIGID = ("validate", *RIGID)
VALIDATE_PLASTIC = ("validate", "--set", "run.fields=false")


def table1(tmp: Path) -> str:
    rigid, plastic = made(*VALIDATE_RIGID)[0], made(*VALIDATE_PLASTIC)[0]
    figure(rigid / "validation.png", "validation-rigid.png")
    figure(plastic / "validation.png", "validation-plastic.png")
    return table1_block(read_validation(rigid / "validation.csv"), read_validation(plastic / "validation.csv"))


def table1_bands(tmp: Path) -> str:
    """Table 1 as distributions: each shot's line, its 10-90 % band over 200 rigid members, and the test."""
    import docs_pages

    out, seconds = made(*docs_pages.BANDS_RIGID)
    bands = docs_pages.read_bands(out / "bands.csv")
    line = read_validation(made(*VALIDATE_RIGID)[0] / "validation.csv")
    lines = [f"`fepen validate --samples 200 --workers 2` ({took(seconds)}, fepen {version()}):", "",
             "| shot | final axis: line / 10–90 % band / test (°) | inside | nose offset: line / band / test (mm) | "
             "inside | depth: line / band / test (mm) | inside |", "|---|---|---|---|---|---|---|"]
    for shot, b in bands.items():
        cols = [shot]
        for q, col, fmt, band in (("final_axis_angle_deg", "axis_deg", ".1f", ".1f"),
                                  ("nose_offset_mm", "nose_offset_mm", ".0f", ".1f"),
                                  ("depth_mm", "Hy_mm", ".1f", ".0f")):
            x = b[q]
            cols += [f"{float(line[shot][col]):{fmt}} / {docs_pages._minus(x['p10'], int(band[1]))}–"
                     f"{docs_pages._minus(x['p90'], int(band[1]))} / {x['test']:.1f}", "yes" if x["inside"] else "no"]
        lines.append("| " + " | ".join(cols) + " |")
    return "\n".join(lines)


#: C8's speed and obliquity with a 2° striking yaw in the plane of fire (its test's other inputs the defaults)
C8_YAWED = ["impact.velocity=893", "impact.obliquity_deg=0.58", "impact.attack_deg=2"]


def tunnel_reload(tmp: Path) -> str:
    """C8's speed and obliquity with a 2° striking yaw, rigid, against the tunnel wall's reload strength."""
    lines = ["| tunnel_reload | final axis (°) | nose offset (mm) | Hy (mm) |", "|---|---|---|---|"]
    for label, sets in (("0.3", ["target.tunnel_reload=0.3"]), ("0.52 (default)", []),
                        ("1.0 (the intact wall)", ["target.tunnel_reload=1.0"]),
                        ("tunnel off", ["effects.tunnel=false"])):
        out = tmp / label.split()[0]
        fepen("run", *RIGID, *_sets([*C8_YAWED, *sets]), "--out", str(out))
        s = json.loads((out / "summary.json").read_text())
        lines.append(f"| {label} | {s['final_axis_angle_deg']:.1f} | {s['nose_offset_mm']:.0f} | {s['Hy_mm']:.0f} |")
    return "\n".join(lines)


def _elastic(shot: str) -> dict:
    out, _ = made("run", *_sets([f"impact.shot={shot}", "effects.fidelity=elastic", "run.fields=false"]))
    return json.loads((out / "summary.json").read_text())


def _mesh_facets(shot: str, tmp: Path) -> dict:
    """A rigid run on the volume mesh's facets (RigidRun(points="mesh")), in a process of its own."""
    code = ("import json; from mpi4py import MPI; import fepen; from fepen.runs.rigid import RigidRun; "
            f"sc = fepen.Scene(sets=['impact.shot={shot}', 'effects.fidelity=rigid']); "
            "s = RigidRun(sc, None, MPI.COMM_SELF, points='mesh').run(); "
            "print(json.dumps({k: s[k] for k in ('Hy_mm', 'final_axis_angle_deg')}))")
    r = subprocess.run([PY, "-c", code], cwd=ROOT, capture_output=True, text=True, env=child_env())
    if r.returncode != 0:
        raise SystemExit(f"make docs: the rigid run on the mesh's facets failed:\n{r.stderr[-2000:]}")
    return json.loads(r.stdout.strip().splitlines()[-1])


def _span(a: np.ndarray, digits: int) -> str:
    """A range of figures as a page prints it: "0.77–0.93", or one figure where both ends print alike."""
    lo, hi = f"{a.min():.{digits}f}", f"{a.max():.{digits}f}"
    return lo if lo == hi else f"{lo}–{hi}"


def fidelity_steps(tmp: Path) -> str:
    """What a switch of fidelity changes on C2, C7 and C8, step by step (depth mm / final axis °)."""
    rigid = read_validation(made(*VALIDATE_RIGID)[0] / "validation.csv")
    plastic = read_validation(made(*VALIDATE_PLASTIC)[0] / "validation.csv")
    lines = ["| shot | rigid, rings on the exact surface | rigid, the mesh's facets (`RigidRun(points=\"mesh\")`) | "
             "elastic | plastic |", "|---|---|---|---|---|"]
    steps = []
    for shot in ("C2", "C7", "C8"):
        m, e = _mesh_facets(shot, tmp), _elastic(shot)
        cols = [f"{float(rigid[shot]['Hy_mm']):.1f} / {float(rigid[shot]['axis_deg']):.2f}",
                f"{m['Hy_mm']:.1f} / {m['final_axis_angle_deg']:.2f}",
                f"{e['Hy_mm']:.1f} / {e['final_axis_angle_deg']:.2f}",
                f"{float(plastic[shot]['Hy_mm']):.1f} / {float(plastic[shot]['axis_deg']):.2f}"]
        lines.append(f"| {shot} | " + " | ".join(cols) + " |")
        steps.append((float(rigid[shot]["Hy_mm"]), m["Hy_mm"], e["Hy_mm"], float(plastic[shot]["Hy_mm"]),
                      [float(rigid[shot]["axis_deg"]), m["final_axis_angle_deg"], e["final_axis_angle_deg"],
                       float(plastic[shot]["axis_deg"])]))
    d = np.array([s[:4] for s in steps])
    sampling, elasticity, plasticity = (100 * (1 - d[:, k + 1] / d[:, k]) for k in range(3))
    axes = max(max(s[4]) - min(s[4]) for s in steps)
    return "\n".join(lines) + "\n\n" + (
        f"The load's sampling (rings to the mesh's facets, the same rigid body) shortens each path by "
        f"{_span(sampling, 1)} %; the body's elasticity (the mesh's rigid body to the elastic one: its compression "
        f"and the nose's ringing, whose velocities add to the points' inertial term) by {_span(elasticity, 2)} %; "
        f"plasticity by at most {np.abs(plasticity).max():.2g} %. "
        f"The final axes agree to {axes:.2f}°.")


def _impulses(history: Path) -> tuple[list[float], float, float]:
    """Each zone's share of the impulse (%), and the tail's peak force (kN) and its time (µs)."""
    with open(history, newline="") as f:
        rows = list(csv.DictReader(f))
    t = np.array([float(r["t_s"]) for r in rows])
    zones = [np.array([float(r[f"{z}_force_N"]) for r in rows]) for z in ("nose", "shank", "tail")]
    imp = [float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(t))) for f in zones]
    k = int(np.argmax(zones[2]))
    return [100 * i / sum(imp) for i in imp], zones[2][k] / 1e3, t[k] * 1e6


def structural_response(tmp: Path) -> str:
    """The paper's Figs. 19-23 in numbers: per shot of the plastic Table 1, its yield, stress and load split."""
    plastic = made(*VALIDATE_PLASTIC)[0]
    lines = ["| shot | V (m/s), α | max PEEQ | first yield (µs, mm behind the tip) | largest von Mises, where "
             "(MPa, mm) | impulse nose / shank / tail | tail's peak force (kN, µs) |", "|---|---|---|---|---|---|---|"]
    for shot, r in read_validation(plastic / "validation.csv").items():
        s = json.loads((plastic / shot / "summary.json").read_text())
        with open(plastic / shot / "hazard.csv", newline="") as f:
            hz = list(csv.DictReader(f))
        top = max(hz, key=lambda h: float(h["peak_von_mises_Pa"]))
        fy = s.get("first_yield")
        share, peak, when = _impulses(plastic / shot / "history.csv")
        lines.append(f"| {shot} | {float(r['v0_m_s']):.0f}, {_t(r['obliquity_deg'])}° | {s['max_peeq']:.2g} | "
                     + (f"{fy['t_s'] * 1e6:.0f}, {fy['axial_from_nose_mm']:.1f}" if fy else "–")
                     + f" | {float(top['peak_von_mises_Pa']) / 1e6:.0f} at {float(top['axial_from_nose_mm']):.0f} | "
                     f"{share[0]:.0f} / {share[1]:.0f} / {share[2]:.0f} % | {peak:.0f} at {when:.0f} |")
    return "\n".join(lines)


# ---- the README's headline figures and pictures ---------------------------------------------------------------
DEFAULT_RUN = ("run", "scenes/default.toml")


def _mean_errors(rows: dict) -> tuple[float, float]:
    """A Table 1's mean nose and tail errors (%)."""
    return (100 * np.mean([float(r["nose_error"]) for r in rows.values()]),
            100 * np.mean([float(r["tail_error"]) for r in rows.values()]))


def readme_headline(tmp: Path) -> str:
    """Table 1's means and C3 in both fidelities, and what the plastic validation costs."""
    rigid_dir, _ = made(*VALIDATE_RIGID)
    plastic_dir, seconds = made(*VALIDATE_PLASTIC)
    rigid, plastic = read_validation(rigid_dir / "validation.csv"), read_validation(plastic_dir / "validation.csv")
    (rn, rt), (pn, pt) = _mean_errors(rigid), _mean_errors(plastic)
    c3r, c3p = (100 * float(t["C3"]["nose_error"]) for t in (rigid, plastic))
    return (f"Table 1, all eight shots (docs/validation.md): mean nose error {rn:.1f} % rigid and {pn:.1f} % "
            f"plastic, mean tail error {rt:.1f} % and {pt:.1f} %; C3's nose within {c3r:.1f} % rigid and {c3p:.1f} % "
            f"plastic. The plastic validation took {took(seconds)}.")


def _hazard_words(summary: dict) -> str:
    """How far the C3 shot yields, in the words of the hazard map's title."""
    peeq = float(summary.get("max_peeq", 0.0))
    if peeq <= 0.0:
        return ("C3 stays elastic (its largest plastic strain is 0): the map shows the largest von Mises stress "
                "each part reached against the steel's yield stress")
    return (f"C3 barely yields (largest plastic strain {peeq:.2g}): the map shows the plastic strain of the "
            f"surface and the largest von Mises stress each part reached against the steel's yield stress")


def readme_pictures(tmp: Path) -> str:
    """The C3 pictures `make run` draws, Table 1's plastic picture and hazard maps, and ParaView's view of C3."""
    run, _ = made(*DEFAULT_RUN)
    plastic_dir, _ = made(*VALIDATE_PLASTIC)
    summary = json.loads((run / "summary.json").read_text())
    figure(run / "history.png", "c3-history.png")
    figure(run / "hazard.png", "c3-hazard.png")
    figure(plastic_dir / "validation.png", "validation-plastic.png")
    figure(plastic_dir / "hazard_maps.png", "hazard-maps.png")
    fepen("view", str(run), "--png", str(tmp / "paraview-c3.png"), "--time", "3e-4")
    figure(tmp / "paraview-c3.png", "paraview-c3.png")
    return "\n".join([
        f"C3 on the default mesh, plastic, one rank (fepen {version()}): the nose ends {summary['Hy_mm']:.1f} mm deep "
        f"and {summary['Hx_mm']:.1f} mm sideways (the test: 349.6 and 81.4 mm).", "",
        "![C3 in ParaView](docs/img/paraview-c3.png)", "",
        "![C3 history](docs/img/c3-history.png)", "",
        "`history.png`: nose and tail depth against time with the test's final depths (dashed), the deceleration, "
        "the path in the plane of incidence against the test's final nose and tail, and the energies.", "",
        "![C3 hazard map](docs/img/c3-hazard.png)", "",
        f"`hazard.png`: along the projectile, {_hazard_words(summary)} (A = 950 MPa), and the eight strain gauges. "
        "A shot that stays elastic says so in the title.", "",
        "The eight Table 1 shots, plastic, and their hazard maps side by side, from `fepen validate --set "
        "run.fields=false` (not from `make run`):", "",
        "![plastic Table 1](docs/img/validation-plastic.png)", "", "![hazard maps](docs/img/hazard-maps.png)"])


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
    out.append(f"- **Cost:** {shots} rigid shots, {took(seconds, ranks)}.")
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
    v, c = res["speeds_m_s"], res["critical_obliquity_deg"]
    rise = c[-1] - c[0]
    trend = (f"A faster projectile bites at larger obliquities: the boundary rises with speed, by {rise:.0f}°"
             if rise > 0 else f"The boundary falls with speed, by {-rise:.0f}°")
    return (ricochet_rows(res) + f"\n\nThe map and the bisections took {took(s)} (fepen {version()}). {trend} "
            f"from {v[0]:g} to {v[-1]:g} m/s.")


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
        f"{embedded} of the {len(rows)} shots embed ({took(s)}, fepen {version()}).", "",
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
        f"shots and {len(ms['response']['resistance_factor'])} for the response: {took(s)} "
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
        f"shots took {took(s)} (fepen {version()})."])


# ---- the sweep's throughput (docs/studies.md) ----------------------------------------------------------------
def _number(pattern: str, text: str) -> float:
    m = re.search(pattern, text)
    if m is None:
        raise SystemExit(f"make docs: the throughput benchmark printed no {pattern!r}:\n{text[-2000:]}")
    return float(m.group(1))


def throughput(tmp: Path) -> str:
    """benchmarks/sweep_throughput.py 2000: a rigid shot as a process, in-process and in a sweep on 1 and 2 cores."""
    env = dict(os.environ, SWEEP_THROUGHPUT_RESULTS=str(tmp / "results.md"))
    r = subprocess.run([PY, "benchmarks/sweep_throughput.py", "2000", str(tmp / "sweeps")], cwd=ROOT,
                       capture_output=True, text=True, env=env)
    if r.returncode != 0:
        raise SystemExit(f"make docs: benchmarks/sweep_throughput.py failed:\n{r.stderr[-2000:]}")
    out = r.stdout
    process = _number(r"one `fepen run` process: ([\d.]+) s", out)
    single = _number(r"single path \(\d+ shots\): ([\d.]+) ms wall", out)
    batched = _number(r"batched \(\d+ shots\): ([\d.]+) ms wall", out)
    w1 = _number(r"1 worker\(s\): ([\d.]+) s wall", out)
    w2 = _number(r"2 worker\(s\): ([\d.]+) s wall", out)
    same = "tables of 1 and 2 workers identical: True" in out
    bitwise = "summaries bitwise the same: True" in out
    return "\n".join([
        f"`benchmarks/sweep_throughput.py 2000` on the 2-core machine with nothing else running (fepen {version()}):",
        "", "| how the shot runs | cost |", "|---|---|",
        f"| one whole `fepen run` process (what a hand-written loop pays) | {process:.2f} s |",
        f"| in-process, one shot at a time (warm) | {single:.1f} ms |",
        f"| in-process, batched (`fepen.runs.batch`) | {batched:.1f} ms |",
        f"| `fepen sweep`, 2000 shots, 1 worker | {w1:.1f} s, {1e3 * w1 / 2000:.1f} ms per shot |",
        f"| `fepen sweep`, 2000 shots, 2 workers (mpirun -n 2) | {w2:.1f} s, {1e3 * w2 / 1000:.1f} ms per shot per "
        f"core |", "",
        f"The batched summaries are the single path's {'to the last bit' if bitwise else 'NOT to the last bit'}, "
        f"and the tables of 1 and 2 workers are {'identical' if same else 'NOT identical'}. At this rate 10,000 "
        f"rigid shots take {w2 / 2000 * 10000 / 60:.1f} minutes on 2 cores."])


# ---- a run's interval (docs/uncertainty.md) ------------------------------------------------------------------
def _run_lines(tmp: Path, name: str, *sets: str) -> tuple[list[str], dict]:
    """A rigid run's printed interval and envelope lines, and its summary."""
    cmd = [PY, "-m", "fepen", "run", *RIGID, *_sets(list(sets)), "--out", str(tmp / name)]
    r = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, env=child_env())
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
    r = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, env=child_env())
    if r.returncode != 0:
        raise SystemExit(f"make docs: the plastic C3 run failed:\n{r.stderr[-2000:]}")
    seconds = time.perf_counter() - t0
    keep = ("depth_mm =", "Hx_mm =", "depth_interval_mm", "lateral_interval_mm")
    lines = [ln.removeprefix("fepen: ") for ln in (r.stdout + r.stderr).splitlines()
             if ln.startswith(keep) or "validated envelope" in ln]
    s = json.loads((tmp / "p" / "summary.json").read_text())
    lo, hi = s["depth_interval_mm"]
    return "\n".join([
        f"plastic at the default mesh, `fepen run scenes/default.toml --set run.fields=false` ({took(seconds, 1)}, "
        f"fepen {version()}):", "", "```", *lines, "```", "",
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
    return (f"`mpirun -n 2 fepen study charge-safety {' '.join(CHARGE_SAFETY)}` ({took(s)}, fepen "
            f"{version()}):\n\n" + text + "\n\n![the charge-safety map](img/charge-safety-map.png)")


def history_columns(tmp: Path) -> str:
    """history.csv's column tables, from their declarations (fepen.io.columns)."""
    from fepen.io import columns

    return columns.markdown()


def run_tables(tmp: Path) -> str:
    """A run's other CSV tables, from their declarations (fepen.io.columns.TABLES)."""
    from fepen.io import columns

    return columns.tables_markdown()


@dataclass(frozen=True)
class Block:
    """One generated part of a page.

    Attributes:
        page: the page it sits on, from the project root.
        make: the generator: a scratch directory -> the block's Markdown (without its provenance line).
        cost_s: its rough cost on 2 cores, seconds (what `--list` prints, with the total).
        command: the command a reader runs to make the figures themselves, named on the page.
        cheap: re-run by tests/system/test_docs_figures.py, which fails when one of its printed digits moves.
    """

    page: str
    make: Callable[[Path], str]
    cost_s: float
    command: str
    cheap: bool = False


BLOCKS = {
    "history-columns": Block("docs/results.md", history_columns, 0, "fepen.io.columns.markdown()", True),
    "run-tables": Block("docs/results.md", run_tables, 0, "fepen.io.columns.tables_markdown()", True),
    "readme-headline": Block("README.md", readme_headline, 120,
                             "fepen validate --set effects.fidelity=rigid; fepen validate --set run.fields=false"),
    "readme-pictures": Block("README.md", readme_pictures, 60,
                             "fepen run scenes/default.toml; fepen view DIR --png --time 3e-4; fepen validate --set "
                             "run.fields=false"),
    "table1": Block("docs/validation.md", table1, 120,
                    "fepen validate --set effects.fidelity=rigid; fepen validate --set run.fields=false"),
    "table1-bands": Block("docs/validation.md", table1_bands, 150, "fepen validate --samples 200 --workers 2"),
    "tunnel-reload": Block("docs/validation.md", tunnel_reload, 10,
                           "fepen run --set effects.fidelity=rigid --set impact.velocity=893 "
                           "--set impact.obliquity_deg=0.58 --set impact.attack_deg=2 "
                           "[--set target.tunnel_reload=F | --set effects.tunnel=false]", True),
    "fidelity-steps": Block("docs/validation.md", fidelity_steps, 150,
                            "fepen validate (both fidelities); RigidRun(points=\"mesh\"); fepen run --set "
                            "effects.fidelity=elastic --set impact.shot=C2|C7|C8"),
    "structural-response": Block("docs/validation.md", structural_response, 120,
                                 "fepen validate --set run.fields=false (each shot's summary.json, hazard.csv, "
                                 "history.csv)"),
    "ballistic-limit": Block("docs/studies.md", ballistic_limit, 15,
                             f"mpirun -n 2 fepen study ballistic-limit {' '.join(_sets(LIMIT_SETS))} --tol 1", True),
    "ricochet": Block("docs/studies.md", ricochet, 20,
                      f"mpirun -n 2 fepen study ricochet {' '.join(_sets(RICOCHET_SETS))}", True),
    "monte-carlo": Block("docs/studies.md", monte_carlo, 30,
                         "mpirun -n 2 fepen sweep demos/studies/c3_scatter.toml"),
    "uncertainty-c3": Block("docs/studies.md", uncertainty_c3, 45,
                            "mpirun -n 2 fepen study uncertainty --scatter demos/studies/c3_scatter.toml"),
    "uncertainty-slab": Block("docs/studies.md", uncertainty_slab, 180,
                              "mpirun -n 2 fepen study ballistic-limit, then fepen study uncertainty (below)"),
    "throughput": Block("docs/studies.md", throughput, 150, "python benchmarks/sweep_throughput.py 2000"),
    "depth-errors": Block("docs/validation-depth.md", depth_errors, 60, "fepen validate-depth --workers 2"),
    "run-interval": Block("docs/uncertainty.md", run_interval, 5,
                          "fepen run --set effects.fidelity=rigid [--set impact.shot=C7]", True),
    "worked-example": Block("docs/uncertainty.md", worked_example, 40,
                            "fepen run scenes/default.toml --set run.fields=false"),
    "charge-safety": Block("docs/charge.md", charge_safety, 150,
                           f"mpirun -n 2 fepen study charge-safety {' '.join(CHARGE_SAFETY)}"),
}

#: the pages' blocks kept in modules of their own (tools/docs_*.py, each with BLOCKS: name -> Block), which use
#: this module's fepen/made/figure/took
EXTRA_MODULES = ("docs_cost", "docs_pages", "docs_theory", "docs_charge")


def _extra_blocks() -> None:
    import importlib

    sys.modules.setdefault("make_docs", sys.modules[__name__])  # one module, also when run as a script
    for name in EXTRA_MODULES:
        BLOCKS.update(importlib.import_module(name).BLOCKS)


#: a block's first line: the command that made its figures and the fepen that ran it
PROVENANCE = "<sub>Made by `{command}` with fepen {version}; `make docs ONLY={name}` makes it again.</sub>"
#: the figures a block may print that belong to the machine, not to fepen (wall times): the drift test masks them
MACHINE_FIGURES = re.compile(r"\d+(?:\.\d+)? s on \d+ ranks?")


def provenance(name: str) -> str:
    """The block's provenance line at today's version."""
    return PROVENANCE.format(command=BLOCKS[name].command, version=version(), name=name)


def block_text(page: str, name: str) -> str:
    """The text now between the block's markers on its page, without its provenance line."""
    text = (ROOT / page).read_text()
    m = re.search(rf"<!-- make docs: {re.escape(name)} -->\n(.*?)\n<!-- /make docs: {re.escape(name)} -->", text,
                  re.S)
    if m is None:
        raise SystemExit(f"make docs: {page} has no block {name!r} (<!-- make docs: {name} --> ... "
                         f"<!-- /make docs: {name} -->)")
    body = m.group(1)
    return body.split("\n", 1)[1] if body.startswith("<sub>Made by ") else body


def stated_provenance(page: str, name: str) -> str | None:
    """The provenance line the block carries on its page (None: none)."""
    text = (ROOT / page).read_text()
    m = re.search(rf"<!-- make docs: {re.escape(name)} -->\n(<sub>Made by .*</sub>)\n", text)
    return m.group(1) if m else None


def replace_block(page: str, name: str, body: str) -> bool:
    """Write the provenance line and body between the block's markers (the page atomically); whether it changed."""
    path = ROOT / page
    text = path.read_text()
    m = re.search(rf"(<!-- make docs: {re.escape(name)} -->\n)(.*?)(\n<!-- /make docs: {re.escape(name)} -->)", text,
                  re.S)
    if m is None:
        block_text(page, name)  # says which block is missing
    new_body = provenance(name) + "\n" + body
    if m.group(2) == new_body:
        return False
    new = text[:m.start(2)] + new_body + text[m.end(2):]
    tmp = path.with_suffix(".md.tmp")
    tmp.write_text(new)
    os.replace(tmp, path)
    return True


def remade(name: str, tmp: Path) -> tuple[str, str]:
    """A block as its page states it and as its command makes it today, both with wall times masked.

    Args:
        name: the block.
        tmp: a scratch directory.

    Returns:
        (stated, made), each the provenance line and the body.
    """
    b = BLOCKS[name]
    stated = f"{stated_provenance(b.page, name)}\n{block_text(b.page, name)}"
    return masked(stated), masked(f"{provenance(name)}\n{b.make(tmp)}")


def masked(text: str) -> str:
    """A block's text with the machine's figures (wall times) masked: what the drift test compares."""
    return MACHINE_FIGURES.sub("… s on N ranks", text)


def main(argv=None) -> int:
    """`make docs`: make the blocks named (all by default) and write them into their pages."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", nargs="+", choices=sorted(BLOCKS), help="the blocks to make (default: all)")
    ap.add_argument("--list", action="store_true", help="list the blocks, their pages and costs")
    args = ap.parse_args(argv)
    if args.list:
        for name, b in BLOCKS.items():
            print(f"{name:18s} {b.page:28s} {b.cost_s:6.0f} s  {'drift-tested' if b.cheap else ''}")
        print(f"{'all':18s} {'':28s} {sum(b.cost_s for b in BLOCKS.values()) / 60:6.1f} min")
        return 0
    for name in args.only or BLOCKS:
        page, make = BLOCKS[name].page, BLOCKS[name].make
        block_text(page, name)  # the markers exist before anything runs
        with tempfile.TemporaryDirectory(prefix=f"fepen-docs-{name}-") as tmp:
            t0 = time.perf_counter()
            body = make(Path(tmp))
        changed = replace_block(page, name, body)
        print(f"{name}: {page} {'changed' if changed else 'unchanged'} ({time.perf_counter() - t0:.0f} s)")
    return 0


sys.path.insert(0, str(Path(__file__).resolve().parent))
_extra_blocks()

if __name__ == "__main__":
    sys.exit(main())
