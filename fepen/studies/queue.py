"""How the groups of a study share its shots (fepen.studies.engine.execute): a queue that rank 0's thread serves,
or, on an MPI without MPI_THREAD_MULTIPLE, a fixed round robin. A group's leader asks for the next run of shots
and sends back the last one's records with its request; a signal to any rank of a group (its ``halting``) is
said with the request, and the dispatcher then hands out no more: every group ends at its next shot boundary.
Neither knows what a shot is: ``work(run, group)`` runs one and returns its records."""

from __future__ import annotations

import threading
import time

from mpi4py import MPI

__all__ = ["parallel", "round_robin", "POLL"]

_REQUEST, _REPLY = 7101, 7102
#: the dispatcher's poll period (s) between requests
POLL = 5e-4


def parallel(runs, work, comm, k: int, log, halting) -> None:
    """The runs of shots by a queue: groups of ``k`` ranks, each leader asking rank 0's dispatcher thread.

    Args:
        runs: the runs of shot indices, in order. work: (run, group communicator) -> its records (on the group's
            leader; any value elsewhere). comm: every rank's communicator. k: ranks per group.
        log: rank 0's record log (``add(record)``, ``halted``). halting: (records) -> whether a signal stops the
            shots (called with no argument: a signal alone).
    """
    group = comm.Split(comm.rank // k, comm.rank)
    queue = comm.Dup()
    groups = comm.size // k
    dispatcher = None
    if comm.rank == 0:
        dispatcher = threading.Thread(target=_dispatch, args=(queue, list(runs), groups, log, halting), daemon=True)
        dispatcher.start()
    try:
        records, halt = None, False
        while True:
            run = None
            if group.rank == 0:
                queue.send((records, halt), dest=0, tag=_REQUEST)
                run = queue.recv(source=0, tag=_REPLY)
            run = group.bcast(run, root=0)
            if not run:
                break
            rs = work(run, group)
            records = rs if group.rank == 0 else None
            halt = halting(rs)
            if group.size > 1:  # a signal to any rank of the group
                halt = group.allreduce(halt, op=MPI.LOR)
    finally:
        if dispatcher is not None:
            dispatcher.join()
        group.Free()
        queue.Free()


def round_robin(runs, work, comm, k: int, log, halting) -> None:
    """The runs of shots dealt in turn to the groups (no dispatcher thread); the arguments as for ``parallel``."""
    group = comm.Split(comm.rank // k, comm.rank)
    mine = []
    for run in runs[comm.rank // k:: comm.size // k]:
        rs = work(run, group)
        if comm.rank == 0:
            for r in rs:
                log.add(r)
        elif group.rank == 0:
            mine.extend(rs)
        halt = halting(rs)
        if group.size > 1 and group.allreduce(halt, op=MPI.LOR) or group.size == 1 and halt:
            break
    for part in comm.gather(mine, root=0) or []:
        for r in part:
            log.add(r)
    group.Free()


def _dispatch(queue, runs: list, groups: int, log, halting) -> None:
    """Rank 0's thread: hand out the pending runs of shots in order to whichever leader asks, record what they
    send back, tell each leader to stop (an empty run) when none is left, or when a signal stopped a group (it
    says so with its request) or rank 0 (``halting()``)."""
    status = MPI.Status()
    nxt, stopped, halted = 0, 0, False
    while stopped < groups:
        if not queue.Iprobe(source=MPI.ANY_SOURCE, tag=_REQUEST, status=status):
            time.sleep(POLL)
            continue
        src = status.Get_source()
        records, halt = queue.recv(source=src, tag=_REQUEST)
        for record in records or ():
            log.add(record)
        halted = halted or halt or halting()
        if halted:
            log.halted = True
        if nxt < len(runs) and not halted:
            queue.send(runs[nxt], dest=src, tag=_REPLY)
            nxt += 1
        else:
            queue.send([], dest=src, tag=_REPLY)
            stopped += 1
