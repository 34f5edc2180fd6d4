"""The integer tags of the projectile mesh (gmsh physical groups, dolfinx meshtags).

volumes: SHELL, CHARGE; surfaces: OUTER (the only surface the target loads), CAVITY (the cavity wall, the
shell's side of the shell-charge interface), CHARGE_FACE (the charge's side of a split wall).
"""

SHELL, CHARGE = 1, 2
OUTER, CAVITY = 11, 12
#: the charge's side of the cavity wall when it has nodes of its own (fepen.geometry.partition.split_wall)
CHARGE_FACE = 13

__all__ = ["SHELL", "CHARGE", "OUTER", "CAVITY", "CHARGE_FACE"]
