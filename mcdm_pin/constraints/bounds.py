"""Cable force bounds ``f_min <= f <= f_max``: the model's at each instant (a muscle's follow its length
and speed, :mod:`mcdm_pin.model.muscles`; the sidecar's otherwise), unless given here."""

from __future__ import annotations

import numpy as np

from ..exceptions import ProblemError
from ..objectives.base import array_spec, optional_array
from .base import Constraint


class CableForceBounds(Constraint):
    def __init__(self, f_min=None, f_max=None):
        self.f_min = None if f_min is None else np.asarray(f_min, dtype=float)
        self.f_max = None if f_max is None else np.asarray(f_max, dtype=float)

    def bind(self, robot) -> "CableForceBounds":
        lo = robot.f_min if self.f_min is None else self.f_min
        hi = robot.f_max if self.f_max is None else self.f_max
        if lo.shape != (robot.m,) or hi.shape != (robot.m,):
            raise ProblemError(f"CableForceBounds: expected {robot.m} lower and upper bounds")
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))) or np.any(lo < 0) or np.any(hi <= lo):
            raise ProblemError("CableForceBounds: expected finite bounds with 0 <= f_min < f_max")
        return self

    def bounds(self, terms, context):
        r = context.robot
        lo = terms.f_min if terms.f_min is not None else r.f_min
        hi = terms.f_max if terms.f_max is not None else r.f_max
        return (lo if self.f_min is None else self.f_min, hi if self.f_max is None else self.f_max)

    def spec(self) -> dict:
        return {"type": "CableForceBounds", "f_min": array_spec(self.f_min), "f_max": array_spec(self.f_max)}

    @classmethod
    def from_spec(cls, spec: dict) -> "CableForceBounds":
        return cls(optional_array(spec, "f_min"), optional_array(spec, "f_max"))

    def __repr__(self) -> str:
        return "CableForceBounds()"
