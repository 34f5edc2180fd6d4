"""The explicit solver on a dolfinx mesh: cell kernels, central differences, target load, contact."""

__all__ = ["kernels", "ckernel", "explicit", "surface", "target_load", "rigid_wall", "shell_charge"]
