"""Many shots on any number of ranks: the engine of ``fepen sweep``, the ballistic-limit and ricochet studies
and ``fepen validate`` (docs/studies.md).

COMM_WORLD (or the communicator given) is split into groups of ``ranks_per_shot`` ranks. The leader of each
group asks rank 0 for a shot, the group runs it on its own communicator, and the leader sends the record back
with its next request: a dynamic queue, since shots differ in cost. On rank 0 a thread serves the queue
(MPI_THREAD_MULTIPLE, which mpi4py asks for) while rank 0's own group runs shots like any other. Rank 0 appends
each record to OUT/shots.jsonl as it arrives (one JSON line, flushed; synced every second), so a killed study starts
again where it stopped and never runs a finished shot twice. Records do not depend on which group ran a
shot: a rigid shot is the same ODE on any group; a deformable one is the same to round-off.

With ``batch`` > 1 a request hands out a run of up to that many shots: the rigid ones that keep no results
directory are integrated together by fepen.runs.batch (one compiled call per projectile, bitwise the single
path's summaries), the others one by one as before.
"""

from __future__ import annotations

import json
import logging
import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from mpi4py import MPI

from fepen.errors import InputError, Interrupted, SimulationError
from fepen.io import rundir
from fepen.studies import queue

__all__ = ["execute", "summaries", "run_shot", "run_shots", "process_shot", "How", "read_records",
           "check_ranks_per_shot", "RECORDS", "BATCH", "chunks", "own_folders"]

RECORDS = "shots.jsonl"
#: the records are synced to the disk at most this often (s)
SYNC = 1.0
#: shots of a request when the caller asks for batches (rigid shots: fepen.runs.batch)
BATCH = 32
#: the status of a shot a signal stopped: never recorded (it runs again when the study is continued)
INTERRUPTED = "interrupted"


def check_ranks_per_shot(ranks_per_shot: int, ranks: int) -> None:
    """The one check of ``--ranks-per-shot`` (fepen sweep, fepen study ballistic-limit and ricochet, execute):
    at least 1 and a divisor of ``ranks``, the number of ranks the shots share.

    Raises:
        InputError: (--ranks-per-shot) else.
    """
    if ranks_per_shot < 1:
        raise InputError("--ranks-per-shot", f"must be at least 1, got {ranks_per_shot}")
    if ranks % ranks_per_shot:
        raise InputError("--ranks-per-shot", f"must divide the number of ranks ({ranks}), got {ranks_per_shot}")


def read_records(out: Path) -> dict:
    """{shot: record} of OUT/shots.jsonl; a line cut short by a kill is ignored (its shot runs again)."""
    records = {}
    path = Path(out) / RECORDS
    if not path.is_file():
        return records
    for line in path.read_text().splitlines():
        try:
            r = json.loads(line)
        except ValueError:
            continue
        if isinstance(r, dict) and isinstance(r.get("shot"), int):
            records[r["shot"]] = r
    return records


class _Log:
    """Appends records to OUT/shots.jsonl, each flushed before the next shot is handed out (a killed process
    loses nothing it flushed) and synced to the disk at most every SYNC seconds (a machine that loses power
    loses at most that much)."""

    def __init__(self, out: Path | None, records: dict, bar):
        from fepen.atomic import open_append

        self.records, self.bar, self.f = records, bar, None
        self.synced = time.monotonic()
        self.added, self.halted = 0, False  # records written now; a shot a signal stopped
        if out is None:  # the records in memory alone (a study's quick calibration)
            return
        self.path = Path(out) / RECORDS
        self.f = open_append(self.path)  # never through a link; fepen's or new in the study's folder
        if self.f.tell() > 0:  # a kill may have cut the last line: start on a new one
            with open(self.path, "rb") as g:
                g.seek(-1, os.SEEK_END)
                if g.read(1) != b"\n":
                    self.f.write("\n")

    def add(self, record: dict) -> None:
        if record["status"] == INTERRUPTED:  # unfinished: it runs again when the study is continued
            self.halted = True
            return
        self.added += 1
        if self.f is not None:
            self.f.write(json.dumps(record, default=float) + "\n")
            self.f.flush()
            if time.monotonic() - self.synced > SYNC:
                os.fsync(self.f.fileno())
                self.synced = time.monotonic()
        self.records[record["shot"]] = record
        if self.bar is not None:
            self.bar.update(1)

    def close(self):
        if self.f is not None:
            self.f.flush()
            os.fsync(self.f.fileno())
            self.f.close()
        if self.bar is not None:
            self.bar.close()


