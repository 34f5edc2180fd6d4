"""Laws on plain arrays: materials, the target, the shell-charge contact, rigid-body mechanics.

No dolfinx, no MPI, no scene: parameters are plain numbers (docs/theory.md §3-§5, §13).
"""

__all__ = ["materials", "uniaxial", "target", "contact", "rigid_body"]
