"""Post-processing and pictures, on rank 0 or from a results directory."""

__all__ = ["figures", "analyses", "slices", "signals", "paraview", "paths", "study_figures"]
