"""Base class of the constraints.

A linear constraint contributes rows (``A x = b``) or bounds (``lb <= x <= ub``); a cone contributes a
:class:`ConeData` (the interaction force as an affine map of ``x`` plus its axis and half-angle),
which the back-ends handle natively (Clarabel, the compiled solver) or by cutting planes (ProxQP).

Like the objectives, a constraint is a small immutable description; :meth:`Constraint.bind` checks it
against a robot and returns a new object with what it needs precomputed.
"""

from __future__ import annotations

from ..qp import ConeData


class Constraint:
    """A constraint on the variables at one instant."""

    bound = True

    def bind(self, robot) -> "Constraint":
        """A checked copy for ``robot``; raises :class:`~mcdm_pin.exceptions.ProblemError` if it does
        not fit."""
        return self

    def validate(self, robot) -> None:
        """Raise :class:`~mcdm_pin.exceptions.ProblemError` if it does not fit ``robot``."""
        self.bind(robot)

    def equalities(self, terms, context):
        """``(A, b)`` rows of ``A x = b``, or ``None``."""
        return None

    def bounds(self, terms, context):
        """``(lower, upper)`` on ``x`` (n each), or ``None``."""
        return None

    def cones(self, terms, context) -> list[ConeData]:
        return []

    def spec(self) -> dict:
        """A JSON-able description that :func:`constraint_from_spec` rebuilds."""
        raise NotImplementedError
