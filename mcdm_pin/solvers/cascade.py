r"""A solver as a visible chain of named stages (:class:`Cascade`).

A stage either *answers* (tries when there is no final answer yet) or *refines* (improves an optimal
answer); :class:`~.base.Stage` has the one signature ``stage(qp, sol, deadline)``. The chains the
library uses are built in one place, :mod:`.chains`.
"""

from __future__ import annotations

import copy

from ..settings import DEFAULT, Settings
from .base import BUDGET, ERROR, OPTIMAL, Solution, Solver, failure, now


class Cascade(Solver):
    """Run ``stages`` in order on each problem (see the module docstring).

    Args:
        stages: the :class:`~.base.Stage` objects.
        name: the back-end's name (reported in results).
        settings: the chain's :class:`~mcdm_pin.settings.Settings`, of which the chain reads the
            per-instant time budget ``budget_s`` (seconds, ``None``: none): a solve that has no final
            answer when it runs out stops before the next stage with status ``budget``. The stages
            hold the same object (:mod:`.chains` builds them with it).
    """

    def __init__(self, stages, name: str = "cascade", settings: Settings = DEFAULT, factory=None):
        self.stages = list(stages)
        self.name = name
        self.settings = settings
        self._factory = factory

    @property
    def budget_s(self) -> float | None:
        """The per-instant time budget, seconds (``settings.budget_s``)."""
        return self.settings.budget_s

    def __repr__(self) -> str:
        return f"Cascade({self.name!r}: {' -> '.join(s.name for s in self.stages)})"

    def stage(self, name: str):
        """The stage called ``name``."""
        for s in self.stages:
            if s.name == name:
                return s
        raise KeyError(name)

    def solve(self, qp, hint: Solution | None = None, deadline: float | None = None) -> Solution:
        """``deadline`` (:func:`~.base.now`): an outer chain's, passed to an inner one (the least-norm
        stage's) so that the budget holds across both; the earlier of it and this chain's own."""
        start = now()
        own = start + self.budget_s if self.budget_s is not None else float("inf")
        deadline = own if deadline is None else min(own, deadline)
        if hint is not None:
            for s in self.stages:
                s.seed(hint)
        sol: Solution | None = None
        iterations = 0
        for s in self.stages:
            if not s.applies(sol):
                continue
            if not s.refines and now() > deadline:
                budget = "the budget" if self.budget_s is None else f"the budget of {self.budget_s:g} s"
                return failure(qp.n, BUDGET, f"no answer within {budget} "
                                             f"(last: {sol.message if sol else 'none'})", iterations,
                               stage=s.name)
            out = s(qp, sol, deadline)
            if out is None:
                continue
            if not s.refines:
                iterations += out.iterations
                if out.iterations != iterations:  # (the first answering stage's count is the sum)
                    out = out.but(iterations=iterations)
            sol = out
        if sol is None:
            return failure(qp.n, ERROR, "no stage answered", iterations)
        if sol.status == OPTIMAL:
            for s in self.stages:
                s.learn(qp, sol)
        return sol

    def reset(self) -> None:
        for s in self.stages:
            s.reset()

    def fresh(self) -> "Cascade":
        """A new chain of the same stages without warm starts (the factory's, when one was given)."""
        if self._factory is not None:
            return self._factory()
        out = copy.deepcopy(self)
        out.reset()
        return out


def solution_summary(sol: Solution) -> str:
    return f"{sol.status} by {sol.stage or '-'} ({sol.iterations} iterations)" + (
        "" if sol.unique is None else (", unique" if sol.unique else ", least-norm among optima"))


__all__ = ["Cascade", "solution_summary"]
