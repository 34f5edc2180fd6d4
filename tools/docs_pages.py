"""make docs' blocks of the figures of docs/charge.md, docs/uncertainty.md, docs/validation-depth.md,
docs/verification.md, docs/projectiles-and-targets.md and docs/theory.md outside tools/make_docs.py's own blocks.

Each generator takes a scratch directory and returns the block's Markdown; BLOCKS registers them with
tools/make_docs.py (which imports this module and merges BLOCKS into its own).
"""

from __future__ import annotations

import make_docs as md  # noqa: F401  (fepen, made, figure, took, version, Block)

#: name -> make_docs.Block
BLOCKS: dict = {}
