"""Base class of the constraints.

A linear constraint contributes rows (``A x = b``) or bounds (``lb <= x <= ub``); a cone contributes a
:class:`ConeData` (the interaction force as an affine map of ``x`` plus its axis and half-angle),
which the back-ends handle natively (Clarabel, the compiled solver) or by cutting planes (ProxQP).

Like the objectives, a constraint is a small immutable description; :meth:`Constraint.bind` checks it
against a robot and returns a new object with what it needs precomputed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class ConeData:
    r"""``|F - (a.F) a| <= tan(angle) (a.F)`` with ``F = g + G x``.

    Attributes:
        joint: the joint's name.
        G: (3, n), g: (3,): the force in the cone's frame as an affine map of x.
        axis: (3,) unit axis in the same frame.
        angle_deg: half-angle, degrees.
        basis: (2, 3) orthonormal vectors spanning the plane normal to ``axis``.
    """

    joint: str
    G: np.ndarray
    g: np.ndarray
    axis: np.ndarray
    angle_deg: float
    basis: np.ndarray

    @property
    def tan(self) -> float:
        return float(np.tan(np.radians(self.angle_deg)))

    def force(self, x) -> np.ndarray:
        return self.g + self.G @ x

    def angle_of(self, x) -> float:
        F = self.force(x)
        along = float(self.axis @ F)
        perp = float(np.linalg.norm(F - along * self.axis))
        return float(np.degrees(np.arctan2(perp, along)))

    def with_angle(self, angle_deg: float) -> "ConeData":
        return ConeData(self.joint, self.G, self.g, self.axis, float(angle_deg), self.basis)


def perpendicular_basis(axis: np.ndarray) -> np.ndarray:
    """Two unit vectors that complete ``axis`` to a right-handed orthonormal frame."""
    a = np.asarray(axis, dtype=float)
    helper = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(helper, a)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a, e1)
    return np.vstack([e1, e2])


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
