"""Checkpoint files of a deformable run (``fepen run --resume DIR``; docs/theory.md §12).

A checkpoint is every rank's arrays in its own file, ``checkpoint/step<N>-rank<r>.npz`` (rank 0's also
holds the run's tables), and ``checkpoint/state.json``, which names the complete step and carries the run's
small state. Files are written under temporary names and renamed; state.json is replaced last, after a
barrier, and older step files are deleted only then, so a run killed at any instant leaves a complete
checkpoint. What goes in is the run's business (DeformableRun.write_checkpoint); this module only writes
and reads it. Resuming needs the same number of ranks as the run it continues.
"""

from __future__ import annotations

import hashlib
import io
import json
from pathlib import Path

import numpy as np

from fepen.atomic import make_dir, replacing, sha256_file
from fepen.errors import InputError
from fepen.io import files, layout
from fepen.version import __version__

#: what fepen writes in checkpoint/ (fepen.io.layout)
_STEPS = layout.RUN.node("checkpoint")


def _save(path: Path, arrays: dict) -> str:
    """Write one rank's arrays (atomically); the sha256 of the file."""
    files.inject("checkpoint")
    buf = io.BytesIO()  # made in memory: a full disk is then an OSError of one write, not inside zipfile
    np.savez(buf, **arrays)
    with replacing(path, ".npz") as tmp:
        tmp.write_bytes(buf.getbuffer())
    return hashlib.sha256(buf.getbuffer()).hexdigest()


def write(out: Path, comm, step: int, t: float, arrays: dict, meta: dict) -> None:
    """Write a checkpoint (collective).

    Args:
        out: the results directory.
        step, t: the step number and time of the state.
        arrays: this rank's arrays (name -> array).
        meta: rank 0's small state (JSON-serialisable), stored in state.json.
    """
    d = Path(out) / "checkpoint"
    files.agree(comm, f"{d}", lambda: make_dir(d))  # fepen's or new, never a link
    name = f"step{step:09d}-rank{comm.rank}.npz"
    digest = files.agree(comm, f"{d / name}", lambda: _save(d / name, arrays), root_only=False)
    digests = comm.gather(digest, root=0)

    def finish():  # state.json last, then the older steps' files
        files.inject("checkpoint")
        state = {"step": step, "t_s": t, "ranks": comm.size, "fepen": __version__, "sha256": digests, **meta}
        state["state_sha256"] = _digest(state)  # the state itself: an edited state.json is refused, never read
        with replacing(d / "state.json") as tmp:
            tmp.write_text(json.dumps(state, indent=1) + "\n")
        for f in d.iterdir():  # the older steps' files (a user's file here stays: fepen.io.layout)
            if _STEPS.node(f.name) is layout.LEAF and f.name.startswith("step") and \
                    not f.name.startswith(f"step{step:09d}-"):
                f.unlink()

    files.agree(comm, f"{d / 'state.json'}", finish)


def _digest(state: dict) -> str:
    """The SHA-256 of a checkpoint's state (its JSON, keys sorted): what fepen wrote, and nothing else, is read
    back (odd but well-formed content would otherwise reach the run's components)."""
    as_read = json.loads(json.dumps(state, default=repr))  # as state.json reads back: tuples lists, keys text
    return hashlib.sha256(json.dumps(as_read, sort_keys=True).encode()).hexdigest()


def read_state(out: Path, comm) -> dict:
    """The state.json of a results directory's last checkpoint (InputError when there is none)."""
    path = Path(out) / "checkpoint" / "state.json"
    if not path.exists():
        raise InputError("--resume", f"{out} holds no checkpoint (checkpoint/state.json); the deformable "
                                     "fidelities write one every run.checkpoint_interval of simulated time")
    try:
        state = json.loads(path.read_text())
        state["ranks"], state["step"]  # noqa: B018 - the fields every checkpoint has
    except (ValueError, KeyError, TypeError, RecursionError):
        raise InputError("--resume", f"{path} is damaged (not the JSON a checkpoint writes); the run cannot be "
                                     "resumed from it: run it again with --force") from None
    if state.get("fepen") != __version__:
        raise InputError("--resume", f"the checkpoint in {out} was written by fepen {state.get('fepen', '< 0.1')}"
                                     f", not this fepen {__version__}: run it again with --force")
    if state.get("state_sha256") != _digest({k: v for k, v in state.items() if k != "state_sha256"}):
        raise InputError("--resume", f"{path} does not match its own checksum (edited or damaged since the run wrote "
                                     "it); the run cannot be resumed from it: run it again with --force")
    if state["ranks"] != comm.size:
        raise InputError("--resume", f"the run in {out} ran on {state['ranks']} ranks; resume it on the same "
                                     f"number (mpirun -n {state['ranks']}), not {comm.size}")
    return state


def read_arrays(out: Path, comm, state: dict, root_names: tuple[str, ...]) -> dict:
    """This rank's arrays of the checkpoint that state.json names; ``root_names``, stored by rank 0 only,
    are sent to every rank (absent ones are left out)."""
    path = Path(out) / "checkpoint" / f"step{state['step']:09d}-rank{comm.rank}.npz"
    arrays, root, problem = {}, None, None
    try:
        if sha256_file(path) != state["sha256"][comm.rank]:
            problem = f"{path} does not match its checksum in state.json (a damaged file)"
        else:
            with np.load(path) as z:
                arrays = {k: z[k] for k in z.files if k not in root_names}
                root = {k: z[k] for k in root_names if k in z.files} if comm.rank == 0 else None
    except (OSError, ValueError, KeyError, IndexError, TypeError) as err:
        problem = f"{path} cannot be read ({type(err).__name__}: {err})"
    problems = [p for p in comm.allgather(problem) if p]
    if problems:
        raise InputError("--resume", f"{problems[0]}; the run cannot be resumed from it: run it again with --force")
    arrays.update(comm.bcast(root, root=0))
    return arrays


def drop(out: Path, comm) -> None:
    """Remove the checkpoints of a completed run (rank 0): what fepen wrote in checkpoint/ (a user's file there
    stays, and the folder with it)."""
    if comm.rank == 0:
        layout.remove_entry(Path(out) / "checkpoint", _STEPS)
