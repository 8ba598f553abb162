"""Constraints: the equation of motion, cable bounds and interaction cones."""

from ..exceptions import ProblemError
from ..qp import ConeData, perpendicular_basis
from .base import Constraint
from .bounds import CableForceBounds
from .cone import InteractionCone
from .equation_of_motion import EquationOfMotion

KINDS = {cls.__name__: cls for cls in (CableForceBounds, InteractionCone, EquationOfMotion)}


def constraint_from_spec(spec: dict) -> Constraint:
    """The constraint described by ``spec`` (as :meth:`Constraint.spec` writes it)."""
    if not isinstance(spec, dict) or spec.get("type") not in KINDS:
        raise ProblemError(f"constraint spec: expected a mapping whose 'type' is one of "
                           f"{', '.join(KINDS)}, got {spec!r}")
    return KINDS[spec["type"]].from_spec(spec)


__all__ = ["ConeData", "Constraint", "perpendicular_basis", "CableForceBounds", "InteractionCone",
           "EquationOfMotion", "constraint_from_spec"]
