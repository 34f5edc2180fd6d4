"""make docs' blocks of the figures of docs/theory.md: what fepen computes from the equations the page states (the
default body as built, the cavity expansion's figures, the near-face stage and the tunnel's wall against the
closed forms, the rigid fidelity's sampling and step, the metal law's check, the resistance factor).

All are cheap (rigid runs in this process, or functions of fepen.laws); each generator takes a scratch directory
and returns the block's Markdown; BLOCKS registers them with tools/make_docs.py (which imports this module and
merges BLOCKS into its own).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import make_docs as md  # (Block, version)
import numpy as np

if str(md.ROOT) not in sys.path:  # these blocks import the project's fepen in process (a worktree's, not the venv's)
    sys.path.insert(0, str(md.ROOT))

#: the paper's concrete as the cavity expansion takes it (Table 3: Y = f_c = 40 MPa, E = 32.5 GPa, λ = 0.67, and
#: T = f_c/10), docs/theory.md §8.1
PAPER_Y, PAPER_E, PAPER_T, PAPER_LAMBDA = 40e6, 32.5e9, 4e6, 0.67


def rigid(*sets: str, **kw):
    """A rigid run of the default scene with these --set values, in this process: (the RigidRun, its summary)."""
    from mpi4py import MPI

    from fepen import scene
    from fepen.runs.rigid import RigidRun

    run = RigidRun(scene.load(None, ["effects.fidelity=rigid", *sets]), None, MPI.COMM_SELF, **kw)
    return run, run.run()


def _pct(x: float, digits: int = 2) -> str:
    """A signed percentage as the page prints it, with a typographic minus."""
    return f"{100 * x:+.{digits}f} %".replace("-", "−")


def _span(values, fmt: str) -> str:
    """A range as the page prints it ("a–b"), one figure where both ends print alike."""
    lo, hi = fmt.format(min(values)), fmt.format(max(values))
    return (lo if lo == hi else f"{lo}–{hi}").replace("-", "−")


# ---- §1: the default body as built -----------------------------------------------------------------------------
def default_body(tmp: Path) -> str:
    """The default projectile as fepen builds it to its mass: nose, cavity, and the nose's length per lost mass."""
    from fepen.geometry import revolution
    from fepen.laws import wear

    run, _ = rigid()
    s, g = run.shape, run.pts
    main_start = s.length - s.base_thickness - s.cavity_length  # the main section's front, behind the tip
    y_c, r_c = revolution.nose_zone(s, g["X"], g["radius"])
    zone = wear.zone_volume(g["X"], g["N"], g["area0"], y_c, r_c)
    per_percent = 1e3 * y_c / (run.shot.built.shell_density * zone) * 0.01 * run.mass  # y_c/(ρ V_zone), §14.3
    return (f"The default body as fepen builds it (`projectile.*` at their defaults, exact geometry): nose "
            f"{1e3 * s.nose_length:.1f} mm long, N\\* = {s.nose_factor():.4f}; the cavity's main section "
            f"{1e3 * s.cavity_length:.1f} mm long, starting {1e3 * (main_start - s.nose_length):.1f} mm behind the "
            f"nose shoulder, the {1e3 * s.step_length:.0f} mm step section ahead of it; wall "
            f"{1e3 * (s.radius - s.cavity_diameter / 2):.1f} mm along the shank; mass {1e3 * run.mass:.1f} g. Its "
            f"nose shortens by {per_percent:.2f} mm per percent of mass it loses (§14.3).")


# ---- §8.1: the cavity expansion's strength ---------------------------------------------------------------------
def cavity_expansion(tmp: Path) -> str:
    """The cavity expansion's c/a and σ_s for the paper's concrete, its σ_s/f_c against f_c, Forrestal's S."""
    from fepen.laws import target as tg

    ca = tg.cavity_ratio(PAPER_Y, PAPER_E, PAPER_T)
    s = tg.quasi_static_stress(PAPER_Y, PAPER_E, PAPER_T, PAPER_LAMBDA)

    def ratio(fc):  # E from ACI, T = f_c/10
        return tg.quasi_static_stress(fc, tg.youngs_modulus_aci(fc), fc / 10, PAPER_LAMBDA) / fc

    return (f"With the paper's concrete (Y = f_c = 40 MPa, E = 32.5 GPa, λ = 0.67, T = 4 MPa): c/a = {ca:.2f} and "
            f"σ_s = {s / 1e6:.0f} MPa = {s / PAPER_Y:.1f} f_c. Its weakness is the dependence on strength: with λ "
            f"fixed σ_s/f_c hardly changes with f_c ({ratio(13e6):.1f} at 13 MPa, {ratio(40e6):.1f} at 40, "
            f"{ratio(160e6):.1f} at 160, with E from ACI), while the tests want S to fall as f_c^−0.54 "
            f"({tg.forrestal_S(13e6):.1f} at 13 MPa, Forrestal's S).")


