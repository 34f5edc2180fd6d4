"""mirror_parts: the partition that shares the nose's work (issue 48): equal cell counts, bands along the axis,
each band's two halves across the plane of the shot (z = 0), mirrored."""

import numpy as np
import pytest

from fepen.geometry.partition import mirror_parts


def _cylinder_cells(n=4000, seed=0):
    """A cloud of small tetrahedra filling a cylinder about y (radius 1, length 6): x (4n, 3), cells (n, 4)."""
    rng = np.random.default_rng(seed)
    r, th, y = np.sqrt(rng.random(n)), 2 * np.pi * rng.random(n), 6.0 * rng.random(n)
    c = np.column_stack([r * np.cos(th), y, r * np.sin(th)])
    x = (c[:, None, :] + 0.01 * rng.standard_normal((n, 4, 3))).reshape(-1, 3)
    return x, np.arange(4 * n).reshape(n, 4), c


@pytest.mark.parametrize("nparts", [1, 2, 3, 4, 6])
def test_parts_have_equal_counts_and_the_shape_asked(nparts):
    x, cells, c = _cylinder_cells()
    part = mirror_parts(x, cells, nparts)
    counts = np.bincount(part, minlength=nparts)
    assert len(counts) == nparts and counts.max() - counts.min() <= 1
    halves = 2 if nparts % 2 == 0 else 1
    bands = nparts // halves
    cc = x[cells].mean(axis=1)
    for b in range(bands):  # band b holds the b-th slice along the axis: its cells lie beyond band b - 1's
        inside = np.isin(part, range(b * halves, (b + 1) * halves))
        if b > 0:
            before = np.isin(part, range((b - 1) * halves, b * halves))
            assert cc[inside, 1].min() >= cc[before, 1].max()
        if halves == 2:  # the two halves across z = 0, as many cells and mirrored: the same mean |z|, x and y
            lo, hi = part == 2 * b, part == 2 * b + 1
            assert cc[lo, 2].max() <= cc[hi, 2].min()
            assert abs(np.median(cc[lo | hi, 2])) < 0.05
            assert abs(cc[lo, 1].mean() - cc[hi, 1].mean()) < 0.1 and abs(cc[lo, 0].mean() - cc[hi, 0].mean()) < 0.05


def test_a_nose_load_is_shared_by_the_two_ranks():
    """The cells near the nose (y < 0.5: one twelfth of the body), where the target acts and the steel flows,
    go half to each rank on 2 ranks; a band partition gave them all to one."""
    x, cells, c = _cylinder_cells()
    part = mirror_parts(x, cells, 2)
    nose = x[cells].mean(axis=1)[:, 1] < 0.5
    share = np.bincount(part[nose], minlength=2) / nose.sum()
    assert share.min() > 0.4
