"""What the rigid and the deformable run share: one skeleton (a template method) that both fidelities fill in.

    Run.run()       the signals, the time loop, the end or the stop, the summary
    Run.advance()   the loop: the due outputs, a step, the stop rules, every SIGNAL_EVERY steps the signals
    Run.record()    a history row from the body's snapshot(), with the layer crossings sampled there
    Run.summary()   the summary with the removal keys and the crossings, once for both
    Run.write_stop  summary.json of a stop, its outcome from fepen.errors.stop_outcome

A body (fepen.runs.rigid.RigidRun, fepen.runs.deformable.DeformableRun) gives its step (``step``), its
stop-rule sample (``extent``), its history snapshot (``snapshot``), its outputs, its summary keys and
``state()/restore()``. This module never imports its subclasses.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field

import numpy as np
from mpi4py import MPI

from fepen.errors import stop_outcome
from fepen.io import columns, files, results, rundir
from fepen.runs import events, interrupts, outputs
from fepen.runs.shot import Shot

#: steps between two looks at the signals (one reduction under MPI)
SIGNAL_EVERY = 20


@dataclass
class Removal:
    """What wear and erosion took off so far (every rank the same numbers)."""

    mass_kg: float = 0.0
    heat_J: float = 0.0
    eroded_cells: int = 0
    kinetic_J: float = 0.0
    elastic_J: float = 0.0
    remaining_kg: float | None = None  #: the mass now, as the body tracks it (None: initial minus mass_kg)
    length_mm: float | None = None  #: the length now (None: the last history row's)


@dataclass
class Snapshot:
    """The state a history row is made of (world frame, SI).

    Attributes:
        tip, tail: positions of the nose tip and the tail centre (m). velocity: centre-of-mass velocity (m/s).
        force: the target's force (N). mass: the projectile's mass now (kg). energies: kinetic, internal_work,
        external_work, elastic, plastic, heat, energy_error, total_energy, energy_ratio (J, -). contact: loaded
        points. dt: the step (s). peeq: the largest plastic strain.
        area: the loaded area (m^2). rear_depth: the shallowest load point's depth (m; the crossings).
        extra: the body's own history columns (charge, interface) by their names in fepen.io.columns.
        removal: what wear and erosion took off, when the body has it at hand (else Run.record asks removal()).
    """

    tip: np.ndarray
    tail: np.ndarray
    velocity: np.ndarray
    force: np.ndarray
    mass: float
    energies: dict
    contact: int
    dt: float
    peeq: float
    area: float
    rear_depth: float
    extra: dict = field(default_factory=dict)
    removal: Removal | None = None
    #: about the centre of mass, world frame: angular velocity (rad/s), the target's moment (N m), angular
    #: momentum (N m s)
    omega: np.ndarray = field(default_factory=lambda: np.zeros(3))
    moment: np.ndarray = field(default_factory=lambda: np.zeros(3))
    momentum: np.ndarray = field(default_factory=lambda: np.zeros(3))
    #: the target's angular impulse about O since the run began (N m s)
    impulse: np.ndarray = field(default_factory=lambda: np.zeros(3))
    centre: np.ndarray = field(default_factory=lambda: np.zeros(3))  # of mass (m, world)


class Run:
    """One shot into one results directory: the skeleton both fidelities share.

    Args:
        shot: the resolved shot (fepen.runs.shot.Shot).
        out: the results directory (None: write nothing).
        comm: the run's communicator.
    """

    fidelity: str = ""
    #: steps between two checks of the stop rules
    check_every: int = 1
    #: the user's probes (fepen.runs.probes), recorded with the history rows, or None
    probes = None

    def __init__(self, shot: Shot, out, comm=MPI.COMM_WORLD):
        self.shot, self.comm = shot, comm
        self.wall_t0 = time.perf_counter()
        self.end = shot.hard_end  # the latest simulated time the loop runs to (s)
        self.wall_before = 0.0  # wall seconds of the runs this one resumes
        self.output_s = 0.0
        self.out = files.prepare(out, comm) if out is not None else None
        self.rows: list[list[float]] = []
        self.history_text = results.history_rows()  # history.csv's rows, each formatted once
        law = shot.law
        self.rules = events.StopRules(shot.target.thickness(law), shot.end_time is None)
        self.crossings = shot.target.crossings(law)  # a layered target's entries and exits, else None
        self.removing = shot.wear is not None or shot.erosion is not None
        self.history = outputs.History(shot.outputs.history_interval, grid=not shot.rigid)
        self.outputs: list = [self.history]
        self.stop: BaseException | None = None  # what stopped the run before its end

    # ---- what a body gives ------------------------------------------------------------------------------
    t: float
    step_count: int

    def step(self) -> None:
        """Advance one step."""
        raise NotImplementedError

    def extent(self) -> tuple[float, float, np.ndarray, np.ndarray, float, float] | None:
        """(lowest and highest load-point y, centre-of-mass velocity, axis tail to nose, mass, striking
        kinetic energy) for the stop rules, or None while the projectile has not reached the target (collective)."""
        raise NotImplementedError

    def snapshot(self) -> Snapshot:
        """The state of a history row (collective)."""
        raise NotImplementedError

    def removal(self) -> Removal:
        """What wear and erosion took off so far (collective)."""
        return Removal()

    def interrupt(self, name: str) -> None:
        """A caught signal: keep what can be kept, then raise Interrupted (collective)."""
        raise NotImplementedError

    def finish_loop(self) -> None:
        """After the loop's end: the final state's history row (and the body's other outputs of it)."""
        self.record()

    def summary_extra(self, loop_s: float) -> dict:
        """The body's own summary keys."""
        return {}

    def stop_extra(self) -> dict:
        """The body's keys of a stop's summary."""
        return {}

    def write_closing(self) -> None:
        """The closing analyses of a completed run."""

    @property
    def columns(self) -> list[str]:
        """history.csv's columns (declared in fepen.io.columns, the groups this run writes)."""
        return columns.history(self)

    #: a charge's groups (fepen.io.columns): deformable runs with a charge
    charged: bool = False
    #: the frictional shell-charge interface's group
    frictional: bool = False

    @property
    def splitting(self) -> bool:
        """Whether the history has the load's split by zone (the target's kind says)."""
        return self.shot.target.splits_load()

    def load_split(self) -> list[float]:
        """The body's LOAD_COLUMNS at the history row's state (collective)."""
        raise NotImplementedError

    @property
    def wall_s(self) -> float:
        return self.wall_before + time.perf_counter() - self.wall_t0

    # ---- the skeleton -----------------------------------------------------------------------------------
    def run(self) -> dict:
        """Advance to the end time or a stop rule; write the outputs; return the summary. A stop (an error, a
        signal, a full disk) closes the outputs, writes summary.json with the stop and raises again."""
        t_loop = time.perf_counter()
        outcome, completed = None, False
        try:
            with interrupts.Interrupts(self.comm) as signals:
                outcome = self.advance(signals)
            self.finish_loop()
            completed = True
        except BaseException as err:
            self.stop = err
            raise
        finally:
            t_out = time.perf_counter()
            try:
                self.close_outputs(completed)
                if completed:
                    self.closing_outcome = outcome or "ended"
                    self.write_closing()
            except BaseException as err:  # a full disk at history.csv's last write: the stop is recorded too
                if self.stop is None:
                    self.stop = err
                raise
            finally:
                self.output_s += time.perf_counter() - t_out
                if self.stop is not None and self.out is not None:
                    self.write_stop(self.stop)
        try:
            return self.write_summary(outcome or "ended", time.perf_counter() - t_loop)
        except BaseException as err:  # a full disk at the last write: the stop's record, in the space held back
            self.stop = err
            if self.out is not None:
                self.write_stop(err)
            raise

    def advance(self, signals) -> str | None:
        """The time loop: the due outputs, a step, the stop rules, every SIGNAL_EVERY steps the signals (a
        caught SIGTERM or SIGINT interrupts after the next outputs). Returns the outcome of a stop rule, or
        None at the end of time."""
        outcome = caught = None
        while outcome is None and self.t < self.end:
            for o in self.outputs:
                if o.due(self):
                    o.write(self)
            if caught is not None:
                self.interrupt(caught)
            self.step()
            outcome = self.stop_rules()
            if self.step_count % SIGNAL_EVERY == 0:
                caught = signals.stop()
        return outcome

    def stop_rules(self) -> str | None:
        """The outcome if a stop rule fires (fepen.runs.events), else None; checked every check_every steps."""
        if self.step_count % self.check_every:
            return None
        sample = self.extent()
        return None if sample is None else self.rules.penetration(*sample)

    def record(self) -> list[float]:
        """Append one history row from the body's snapshot (and sample the layer crossings there)."""
        s = self.snapshot()
        row = columns.values(self, self.t, s)
        results.finite_row(row, self.step_count, self.t)
        self.rows.append(row)
        if self.probes is not None:
            self.probes.record(self)
        if self.crossings is not None:
            self.crossings.update(self.t, -float(s.tip[1]), s.rear_depth, float(np.linalg.norm(s.velocity)))
        return row

    def close_outputs(self, completed: bool) -> None:
        """Close every output (history.csv, the fields, the checkpoints, the bar); while stopping, a failing
        close is logged, not raised (the stop's own error is the one to report)."""
        for o in reversed(self.outputs):
            if self.stop is None:
                o.close(self, completed)
                continue
            try:
                o.close(self, completed)
            except Exception as err:  # noqa: BLE001 - into fepen.log: the console says only the stop
                rundir.log_line(f"fepen: while stopping, {type(o).__name__.lower()} output: {err}")

    def write_history(self) -> None:
        """history.csv (and probes.csv) of the rows so far (collective)."""
        if self.out is not None:
            results.write_history(self.rows, self.out, self.comm, self.columns, self.history_text)
            if self.probes is not None:
                o = self.shot.outputs
                self.probes.write(self.out, self.comm, o.acceleration_filter_hz, o.acceleration_filter)

    # ---- the summary --------------------------------------------------------------------------------------
    def removal_summary(self) -> dict:
        """Mass loss, length change, eroded cells, the wear heat and the removed energies (zero when wear and
        erosion are off), and the layer crossings' state."""
        r = self.removal()
        mass0 = self.initial_mass
        length0 = self.shot.built.shape.length * 1e3
        length = r.length_mm if r.length_mm is not None else (
            self.rows[-1][results.COL["length_mm"]] if self.rows else length0)
        return {"mass_loss_kg": r.mass_kg, "mass_loss_percent": 100.0 * r.mass_kg / mass0,
                "remaining_mass_kg": r.remaining_kg if r.remaining_kg is not None else mass0 - r.mass_kg,
                "length_change_mm": length - length0,
                "eroded_cells": r.eroded_cells,
                "crossings": self.crossings.state() if self.crossings is not None else None,
                "wear_heat_J": r.heat_J, "removed_kinetic_J": r.kinetic_J, "removed_elastic_J": r.elastic_J}

    initial_mass: float
    #: further summary blocks the caller computed (fepen.api.run: attitude_sensitivity)
    summary_blocks: dict = {}
    #: history.png drawn by the closing analyses (beside the other figures), not again by write_summary
    history_drawn: bool = False
    #: the outcome of a completed run, known to its closing analyses (their figures band its depth interval)
    closing_outcome: str = "ended"

    def predicted(self, outcome: str) -> dict:
        """The run's validated-envelope verdict and intervals from its last history row, before its summary is
        written: what the closing's figures band (the same figures summary.json will give)."""
        return prediction(self.shot.envelope, outcome,
                          results.summary(self.shot.scene, self.shot.experiment, self.rows, outcome, {}))

    def write_summary(self, outcome: str, loop_s: float) -> dict:
        """The summary (summary.json when the run has a directory). The figure, with the summary's depth interval,
        before summary.json (the last file of a run that ended well), and wall_s read last, just before
        summary.json: it covers the figure."""
        extra = {"steps": self.step_count, "end_time_s": self.t, "wall_s": None,  # read below, last
                 "ranks": self.comm.size, "fidelity": self.fidelity,
                 "peak_memory_bytes": files.peak_memory_bytes(self.comm)}
        extra.update(self.summary_extra(loop_s))
        extra.update(self.removal_summary())
        extra.update(self.summary_blocks)
        summary = results.summary(self.shot.scene, self.shot.experiment, self.rows, outcome, extra)
        if summary["experiment"] is not None:  # a run cut at its end time is not the test's finished shot
            summary["experiment"]["compared"] = outcome != "ended"
        if self.crossings is not None:
            summary.update(self.crossings.summary(self.shot.law, 1e-3 * summary["depth_mm"]))
        summary.update(prediction(self.shot.envelope, outcome, summary))
        if self.out is not None and self.shot.outputs.figures and not self.history_drawn:  # a closing drew it
            from fepen.post import figures  # (closing.shared)

            files.agree(self.comm, "history.png",
                        lambda: figures.history_figure(self.out, self.shot.experiment, MPI.COMM_SELF, summary))
        summary["wall_s"] = self.wall_s
        _whole_process(summary, self.wall_before)
        if self.out is not None:
            results.write_summary(self.out, summary, self.comm)
        return summary

    def write_stop(self, err: BaseException) -> None:
        """summary.json of a stopped run: its outcome (fepen.errors.OUTCOMES), stop_reason, stop_time_s,
        where (rank 0, no collective: the stop may have come from one rank; a full disk leaves the last one)."""
        steps, t = getattr(self, "step_count", 0), getattr(self, "t", 0.0)
        reason = str(err).splitlines()[0] if str(err) else type(err).__name__
        extra = {"steps": steps, "end_time_s": t, "ranks": self.comm.size, "fidelity": self.fidelity,
                 "wall_s": self.wall_s, **self.stop_extra()}
        summary = results.stop_summary(self.shot.scene, self.rows, stop_outcome(err).name, reason,
                                       {"step": steps, "t_s": t}, extra)
        if self.comm.rank == 0:
            rundir.release_reserve()
            try:
                files.write_json(self.out / "summary.json", summary, MPI.COMM_SELF)
            except OSError as e:
                rundir.log_line(f"fepen: summary.json of the stop not written: {e}")


def prediction(facts: dict, outcome: str, summary: dict) -> dict:
    """The summary's validated-envelope verdict and intervals (docs/uncertainty.md): "envelope",
    "depth_interval_mm", "lateral_interval_mm", "interval"."""
    from fepen.stats import envelope, interval

    verdict = envelope.verdict(facts)
    out = {"envelope": {**verdict, "line": envelope.line(verdict)}}
    out.update(interval.predict(facts, verdict, outcome, 1e-3 * summary["depth_mm"], 1e-3 * summary["Hx_mm"]))
    return out


def process_age_s() -> float | None:
    """Seconds since this process started (Linux's /proc), None where that cannot be read."""
    try:
        ticks = int(open("/proc/self/stat").read().rsplit(")", 1)[1].split()[19])
        uptime = float(open("/proc/uptime").read().split()[0])
        return max(uptime - ticks / os.sysconf("SC_CLK_TCK"), 0.0)
    except (OSError, ValueError, IndexError):
        return None


def _whole_process(extra: dict, wall_before: float) -> None:
    """``wall_s`` of a command-line run: the whole process (interpreter, imports, scene, mesh, compilation, loop,
    output), and ``time_split_s`` gains ``other``, what its named phases leave out, so that it sums to wall_s.
    A resumed run (wall_before > 0) or an API call keeps the run's own wall time; ``other`` still closes the sum."""
    from fepen.io import rundir

    whole = extra["wall_s"]
    age = process_age_s() if rundir._in_cli and wall_before == 0.0 else None
    if age is not None:
        whole = max(whole, age)
    split = extra.get("time_split_s")
    if split is not None:
        split["other"] = max(whole - sum(split.values()), 0.0)
        whole = sum(split.values())
    extra["wall_s"] = whole