def run_shot(i: int, scene, out, comm) -> dict:
    """Run shot i on comm; its record: shot, status ("ok", "stopped": the simulation could not go on,
    "bad-input"), message, summary (without the scene and versions), wall_s, ranks.

    Args:
        i: the shot's index. scene: its resolved Scene. out: its results directory, or None (a rigid shot
            then writes nothing). comm: the group's communicator.
    """
    from fepen.runs import resolve, run_in_directory, setup
    from fepen.runs.rigid import RigidRun

    t0 = time.perf_counter()
    summary = None
    try:
        if out is None and scene.effects.fidelity == "rigid":
            summary = RigidRun(scene, None, comm).run()
        else:
            sh = resolve(scene)  # bad input before the shot's folder is claimed, as fepen.api.run
            setup.announce(scene, comm, sh.built)
            summary = run_in_directory(scene, out, comm, "force", sh=sh)  # the study owns its shots' folders
            summary = json.loads(json.dumps(summary))  # as summary.json holds it (and shots.jsonl gives it back)
    except (SimulationError, InputError, Interrupted) as err:  # Interrupted: a signal; the study stops after it
        summary = err
    return _record(i, summary, time.perf_counter() - t0, comm)


def _record(i: int, result, wall: float, comm) -> dict:
    """A shot's record from its summary or the SimulationError or InputError it raised."""
    summary, status, message = None, "ok", ""
    if isinstance(result, Interrupted):  # not recorded: the shot runs again when the study is continued
        status, message = INTERRUPTED, str(result)
    elif isinstance(result, SimulationError):
        status, message = "stopped", str(result)
    elif isinstance(result, InputError):
        status, message = "bad-input", f"{result.key}: {result.message}"
    elif result is not None:
        summary = {k: v for k, v in result.items() if k not in ("scene", "versions")}
    return {"shot": i, "status": status, "message": message, "summary": summary, "wall_s": wall, "ranks": comm.size}


@dataclass(frozen=True)
class How:
    """How a round's shots run (execute's options, handed down to each group).

    Attributes:
        keep: Scene -> whether the shot keeps its results folder.
        folder: (out, index) -> a kept shot's folder, or None (OUT/shots/NNNNN).
        process: 0, or each shot is a whole ``fepen run`` process on this many ranks (its record's wall_s is the
            process's: what a user waits), its folder always kept.
    """

    keep: Callable
    folder: Callable | None = None
    process: int = 0

    def where(self, out: Path, i: int) -> Path:
        return (self.folder or _shot_dir)(out, i)


def run_shots(indices, scene_of, out: Path, comm, how: How) -> list[dict]:
    """The records of shots ``indices`` on comm, in order: the rigid shots that keep no results directory in
    one batch (fepen.runs.batch: each its share of the batch's wall time), the others by run_shot, or each a
    whole process (How.process).

    Args:
        indices: shot indices. scene_of: index -> resolved Scene. out: the study's directory. comm: the group's
            communicator. how: How.
    """
    from fepen.runs import batch

    scenes = [(i, scene_of(i)) for i in indices]
    if how.process:
        return [process_shot(i, sc, how.where(out, i), how.process) for i, sc in scenes]
    keep = how.keep
    together = [(i, sc) for i, sc in scenes if not keep(sc) and sc.effects.fidelity == "rigid"]
    records = {}
    if together:
        t0 = time.perf_counter()
        results = batch.summaries([sc for _, sc in together], comm)
        wall = (time.perf_counter() - t0) / len(together)
        for (i, _), result in zip(together, results):
            records[i] = _record(i, result, wall, comm)
    for i, sc in scenes:
        if i not in records:
            records[i] = run_shot(i, sc, how.where(out, i) if keep(sc) else None, comm)
    return [records[i] for i in indices]


