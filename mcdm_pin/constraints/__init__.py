"""Constraints: the equation of motion, cable bounds and interaction cones."""

from .base import ConeData, Constraint, perpendicular_basis
from .bounds import CableForceBounds
from .cone import InteractionCone
from .equation_of_motion import EquationOfMotion

__all__ = ["ConeData", "Constraint", "perpendicular_basis", "CableForceBounds", "InteractionCone",
           "EquationOfMotion"]
