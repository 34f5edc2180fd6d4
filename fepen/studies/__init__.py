"""Many runs: Table 1 (validate), the public depth sets (depth, calibration), the accuracy/cost study, whole
fepen processes, the shot engine on MPI groups, sweeps and their figures, the limit studies (ballistic limit,
ricochet), the uncertainty study and the closed forms they are checked against."""

__all__ = ["validate", "depth", "calibration", "wear_calibration", "accuracy_cost", "processes", "engine",
           "sweep", "sweep_figures", "limits", "closed_forms", "prediction_errors", "uncertainty"]
