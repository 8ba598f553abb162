r"""Case 1: :math:`J(f) = \sum_i w_i f_i^2` (``f^T f`` with unit weights)."""

from __future__ import annotations

import numpy as np

from ..exceptions import ProblemError
from .base import Objective, Quadratic


class MinCableForces(Objective):
    """Minimise the weighted squared cable forces.

    Args:
        weights: per-cable weights (m,), non-negative; default all ones.
    """

    symmetric = True

    def __init__(self, weights=None):
        self.weights = None if weights is None else np.asarray(weights, dtype=float)

    def validate(self, robot) -> None:
        if self.weights is not None:
            if self.weights.shape != (robot.m,) or not np.all(np.isfinite(self.weights)) \
                    or np.any(self.weights < 0):
                raise ProblemError(f"MinCableForces: expected {robot.m} finite non-negative weights, "
                                   f"got {self.weights!r}")

    def quadratic(self, terms, context) -> Quadratic:
        m = terms.L.shape[0]
        cached = getattr(self, "_cached", None)
        if cached is None or cached.c.shape != (m,):
            # the same at every instant: built once and shared (nothing writes into a QP's arrays;
            # they are not flagged read-only because numba compiles read-only arrays separately)
            w = np.ones(m) if self.weights is None else self.weights
            P, c = np.diag(w), np.zeros(m)
            cached = self._cached = Quadratic(P, c, 0.0)
        return cached

    def __repr__(self) -> str:
        return "MinCableForces()" if self.weights is None else f"MinCableForces({self.weights.tolist()})"
