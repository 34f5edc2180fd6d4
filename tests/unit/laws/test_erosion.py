"""The erosion criteria (fepen.laws.erosion), mesh-free."""

import numpy as np

from fepen.laws import erosion


def test_each_criterion_alone_and_together():
    eps = np.array([0.0, 0.99, 1.0, 2.0, 0.0])
    step = np.array([1.0, 1.0, 1.0, 1.0, 0.05]) * 1e-7
    dt0 = 1e-7
    assert erosion.failed(eps, step, dt0, 1.0, 0.1).tolist() == [False, False, True, True, True]
    assert erosion.failed(eps, step, dt0, None, 0.1).tolist() == [False, False, False, False, True]
    assert erosion.failed(eps, step, dt0, 1.0, 0.0).tolist() == [False, False, True, True, False]
    # an eroded cell's step is inf: never eroded twice by the step criterion
    assert not erosion.failed(np.zeros(1), np.full(1, np.inf), dt0, None, 0.9)[0]


def test_the_step_criterion_is_a_strict_bound():
    dt0 = 2e-7
    step = np.array([0.1 * dt0 * (1 - 1e-12), 0.1 * dt0, 0.1 * dt0 * (1 + 1e-12)])
    assert erosion.failed(np.zeros(3), step, dt0, None, 0.1).tolist() == [True, False, False]
