"""Checkpoints of a deformable run, and resuming from them (``fepen run --resume DIR``).

A checkpoint is the whole state between two steps: every rank's nodal and cell arrays of the solver (its
own file, ``checkpoint/step<N>-rank<r>.npz``), and on rank 0 the run's bookkeeping (clocks of history,
output and checkpoints, the history rows, the strain-gauge rows, the last target force) and
``checkpoint/state.json``, which names the complete step. Files are written under temporary names and
renamed; state.json is replaced last, after a barrier, and older step files are deleted only then, so a
run killed at any instant leaves a complete checkpoint to resume from.

Resuming rebuilds the mesh and solver from the results directory's scene.toml (deterministic for the same
number of ranks), checks that each rank finds the same reference nodes as before, and puts the arrays back
in place. The continued run then performs the very same floating-point operations as an uninterrupted one.
Resuming needs the same number of ranks as the run it continues.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
from mpi4py import MPI

from fepen.errors import InputError

#: solver arrays saved per rank (nodal arrays include ghost nodes)
ARRAYS = ("U", "Vel", "acc", "fint", "fext", "s", "eps_p", "temp", "sy0")
#: solver scalars, saved per rank (the work and dissipation sums are each rank's own)
SCALARS = ("t", "step_count", "dt", "dt_prev", "dt0", "dt_min", "_w_int", "_w_ext", "_plastic", "_heat", "ke0",
           "_w_if_n", "_w_if_t")


def _atomic_savez(path: Path, **arrays) -> None:
    tmp = path.with_name(path.name + f".tmp{os.getpid()}.npz")
    np.savez(tmp, **arrays)
    os.replace(tmp, path)


def write(sim, wall_s: float) -> None:
    """Write a checkpoint of a Simulation (collective).

    Args:
        sim: the fepen.simulation.Simulation, between two steps.
        wall_s: wall seconds spent so far (carried into the resumed run's wall_s).
    """
    s, comm = sim.solver, sim.comm
    d = Path(sim.out) / "checkpoint"
    if comm.rank == 0:
        d.mkdir(exist_ok=True)
    comm.barrier()
    step = s.step_count
    arrays = {k: getattr(s, k) for k in ARRAYS}
    arrays["X"] = s.X
    # per rank: the energy accumulators are this rank's partial sums
    arrays["scalars"] = np.array([float(getattr(s, k)) for k in SCALARS])
    if comm.rank == 0:
        arrays["rows"] = np.array(sim.rows, dtype=float)
        arrays["gauge_rows"] = np.array(sim.gauges.rows, dtype=float)
        if sim.sections is not None:
            arrays["section_rows"] = np.array(sim.sections.rows, dtype=float)
        arrays["load"] = np.array([*sim.load.force, sim.load.contact_nodes, getattr(sim.load, "area", 0.0)])
    _atomic_savez(d / f"step{step:09d}-rank{comm.rank}.npz", **arrays)
    comm.barrier()
    if comm.rank == 0:
        state = {"step": step, "t_s": s.t, "ranks": comm.size, "wall_s": wall_s,
                 "loop": sim.loop_state(),
                 "field_times_s": list(sim.fields.times) if sim.fields is not None else []}
        tmp = d / f"state.json.tmp{os.getpid()}"
        tmp.write_text(json.dumps(state, indent=1) + "\n")
        os.replace(tmp, d / "state.json")
        for f in d.iterdir():
            if f.name.startswith("step") and not f.name.startswith(f"step{step:09d}-"):
                f.unlink()
    comm.barrier()


def read_state(out: Path, comm) -> dict:
    """The state.json of a results directory's last checkpoint (InputError when there is none)."""
    path = Path(out) / "checkpoint" / "state.json"
    if not path.exists():
        raise InputError("--resume", f"{out} holds no checkpoint (checkpoint/state.json); the deformable "
                                     "fidelities write one every run.checkpoint_interval of simulated time")
    state = json.loads(path.read_text())
    if state["ranks"] != comm.size:
        raise InputError("--resume", f"the run in {out} ran on {state['ranks']} ranks; resume it on the same "
                                     f"number (mpirun -n {state['ranks']}), not {comm.size}")
    return state


def restore(sim, state: dict) -> None:
    """Put a checkpoint back into a freshly built Simulation (collective)."""
    s, comm = sim.solver, sim.comm
    d = Path(sim.out) / "checkpoint"
    with np.load(d / f"step{state['step']:09d}-rank{comm.rank}.npz") as z:
        same = z["X"].shape == s.X.shape and np.array_equal(z["X"], s.X)
        if not comm.allreduce(same, op=MPI.LAND):
            raise InputError("--resume", "the mesh rebuilt from scene.toml differs from the checkpointed one "
                                         "(another fepen or gmsh version, or another partition)")
        for k in ARRAYS:
            np.copyto(getattr(s, k), z[k])  # in place: compiled kernels hold these arrays' addresses
        scalars = z["scalars"]
        rows = z["rows"] if comm.rank == 0 else None
        gauge_rows = z["gauge_rows"] if comm.rank == 0 else None
        load = z["load"] if comm.rank == 0 else None
        section_rows = z["section_rows"] if comm.rank == 0 and "section_rows" in z else None
    rows, gauge_rows, load, section_rows = comm.bcast((rows, gauge_rows, load, section_rows), root=0)
    if sim.sections is not None and section_rows is not None:
        sim.sections.rows = [list(r) for r in section_rows]
    for k, v in zip(SCALARS, scalars):
        setattr(s, k, int(v) if k == "step_count" else float(v))
    sim.rows = [list(r) for r in rows]
    sim.gauges.rows = [list(r) for r in gauge_rows]
    sim.load.force = np.array(load[:3])
    sim.load.contact_nodes = int(load[3])
    if hasattr(sim.load, "area"):
        sim.load.area = float(load[4])
    sim.set_loop_state(state["loop"])
