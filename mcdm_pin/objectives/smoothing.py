r"""Smoothing along a trajectory: :math:`J(f) = w\,|f - f_{prev}|^2`, with :math:`f_{prev}` the
previous instant's forces (no term at the first instant). It makes a positive semidefinite objective
definite, so the forces are unique and continuous in time."""

from __future__ import annotations

import numpy as np

from ..exceptions import ProblemError
from .base import Objective, Quadratic


class Smoothing(Objective):
    def __init__(self, weight: float):
        if not np.isfinite(weight) or weight < 0:
            raise ProblemError(f"Smoothing: weight must be finite and >= 0, got {weight!r}")
        self.weight = float(weight)

    def quadratic(self, terms, context) -> Quadratic:
        m = terms.L.shape[0]
        prev = context.f_prev
        if prev is None or self.weight == 0.0 or not np.all(np.isfinite(prev)):
            return Quadratic(np.zeros((m, m)), np.zeros(m), 0.0, np.zeros(m), np.zeros((0, m)))
        w = self.weight
        return Quadratic(2.0 * w * np.eye(m), -2.0 * w * prev, float(w * prev @ prev), np.full(m, 2.0 * w),
                         np.zeros((0, m)))

    def spec(self) -> dict:
        return {"type": "Smoothing", "weight": self.weight}

    @classmethod
    def from_spec(cls, spec: dict) -> "Smoothing":
        return cls(spec["weight"])

    def __repr__(self) -> str:
        return f"Smoothing({self.weight:g})"
