"""Throughput of rigid shots in a sweep, in one run: a rigid C3-like shot as a whole ``fepen run`` process
(what a hand-written loop of processes pays); the Monte Carlo shots of demos/studies/c3_scatter.toml
in-process by the single path (``RigidRun.run``, warm: imports, the projectile's load points and the compiled
kernels kept, as a sweep keeps them) and by the batched path (``fepen.runs.batch``, one compiled call per
run of shots), wall and CPU time per shot, and whether their summaries are the same to the last bit; then a
Monte Carlo sweep of SHOTS rigid shots (v0 ± 20 m/s, obliquity ± 1°, yaw ± 0.5°, f_c ± 10 %), which runs
them in batches, serially and on 2 workers (two MPI ranks taking runs of shots from the queue). Prints ms per
shot per core and the projection for 10,000 shots on 2 cores; writes benchmarks/sweep_throughput_results.md
(or $SWEEP_THROUGHPUT_RESULTS: make docs' throughput block).

    .venv/bin/python benchmarks/sweep_throughput.py [SHOTS [DIR]]   (default 2000; serially, it starts mpirun;
                                                                      DIR: keep the two sweeps in DIR/w1, DIR/w2)
"""

import os
import sys
import tempfile
import time
from pathlib import Path

from mpi4py import MPI

from fepen.runs import batch
from fepen.runs.rigid import RigidRun
from fepen.studies import processes, sweep

DEMO = processes.ROOT / "demos" / "studies" / "c3_scatter.toml"  # seed 2026, resized to SHOTS
#: shots of the in-process comparison (single path, batched path)
SINGLE, BATCHED = 40, 400
MACHINE = ("wall_s", "time_split_s", "peak_memory_bytes", "versions")


def _timed(fn):
    w, c = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - w, time.process_time() - c


def in_process(say) -> None:
    """The single and the batched path on the same Monte Carlo shots, in this process."""
    sw = sweep.read(DEMO)
    scenes = [sw.scene(i) for i in range(BATCHED)]
    RigidRun(scenes[0], None, MPI.COMM_SELF).run()  # warm: kernels built, projectile and load points kept
    batch.summaries(scenes[:2])
    ref, w1, c1 = _timed(lambda: [RigidRun(sc, None, MPI.COMM_SELF).run() for sc in scenes[:SINGLE]])
    got, w2, c2 = _timed(lambda: batch.summaries(scenes))
    same = all({k: v for k, v in a.items() if k not in MACHINE} == {k: v for k, v in b.items() if k not in MACHINE}
               for a, b in zip(ref, got))
    say(f"in-process, single path ({SINGLE} shots): {1e3 * w1 / SINGLE:.1f} ms wall, {1e3 * c1 / SINGLE:.1f} ms CPU "
        f"per shot; batched ({BATCHED} shots): {1e3 * w2 / BATCHED:.1f} ms wall, {1e3 * c2 / BATCHED:.1f} ms CPU per "
        f"shot ({c1 / SINGLE / (c2 / BATCHED):.1f}x); summaries bitwise the same: {same}")


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
        say(f"rigid C3, one `fepen run` process: {process_s:.2f} s")
        in_process(say)
        (tmp / "mc.toml").write_text(sweep.resized(DEMO, n))
        walls = {}
        for workers in (1, 2):
            t0 = time.perf_counter()
            r = processes.run(["sweep", tmp / "mc.toml", "--out", tmp / f"w{workers}", "--workers", workers,
                               "--fresh"])
            walls[workers] = time.perf_counter() - t0
            assert r.returncode == 0, r.stderr
            per = 1e3 * walls[workers] * workers / n
            say(f"Monte Carlo sweep (batched), {n} rigid shots, {workers} worker(s): {walls[workers]:.1f} s wall, "
                f"{per:.1f} ms per shot per core (whole command, start-up and table included)")
        same = (tmp / "w1" / "sweep.csv").read_text() == (tmp / "w2" / "sweep.csv").read_text()
        say(f"tables of 1 and 2 workers identical: {same}")
        say(f"projected 10,000 rigid shots on 2 cores: {walls[2] / n * 10000 / 60:.1f} min")
    out = Path(os.environ.get("SWEEP_THROUGHPUT_RESULTS", Path(__file__).with_name("sweep_throughput_results.md")))
    out.write_text("# Rigid shots in a sweep\n\n`benchmarks/sweep_throughput.py " + str(n) + "`, 2 cores.\n\n"
                   + "\n".join(f"- {ln}" for ln in lines) + "\n")


if __name__ == "__main__":
    main()