#: the friction refit fepen carried until it was retired (docs/theory.md §8.1): a, D0 with the paper's μ = 0.1
FRICTION_REFIT = ["effects.friction=true", "target.S_coefficient=62.59", "target.S_size=0.06558"]
C3_TEST_HY_MM = 349.6  # Table 1 (fepen/data/table1.csv): C3's measured depth


def friction_refit(tmp: Path) -> str:
    """The default C3 shot, rigid, with the retired friction refit on today's defaults."""
    _, s = rigid(*FRICTION_REFIT)
    return (f"With today's defaults it drives C3 {100 * (s['Hy_mm'] / C3_TEST_HY_MM - 1):.0f} % too deep "
            f"({s['Hy_mm']:.0f} against the test's {C3_TEST_HY_MM:.0f} mm, rigid).")


# ---- §8.3: the near-face stage against Li and Chen's crater ----------------------------------------------------
CRATER_V0, CRATER_FC = 800.0, 40e6


def near_face_ratio(crh: float, *sets: str) -> float:
    """fepen's near-face gain over the closed form's k d/2 (tests/system/test_crater.py): the depth beyond the
    closed form's with the full tunnel force from the face, over the closed form's gain with Li and Chen's crater
    of k = 0.707 + sqrt(ψ − 1/4) diameters."""
    from fepen.laws import target as tg
    from fepen.studies import depth

    sigma = tg.forrestal_S(CRATER_FC) * CRATER_FC
    _, s = rigid(f"projectile.crh={crh}", f"impact.velocity={CRATER_V0}", "impact.obliquity_deg=0",
                 "impact.attack_deg=0", f"target.quasi_static_stress={sigma}",
                 f"target.compressive_strength={CRATER_FC}", "target.separation_angle_deg=0", "effects.tunnel=false",
                 *sets)
    k = 0.707 + math.sqrt(crh - 0.25)
    row = depth.Row("normal", 0.0236, 0.144, 0.367, crh, CRATER_V0, CRATER_FC, 2400.0, 1.0)
    full = 1e3 * depth.closed_form_depth(row, S=sigma / CRATER_FC, k=1e-9)
    gain = 1e3 * depth.closed_form_depth(row, S=sigma / CRATER_FC, k=k) - full
    return (s["Hy_mm"] - full) / gain


def crater_check(tmp: Path) -> str:
    """The near-face work saved, in units of the closed form's k d/2, at reach 1 and at the calibrated reach."""
    crhs = (2.0, 3.0, 4.0)
    r1 = [near_face_ratio(c, "target.free_surface_range=1") for c in crhs]
    r2 = [near_face_ratio(c) for c in crhs]
    return (f"Rigid, normal, {CRATER_V0:.0f} m/s, σ_s = Forrestal's S f_c at 40 MPa, the whole nose loaded, no tunnel "
            f"(tests/system/test_crater.py): with the plastic zone cut exactly at the face (reach 1) fepen saves "
            f"{_span(r1, '{:.2f}')} k d/2 for CRH 2, 3, 4; at the calibrated reach 2, {_span(r2, '{:.2f}')} k d/2.")


# ---- §8.7: the tunnel's wall, the end of the path, Forrestal's closed form at the defaults ----------------------
CLOSED_SIGMA_FC = 40e6
CRHS, SPEEDS = (2.0, 3.0, 4.5), (300.0, 600.0, 900.0)


