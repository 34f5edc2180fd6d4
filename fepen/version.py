"""fepen's version (one place; the package, results and checkpoints read it here)."""

__version__ = "0.7.0"
#: the layout of summary.json (its keys, their units and signs), raised when a key changes meaning or goes:
#: 2 from 0.2.0 (Tx_mm and Ty_mm signed, wall_s the whole process; CHANGELOG.md); 3 (unreleased): Hx_mm and
#: Hy_mm signed like Tx_mm and Ty_mm (a nose above the face: Hy_mm < 0; they were magnitudes)
SUMMARY_FORMAT = 3
