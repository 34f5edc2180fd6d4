"""A console that speaks only for fepen (issue 46, acceptance 4): a first deformable run, its JIT and font caches
empty, prints no line fepen did not write, and no progress bar into a redirected stderr; what the other packages
said (ffcx's compiler lines, matplotlib's font cache) is in fepen.log, named by its logger.

Before: logging.basicConfig on the root logger printed ffcx's gcc lines and matplotlib's "generated new
fontManager" as "fepen: ..." lines, and the run's tqdm bar went into a redirected stderr (a Slurm .err file)."""

import os
import subprocess

from fepen.studies import processes


def test_a_first_deformable_run_prints_only_fepen_lines(tmp_path):
    env = dict(processes.mpi_env(), XDG_CACHE_HOME=str(tmp_path / "cache"), MPLCONFIGDIR=str(tmp_path / "mpl"),
               NUMBA_CACHE_DIR=str(tmp_path / "numba"), FEPEN_MESH_CACHE=os.environ.get("FEPEN_MESH_CACHE", ""))
    env.pop("FEPEN_PROGRESS", None)
    out = tmp_path / "run"
    r = subprocess.run(processes.command(["run", "--set", "mesh.size=0.005", "--set", "run.end_time=5e-5",
                                          "--set", "run.fields=false", "--out", str(out)], 1, True),
                       cwd=processes.ROOT, capture_output=True, text=True, env=env, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    assert "\r" not in r.stderr and "µs/s" not in r.stderr  # no progress bar in a pipe
    foreign = [ln for ln in r.stderr.splitlines() if ln and not ln.startswith("fepen")]
    assert not foreign, foreign
    disguised = [ln for ln in r.stderr.splitlines() if any(w in ln for w in ("gcc", "build_ext", "fontManager"))]
    assert not disguised, disguised  # another package's line given fepen's prefix
    assert all(" = " in ln or ln.startswith(("written:", "inside", "outside", "depth_interval"))
               for ln in r.stdout.splitlines() if ln), r.stdout
    log = (out / "fepen.log").read_text().splitlines()
    chatter = [ln for ln in log if ln and not ln.startswith(("fepen", "#"))]
    assert any("font" in ln for ln in chatter), chatter[:5]  # the font cache was built, and said so, here
    assert len(chatter) >= 3  # and the compiler's lines
