r"""A solver as a visible chain of named stages (:class:`Cascade`), and the chains the library uses.

A stage either *answers* (tries when there is no final answer yet) or *refines* (improves an optimal
answer); :class:`~.base.Stage` has the one signature ``stage(qp, sol, deadline)``. The default chain:

==================  =======  ==========================================================================
stage               kind     what it does
==================  =======  ==========================================================================
``warm_active_set``  answer  the previous instant's active set, corrected by block pivoting; a
                             verified KKT point or nothing (:mod:`.active_set`)
``ipm``              answer  the compiled interior-point method with crossover to the active set
                             (:mod:`.ipm`): every cold instant
``clarabel``         answer  Clarabel's exact cone program (:mod:`.clarabel_`), on the scaled problem
``proxqp``           answer  ProxQP with the cones by cutting planes (:mod:`.proxqp_`): the last resort
``sqp_polish``       answer  SQP from the cutting planes' point once the cuts crowd (:mod:`.proxqp_`)
``polish``           refine  the exact KKT point of the answer's active set (:mod:`.active_set`)
``project``          refine  onto the bounds when the miss is within tolerance (:mod:`.check`)
``least_norm``       refine  among equally optimal answers, the one of least ``|x|^2`` (:mod:`.least_norm`)
``check``            refine  the KKT check: an answer that fails it becomes ``inaccurate`` (:mod:`.check`)
==================  =======  ==========================================================================

``get_solver("proxqp")``, ``("clarabel")``, ``("compiled")`` are single-method chains (no other
method answers for them: the ``stage`` field of every answer says which stage produced it).
"""

from __future__ import annotations

from .. import tolerances as tol
from .base import BUDGET, ERROR, OPTIMAL, Solution, Solver, failure, now


class Cascade(Solver):
    """Run ``stages`` in order on each problem (see the module docstring).

    Args:
        stages: the :class:`~.base.Stage` objects.
        name: the back-end's name (reported in results).
        budget_s: per-instant time budget, seconds (``None``: none). A solve that has no final answer
            when it runs out stops before the next stage with status ``budget``.
    """

    def __init__(self, stages, name: str = "cascade", budget_s: float | None = tol.BUDGET_S, factory=None):
        self.stages = list(stages)
        self.name = name
        self.budget_s = budget_s
        self._factory = factory

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
        if self._factory is not None:
            return self._factory()
        return make_solver(self.name, budget_s=self.budget_s)


def make_solver(name: str = "default", budget_s: float | None = tol.BUDGET_S, **options) -> Cascade:
    """The chain called ``name`` (see :data:`BACKENDS`)."""
    from .active_set import Polish, WarmActiveSet
    from .check import Check, Project
    from .clarabel_ import ClarabelStage
    from .ipm import IPMStage
    from .least_norm import LeastNorm
    from .proxqp_ import ProxQPStage, SQPPolish

    def chain(first):
        # every chain ends with the polish: the exact KKT point of the answer's active set. The
        # least-norm stage pins P x at the first stage's answer, and an interior point's P x is only
        # accurate to ~1e-5 where the objective is flat (human arm, abduct, case 3: Clarabel's
        # least-norm forces differed from the others' by 4.7e-6 relative before the polish, ProxQP's
        # by 1.4e-6; 1.5e-15 after)
        def stages():
            return [f() for f in first] + [Polish(), Project()]

        inner = Cascade(stages(), name=f"{name} (least-norm stage)", budget_s=None)
        return Cascade(stages() + [LeastNorm(inner), Check()], name=name, budget_s=budget_s,
                       factory=lambda: make_solver(name, budget_s, **options))

    if name == "default":
        # Clarabel before ProxQP: where the compiled method breaks down (an instant infeasible by
        # 6e-6 deg: the 2-link arm, traj2, t = 0.32 s, a 4.95374 deg cone) Clarabel answers in 2 ms,
        # where the cutting planes' SQP polish ran 7.6 M ProxQP iterations (24 s) before failing
        return chain([WarmActiveSet, IPMStage, ClarabelStage, lambda: ProxQPStage(**options), SQPPolish])
    if name == "compiled":
        return chain([WarmActiveSet, IPMStage])
    if name == "proxqp":
        return chain([lambda: ProxQPStage(**options), SQPPolish])
    if name == "clarabel":
        return chain([lambda: ClarabelStage(**options)])
    from ..exceptions import SolverError
    raise SolverError(f"unknown solver {name!r}; expected one of {', '.join(BACKENDS)}")


BACKENDS = ("default", "compiled", "proxqp", "clarabel")


def solution_summary(sol: Solution) -> str:
    return f"{sol.status} by {sol.stage or '-'} ({sol.iterations} iterations)" + (
        "" if sol.unique is None else (", unique" if sol.unique else ", least-norm among optima"))


__all__ = ["Cascade", "make_solver", "BACKENDS", "solution_summary"]
