"""make docs' blocks of the accuracy-cost ladder (docs/accuracy-cost.md), the hard cases (docs/hard-cases.md)
and wear's Table 1 (docs/wear.md).

Each generator takes a scratch directory and returns the block's Markdown; BLOCKS registers them with
tools/make_docs.py (which imports this module and merges BLOCKS into its own).
"""

from __future__ import annotations

import make_docs as md  # noqa: F401  (fepen, made, figure, took, version, Block)

#: name -> make_docs.Block
BLOCKS: dict = {}
