"""fepen's version (one place; the package, results and checkpoints read it here)."""

__version__ = "0.1.0"
