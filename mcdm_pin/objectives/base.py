r"""Base class of the objectives.

Every objective is a quadratic in the problem's variables :math:`x` (the cable forces; with actuated
joints, the forces then the actuator torques), in the convention every back-end uses:

.. math:: J(x) = \tfrac12\, x^T P x + c^T x + r,

contributed by :meth:`Objective.quadratic` at one instant. So ``f^T f`` has ``P = 2 I``. Objectives
add up and scale with ``+`` and ``*`` (``MinCableForces() + 10 * MinInteractions()``); the problem
sums their ``(P, c, r)``.

**Structure.** A term may also say how its Hessian is built: ``P = diag(d) + F^T F`` (``d`` (n,),
``F`` (k, n)). The compiled solver uses it (a diagonal plus a low-rank part is far cheaper to factor
than a dense matrix); sums of structured terms with non-negative weights stay structured.

**Binding.** An objective is a small immutable description (weights by joint name, ...);
:meth:`Objective.bind` checks it against a robot and returns a *new* object with what it needs at
every instant precomputed. Nothing mutates a shared objective.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..exceptions import ProblemError


@dataclass
class Quadratic:
    r"""``J(x) = 1/2 x^T P x + c^T x + r``; when known, ``P = diag(diag) + factor^T factor``."""

    P: np.ndarray
    c: np.ndarray
    r: float = 0.0
    diag: np.ndarray | None = None
    factor: np.ndarray | None = None

    @property
    def structured(self) -> bool:
        return self.diag is not None and self.factor is not None

    def value(self, x) -> float:
        x = np.asarray(x, dtype=float)
        return float(0.5 * x @ self.P @ x + self.c @ x + self.r)


class Objective:
    """A term of the cost. Subclasses implement :meth:`quadratic` and :meth:`spec`, and
    :meth:`bind` when they depend on the robot."""

    bound = True  # objectives that need nothing from the robot are bound from the start

    def bind(self, robot) -> "Objective":
        """A checked copy of this term for ``robot``; raises :class:`~mcdm_pin.exceptions.ProblemError`
        if it does not fit."""
        return self

    def validate(self, robot) -> None:
        """Raise :class:`~mcdm_pin.exceptions.ProblemError` if the term does not fit ``robot``."""
        self.bind(robot)

    def quadratic(self, terms, context) -> Quadratic:
        """The term at one instant.

        Args:
            terms: the :class:`~mcdm_pin.terms.Terms` of the instant.
            context: the :class:`~mcdm_pin.problem.Context` (robot, previous forces).
        """
        raise NotImplementedError

    def spec(self) -> dict:
        """A JSON-able description (``{"type": ..., ...}``) that :func:`objective_from_spec` rebuilds."""
        raise NotImplementedError

    def _bound_for(self, context) -> "Objective":
        """This term bound to the context's robot (a term used without :meth:`bind`)."""
        return self if self.bound else self.bind(context.robot)

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
        for wt in w:
            if not np.isfinite(wt):
                raise ProblemError(f"objective weights must be finite, got {wt!r}")
        self.terms, self.weights = tuple(flat), tuple(float(x) for x in w)
        self.bound = all(t.bound for t in self.terms)

    def bind(self, robot) -> "Sum":
        return Sum([t.bind(robot) for t in self.terms], list(self.weights))

    def quadratic(self, terms, context) -> Quadratic:
        parts = [(t.quadratic(terms, context), w) for t, w in zip(self.terms, self.weights) if w != 0.0]
        n = terms.L.shape[0]
        if not parts:
            return Quadratic(np.zeros((n, n)), np.zeros(n), 0.0, np.zeros(n), np.zeros((0, n)))
        P = sum(w * q.P for q, w in parts)
        c = sum(w * q.c for q, w in parts)
        r = float(sum(w * q.r for q, w in parts))
        diag = factor = None
        if all(q.structured and w >= 0 for q, w in parts):
            diag = sum(w * q.diag for q, w in parts)
            factor = np.vstack([np.sqrt(w) * q.factor for q, w in parts])
        return Quadratic(P, c, r, diag, factor)

    def spec(self) -> dict:
        return {"type": "Sum", "terms": [t.spec() for t in self.terms], "weights": list(self.weights)}

    def __repr__(self) -> str:
        return " + ".join(f"{w:g} * {t!r}" for t, w in zip(self.terms, self.weights))


def optional_array(spec: dict, key: str):
    value = spec.get(key)
    return None if value is None else np.asarray(value, dtype=float)


def array_spec(x) -> list | None:
    return None if x is None else np.asarray(x, dtype=float).tolist()
