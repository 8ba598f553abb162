"""Objectives: small composable quadratic terms in the problem's variables (``1/2 x^T P x + c^T x + r``)."""

from ..exceptions import ProblemError
from .activations import MinActivations
from .base import Objective, Quadratic, Sum
from .cable_forces import MinCableForces
from .cable_sum import MinCableForceSum
from .interactions import MinInteractions
from .smoothing import Smoothing

KINDS = {cls.__name__: cls for cls in (MinCableForces, MinCableForceSum, MinInteractions, Smoothing,
                                       MinActivations)}


def objective_from_spec(spec: dict) -> Objective:
    """The objective described by ``spec`` (as :meth:`Objective.spec` writes it)."""
    if not isinstance(spec, dict) or "type" not in spec:
        raise ProblemError(f"objective spec: expected a mapping with a 'type', got {spec!r}")
    kind = spec["type"]
    if kind == "Sum":
        return Sum([objective_from_spec(t) for t in spec["terms"]], list(spec["weights"]))
    if kind not in KINDS:
        raise ProblemError(f"objective spec: unknown type {kind!r}; expected Sum or one of "
                           f"{', '.join(KINDS)}")
    return KINDS[kind].from_spec(spec)


__all__ = ["Objective", "Quadratic", "Sum", "MinActivations", "MinCableForces", "MinCableForceSum", "MinInteractions",
           "Smoothing", "objective_from_spec"]
