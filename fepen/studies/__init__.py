"""Many runs, each a Study of one skeleton (study: plan, digest, rounds of shots, result, files; the registry STUDIES;
record: its inputs and its verdict) on one executor (engine: MPI groups taking shots from a queue, queue: how the
groups share them, rigid shots batched, whole processes): sweeps of a spec (spec, shot_table, monte_carlo, sweep),
Table 1 (validate) and its ensembles (bands), the public depth sets (depth), the limit studies (limits: ballistic
limit, ricochet), the charge-safety map (charge_safety), the uncertainty study (uncertainty, resistance,
uncertainty_report), the accuracy/cost study (accuracy_cost), the calibrations (calibration, wear_calibration) and
fepen/data's table of errors (prediction_errors); whole fepen processes (processes) and the closed forms they are
checked against."""

__all__ = ["study", "rounds", "products", "record", "spec", "shot_table", "monte_carlo", "engine", "queue",
           "processes", "sweep", "validate", "bands", "depth", "limits", "charge_safety", "uncertainty", "resistance",
           "uncertainty_report", "accuracy_cost", "calibration", "wear_calibration", "prediction_errors",
           "closed_forms"]
