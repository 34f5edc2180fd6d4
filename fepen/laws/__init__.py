"""Laws on plain arrays: materials, the target (and layered targets), the shell-charge contact, the charge's
safety criteria, rigid-body mechanics, nose wear, element erosion, the energy balance, the tunnel the
projectile opens.

No dolfinx, no MPI, no scene: parameters are plain numbers (docs/theory.md §3-§5, §13).
"""

__all__ = ["materials", "uniaxial", "target", "layers", "contact", "explosive", "rigid_body", "wear", "erosion",
           "energy", "tunnel"]
