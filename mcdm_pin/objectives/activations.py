r"""Muscle activations: :math:`J = \sum_i w_i a_i^2` over the muscles, the biomechanics standard.

A muscle's tension at an instant is :math:`f_i = p_i + g_i a_i` (passive force :math:`p_i`, gain
:math:`g_i = F_0 F_L F_V`, :mod:`mcdm_pin.model.muscles`), so

.. math::

    w_i a_i^2 = \frac{w_i}{g_i^2} (f_i - p_i)^2:\qquad
    P_{ii} = \frac{2 w_i}{g_i^2},\quad c_i = -\frac{2 w_i p_i}{g_i^2},\quad r = \sum_i \frac{w_i p_i^2}{g_i^2}.

Where a muscle has no gain at an instant (outside its force-length range, or shortening at its top
speed) its tension is fixed at the passive force by its bounds and its activation is free: it adds
nothing here. Cables that are not muscles add nothing either: combine with
:class:`~mcdm_pin.objectives.cable_forces.MinCableForces` (weights 0 on the muscles) for them.
"""

from __future__ import annotations

import numpy as np

from ..exceptions import ProblemError
from .base import Objective, Quadratic, array_spec, optional_array


class MinActivations(Objective):
    """Minimise ``sum_i w_i a_i^2`` over the robot's muscles.

    Args:
        weights: one non-negative weight per muscle (the robot's muscle order); default all ones.
    """

    symmetric = True

    def __init__(self, weights=None, _index=None, _m: int | None = None):
        self.weights = None if weights is None else np.asarray(weights, dtype=float)
        self.bound = _index is not None
        self._index, self._m = _index, _m

    def bind(self, robot) -> "MinActivations":
        cables = robot.cables
        if cables.muscles is None:
            raise ProblemError("MinActivations: the robot has no muscles (its cables' tensions are not "
                               "activations); use MinCableForces")
        k = len(cables.muscle_index)
        if self.weights is not None and (self.weights.shape != (k,) or not np.all(np.isfinite(self.weights))
                                         or np.any(self.weights < 0)):
            raise ProblemError(f"MinActivations: expected {k} finite non-negative weights (one per muscle), "
                               f"got {self.weights!r}")
        return MinActivations(self.weights, _index=cables.muscle_index, _m=robot.m)

    def quadratic(self, terms, context) -> Quadratic:
        if not self.bound:
            return self._bound_for(context).quadratic(terms, context)
        state, k, m = terms.muscles, self._index, self._m
        w = np.ones(len(k)) if self.weights is None else self.weights
        gain = np.asarray(state.gain, dtype=float)
        inv2 = np.divide(w, gain * gain, out=np.zeros(len(k)), where=gain > 0)
        diag = np.zeros(m)
        c = np.zeros(m)
        diag[k] = 2.0 * inv2
        c[k] = -2.0 * inv2 * state.passive
        r = float(np.sum(inv2 * state.passive * state.passive))
        return Quadratic(np.diag(diag), c, r, diag, np.zeros((0, m)))

    def spec(self) -> dict:
        return {"type": "MinActivations", "weights": array_spec(self.weights)}

    @classmethod
    def from_spec(cls, spec: dict) -> "MinActivations":
        return cls(optional_array(spec, "weights"))

    def __repr__(self) -> str:
        return "MinActivations()" if self.weights is None else f"MinActivations({self.weights.tolist()})"