def chunks(pending: list, batch: int, groups: int) -> list[list]:
    """The pending shots in runs of at most ``batch``, and at most a quarter of a group's share (so that the
    groups still share the end of a study).

    Args:
        pending: shot indices. batch: the most shots of a run. groups: the groups sharing them.
    """
    size = max(1, min(batch, -(-len(pending) // (4 * groups))))
    return [pending[j:j + size] for j in range(0, len(pending), size)]


def process_shot(i: int, scene, out: Path, ranks: int) -> dict:
    """Shot i as a whole ``fepen run`` process on ``ranks`` ranks into ``out`` (its scene handed over as a
    TOML file of its own, outside the folder); its record, with the process's wall time as wall_s."""
    import tempfile

    from fepen import scene as fscene
    from fepen.studies import processes

    with tempfile.TemporaryDirectory(prefix="fepen-shot-") as tmp:
        path = Path(tmp) / "scene.toml"
        path.write_text(fscene.to_toml(scene))
        code, wall, message = processes.run_fepen_process(["run", path, "--out", out, "--force"], ranks)
    summary = None
    if code == 0:
        summary = json.loads((Path(out) / "summary.json").read_text())
        summary = {k: v for k, v in summary.items() if k not in ("scene", "versions")}
    status = "ok" if code == 0 else "bad-input" if code == 2 else "stopped" if code == 3 else "failed"
    return {"shot": i, "status": status, "message": "" if code == 0 else message, "summary": summary,
            "wall_s": wall, "ranks": ranks}


def execute(n: int, scene_of, out, comm=None, ranks_per_shot: int = 1, keep=None, say=None,
            desc: str = "shots", batch: int = 1, progress: bool = True, folder=None,
            process: int = 0, stop=None) -> tuple[dict, int, bool]:
    """Run the shots 0 … n−1 not yet recorded in OUT/shots.jsonl.

    Args:
        n: number of shots. scene_of: shot index -> resolved Scene. out: the results directory (exists), or None
            (the records in memory only: no shot keeps a folder).
        comm: the communicator (None: COMM_WORLD). ranks_per_shot: ranks per group; divides comm.size.
        keep: Scene -> whether the shot writes its results directory OUT/shots/NNNNN (None: never for rigid
            shots). say: prints a line (rank 0). desc: the progress bar's label.
        batch: the most rigid shots of one batch. progress: the bar of shots done over the total on rank 0,
            where fepen.progress shows one (a terminal, mpirun's terminal, a notebook; FEPEN_PROGRESS).
        folder: (out, index) -> the folder of a shot that keeps its results (None: OUT/shots/NNNNN).
        process: 0, or each shot a whole ``fepen run`` process on this many ranks (How).
        stop: the study's fepen.runs.interrupts.Interrupts, or None: a signal it catches (or a shot stopped by one)
            ends the round at its next shot boundary: no new shot starts, the shots in flight end (a deformable
            one at its next check, with a checkpoint) and are not recorded, so that they run again.

    Returns:
        ({shot: record} of every finished shot on rank 0, {} elsewhere; the number of shots recorded now (rank
        0); whether a signal stopped the round on this rank's side (rank 0: on any group's)).
    """
    comm = MPI.COMM_WORLD if comm is None else comm
    k = ranks_per_shot
    check_ranks_per_shot(k, comm.size)
    how = How(keep or (lambda sc: sc.effects.fidelity != "rigid"), folder, process)
    out = Path(out) if out is not None else None  # None: the records in memory, none kept
    records = read_records(out) if comm.rank == 0 and out is not None else {}
    pending = comm.bcast([i for i in range(n) if i not in records] if comm.rank == 0 else None, root=0)
    groups = comm.size // k
    if out is not None and folder is None and comm.rank == 0 and groups > 1:
        rundir.own_name(out, "shots")  # before another group's rank makes it
    if comm.rank == 0 and say is not None:
        done = n - len(pending)
        say(f"{desc}: {n}" + (f", {done} done before (OUT/{RECORDS})" if done else "")
            + f"; {groups} group{'s' if groups > 1 else ''} of {k} rank{'s' if k > 1 else ''}")
    log = None
    if comm.rank == 0:
        from fepen import progress as fprogress

        bar = fprogress.bar(progress, total=len(pending), unit="shot", desc=desc, leave=False) if pending else None
        log = _Log(out, records, bar)
    quiet = logging.getLogger("fepen")
    level = quiet.level
    quiet.setLevel(logging.ERROR)  # the shots' notes were said once when the study was read
    interval = sys.getswitchinterval()
    halted = _halting(stop)

    def work(run, group):  # a run of shots on a group
        return run_shots(run, scene_of, out, group, how)

    def halting(records=()):  # a signal stops the shots, or stopped one of them
        return _halting(stop, records)

    try:
        runs = [] if halted else chunks(pending, batch, groups)
        if comm.size == 1:
            for run in runs:
                for r in run_shots(run, scene_of, out, comm, how):
                    log.add(r)
                if _halting(stop) or log.halted:
                    break
        elif MPI.Query_thread() < MPI.THREAD_MULTIPLE:  # no dispatcher thread: a fixed round robin
            if comm.rank == 0 and say is not None:
                say(f"{desc}: this MPI has no MPI_THREAD_MULTIPLE: shots go round robin, not by a queue")
            queue.round_robin(runs, work, comm, k, log, halting)
        else:
            sys.setswitchinterval(1e-3)  # rank 0's dispatcher answers within a millisecond or so
            queue.parallel(runs, work, comm, k, log, halting)
    finally:
        quiet.setLevel(level)
        sys.setswitchinterval(interval)
        if log is not None:
            log.close()
    halted = halted or _halting(stop) or (log is not None and log.halted)
    return records, (log.added if log is not None else 0), halted


def _halting(stop, records=()) -> bool:
    """A signal asks the shots to stop (``stop``: the study's Interrupts), or one of ``records`` is a shot a signal
    stopped."""
    return bool(stop is not None and stop.caught) or any(r["status"] == INTERRUPTED for r in records)


def _shot_dir(out: Path, i: int) -> Path:
    return out / "shots" / f"{i:05d}"



def summaries(scenes, comm=None) -> list:
    """The summaries of shots that keep no folder, run here and now (the executor in memory: no records file;
    rigid shots batched, fepen.runs.batch), in order: a summary dict, or the InputError of a shot fepen cannot
    build. A shot the simulation could not finish raises its SimulationError.

    Args:
        scenes: resolved Scenes. comm: the communicator (None: COMM_SELF); every rank gets the summaries.
    """
    comm = MPI.COMM_SELF if comm is None else comm
    records, _, _ = execute(len(scenes), lambda i: scenes[i], None, comm, keep=lambda sc: False, batch=BATCH,
                         progress=False)
    records = comm.bcast(records if comm.rank == 0 else None, root=0) if comm.size > 1 else records
    out = []
    for i in range(len(scenes)):
        r = records[i]
        if r["status"] == "stopped":
            raise SimulationError(r["message"])
        out.append(r["summary"] if r["status"] == "ok" else InputError(*r["message"].split(": ", 1))
                   if ": " in r["message"] else InputError("", r["message"]))
    return out


def own_folders(out: Path, folder: Path, scenes, shot_folder=None, process: int = 0) -> None:
    """Rank 0, before a study's round (its scenes, shot_folder and process as Round's): the top-level folders its
    kept shots will be in (OUT/shots, OUT/runs, OUT/C1, ...) in the study's manifest before any group makes them
    (the other ranks' writes, and a shot run as a process of its own, are not recorded where they happen:
    fepen.atomic.Claim's strict owner is rank 0). A name already there stays what it is (a user's was refused
    when the folder was claimed)."""
    import os

    from fepen import atomic

    claim = atomic.claim_of(out)
    if claim is None:
        return
    how = How(lambda sc: True, shot_folder, process)
    tops = set()
    for i in range(len(scenes)):
        try:
            tops.add(Path(os.path.abspath(how.where(folder, i))).relative_to(claim.dir).parts[0])
        except (ValueError, IndexError):
            continue
    for top in sorted(tops):  # a study that declares no folder of its shots keeps none
        if not os.path.lexists(claim.dir / top) and claim.declared is not None and claim.declared(top):
            claim.own(top)
