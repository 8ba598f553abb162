r"""The force distribution inside a control tick: a deadline, and a safe answer when it is missed.

At every tick :class:`Controller` forms the desired acceleration with its law
(:mod:`mcdm_pin.control.laws`) and asks :class:`~mcdm_pin.inverse_dynamics.InverseDynamics` for the
cable forces at the *measured* state, warm started from the previous tick (the solver keeps its last
answer). The tick's latency is the wall time of both, from reading the state to having forces.

**Deadline.** The solver chain gets a time budget (``budget`` of the deadline, default 80 %): it stops
between two stages once the budget is spent (status ``budget``). A stage is not interrupted, so an
answer can still arrive late: the tick then *misses* its deadline, the late answer is discarded and
the fallback is applied, as a real-time system would have sent the fallback at the deadline (in this
simulation the plant's clock does not wait for the computation; nothing here preempts it). While the
kernels run uncompiled the solver's budget grows as :class:`~mcdm_pin.inverse_dynamics.InverseDynamics`
makes it grow (:data:`mcdm_pin.jit.UNCOMPILED_SLOWDOWN`); the deadline does not.

**Fallback: the previous tick's forces.** Applied when the answer is late, or is not ``optimal`` (over
budget, infeasible, inaccurate, or the state is one at which the model is undefined). Why these and
not the least-squares forces nearest to feasibility: (1) they cost nothing, so they are on time when
the solve was not; (2) they were within the cable bounds (and the cones) at the previous tick, and
the bounds do not move, so no cable goes slack or over its limit; (3) at 1 kHz the state moves by
``O(dt)``, so the equation-of-motion error they leave is of order ``dt`` times the rate of change of
the forces, and the next on-time tick corrects it (the PD terms see the error). The least-squares
forces would need another solve (the time that was lacking), and at an infeasible instant they break
the bounds or the equation of motion anyway. The first tick has no previous forces:
:meth:`Controller.start` solves the initial state before the loop, without a deadline, and refuses to
start when that instant has no optimal answer. Every fallback is counted by reason
(:attr:`Controller.fallbacks`).
"""

from __future__ import annotations

import time
from collections import Counter
from dataclasses import dataclass

import numpy as np

from ..exceptions import McdmError, ProblemError, SolverError
from ..inverse_dynamics import InverseDynamics
from ..settings import DEFAULT
from ..problem import Problem
from ..solvers import OPTIMAL

LATE = "late"
REASONS = (LATE, "budget", "infeasible", "inaccurate", "max_iter", "error")


@dataclass
class Tick:
    """One tick's outcome: the applied forces ``f`` (N); the latency (wall time) of the whole tick
    and of the distribution alone, and the CPU time of the tick's thread (s; below the latency when
    the operating system ran something else meanwhile); the solver's status and the stage that
    answered; the fallback reason (``None``: the solver's forces were applied)."""

    f: np.ndarray
    latency_s: float
    distribution_s: float
    cpu_s: float
    status: str
    stage: str
    fallback: str | None


