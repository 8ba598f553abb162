r"""Objectives + constraints -> one quadratic problem with cones, at one instant.

.. math::

    \min_f\; f^T P f + c^T f + r \quad \text{s.t.}\quad A f = b,\;\; f_{min} \le f \le f_{max},\;\;
    \|F_{k,\perp}\| \le \tan\rho^*_k\, F_{k,z}\;\; (F_k = g_k + G_k f).

:func:`case_problem` builds the source paper's three cases.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .constraints import CableForceBounds, ConeData, Constraint, EquationOfMotion, InteractionCone
from .exceptions import ProblemError
from .objectives import MinCableForces, MinInteractions, Objective, Smoothing, Sum


@dataclass
class Context:
    """What an objective or constraint may read besides the terms: the robot and the previous
    instant's forces (for smoothing)."""

    robot: object
    f_prev: np.ndarray | None = None


@dataclass
class QPData:
    """One instant's problem, ready for a back-end (see the module docstring)."""

    P: np.ndarray
    c: np.ndarray
    r: float
    A: np.ndarray
    b: np.ndarray
    lb: np.ndarray
    ub: np.ndarray
    cones: list[ConeData] = field(default_factory=list)

    @property
    def n(self) -> int:
        return len(self.c)

    def objective(self, f) -> float:
        f = np.asarray(f, dtype=float)
        return float(f @ self.P @ f + self.c @ f + self.r)

    def without_cones(self) -> "QPData":
        return QPData(self.P, self.c, self.r, self.A, self.b, self.lb, self.ub, [])

    def with_cones(self, cones) -> "QPData":
        return QPData(self.P, self.c, self.r, self.A, self.b, self.lb, self.ub, list(cones))


class Problem:
    """An inverse-dynamics problem: an objective and constraints.

    The equation of motion and the cable bounds are always included (added if missing).

    Args:
        robot: the :class:`~mcdm_pin.robot.Robot`.
        objective: an :class:`~mcdm_pin.objectives.Objective` (sums allowed).
        constraints: extra constraints, e.g. :class:`~mcdm_pin.constraints.InteractionCone`.
    """

    def __init__(self, robot, objective: Objective, constraints=()):
        self.robot = robot
        self.objective = objective
        constraints = list(constraints)
        if not any(isinstance(c, EquationOfMotion) for c in constraints):
            constraints.insert(0, EquationOfMotion())
        if not any(isinstance(c, CableForceBounds) for c in constraints):
            constraints.insert(1, CableForceBounds())
        for c in constraints:
            if not isinstance(c, Constraint):
                raise ProblemError(f"expected Constraint objects, got {c!r}")
        self.constraints = constraints
        objective.validate(robot)
        for c in constraints:
            c.validate(robot)
        names = [c.joint for c in constraints if isinstance(c, InteractionCone)]
        if len(set(names)) != len(names):
            raise ProblemError(f"more than one cone on a joint: {names}")
        # the user's objective without smoothing terms: what is reported as "objective"
        terms = objective.terms if isinstance(objective, Sum) else [objective]
        weights = objective.weights if isinstance(objective, Sum) else [1.0]
        self._primary = Sum([t for t in terms if not isinstance(t, Smoothing)],
                            [w for t, w in zip(terms, weights) if not isinstance(t, Smoothing)])
        self.has_smoothing = any(isinstance(t, Smoothing) for t in terms)

    @property
    def cone_constraints(self) -> list[InteractionCone]:
        return [c for c in self.constraints if isinstance(c, InteractionCone)]

    def assemble(self, terms, context: Context) -> QPData:
        quad = self.objective.quadratic(terms, context)
        m = terms.L.shape[0]
        A_rows, b_rows, cones = [], [], []
        lb, ub = np.full(m, -np.inf), np.full(m, np.inf)
        for con in self.constraints:
            eq = con.equalities(terms, context)
            if eq is not None:
                A_rows.append(eq[0])
                b_rows.append(eq[1])
            bd = con.bounds(terms, context)
            if bd is not None:
                lb, ub = np.maximum(lb, bd[0]), np.minimum(ub, bd[1])
            cones.extend(con.cones(terms, context))
        A = np.vstack(A_rows) if A_rows else np.zeros((0, m))
        b = np.concatenate(b_rows) if b_rows else np.zeros(0)
        P = 0.5 * (quad.P + quad.P.T)
        return QPData(P=P, c=quad.c, r=quad.r, A=A, b=b, lb=lb, ub=ub, cones=cones)

    def value(self, terms, f, context: Context, qp: QPData | None = None) -> float:
        """The objective at ``f`` without smoothing terms (``qp``: the assembled problem, reused
        when there is no smoothing term)."""
        if qp is not None and not self.has_smoothing:
            return qp.objective(f)
        return self._primary.quadratic(terms, context).value(f)

    def describe(self) -> str:
        return f"minimise {self.objective!r} subject to {', '.join(map(repr, self.constraints))}"


def case_problem(robot, case: int, alpha: dict | None = None, beta: dict | None = None,
                 cones: dict | None = None,
                 frame: str = "socket", smoothing: float = 0.0, cable_weights=None) -> Problem:
    """The source paper's cases.

    Args:
        case: 1 (min f^T f), 2 (min interactions), 3 (case 2 + stability cones).
        alpha: ``{joint: weight}`` of |F|^2 overriding the sidecar's (cases 2 and 3).
        beta: ``{joint: weight}`` of |M|^2 overriding the sidecar's (cases 2 and 3).
        cones: ``{joint: degrees}`` overriding or adding cones (case 3); default: every joint with a
            ``cone_deg`` in the sidecar.
        frame: the cone's frame, ``socket`` or ``child``.
        smoothing: weight of ``|f - f_prev|^2`` along a trajectory (0: off).
        cable_weights: per-cable weights of case 1.
    """
    if case not in (1, 2, 3):
        raise ProblemError(f"case must be 1, 2 or 3, got {case!r}")
    if case == 1:
        objective: Objective = MinCableForces(cable_weights)
    else:
        objective = MinInteractions(alpha=alpha, beta=beta)
    if smoothing:
        objective = objective + Smoothing(smoothing)
    constraints: list[Constraint] = []
    if case == 3:
        chosen = {j.name: j.cone_deg for j in robot.joints if j.cone_deg is not None}
        chosen.update(cones or {})
        if not chosen:
            raise ProblemError("case 3 needs at least one cone: give cone_deg in the sidecar or --cone")
        constraints = [InteractionCone(j, deg, frame=frame) for j, deg in chosen.items()]
    return Problem(robot, objective, constraints)
