"""The interior-point method's crossover schedule (mcdm_pin/solvers/_ipm.py, "Crossover"): the first
attempt is made as soon as the gap allows it. A later one is made only for an active set that reads
the same at two successive iterations (an attempt solves the active set's whole KKT system, and while
the indicators still change it fails). The same guess is never tried twice. The kernels run here as
their Python code, so nothing compiles."""

from __future__ import annotations

import numpy as np

from mcdm_pin import jit
from mcdm_pin.qp import QPData
from mcdm_pin.settings import DEFAULT
from mcdm_pin.solvers._structs import Slacks
from mcdm_pin.solvers.ipm import ipm_arguments


def test_a_later_crossover_waits_for_an_active_set_read_at_two_successive_iterations(monkeypatch):
    monkeypatch.setattr(jit, "_COMPILED", False)
    ipm, kkt = jit.kernels("solvers._ipm"), jit.kernels("solvers._kkt")
    # minimise 1/2 |x|^2 + c^T x over x1 + x2 + x3 = 1, 0 <= x <= 1: x3 at its lower bound
    qp = QPData(np.eye(3), np.array([-1.0, -2.0, 3.0]), 0.0, np.ones((1, 3)), np.ones(1), np.zeros(3), np.ones(3),
                [])
    kqp, cones, limits = ipm_arguments(qp, DEFAULT)
    # an interior iterate whose indicators read x3 at its lower bound (its slack below its multiplier)
    x = np.array([0.05, 0.9, 0.05])
    slacks = Slacks(1.0 - x, np.full(3, 1e-3), x.copy(), np.array([1e-3, 1e-3, 1.0]), np.zeros((0, 3)),
                    np.zeros((0, 3)))
    bounded = np.arange(3, dtype=np.int64)

    def attempt(memo, anyway):
        return ipm._crossover(x, slacks, bounded, bounded, kqp, cones, limits, memo, anyway)

    memo = ipm._guess_memo(3, 0)
    tried, run = attempt(memo, False)  # a later attempt, the first reading: not tried
    assert tried == 0 and run.code == -1
    assert list(memo[2]) == [0, 0, 1]  # (the reading kept)
    tried, run = attempt(memo, False)  # read again, the same: tried, and right
    assert tried == 1 and run.code == kkt.FOUND
    np.testing.assert_allclose(run.f, [0.0, 1.0, 0.0], atol=1e-12)
    tried, _ = attempt(memo, False)  # the guess just tried: not again
    assert tried == 0
    tried, run = attempt(ipm._guess_memo(3, 0), True)  # the first attempt (or converged iterations): at once
    assert tried == 1 and run.code == kkt.FOUND