def after_the_nose(crh: float, v0: float, *sets: str) -> tuple[float, float]:
    """(the depth after the nose is in, Forrestal's tunnel-stage closed form M/(2π a² ρ N*) ln(1 + N* ρ V_e²/σ_s)
    from the speed V_e at which it was in) (m), as tests/system/test_rigid.py takes them."""
    from fepen.laws import target as tg

    sigma = tg.forrestal_S(CLOSED_SIGMA_FC) * CLOSED_SIGMA_FC
    run, s = rigid(f"projectile.crh={crh}", f"impact.velocity={v0}", f"target.quasi_static_stress={sigma}",
                   "target.inertial_factor=1", "effects.crater=none", "effects.free_surface=false",
                   "effects.friction=false", "impact.obliquity_deg=0", "impact.attack_deg=0",
                   "target.separation_angle_deg=1", *sets)
    ln_mm = run.shape.nose_length * 1e3
    rows = np.array(run.rows)
    from fepen.io.results import COL

    d, v = rows[:, COL["nose_y_mm"]], rows[:, COL["speed_m_s"]]
    i = int(np.flatnonzero(d >= ln_mm)[0])
    ve = float(np.interp(ln_mm, d[i - 1:i + 1], v[i - 1:i + 1]))
    a, N, rho = 0.5 * run.shape.diameter, tg.ogive_nose_factor(crh), 2400.0
    return (s["Hy_mm"] - ln_mm) * 1e-3, run.mass / (2 * math.pi * a * a * rho * N) * math.log(1 + N * rho * ve**2
                                                                                                 / sigma)


def loaded_projected_area(run) -> float:
    """The projected area (m²) of the load points a body moving along its axis loads: the forward-facing points
    beyond the separation angle (sin φ = −n_y > sin φ_min)."""
    ny = -run.pts["N"][:, 1]
    cut = max(math.sin(run.law.phi_min), 0.0) if run.law.separation else 0.0
    return float(np.sum(run.pts["area0"] * ny * (ny > cut)))


def tunnel_wall(tmp: Path) -> str:
    """The wall's figures for the paper's concrete and the default C3 shot, then the closed form at the defaults."""
    from fepen.laws import target as tg
    from fepen.runs import budget, events

    ca = tg.cavity_ratio(PAPER_Y, PAPER_E, PAPER_T)
    f = tg.reload_fraction(PAPER_Y, PAPER_LAMBDA, ca)
    grid = [tg.reload_fraction(PAPER_Y, lam, c) for lam in np.linspace(0.5, 0.8, 7) for c in np.linspace(4, 6, 9)]
    run, _ = rigid()
    sh = run.shape
    wall = budget.wall_step(run.mass, sh.diameter, sh.length, run.law)
    step = budget.default_step(run.mass, run.v0, sh.diameter, run.law)
    bound = events.end_of_path(run.mass, run.law.sigma_s * loaded_projected_area(run))
    lines = ["| the paper's concrete, the default C3 shot | value |", "|---|---|",
             f"| c/a of the cavity expansion (§8.1) | {ca:.2f} |",
             f"| wall stiffness k over the intact medium's 2G/a (ν = {tg.WALL_POISSON_DEFAULT}) | "
             f"{tg.wall_modulus(1.0, tg.WALL_POISSON_DEFAULT, ca) * (1 + tg.WALL_POISSON_DEFAULT):.2f} |",
             f"| reload strength f; over λ 0.5–0.8 and c/a 4–6 | {f:.2f}; {_span(grid, '{:.2f}')} |",
             f"| C3's RK4 step; the wall's longest, 1/ω | {1e6 * step:.1f} µs; {1e6 * wall:.1f} µs |",
             f"| C3's σ_s; the end of its path short of the rest by at most M v²/(2F) at 5 m/s | "
             f"{run.law.sigma_s / 1e6:.0f} MPa; {1e3 * bound:.3f} mm |"]
    on, off = {}, {}
    for crh in CRHS:
        for v0 in SPEEDS:
            d_on, closed = after_the_nose(crh, v0)
            d_off, _ = after_the_nose(crh, v0, "effects.tunnel=false")
            on[crh, v0], off[crh, v0] = d_on / closed - 1, d_off / closed - 1
    gap = max(abs(on[k] - off[k]) for k in on)
    table = ["| CRH | " + " | ".join(f"{v:.0f} m/s: tunnel on / off" for v in SPEEDS) + " |",
             "|---" * (len(SPEEDS) + 1) + "|"]
    for crh in CRHS:
        table.append(f"| {crh:g} | " + " | ".join(f"{_pct(on[crh, v])} / {_pct(off[crh, v])}" for v in SPEEDS) + " |")
    return "\n".join([*lines, "", "Forrestal's tunnel-stage closed form at the defaults (the tunnel on, normal "
                      "incidence, σ_s = Forrestal's S f_c at 40 MPa = "
                      f"{tg.forrestal_S(CLOSED_SIGMA_FC) * CLOSED_SIGMA_FC / 1e6:.0f} MPa, ρ 2400 kg/m³, crater, free "
                      "surface and friction off, separation on at 1°): fepen's depth after the nose is in, against "
                      "the closed form from the speed at which it was in (tests/system/test_rigid.py):", "", *table,
                      "", f"The tunnel on and off agree to {max(100 * gap, 0.01):.2f} point."])


