"""The closing analyses of a completed deformable run: the gauges and hazard map, the charge's sections and
report, the accelerations (raw and filtered), the stress maps and the trajectory, or the deformed picture,
and the nose profile. Each computes and writes its own quantity; ``Closing.summary()`` hands the peaks, the
charge report and the nose profile to the summary.
"""

from __future__ import annotations

import numpy as np
from mpi4py import MPI

from fepen.data.experiments import shot as table1_shot
from fepen.io import results, table
from fepen.post import analyses, signals, slices
from fepen.solver import diagnostics


class Closing:
    """What a completed deformable run writes after its loop, and the summary keys it gives."""

    def __init__(self):
        self.peaks: dict | None = None
        self.charge: dict | None = None
        self.profile: dict | None = None
        self.first_yield: dict | None = None
        self.safety: dict | None = None

    def write(self, run) -> None:
        """Write the closing analyses of ``run`` (a fepen.runs.deformable.DeformableRun; collective)."""
        figures = run.shot.outputs.figures
        hazard = run.gauges.write(run.out, figures)
        self.first_yield = run.gauges.first_yield()
        if run.sections is not None:
            run.sections.write(run.out)
        self.peaks = accelerations(run)
        if run.pm.charge:
            report = None
            if run.comm.rank == 0:
                report = slices.charge_report(run.out, run.sections.sections, self.peaks["charge_acc"]["t_s"],
                                              figures=figures)
            self.charge = run.comm.bcast(report, root=0)
        if getattr(run, "safety", None) is not None:
            self.safety = run.safety.summary(self.peaks.get("charge_acc"))
        s = run.solver
        name, out = run.shot.experiment, run.out
        band = run.predicted(run.closing_outcome) if figures else None  # the depth interval the figures show
        jobs = []  # the figures (and stress maps' .vtu), drawn by the ranks at once: (draw, names, weight)
        if run.fields is not None:  # the cut planes at peak load and at the end, and the shot (Figs. 18, 20-21)
            jobs += [(lambda stem=stem, t=t: slices.stress_maps(out, out / f"{stem}.png", t, figures),
                      ((f"{stem}.png",) if figures else ()) + (f"{stem}.vtu",), 4.0)
                     for stem, t in (("stress_maps_peak", self.peaks["decel"]["t_s"]), ("stress_maps_end", None))]
            if figures:
                test = table1_shot(name) if name else None
                jobs.append((lambda: slices.trajectory_figure(out, out / "trajectory.png", test, summary=band),
                             ("trajectory.png",), 1.0))
        if figures:  # history.csv is whole: closed before the closing analyses
            from fepen.post import figures as figs

            jobs += [(hazard, ("hazard.png",), 2.0),
                     (lambda: figs.history_figure(out, name, MPI.COMM_SELF, band), ("history.png", "attitude.png"),
                      1.5)]
            run.history_drawn = True
        shared(run.comm, out, jobs)
        if run.fields is None and figures:
            analyses.deformed_picture(s, run.out / "deformed.png", f"t = {s.t * 1e6:.0f} µs, max PEEQ "
                                      f"{diagnostics.max_peeq(s):.3g}", run.gauges.peak_von_mises)
        m = run.model
        if m.surface is not None:
            self.profile = analyses.nose_profile(s, run.pm.shape, m.tip, m.tail, m.surface.tri, run.out, figures)

    def summary(self) -> dict:
        """The summary keys of the closing analyses (None where they were not written)."""
        return {"peak_accelerations": self.peaks, "charge": self.charge, "nose_profile": self.profile,
                "first_yield": self.first_yield, "charge_safety": self.safety}


def shared(comm, out, jobs: list) -> None:
    """Jobs that read the run's files and write files of their own (the figures), shared out over the ranks:
    the heaviest first, each to the rank with the least weight so far (on 2 ranks the two stress maps are drawn
    at once, the lighter figures beside them; collective). Rank 0 first records in the run's manifest the names
    the other ranks are about to write (its claim on the directory, fepen.atomic: the manifest lists every file
    a run writes, whichever rank wrote it).

    Args:
        comm: the run's communicator. out: the run's directory.
        jobs: (callable without arguments, the names it writes in ``out``, its weight: the time it takes,
            in any unit) triples.

    Raises:
        On every rank, when a job failed on any: the job's own exception on its rank, a RuntimeError naming the
        rank and the error elsewhere (no rank is left waiting for another).
    """
    from fepen import atomic

    load, rank_of = [0.0] * comm.size, {}
    for k in sorted(range(len(jobs)), key=lambda k: (-jobs[k][2], k)):  # the same plan on every rank
        r = min(range(comm.size), key=lambda r: (load[r], r))
        rank_of[k] = r
        load[r] += jobs[k][2]
    claim = atomic.claim_of(out) if comm.rank == 0 and comm.size > 1 and out is not None else None
    for k, (_, names, _) in enumerate(jobs):
        if claim is not None and rank_of[k]:
            for name in names:
                claim.own(name)
    error = None
    for k, (job, _, _) in enumerate(jobs):
        if rank_of[k] == comm.rank and error is None:
            try:
                job()
            except Exception as e:  # raised below, once every rank knows
                error = e
    said = comm.allgather(None if error is None else f"{type(error).__name__}: {error}")
    if error is not None:
        raise error
    for rank, what in enumerate(said):
        if what is not None:
            raise RuntimeError(f"a closing figure failed on rank {rank}: {what}")


def accelerations(run) -> dict:
    """accelerations.csv: the target deceleration (and with a charge each body's axial acceleration), raw and
    low-pass filtered (run.acceleration_filter, fepen.post.signals.acceleration_filter). Returns the peaks."""
    rows = np.array(run.rows)
    t = rows[:, 0]
    columns = run.columns
    names = ["decel_g"] + (results.CHARGE_COLUMNS if run.pm.charge else [])
    cut, kind = run.shot.outputs.acceleration_filter_hz, run.shot.outputs.acceleration_filter
    cols, header, peaks = [t], ["t_s"], {}
    for name in names:
        raw = rows[:, columns.index(name)]
        filt = signals.acceleration_filter(t, raw, kind, cut)
        cols += [raw, filt]
        header += [name, name.replace("_g", "_filtered_g")]
        k = int(np.argmax(np.abs(filt)))
        depth = rows[k, columns.index("nose_y_mm")]
        peaks[name.replace("_g", "")] = {"filtered_g": float(filt[k]), "t_s": float(t[k]),
                                         "nose_depth_mm": float(depth),
                                         "raw_peak_g": float(raw[np.argmax(np.abs(raw))])}
    table.write(run.out / "accelerations.csv", header, np.column_stack(cols).tolist(), table.DIGITS, run.comm)
    return peaks
