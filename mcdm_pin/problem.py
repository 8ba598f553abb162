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
    _cone_arrays: tuple | None = field(default=None, repr=False, compare=False)
    _H: np.ndarray | None = field(default=None, repr=False, compare=False)

    @property
    def n(self) -> int:
        return len(self.c)

    @property
    def H(self) -> np.ndarray:
        """The objective's Hessian ``2 P``."""
        if self._H is None:
            self._H = 2.0 * self.P
        return self._H

    def cone_arrays(self) -> tuple:
        """The cones stacked for vectorised and compiled code: ``G`` (k, 3, n), ``g`` (k, 3),
        ``axis`` (k, 3), ``tan`` (k,), ``basis0`` (k, 3) (a unit vector normal to each axis)."""
        if self._cone_arrays is None and not self.cones:
            n = self.n
            self._cone_arrays = (np.zeros((0, 3, n)), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0),
                                 np.zeros((0, 3)))
        elif self._cone_arrays is None:
            n, cs = self.n, self.cones
            self._cone_arrays = (
                np.array([c.G for c in cs], dtype=float).reshape(len(cs), 3, n),
                np.array([c.g for c in cs], dtype=float).reshape(len(cs), 3),
                np.array([c.axis for c in cs], dtype=float).reshape(len(cs), 3),
                np.array([c.tan for c in cs], dtype=float),
                np.array([c.basis[0] for c in cs], dtype=float).reshape(len(cs), 3))
        return self._cone_arrays

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
        self._plan = None

    @property
    def cone_constraints(self) -> list[InteractionCone]:
        return [c for c in self.constraints if isinstance(c, InteractionCone)]

    def assemble(self, terms, context: Context) -> QPData:
        quad = self.objective.quadratic(terms, context)
        m = terms.L.shape[0]
        if self._plan is None:
            self._plan = self._make_plan(context.robot)
        plan = self._plan
        A_rows, b_rows, cones = [], [], []
        lb = ub = None
        for con in plan["bounds"]:
            lo, hi = con.bounds(terms, context)
            # one bounds constraint (the usual case): its arrays as they are, read afresh each instant
            lb, ub = (lo, hi) if lb is None else (np.maximum(lb, lo), np.minimum(ub, hi))
        if lb is None:
            lb, ub = np.full(m, -np.inf), np.full(m, np.inf)
        for con in plan["general"]:
            eq = con.equalities(terms, context)
            if eq is not None:
                A_rows.append(eq[0])
                b_rows.append(eq[1])
            bd = con.bounds(terms, context)
            if bd is not None:
                lb, ub = np.maximum(lb, bd[0]), np.minimum(ub, bd[1])
            cones.extend(con.cones(terms, context))
        if A_rows:
            A = np.vstack([terms.L.T] + A_rows) if plan["eom"] else np.vstack(A_rows)
            b = np.concatenate([-terms.tau] + b_rows) if plan["eom"] else np.concatenate(b_rows)
        elif plan["eom"]:
            A, b = terms.L.T, -terms.tau
        else:
            A, b = np.zeros((0, m)), np.zeros(0)
        P = quad.P if getattr(self.objective, "symmetric", False) else 0.5 * (quad.P + quad.P.T)
        qp = QPData(P=P, c=quad.c, r=quad.r, A=A, b=b, lb=lb, ub=ub, cones=cones)
        batch = plan["cones"]
        if batch is not None and not cones:
            qp.cones, qp._cone_arrays = batch(terms)
        elif batch is not None:
            qp.cones = batch(terms)[0] + cones
        return qp

    def _make_plan(self, robot) -> dict:
        """What :meth:`assemble` does at every instant, decided once: the equation of motion and the
        cable bounds directly, the cones in one batch, other constraints through their methods."""
        from .constraints.cone import ConeBatch

        general, eom, bounds = [], False, []
        cone_cons = []
        for con in self.constraints:
            if type(con) is EquationOfMotion and not eom:
                eom = True
            elif type(con) is CableForceBounds:
                bounds.append(con)
            elif type(con) is InteractionCone:
                cone_cons.append(con)
            else:
                general.append(con)
        return dict(general=general, eom=eom, bounds=bounds,
                    cones=ConeBatch(robot, cone_cons) if cone_cons else None)

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
