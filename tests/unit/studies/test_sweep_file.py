"""Sweep files (fepen.studies.sweep.read): grids, ranges, Monte Carlo samples (their statistics, seeds, Latin
hypercube strata, truncation), tables, and bad input named by key, all without running a shot."""

import math

import numpy as np
import pytest
from scipy import stats

from fepen.errors import InputError
from fepen.studies import sweep

RIGID = '[base]\neffects.fidelity = "rigid"\n'


def write(tmp_path, text, name="s.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_grid_is_every_combination_first_key_slowest(tmp_path):
    s = sweep.read(write(tmp_path, RIGID + '[grid]\n"impact.velocity" = [500.0, 600.0]\n'
                         '"impact.obliquity_deg" = { start = 0.0, stop = 30.0, num = 4 }\n'
                         'target.compressive_strength = [3e7, 4e7, 5e7]\n'))
    assert s.kind == "grid" and s.keys == ["impact.velocity", "impact.obliquity_deg", "target.compressive_strength"]
    assert len(s.shots) == 2 * 4 * 3
    assert [sh["impact.velocity"] for sh in s.shots[:12]] == [500.0] * 12
    assert [sh["impact.obliquity_deg"] for sh in s.shots[:12:3]] == [0.0, 10.0, 20.0, 30.0]
    assert s.scene(23).impact.velocity == 600.0 and s.scene(23).target.compressive_strength == 5e7


def test_range_by_step_includes_the_stop(tmp_path):
    s = sweep.read(write(tmp_path, RIGID + '[grid]\n"impact.velocity" = '
                                           '{ start = 300.0, stop = 900.0, step = 150.0 }\n'))
    assert [sh["impact.velocity"] for sh in s.shots] == [300.0, 450.0, 600.0, 750.0, 900.0]


def test_shot_impact_values_become_keys_when_varied(tmp_path):
    """impact.shot = C3 in the base fixes v0, obliquity and attack; varying one of them keeps the other two."""
    s = sweep.read(write(tmp_path, '[base]\nimpact.shot = "C3"\neffects.fidelity = "rigid"\n'
                                   '[grid]\n"impact.velocity" = [400.0]\n'))
    sc = s.scene(0)
    assert sc.impact.velocity == 400.0 and sc.impact.obliquity_deg == 10.5 and sc.impact.attack_deg == 0.1


MC = RIGID + """[monte_carlo]
samples = {n}
seed = {seed}
latin_hypercube = {lhs}
[monte_carlo.vary]
"impact.velocity" = {{ distribution = "normal", std = 20.0 }}
"impact.obliquity_deg" = {{ distribution = "truncated-normal", mean = 0.5, std = 1.0, low = 0.0, high = 2.0 }}
"target.compressive_strength" = {{ distribution = "normal", std_percent = 10.0 }}
"impact.attack_deg" = {{ distribution = "uniform", low = -0.5, high = 0.5 }}
"""


def sample(tmp_path, n=4000, seed=3, lhs="false"):
    return sweep.read(write(tmp_path, MC.format(n=n, seed=seed, lhs=lhs)))


def test_monte_carlo_statistics(tmp_path):
    """Means and deviations within 4 standard errors; the normal's mean is the base scene's value."""
    s = sample(tmp_path)
    v = np.array([sh["impact.velocity"] for sh in s.shots])
    n = len(v)
    assert abs(v.mean() - 584.3) < 4 * 20 / math.sqrt(n)  # the default scene's v0
    assert abs(v.std(ddof=1) - 20) < 4 * 20 / math.sqrt(2 * n)
    fc = np.array([sh["target.compressive_strength"] for sh in s.shots])
    assert abs(fc.std(ddof=1) / 40e6 - 0.10) < 4 * 0.1 / math.sqrt(2 * n)
    a = np.array([sh["impact.attack_deg"] for sh in s.shots])
    assert a.min() >= -0.5 and a.max() <= 0.5 and abs(a.mean()) < 4 * (1 / math.sqrt(12)) / math.sqrt(n)
    ob = np.array([sh["impact.obliquity_deg"] for sh in s.shots])
    assert ob.min() >= 0.0 and ob.max() <= 2.0
    tn = stats.truncnorm(-0.5, 1.5, loc=0.5, scale=1.0)
    assert abs(ob.mean() - tn.mean()) < 4 * tn.std() / math.sqrt(n)
    assert stats.kstest(ob, tn.cdf).pvalue > 1e-3


def test_monte_carlo_is_seeded(tmp_path):
    a = sample(tmp_path, n=50, seed=7)
    b = sample(tmp_path, n=50, seed=7)
    c = sample(tmp_path, n=50, seed=8)
    assert a.shots == b.shots and a.digest == b.digest
    assert a.shots != c.shots and a.digest != c.digest


def test_latin_hypercube_has_one_shot_per_stratum(tmp_path):
    n = 200
    s = sample(tmp_path, n=n, lhs="true")
    a = np.array([sh["impact.attack_deg"] for sh in s.shots])  # uniform on [-0.5, 0.5]: strata of 1/n
    assert sorted(np.floor((a + 0.5) * n).astype(int)) == list(range(n))
    v = np.array([sh["impact.velocity"] for sh in s.shots])
    u = stats.norm.cdf(v, 584.3, 20.0)
    assert sorted(np.floor(u * n + 1e-9).astype(int)) == list(range(n))


def test_table_of_shots(tmp_path):
    write(tmp_path, "impact.velocity,impact.obliquity_deg,target.material\n500,0,concrete\n650.5,15,limestone\n",
          "shots.csv")
    s = sweep.read(write(tmp_path, RIGID + '[table]\nfile = "shots.csv"\n'))
    assert s.kind == "table" and len(s.shots) == 2
    assert s.scene(1).impact.velocity == 650.5 and s.scene(1).target.material == "limestone"


@pytest.mark.parametrize("text, key", [
    (RIGID, "SWEEP"),  # no grid, Monte Carlo or table
    (RIGID + '[grid]\n"impact.speed" = [1.0]\n', "grid.impact.speed"),
    (RIGID + '[grid]\n"impact.velocity" = []\n', "grid.impact.velocity"),
    (RIGID + '[grid]\n"impact.velocity" = { start = 1.0, stop = 2.0 }\n', "grid.impact.velocity"),
    (RIGID + '[grid]\n"impact.velocity" = [500.0, -1.0]\n', "shot 1: impact.velocity"),
    (RIGID + '[grid]\n"impact.velocity" = [500.0]\n[monte_carlo]\nsamples = 3\n', "SWEEP"),
    (RIGID + '[monte_carlo]\nsamples = 0\n[monte_carlo.vary]\n"impact.velocity" = '
             '{ distribution = "normal", std = 1.0 }\n', "monte_carlo.samples"),
    (RIGID + '[monte_carlo]\nsamples = 3\n[monte_carlo.vary]\n"impact.velocity" = { distribution = "gamma" }\n',
     "monte_carlo.vary.impact.velocity.distribution"),
    (RIGID + '[monte_carlo]\nsamples = 3\n[monte_carlo.vary]\n"impact.velocity" = { distribution = "normal" }\n',
     "monte_carlo.vary.impact.velocity.std"),
    (RIGID + '[monte_carlo]\nsamples = 3\n[monte_carlo.vary]\n"impact.velocity" = { distribution = "normal", '
             'std = 1.0, low = 0.0 }\n', "monte_carlo.vary.impact.velocity.low"),
    (RIGID + '[monte_carlo]\nsamples = 3\n[monte_carlo.vary]\n"target.thickness" = { distribution = "normal", '
             'std = 1.0 }\n', "monte_carlo.vary.target.thickness.mean"),
    (RIGID + '[table]\nfile = "missing.csv"\n', "table.file"),
    (RIGID + '[grid]\n"impact.velocity" = [500.0]\n[output]\ndigits = 2\n', "output.digits"),
    ('[sweeps]\n', "sweeps"),
    ('[grid\n', "SWEEP"),
])
def test_bad_sweep_files_name_the_key(tmp_path, text, key):
    with pytest.raises(InputError) as err:
        sweep.read(write(tmp_path, text))
    assert err.value.key == key, str(err.value)


def test_a_monte_carlo_sweep_reports_the_designers_probabilities():
    """sweep.md of a Monte Carlo sweep: P(perforation), P(ricochet) and P(|final axis| > 10°) with their Wilson
    intervals, over the shots that finished; the final axis among the summarised figures."""
    from types import SimpleNamespace

    from fepen.stats.sampling import wilson
    from fepen.studies.sweep import report

    outcomes = ["perforated", "embedded", "ricochet", "embedded"]
    axes = [2.0, 12.0, -40.0, 5.0]
    rows = [{"shot": i, "impact.velocity": 500.0 + i, "status": "ok", "outcome": o, "depth_mm": 100.0 + i,
             "final_axis_angle_deg": a} for i, (o, a) in enumerate(zip(outcomes, axes))]
    rows.append({"shot": 4, "impact.velocity": 504.0, "status": "error", "outcome": None, "depth_mm": None,
                 "final_axis_angle_deg": None})
    sw = SimpleNamespace(kind="monte-carlo", keys=["impact.velocity"], shots=[{}] * 5)
    text = report(sw, rows, 1.0, 5, 1, 1)
    lo, hi = wilson(1, 4)
    assert f"| perforation | 1/4 | 0.250 | {lo:.3f}-{hi:.3f} |" in text
    assert "| ricochet | 1/4 | 0.250 |" in text
    assert "| final axis beyond 10° | 2/4 | 0.500 |" in text
    assert "| `final_axis_angle_deg` | 4 |" in text
    grid = report(SimpleNamespace(kind="grid", keys=["impact.velocity"], shots=[{}] * 5), rows, 1.0, 5, 1, 1)
    assert "| perforation |" not in grid  # a grid's proportions are not probabilities