class Controller:
    """Computed torque + force distribution with a deadline (module docstring).

    Args:
        robot: the controller's model of the robot (:class:`~mcdm_pin.robot.Robot`; may differ from the
            plant's, e.g. :func:`~mcdm_pin.control.loop.scaled_masses`).
        problem: the distribution's :class:`~mcdm_pin.problem.Problem` (any case; cones included), or
            the paper's case number with ``options`` as :func:`~mcdm_pin.problem.case_problem`.
        law: a :class:`~mcdm_pin.control.laws.JointSpaceLaw` or :class:`~mcdm_pin.control.laws.TaskSpaceLaw`.
        deadline_s: the tick's deadline, s (1 ms at 1 kHz).
        budget: the share of the deadline given to the solver chain as its time budget.
        solver: the back-end name (as :class:`~mcdm_pin.inverse_dynamics.InverseDynamics`).
    """

    def __init__(self, robot, problem, law, deadline_s: float = 1e-3, budget: float = 0.8,
                 solver: str = "default", **options):
        if not (np.isfinite(deadline_s) and deadline_s > 0):
            raise ProblemError(f"deadline_s: expected a finite time > 0 s, got {deadline_s!r}")
        if not (0.0 < budget <= 1.0):
            raise ProblemError(f"budget: expected a share of the deadline in (0, 1], got {budget!r}")
        settings = DEFAULT.replace(budget_s=budget * deadline_s)
        if isinstance(problem, Problem):
            self.ident = InverseDynamics(robot, problem, solver=solver, diagnose=False, settings=settings)
        else:
            self.ident = InverseDynamics.for_case(robot, problem, solver=solver, diagnose=False, settings=settings,
                                                  **options)
        self.robot, self.law = robot, law
        self.deadline_s = float(deadline_s)
        self.fallbacks: Counter = Counter()
        self.misses = 0
        self.f_applied: np.ndarray | None = None

    def start(self, q, v, q_r, v_r, a_r) -> np.ndarray:
        """Solve the first tick without a deadline (the fallback needs previous forces); returns them.

        Raises:
            SolverError: that instant has no optimal answer (the loop cannot start safely).
        """
        self.ident.reset()
        self.fallbacks.clear()
        self.misses = 0
        chain = self.ident.solver.inner  # the solver chain (a Cascade) inside the scaling wrapper
        settings = chain.settings  # (its budget lifted for this solve)
        chain.settings = settings.replace(budget_s=None)
        try:
            res = self.ident.solve(q, v, self.law(q, v, q_r, v_r, a_r))
        finally:
            chain.settings = settings
        if res.status != OPTIMAL:
            raise SolverError(f"Controller.start: the initial state has no optimal force distribution "
                              f"({res.status}: {res.message})")
        if hasattr(self.law, "reset"):  # the loop's first tick starts the law's integral afresh
            self.law.reset()
        self.f_applied = res.f.copy()
        return self.f_applied

    def warm(self, q, v, q_r, v_r, a_r, ticks: int = 20) -> None:
        """Run every code path of a tick before the loop, so that no first call (a module's import, a
        solver's set-up, a compiled kernel's cache load or new specialisation) falls inside a tick:
        each answering stage of the solver chain alone on the problem of this state (without a
        budget), then :meth:`start` and ``ticks`` ticks at this state. Call :meth:`start` afterwards:
        it forgets the warm start, the law's integral and the counters."""
        chain = self.ident.solver.inner  # the solver chain (a Cascade) inside the scaling wrapper
        stages, settings = chain.stages, chain.settings
        chain.settings = settings.replace(budget_s=None)
        try:
            for alone in [s for s in stages if not s.refines]:
                chain.stages = [alone] + [s for s in stages if s.refines]
                self.ident.reset()
                try:
                    self.ident.solve(q, v, self.law(q, v, q_r, v_r, a_r))
                except McdmError:  # (a stage that refuses this problem alone: nothing of it to warm)
                    pass
        finally:
            chain.stages, chain.settings = stages, settings
        self.start(q, v, q_r, v_r, a_r)
        for _ in range(ticks):
            self.tick(q, v, q_r, v_r, a_r)

    def tick(self, q, v, q_r, v_r, a_r) -> Tick:
        """Forces for the measured state ``(q, v)`` and the reference ``(q_r, v_r, a_r)``."""
        if self.f_applied is None:
            raise ProblemError("Controller.tick before Controller.start")
        c0 = time.thread_time()
        t0 = time.perf_counter()
        qdd = self.law(q, v, q_r, v_r, a_r)
        t1 = time.perf_counter()
        try:
            res = self.ident.solve(q, v, qdd)
            status, f, stage = res.status, res.f, res.stage
        except McdmError:  # the model is undefined at this measured state (e.g. a zero-length segment)
            status, f, stage = "error", None, ""
        t2 = time.perf_counter()
        c2 = time.thread_time()
        reason = None
        if t2 - t0 > self.deadline_s:
            self.misses += 1
            reason = LATE
        elif status != OPTIMAL:
            reason = status if status in REASONS else "error"
        if reason is None:  # (a copy: the solver may reuse its answer's memory at the next tick)
            self.f_applied = f.copy()
        else:
            self.fallbacks[reason] += 1
        return Tick(self.f_applied, t2 - t0, t2 - t1, c2 - c0, status, stage, reason)
