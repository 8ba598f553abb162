"""Solvers: stages behind one signature, chained into back-ends (:mod:`.chains`)."""

from __future__ import annotations

from ..settings import DEFAULT, Settings
from .base import (BUDGET, ERROR, INACCURATE, INFEASIBLE, MAX_ITER, OPTIMAL, SOFTENED, STATUSES, Solution,
                   Solver, Stage)
from .cascade import Cascade
from .chains import BACKENDS, ClarabelSolver, ProxQPSolver, make_solver


def get_solver(name="default", settings: Settings = DEFAULT, **options) -> Solver:
    """A back-end by name (:data:`BACKENDS`): ``default`` (the full cascade), ``compiled`` (the compiled
    active set and interior-point method alone), ``proxqp`` (ProxQP alone), ``clarabel`` (Clarabel
    alone, the exact reference), built with ``settings`` (:class:`~mcdm_pin.settings.Settings`); a
    :class:`Solver` is returned as it is."""
    if isinstance(name, Solver):
        return name
    return make_solver(name, settings, **options)


__all__ = ["get_solver", "make_solver", "Solver", "Solution", "Stage", "Cascade", "ProxQPSolver", "ClarabelSolver",
           "BACKENDS", "STATUSES", "OPTIMAL", "INFEASIBLE", "MAX_ITER", "SOFTENED", "INACCURATE", "BUDGET", "ERROR"]
