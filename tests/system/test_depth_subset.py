"""A fixed subset of the shipped depth sets through the rigid fidelity at fepen's defaults: each set's mean
|error| is what docs/validation-depth.md states (its "CI subset" table), so that a change of the law or of the
calibrated constants that moves the depths cannot go unseen."""

import re
from pathlib import Path

import numpy as np
import pytest

from fepen.studies import depth

DOC = Path(__file__).resolve().parents[2] / "docs" / "validation-depth.md"
FIRST = 2  # the first two shots of every shipped set


def stated() -> dict[str, float]:
    """The doc's CI-subset table (its make docs block depth-ci-subset): set -> mean |error| (%)."""
    text = DOC.read_text()
    part = text[text.index("<!-- make docs: depth-ci-subset -->"):text.index("<!-- /make docs: depth-ci-subset -->")]
    return {m[1]: float(m[2]) for m in re.finditer(r"^\| (\S+) \| \d+ \| ([\d.]+) % \|", part, re.M)}


def subset_errors() -> dict[str, float]:
    """Each shipped set's mean |P/P_meas - 1| (%) over its first FIRST shots, default law, rigid."""
    out = {}
    for name, path in depth.shipped_sets().items():
        rows = depth.read_set(path)[:FIRST]
        pred = [depth.rigid_depth(r) for r in rows]
        out[name] = 100.0 * depth.errors(pred, [r.depth for r in rows])["mean_abs"]
    return out


@pytest.mark.slow
def test_the_subset_gives_the_figures_the_doc_states():
    want, got = stated(), subset_errors()
    assert set(want) == set(got) and len(got) == 12
    assert np.allclose([got[k] for k in want], list(want.values()), atol=0.06), {k: round(v, 2) for k, v in got.items()}


if __name__ == "__main__":  # print the table for the doc
    for k, v in subset_errors().items():
        print(f"| {k} | {FIRST} | {v:.1f} % |")