# ---- §9: the rigid fidelity's sampling and step ----------------------------------------------------------------
SHOTS = ("C2", "C3", "C7", "C8")


def rigid_step(tmp: Path) -> str:
    """Each default shot at its step against half the step; the energy error at the step and at 1.5 times it; the
    low-speed crossing of the step's two time scales, and C3 at 1 m/s against a step 26 times finer."""
    from fepen.runs import budget

    lines = ["| shot | Hy, Hx (mm) | half the step: Hy, Hx moved by | energy error at the step; at 1.5 × it |",
             "|---|---|---|---|"]
    for shot in SHOTS:
        run, s = rigid(f"impact.shot={shot}")
        _, h = rigid(f"impact.shot={shot}", f"run.rigid_step={run.dt / 2}")
        _, w = rigid(f"impact.shot={shot}", f"run.rigid_step={run.dt * 1.5}")
        dx = h["Hx_mm"] - s["Hx_mm"]
        moved = f"{_pct(h['Hy_mm'] / s['Hy_mm'] - 1, 3)}, " + (f"{dx:+.2f} mm".replace("-", "−") if abs(dx) >= 0.005
                                                                else "0.00 mm")
        lines.append(f"| {shot} | {s['Hy_mm']:.1f}, {s['Hx_mm']:.1f} | {moved} | {s['energy_error']:.1e}; "
                     f"{w['energy_error']:.1e} |")
    run, s = rigid("impact.velocity=1")
    _, fine = rigid("impact.velocity=1", f"run.rigid_step={run.dt / 26}")
    t_stop, t_crater = budget.time_scales(run.mass, 1.0, run.shape.diameter, run.law)
    cross = t_crater / t_stop  # t_stop grows as v0 (here at 1 m/s): the two meet at this speed (m/s)
    return "\n".join(lines) + (
        f"\n\nThe step's two time scales meet at {cross:.0f} m/s for the default body in the default concrete; C3 at "
        f"1 m/s takes {run.step_count} steps to {s['Hy_mm']:.4f} mm, against {fine['Hy_mm']:.4f} mm at a step 26 "
        f"times finer.")


def rigid_rings(tmp: Path) -> str:
    """Each default shot on its D/6 rings against rings of 2.5 mm and 0.5 mm panels."""
    lines = ["| shot | Hy, Hx (mm), D/6 rings (the default) | 2.5 mm panels: Hy, Hx (the default's Hy against it) | "
             "0.5 mm panels: Hy, Hx (the default's Hy against it) |", "|---|---|---|---|"]
    for shot in SHOTS:
        run, s = rigid(f"impact.shot={shot}")
        cols = [f"{s['Hy_mm']:.1f}, {s['Hx_mm']:.1f} ({len(run.pts['X'])} points)"]
        for panel in (0.0025, 0.0005):
            r, p = rigid(f"impact.shot={shot}", f"mesh.rigid_panel={panel}")
            cols.append(f"{p['Hy_mm']:.1f}, {p['Hx_mm']:.1f} ({_pct(s['Hy_mm'] / p['Hy_mm'] - 1)}; "
                        f"{len(r.pts['X'])} points)")
        lines.append(f"| {shot} | " + " | ".join(cols) + " |")
    return "\n".join(lines)


# ---- §16: the metal law against Forrestal and Warren --------------------------------------------------------------
ROD = ["target.material='6061-T6511'", "projectile.diameter=0.0071", "projectile.length=0.071",
       "projectile.cavity_diameter=0", "projectile.material.name='aisi-4340'", "impact.obliquity_deg=0",
       "impact.attack_deg=0", "effects.free_surface=false", "effects.tunnel=false"]
METAL_SPEEDS = (400.0, 800.0, 1100.0)


