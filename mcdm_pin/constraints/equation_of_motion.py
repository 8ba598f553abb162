r"""The equation of motion :math:`M\ddot q + h = -L^T f`, i.e. :math:`L^T f = -(M\ddot q + h)`."""

from __future__ import annotations

from .base import Constraint


class EquationOfMotion(Constraint):
    def equalities(self, terms, context):
        return terms.L.T, -terms.tau

    def spec(self) -> dict:
        return {"type": "EquationOfMotion"}

    @classmethod
    def from_spec(cls, spec: dict) -> "EquationOfMotion":
        return cls()

    def __repr__(self) -> str:
        return "EquationOfMotion()"
