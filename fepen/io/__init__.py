"""The files a run writes: atomic text and JSON, history and summary, crash-safe fields, the run directory
(refusal, --force, lock, run.json, fepen.log), what each kind of record owns in its folder, VTK XML grids."""

__all__ = ["files", "table", "columns", "results", "fields", "rundir", "probes", "vtu", "layout"]
