"""Throughput of rigid shots in a sweep, in one run: a rigid C3-like shot as a whole ``fepen run`` process
(what a hand-written loop of processes pays), the same shot in-process the first time and then warm (imports,
the projectile's load points and the compiled kernels kept, as a sweep keeps them), and a Monte Carlo sweep
of SHOTS rigid shots (v0 ± 20 m/s, obliquity ± 1°, yaw ± 0.5°, f_c ± 10 %) serially and on 2 workers (two
MPI ranks taking shots from the queue). Prints ms per shot per core and the projection for 10,000 shots on 2
cores; writes benchmarks/sweep_throughput_results.md.

    .venv/bin/python benchmarks/sweep_throughput.py [SHOTS [DIR]]   (default 2000; serially, it starts mpirun;
                                                                      DIR: keep the two sweeps in DIR/w1, DIR/w2)
"""

import sys
import tempfile
import time
from pathlib import Path

from mpi4py import MPI

from fepen import scene
from fepen.runs.rigid import RigidRun
from fepen.studies import processes, sweep

DEMO = processes.ROOT / "demos" / "studies" / "c3_scatter.toml"  # seed 2026, resized to SHOTS


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 2000
    lines = []

    def say(line):
        print(line, flush=True)
        lines.append(line)

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(sys.argv[2]) if len(sys.argv) > 2 else Path(tmp)
        tmp.mkdir(parents=True, exist_ok=True)
        t0 = time.perf_counter()
        r = processes.run(["run", "scenes/default.toml", "--set", "effects.fidelity=rigid", "--set",
                           "run.fields=false", "--out", tmp / "one"])
        process_s = time.perf_counter() - t0
        assert r.returncode == 0, r.stderr
        sc = scene.load("scenes/default.toml", ["effects.fidelity=rigid"])
        t0 = time.perf_counter()
        RigidRun(sc, None, MPI.COMM_SELF).run()
        first_s = time.perf_counter() - t0
        warm = []
        for _ in range(20):
            t0 = time.perf_counter()
            RigidRun(sc, None, MPI.COMM_SELF).run()
            warm.append(time.perf_counter() - t0)
        warm.sort()
        say(f"rigid C3, one `fepen run` process: {process_s:.2f} s; in-process, first: {1e3 * first_s:.0f} ms; "
            f"warm: median {1e3 * warm[10]:.1f} ms, best {1e3 * warm[0]:.1f} ms")
        (tmp / "mc.toml").write_text(sweep.resized(DEMO, n))
        walls = {}
        for workers in (1, 2):
            t0 = time.perf_counter()
            r = processes.run(["sweep", tmp / "mc.toml", "--out", tmp / f"w{workers}", "--workers", workers,
                               "--fresh"])
            walls[workers] = time.perf_counter() - t0
            assert r.returncode == 0, r.stderr
            per = 1e3 * walls[workers] * workers / n
            say(f"Monte Carlo sweep, {n} rigid shots, {workers} worker(s): {walls[workers]:.1f} s wall, "
                f"{per:.1f} ms per shot per core (whole command, start-up and table included)")
        same = (tmp / "w1" / "sweep.csv").read_text() == (tmp / "w2" / "sweep.csv").read_text()
        say(f"tables of 1 and 2 workers identical: {same}")
        say(f"projected 10,000 rigid shots on 2 cores: {walls[2] / n * 10000 / 60:.1f} min")
    out = Path(__file__).with_name("sweep_throughput_results.md")
    out.write_text("# Rigid shots in a sweep\n\n`benchmarks/sweep_throughput.py " + str(n) + "`, 2 cores.\n\n"
                   + "\n".join(f"- {ln}" for ln in lines) + "\n")


if __name__ == "__main__":
    main()
