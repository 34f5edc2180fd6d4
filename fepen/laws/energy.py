"""The energy balance of a run, one formula for both fidelities (docs/theory.md §11).

    error = |KE + KE_removed + W_int − KE_0 − W_ext − W_interface| / max(KE_0, |W_ext|, KE)

KE_removed is the kinetic energy the removed material (wear, erosion) carried away when it was removed;
W_interface the work of the shell–charge contact forces (normal work − friction dissipation). The rigid body
has no internal work and no interface.
"""

from __future__ import annotations

__all__ = ["balance_error"]


def balance_error(kinetic: float, initial_kinetic: float, external_work: float, internal_work: float = 0.0,
                  removed_kinetic: float = 0.0, interface_work: float = 0.0) -> float:
    """The relative energy-balance error.

    Args:
        kinetic: KE now (J). initial_kinetic: KE_0 (J). external_work: W_ext, the target's work (J).
        internal_work: W_int (J). removed_kinetic: KE_removed (J). interface_work: W_interface (J).

    Returns:
        The error relative to the largest of KE_0, |W_ext| and KE.
    """
    scale = max(initial_kinetic, abs(external_work), kinetic, 1e-300)
    return abs(kinetic + removed_kinetic + internal_work - initial_kinetic - external_work - interface_work) / scale
