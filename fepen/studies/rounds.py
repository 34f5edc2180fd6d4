"""A study's rounds: what its ``rounds`` generator yields (a Round of shots, a Sub study run in a folder of its own,
the Inputs its later rounds read) and their driver on the one executor (fepen.studies.engine), with the study's
RunInfo (how it is being run, what its rounds found).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from fepen.studies.products import Inputs

__all__ = ["Round", "Sub", "RunInfo", "drive"]


@dataclass
class Round:
    """One round of shots a study hands the executor.

    Attributes:
        scenes: the shots' resolved Scenes, in order.
        folder: where the round's records are kept, under the study's folder ("": the folder itself; a killed
            study resumes a round from its records).
        keep: Scene -> whether the shot keeps its results folder (None: the deformable shots do).
        shot_folder: (round folder, index) -> a kept shot's folder (None: ROUND/shots/NNNNN).
        batch: the rigid shots that keep no folder may run together (fepen.runs.batch).
        label: the progress bar's and the console's word for the shots ("": the round says nothing).
        then: the next round depends on this one's records: every rank receives them (else rank 0 alone).
        process: 0, or each shot a whole ``fepen run`` process on this many ranks (its wall time is the
            process's; fepen.studies.engine.process_shot).
    """

    scenes: Sequence
    folder: str = ""
    keep: Callable | None = None
    shot_folder: Callable | None = None
    batch: bool = True
    label: str = "shots"
    then: bool = False
    process: int = 0


@dataclass
class Sub:
    """A study run inside another's folder, as one of its rounds (the uncertainty study's two samples are two
    sweeps): ``result = yield Sub(...)`` gives its public result.

    Attributes:
        study: the Study (fepen.studies.study). plan: its plan. folder: its folder under the outer study's.
            label: put before each of its console lines.
    """

    study: object
    plan: object
    folder: str
    label: str = ""


@dataclass
class RunInfo:
    """How the study is being run, for its result and its files: when it began, the shots run now (the rest came
    from the records of an earlier, killed run), the ranks, and the console."""

    t0: float
    ranks: int
    ranks_per_shot: int
    say: Callable = print
    ran: int = 0
    records: list = field(default_factory=list)
    stop: object = None  #: the study's fepen.runs.interrupts.Interrupts while its rounds run
    out: Path | None = None  #: the study's folder (made)
    found: object = None  #: what the rounds returned (their generator's return value: e.g. a bisection's steps)

    @property
    def wall_s(self) -> float:
        """Wall seconds since the study began."""
        return time.perf_counter() - self.t0


def drive(study, plan, out: Path, comm, info: RunInfo, progress: bool, run) -> None:
    """Drive the study's rounds on the executor (``run``: fepen.studies.study.run, for a Sub), each round's
    records into info.records (rank 0's; the other ranks' only for a round whose records decide the next,
    Round.then); a signal ends them at a shot boundary
    (Interrupted on every rank: the study's record says "interrupted", and the same command continues it)."""
    from mpi4py import MPI

    from fepen.studies import engine

    gen = study.rounds(plan)
    records = None
    while True:
        try:
            rnd = gen.send(records) if records is not None else next(gen)
        except StopIteration as end:
            info.found = end.value
            return
        if isinstance(rnd, Inputs):  # files the next rounds read, written by rank 0; every rank gets the folder
            from fepen.io import files

            files.agree(comm, str(out), lambda r=rnd: r.write(out, info.say))
            records = out
            continue
        if isinstance(rnd, Sub):
            say = info.say if not rnd.label else (lambda *ls, n=rnd.label: info.say(*(f"{n}: {x}" for x in ls)))
            records = run(rnd.study, rnd.plan, out / rnd.folder, comm, info.ranks_per_shot, False, say, progress)
            info.ran += records["ran"]
            continue
        folder = out / rnd.folder if rnd.folder else out
        if rnd.folder:  # fepen's or new in the study's folder, never a link; a refusal reaches every rank
            from fepen.atomic import make_dir
            from fepen.io import files

            files.agree(comm, str(folder), lambda f=folder: make_dir(f))
        if comm.rank == 0:
            engine.own_folders(out, folder, rnd.scenes, rnd.shot_folder, rnd.process)
        recs, ran, halted = engine.execute(len(rnd.scenes), lambda i, s=rnd.scenes: s[i], folder, comm,
                                           info.ranks_per_shot, keep=rnd.keep, say=info.say if rnd.label else None,
                                           desc=rnd.label or "shots", batch=engine.BATCH if rnd.batch else 1,
                                           progress=progress, folder=rnd.shot_folder, process=rnd.process,
                                           stop=info.stop)
        if (comm.allreduce(halted, op=MPI.LOR) if comm.size > 1 else halted):
            from fepen.errors import Interrupted

            what = info.stop.name if info.stop is not None and info.stop.name else "a signal to another rank"
            what = "a signal passed on through mpirun (SIGUSR1)" if what == "SIGUSR1" else what
            raise Interrupted(f"{what} stopped the {study.name} at a shot boundary, {info.ran + ran} shot(s) "
                              "recorded now; the same command continues it (the shots in flight run again)")
        records = comm.bcast(recs if comm.rank == 0 else None, root=0) if rnd.then and comm.size > 1 else recs
        info.records.append(records)
        info.ran += ran
