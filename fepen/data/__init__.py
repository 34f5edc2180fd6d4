"""fepen's shipped data, one name for the tables and libraries in this folder (docs/theory.md §4, §16;
docs/paper.md):

- ``experiments``: the paper's Table 1 (table1.csv): ``SHOTS``, ``Shot``, ``shot``;
- ``steels``: the named projectile steels (steels.toml), ``projectile.material.name``: ``STEELS``;
- ``targets``: the named target materials (targets.toml), ``target.material``: ``TARGETS``, ``FAMILIES``,
  ``CONSTANTS``;
- ``explosives``: the named explosives (explosives.toml), ``charge.explosive``: ``EXPLOSIVES``, the thresholds of
  the charge-safety criteria;
- ``prediction_errors``: fepen's errors on the public data (prediction_errors.csv), for the validated
  envelope and the prediction intervals.

``depth/`` holds the depth data sets of ``fepen validate-depth`` (fepen.studies.depth). Plain Python and the
standard library only: the scene and every layer above may import it.
"""

from fepen.data.experiments import SHOTS, Shot, shot
from fepen.data.explosives import EXPLOSIVES
from fepen.data.steels import STEELS
from fepen.data.steels import names as steel_names
from fepen.data.targets import CONSTANTS, FAMILIES, TARGETS

__all__ = ["experiments", "steels", "targets", "explosives", "prediction_errors", "digests", "EXPLOSIVES",
           "SHOTS", "Shot", "shot", "STEELS", "steel_names", "TARGETS", "FAMILIES",
           "CONSTANTS"]


def digests() -> dict[str, str]:
    """{path below fepen/data: SHA-256} of every data file shipped here (tables and libraries, not code): what a
    continued study checks it still reads (fepen.studies.study: a recalibrated target is another model)."""
    import hashlib
    from pathlib import Path

    root = Path(__file__).parent
    out = {}
    for path in sorted(root.rglob("*")):
        if path.is_file() and path.suffix in (".toml", ".csv", ".json"):
            out[path.relative_to(root).as_posix()] = hashlib.sha256(path.read_bytes()).hexdigest()
    return out
