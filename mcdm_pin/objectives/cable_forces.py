r"""Case 1: :math:`J(f) = \sum_i w_i f_i^2` (``f^T f`` with unit weights): ``P = 2 diag(w)``."""

from __future__ import annotations

import numpy as np

from ..exceptions import ProblemError
from .base import Objective, Quadratic, array_spec, optional_array


class MinCableForces(Objective):
    """Minimise the weighted squared cable forces.

    Args:
        weights: per-cable weights (m,), non-negative; default all ones.
    """

    symmetric = True

    def __init__(self, weights=None, _m: int | None = None):
        self.weights = None if weights is None else np.asarray(weights, dtype=float)
        self.bound = _m is not None
        self._quad = None
        if _m is not None:
            # the same at every instant: built once and shared (nothing writes into a QP's arrays;
            # they are not flagged read-only because numba compiles read-only arrays separately)
            w = np.ones(_m) if self.weights is None else self.weights
            self._quad = Quadratic(np.diag(2.0 * w), np.zeros(_m), 0.0, 2.0 * w, np.zeros((0, _m)))

    def bind(self, robot) -> "MinCableForces":
        if self.weights is not None:
            if self.weights.shape != (robot.m,) or not np.all(np.isfinite(self.weights)) \
                    or np.any(self.weights < 0):
                raise ProblemError(f"MinCableForces: expected {robot.m} finite non-negative weights, "
                                   f"got {self.weights!r}")
        return MinCableForces(self.weights, _m=robot.m)

    def quadratic(self, terms, context) -> Quadratic:
        if not self.bound:
            return self._bound_for(context).quadratic(terms, context)
        return self._quad

    def spec(self) -> dict:
        return {"type": "MinCableForces", "weights": array_spec(self.weights)}

    @classmethod
    def from_spec(cls, spec: dict) -> "MinCableForces":
        return cls(optional_array(spec, "weights"))

    def __repr__(self) -> str:
        return "MinCableForces()" if self.weights is None else f"MinCableForces({self.weights.tolist()})"