def metal_check(tmp: Path) -> str:
    """demos/targets/metal_plate.py's check: the rod's rigid depth against the closed form with the nose entering,
    and the often-quoted form without it."""
    from fepen.geometry import revolution
    from fepen.studies import closed_forms

    rows = []
    for v in METAL_SPEEDS:
        run, s = rigid(*ROD, f"impact.velocity={v}")
        shape, law = run.shape, run.law
        r, slope, ln = closed_forms.tangent_ogive(shape.radius, shape.crh)
        N = shape.nose_factor()
        closed = 1e3 * closed_forms.depth_with_nose_entry(r, slope, ln, run.mass, law.density, law.B, law.sigma_s,
                                                          N, v)
        plain = 1e3 * run.mass / (2 * math.pi * shape.radius**2 * law.density * N * law.B) * math.log(
            1 + N * law.B * law.density * v * v / law.sigma_s)
        rows.append((v, s["Hy_mm"], closed, plain))
    mass = 1e3 * revolution.mass_properties(shape, run.shot.built.shell_density)[0]
    table = ["| V (m/s) | fepen (mm) | closed form (mm) | fepen's error | without the nose's entry (mm) |",
             "|---|---|---|---|---|"]
    table += [f"| {v:.0f} | {d:.1f} | {c:.1f} | {_pct(d / c - 1, 3)} | {p:.1f} ({_pct(p / c - 1, 1)}) |"
              for v, d, c, p in rows]
    return (f"For 6061-T6511, σ_s = {law.sigma_s / law.Y:.3f} Y = {law.sigma_s / 1e9:.3f} GPa. The rod: "
            f"{mass:.1f} g, rigid, normal, no free-surface rule, no tunnel:\n\n" + "\n".join(table))


# ---- §19: the resistance factor -----------------------------------------------------------------------------------
FACTORS = (0.8, 1.25, 2.0)


def resistance_factor(tmp: Path) -> str:
    """C3 at normal incidence, rigid, with the resistance factor λ: the depth over λ = 1's."""
    normal = ["impact.obliquity_deg=0", "impact.attack_deg=0"]
    base = rigid(*normal)[1]["Hy_mm"]
    parts = [f"λ = {f:g} gives {rigid(*normal, f'target.resistance_factor={f}')[1]['Hy_mm'] / base:.3f}×"
             for f in FACTORS]
    return f"C3 at normal incidence, rigid ({base:.1f} mm at λ = 1): " + ", ".join(parts) + " the depth."


BLOCKS = {
    "theory-default-body": md.Block("docs/theory.md", default_body, 1,
                                    "fepen.runs.rigid.RigidRun on the default scene (its built body)", True),
    "theory-cavity-expansion": md.Block("docs/theory.md", cavity_expansion, 0,
                                        "fepen.laws.target.cavity_ratio, quasi_static_stress, forrestal_S", True),
    "theory-friction-refit": md.Block("docs/theory.md", friction_refit, 1,
                                      f"fepen run --set effects.fidelity=rigid {' '.join(md._sets(FRICTION_REFIT))}",
                                      True),
    "theory-crater": md.Block("docs/theory.md", crater_check, 3,
                              "tests/system/test_crater.py's near_face_ratio: fepen run --set effects.fidelity=rigid "
                              "--set projectile.crh=2|3|4 --set impact.velocity=800 ... [--set "
                              "target.free_surface_range=1]", True),
    "theory-tunnel": md.Block("docs/theory.md", tunnel_wall, 4,
                              "fepen.laws.target, fepen.runs.budget on C3; tests/system/test_rigid.py's after_the_nose "
                              "(CRH 2|3|4.5, 300|600|900 m/s, the tunnel on and off)", True),
    "theory-rigid-step": md.Block("docs/theory.md", rigid_step, 5,
                                  "fepen run --set effects.fidelity=rigid --set impact.shot=C2|C3|C7|C8 [--set "
                                  "run.rigid_step=DT/2|1.5 DT]; --set impact.velocity=1 [--set run.rigid_step=DT/26]",
                                  True),
    "theory-rigid-rings": md.Block("docs/theory.md", rigid_rings, 6,
                                   "fepen run --set effects.fidelity=rigid --set impact.shot=C2|C3|C7|C8 [--set "
                                   "mesh.rigid_panel=0.0025|0.0005]", True),
    "theory-metal": md.Block("docs/theory.md", metal_check, 2,
                             "demos/targets/metal_plate.py --speeds 400,800,1100 (in process)", True),
    "theory-resistance": md.Block("docs/theory.md", resistance_factor, 2,
                                  "fepen run --set effects.fidelity=rigid --set impact.obliquity_deg=0 --set "
                                  "impact.attack_deg=0 [--set target.resistance_factor=0.8|1.25|2]", True),
}
