"""Statistics of fepen's own error, below the runs that report it (docs/uncertainty.md): the validated envelope (the
public shots' ranges, and a scene's verdict), the prediction interval (a random-effects model of the errors on the
public data) and the statistics of a sample of shots (Wilson's interval, fepen's error drawn per shot, importance
reweighting, quantiles) and the distributions of a test's unmeasured inputs (striking). Plain numbers in, plain
numbers out: no scene, no MPI."""

__all__ = ["envelope", "interval", "sampling", "striking"]
