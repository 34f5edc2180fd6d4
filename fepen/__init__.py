"""fepen: deformable projectile penetrating concrete by the projectile-target separation method.

Only the projectile is meshed (FEniCSx/dolfinx 0.5); the concrete acts through a cavity-expansion
resistance law applied node by node on the deformed projectile surface.
"""

__version__ = "0.1.0"
