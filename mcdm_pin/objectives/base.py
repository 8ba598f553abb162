r"""Base class of the objectives.

Every objective is a quadratic in the cable forces :math:`f \in \mathbb{R}^m`,

.. math:: J(f) = f^T P f + c^T f + r,

contributed by :meth:`Objective.quadratic` at one instant. Objectives add up and scale with ``+`` and
``*`` (``MinCableForces() + 10 * MinInteractions()``); the problem sums their ``(P, c, r)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Quadratic:
    """``J(f) = f^T P f + c^T f + r``."""

    P: np.ndarray
    c: np.ndarray
    r: float = 0.0

    def value(self, f) -> float:
        f = np.asarray(f, dtype=float)
        return float(f @ self.P @ f + self.c @ f + self.r)


class Objective:
    """A term of the cost. Subclasses implement :meth:`quadratic`."""

    def quadratic(self, terms, context) -> Quadratic:
        """The term at one instant.

        Args:
            terms: the :class:`~mcdm_pin.terms.Terms` of the instant.
            context: the :class:`~mcdm_pin.problem.Context` (robot, previous forces).
        """
        raise NotImplementedError

    def validate(self, robot) -> None:
        """Raise :class:`~mcdm_pin.exceptions.ProblemError` if the term does not fit ``robot``."""

    def __add__(self, other: "Objective") -> "Objective":
        return Sum([self, other])

    def __rmul__(self, weight: float) -> "Objective":
        return Sum([self], [float(weight)])

    __mul__ = __rmul__


class Sum(Objective):
    """A weighted sum of objectives."""

    def __init__(self, terms, weights=None):
        flat, w = [], []
        for t, wt in zip(terms, weights or [1.0] * len(terms)):
            if isinstance(t, Sum):
                flat.extend(t.terms)
                w.extend(wt * x for x in t.weights)
            else:
                flat.append(t)
                w.append(wt)
        self.terms, self.weights = flat, w

    def quadratic(self, terms, context) -> Quadratic:
        m = terms.L.shape[0]
        out = Quadratic(np.zeros((m, m)), np.zeros(m), 0.0)
        for t, w in zip(self.terms, self.weights):
            if w == 0.0:
                continue
            q = t.quadratic(terms, context)
            out.P += w * q.P
            out.c += w * q.c
            out.r += w * q.r
        return out

    def validate(self, robot) -> None:
        for t in self.terms:
            t.validate(robot)

    def __repr__(self) -> str:
        return " + ".join(f"{w:g} * {t!r}" for t, w in zip(self.terms, self.weights))
