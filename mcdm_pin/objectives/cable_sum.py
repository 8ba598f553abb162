r"""The 1-norm :math:`J(f) = \sum_i w_i f_i` (forces are non-negative, so this is :math:`\|f\|_1`):
a linear program, CASPR's other classic."""

from __future__ import annotations

import numpy as np

from ..exceptions import ProblemError
from .base import Objective, Quadratic, array_spec, optional_array


class MinCableForceSum(Objective):
    """Minimise the weighted sum of the cable forces."""

    def __init__(self, weights=None, _m: int | None = None):
        self.weights = None if weights is None else np.asarray(weights, dtype=float)
        self.bound = _m is not None
        self._m = _m

    def bind(self, robot) -> "MinCableForceSum":
        if self.weights is not None and (self.weights.shape != (robot.m,)
                                         or not np.all(np.isfinite(self.weights))):
            raise ProblemError(f"MinCableForceSum: expected {robot.m} finite weights")
        return MinCableForceSum(self.weights, _m=robot.m)

    def quadratic(self, terms, context) -> Quadratic:
        m = terms.L.shape[0]
        w = np.ones(m) if self.weights is None else self.weights
        return Quadratic(np.zeros((m, m)), w.copy(), 0.0, np.zeros(m), np.zeros((0, m)))

    def spec(self) -> dict:
        return {"type": "MinCableForceSum", "weights": array_spec(self.weights)}

    @classmethod
    def from_spec(cls, spec: dict) -> "MinCableForceSum":
        return cls(optional_array(spec, "weights"))

    def __repr__(self) -> str:
        return "MinCableForceSum()"
