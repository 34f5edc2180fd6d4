"""fepen: deformable projectile penetrating concrete by the projectile-target separation method.

Only the projectile is meshed (FEniCSx: dolfinx 0.5.2, Debian bookworm's, or 0.11, the current release;
docs/install.md); the concrete acts through a cavity-expansion resistance law applied node by node on the
deformed projectile surface.

The API (docs/api.md): ``fepen.Scene``, ``fepen.run(scene, out=None, comm=None) -> Result``,
``fepen.load(results_dir) -> Result``, ``fepen.resume(results_dir)``, ``fepen.mesh(scene, out) -> dict``,
``fepen.sweep(spec, out=None) -> pandas.DataFrame``, ``fepen.study(name, out=None, **options) -> dict``
(every study the command line runs). The layers, bottom up: ``data``, ``stats`` and ``laws`` (plain arrays),
``geometry``, ``solver`` (dolfinx, through ``dolfinx_api``), ``io``, ``post`` and ``scene``, ``runs``,
``studies``, ``api``, ``cli``.
"""

import os
import sys
from pathlib import Path

from fepen.version import __version__

__all__ = ["Scene", "Result", "run", "load", "resume", "mesh", "sweep", "study", "InputError", "SimulationError",
           "MachineFault", "Interrupted", "__version__"]

# numba highlights its error messages with colorama when colorama is installed (Debian's paraview brings
# it): colorama then writes an ANSI reset to a terminal's stdout at exit, which under mpirun (whose ranks'
# stdout is a pseudo-terminal) lands in the output of `--json` demos and of fepen's own commands.
os.environ.setdefault("NUMBA_DISABLE_ERROR_MESSAGE_HIGHLIGHTING", "1")


def _numba_cache_per_rank() -> None:
    """Under mpirun, give each rank its own numba cache (``~/.cache/fepen/numba/rankN``).

    numba's on-disk cache is not safe against processes compiling and writing the same entries at once
    (numba issues #4807, #10128: segmentation faults); the ranks of a run whose cache is cold or stale
    (a fresh clone, an edited kernel) would do exactly that. A serial run keeps numba's default (the
    __pycache__ beside the sources). NUMBA_CACHE_DIR, if set, is left alone. Under pytest-xdist (make test's
    system lane) two workers may each start an mpirun job at once: their ranks N would share rankN, so each
    worker's runs get folders of their own (``~/.cache/fepen/numba/gwK/rankN``; PYTEST_XDIST_WORKER reaches
    the ranks through the environment).
    """
    env = os.environ
    rank = env.get("OMPI_COMM_WORLD_RANK", env.get("PMI_RANK"))
    size = env.get("OMPI_COMM_WORLD_SIZE", env.get("PMI_SIZE"))
    if rank is None or size in (None, "1") or "NUMBA_CACHE_DIR" in env:
        return
    folder = Path(env.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "fepen" / "numba"
    folder = folder / env.get("PYTEST_XDIST_WORKER", "") / f"rank{rank}"
    env["NUMBA_CACHE_DIR"] = str(folder)
    if "numba" in sys.modules:  # imported before fepen: dispatchers made from now on read the config
        sys.modules["numba"].config.CACHE_DIR = str(folder)


_numba_cache_per_rank()


def __dir__() -> list[str]:
    """The API (``__all__``), for ``dir(fepen)`` and tab completion; not the helpers this file imports."""
    return sorted(__all__)


def __getattr__(name):
    """The API, imported on first use: ``import fepen`` stays cheap (no dolfinx, no MPI)."""
    if name in ("Scene", "Result", "run", "load", "resume", "mesh", "sweep", "study"):
        from fepen import api

        return getattr(api, name)
    if name in ("InputError", "SimulationError", "MachineFault", "Interrupted"):
        from fepen import errors

        return getattr(errors, name)
    raise AttributeError(f"module 'fepen' has no attribute {name!r}")
