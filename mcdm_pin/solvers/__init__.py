"""Solver back-ends behind one signature: ``solver.solve(qp: QPData) -> Solution``."""

from __future__ import annotations

from ..exceptions import SolverError
from .base import (ERROR, INACCURATE, INFEASIBLE, MAX_ITER, OPTIMAL, SOFTENED, STATUSES, Solution,
                   Solver)
from .proxqp_ import ProxQPSolver

BACKENDS = ("proxqp", "clarabel")


def get_solver(name: str = "proxqp", **options) -> Solver:
    """A back-end by name: ``proxqp`` (default) or ``clarabel`` (exact reference, optional)."""
    if isinstance(name, Solver):
        return name
    if name == "proxqp":
        return ProxQPSolver(**options)
    if name == "clarabel":
        from .clarabel_ import ClarabelSolver
        return ClarabelSolver(**options)
    raise SolverError(f"unknown solver {name!r}; expected one of {', '.join(BACKENDS)}")


__all__ = ["get_solver", "Solver", "Solution", "ProxQPSolver", "BACKENDS", "STATUSES", "OPTIMAL",
           "INFEASIBLE", "MAX_ITER", "SOFTENED", "INACCURATE", "ERROR"]
