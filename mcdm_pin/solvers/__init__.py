"""Solvers: stages behind one signature, chained into back-ends (:mod:`.chains`)."""

from __future__ import annotations

from .. import tolerances as _tol
from .base import (BUDGET, ERROR, INACCURATE, INFEASIBLE, MAX_ITER, OPTIMAL, SOFTENED, STATUSES, Solution,
                   Solver, Stage)
from .cascade import Cascade
from .chains import BACKENDS, ClarabelSolver, ProxQPSolver, make_solver


def get_solver(name="default", budget_s: float | None = _tol.BUDGET_S, **options) -> Solver:
    """A back-end by name (:data:`BACKENDS`): ``default`` (the full cascade), ``compiled`` (the compiled
    active set and interior-point method alone), ``proxqp`` (ProxQP alone), ``clarabel`` (Clarabel
    alone, the exact reference); a :class:`Solver` is returned as it is."""
    if isinstance(name, Solver):
        return name
    return make_solver(name, budget_s=budget_s, **options)


__all__ = ["get_solver", "make_solver", "Solver", "Solution", "Stage", "Cascade", "ProxQPSolver", "ClarabelSolver",
           "BACKENDS", "STATUSES", "OPTIMAL", "INFEASIBLE", "MAX_ITER", "SOFTENED", "INACCURATE", "BUDGET", "ERROR"]
