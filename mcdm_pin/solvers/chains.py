r"""The solver chains the library uses, each built here and nowhere else.

A chain is a :class:`~.cascade.Cascade` of named stages; a stage either *answers* (tries when there is
no final answer yet) or *refines* (improves an optimal answer). The default chain:

==================  =======  ==========================================================================
stage               kind     what it does
==================  =======  ==========================================================================
``flat_objective``   answer  where the objective is a constant, the least-norm feasible point, by the
                             least-norm stage's chain (:mod:`.least_norm`)
``warm_active_set``  answer  the previous instant's active set, corrected by block pivoting; a
                             verified KKT point or nothing (:mod:`.active_set`)
``dual_active_set``  answer  a cold instant of a problem with a diagonal objective and no cones (case
                             1, the muscles' activations): the active set read off the dual's
                             optimum, verified (:mod:`.active_set`)
``ipm``              answer  the compiled interior-point method with crossover to the active set
                             (:mod:`.ipm`): every other cold instant
``clarabel``         answer  Clarabel's exact cone program (:mod:`.clarabel_`), on the scaled problem
``proxqp``           answer  ProxQP with the cones by cutting planes (:mod:`.proxqp_`)
``sqp_polish``       answer  SQP from the cutting planes' point once the cuts crowd (:mod:`.proxqp_`)
``polish``           refine  the exact KKT point of the answer's active set (:mod:`.active_set`)
``project``          refine  onto the bounds when the miss is within tolerance (:mod:`.check`)
``least_norm``       refine  among equally optimal answers, the one of least ``|x|^2`` (:mod:`.least_norm`)
``check``            refine  the KKT check: an answer that fails it becomes ``inaccurate`` (:mod:`.check`)
==================  =======  ==========================================================================

``get_solver("proxqp")``, ``("clarabel")``, ``("compiled")`` are single-method chains (no other
method answers for them: the ``stage`` field of every answer says which stage produced it).
:func:`ProxQPSolver` and :func:`ClarabelSolver` build the ProxQP and Clarabel chains with their
options.
"""

from __future__ import annotations

from ..exceptions import SolverError
from ..settings import DEFAULT, Settings
from ..vocabulary import BACKENDS
from .active_set import DualActiveSet, Polish, WarmActiveSet
from .cascade import Cascade
from .check import Check, Project
from .clarabel_ import ClarabelStage
from .ipm import IPMStage
from .least_norm import FlatObjective, LeastNorm
from .proxqp_ import ProxQPStage, SQPPolish


def chain(name: str, first, settings: Settings, factory, polish: bool = True) -> Cascade:
    """``first`` (stage factories, each called with ``settings``: the answering stages), then the
    polish (``polish``) and the projection, then the least-norm stage (running the same stages on the
    least-norm problem) and the check; every stage and both chains hold ``settings`` (the inner chain
    without a budget of its own: the outer one's deadline bounds it); ``factory`` makes a fresh copy
    (:meth:`Cascade.fresh`)."""

    # the polish gives the exact KKT point of the answer's active set: the least-norm stage pins
    # P x at the first stage's answer, and an interior point's P x is accurate to ~1e-5 only where
    # the objective is flat
    def stages():
        return [f(settings) for f in first] + ([Polish(settings)] if polish else []) + [Project(settings)]

    inner = Cascade(stages(), name=f"{name} (least-norm stage)", settings=settings.replace(budget_s=None))
    return Cascade([FlatObjective(inner, settings)] + stages() + [LeastNorm(inner, settings), Check(settings)],
                   name=name, settings=settings, factory=factory)


def make_solver(name: str = "default", settings: Settings = DEFAULT, **options) -> Cascade:
    """The chain called ``name`` (:data:`BACKENDS`) with ``settings`` (tolerances, pivot limits, budget:
    :class:`~mcdm_pin.settings.Settings`); ``options``: the ProxQP stage's (:class:`~.proxqp_.ProxQPStage`)
    for the chains that have one."""
    factory = lambda: make_solver(name, settings, **options)  # noqa: E731
    proxqp = lambda s: ProxQPStage(s, **options)  # noqa: E731
    if name == "default":
        # Clarabel before ProxQP: where the compiled method breaks down (an instant infeasible by a
        # few micro-degrees of cone) Clarabel's exact cone program answers in milliseconds, where
        # the cutting planes' SQP polish may run millions of ProxQP iterations before failing
        first = [WarmActiveSet, DualActiveSet, IPMStage, ClarabelStage, proxqp, SQPPolish]
    elif name == "compiled":
        first = [WarmActiveSet, DualActiveSet, IPMStage]
    elif name == "proxqp":
        first = [proxqp, SQPPolish]
    elif name == "clarabel":
        first = [ClarabelStage]
    else:
        raise SolverError(f"unknown solver {name!r}; expected one of {', '.join(BACKENDS)}")
    if options and name in ("compiled", "clarabel"):
        raise SolverError(f"solver {name!r} takes no options (got {', '.join(options)}); its tolerances and "
                          f"limits are settings (mcdm_pin.settings.Settings)")
    return chain(name, first, settings, factory)


def ProxQPSolver(active_set: bool = True, fallback: bool = True, settings: Settings = DEFAULT,
                 **options) -> Cascade:
    """A ProxQP-based chain, as the library's default was before the compiled interior-point method:
    ``active_set`` adds the warm active set and the polish, ``fallback`` Clarabel for the instants on
    which ProxQP stalls; ``options``: :class:`~.proxqp_.ProxQPStage`'s."""
    first = ([WarmActiveSet] if active_set else []) + [lambda s: ProxQPStage(s, **options), SQPPolish]
    first += [ClarabelStage] if fallback else []
    return chain("proxqp", first, settings, polish=active_set,
                 factory=lambda: ProxQPSolver(active_set, fallback, settings, **options))


def ClarabelSolver(settings: Settings = DEFAULT) -> Cascade:
    """The Clarabel-only chain (``make_solver("clarabel")``; its tolerances: ``settings``'
    ``clarabel_*``)."""
    return make_solver("clarabel", settings)


__all__ = ["BACKENDS", "chain", "make_solver", "ProxQPSolver", "ClarabelSolver"]
