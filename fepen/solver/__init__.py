"""The explicit solver on a dolfinx mesh: cell kernels, central differences, what is read off it and
changes its reference body, target load, contact."""

__all__ = ["kernels", "ckernel", "assembly", "state", "time_step", "explicit", "probes", "diagnostics", "reference",
           "failures", "surface", "node_points", "target_load", "rigid_wall", "shell_charge", "erosion", "recession",
           "traffic"]
