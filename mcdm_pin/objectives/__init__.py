"""Objectives: small composable quadratic terms in the cable forces."""

from .base import Objective, Quadratic, Sum
from .cable_forces import MinCableForces
from .cable_sum import MinCableForceSum
from .interactions import MinInteractions
from .smoothing import Smoothing

__all__ = ["Objective", "Quadratic", "Sum", "MinCableForces", "MinCableForceSum", "MinInteractions",
           "Smoothing"]
