r"""Objectives + constraints -> one quadratic problem with cones, at one instant.

.. math::

    \min_x\; \tfrac12\, x^T P x + c^T x + r \quad \text{s.t.}\quad A x = b,\;\; l \le x \le u,\;\;
    \|F_{k,\perp}\| \le \tan\rho^*_k\, F_{k,z}\;\; (F_k = g_k + G_k x).

The variables ``x`` are the cable forces, then, for a hybrid robot (actuated joints, HCDM), the
actuator torques/forces: ``x = [f; tau_act]``, with the equation of motion
``L^T f - S tau_act = -(M qdd + h)`` (:mod:`mcdm_pin.model.actuators`), the actuators' bounds, and
``w_a |tau_a|^2`` (the sidecar's ``actuated: weight``) added to every case's objective: CASPR's
convention, where the joint actuators join the cables as weighted unknowns of the same program. An
actuator's torque acts inside its joint, so the interaction wrenches and the cones depend on ``f``
only. Nothing here or in the solvers assumes ``l >= 0`` or that every variable is a cable.

:func:`case_problem` builds the source paper's three cases. A :class:`Problem` is data:
:meth:`Problem.spec` gives a JSON-able description and :meth:`Problem.from_spec` rebuilds it.
"""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np

from . import jit
from .constraints import (CableForceBounds, Constraint, EquationOfMotion, InteractionCone,
                          constraint_from_spec)
from .constraints.cone import ConeBatch
from .exceptions import ProblemError
from .objectives import MinActivations, MinCableForces, MinInteractions, Objective, Smoothing, Sum, objective_from_spec
from .qp import ConeData, QPData
from .vocabulary import CASES

_NO_F = np.zeros(0)
_NO_P = np.zeros((0, 0))


@dataclass
class Context:
    """What an objective or constraint may read besides the terms: the robot and the previous
    instant's forces (for smoothing)."""

    robot: object
    f_prev: np.ndarray | None = None


class Problem:
    """An inverse-dynamics problem: an objective and constraints, bound to a robot.

    The equation of motion and the cable bounds are always included (added if missing). The
    objective and constraints given are not changed: the problem keeps bound copies
    (:meth:`~mcdm_pin.objectives.Objective.bind`).

    Args:
        robot: the :class:`~mcdm_pin.robot.Robot`.
        objective: an :class:`~mcdm_pin.objectives.Objective` (sums allowed).
        constraints: extra constraints, e.g. :class:`~mcdm_pin.constraints.InteractionCone`.
    """

    def __init__(self, robot, objective: Objective, constraints=()):
        self.robot = robot
        constraints = list(constraints)
        if not any(isinstance(c, EquationOfMotion) for c in constraints):
            constraints.insert(0, EquationOfMotion())
        if not any(isinstance(c, CableForceBounds) for c in constraints):
            constraints.insert(1, CableForceBounds())
        for c in constraints:
            if not isinstance(c, Constraint):
                raise ProblemError(f"expected Constraint objects, got {c!r}")
        if not isinstance(objective, Objective):
            raise ProblemError(f"expected an Objective, got {objective!r}")
        self.objective = objective.bind(robot)
        self.constraints = [c.bind(robot) for c in constraints]
        names = [c.joint for c in self.constraints if isinstance(c, InteractionCone)]
        if len(set(names)) != len(names):
            raise ProblemError(f"more than one cone on a joint: {names}")
        # the user's objective without smoothing terms: what is reported as "objective"
        terms = self.objective.terms if isinstance(self.objective, Sum) else [self.objective]
        weights = self.objective.weights if isinstance(self.objective, Sum) else [1.0]
        self._primary = Sum([t for t in terms if not isinstance(t, Smoothing)],
                            [w for t, w in zip(terms, weights) if not isinstance(t, Smoothing)])
        self.has_smoothing = any(isinstance(t, Smoothing) for t in terms)
        self._plan = self._make_plan()
        self.actuation = _Actuation.of(robot)

    @property
    def n_variables(self) -> int:
        """Unknowns per instant: the cables, then the actuator components (hybrid robots)."""
        return self.robot.m + (0 if self.actuation is None else self.actuation.n)

    @property
    def cone_constraints(self) -> list[InteractionCone]:
        return [c for c in self.constraints if isinstance(c, InteractionCone)]

    # ------------------------------------------------------------------------------- as data
    def spec(self) -> dict:
        """A JSON-able description: ``{"objective": {...}, "constraints": [{...}, ...]}``."""
        return {"version": 1, "objective": self.objective.spec(),
                "constraints": [c.spec() for c in self.constraints]}

    def to_json(self) -> str:
        return json.dumps(self.spec(), sort_keys=True)

    @classmethod
    def from_spec(cls, robot, spec) -> "Problem":
        """The problem described by ``spec`` (a dict from :meth:`spec`, or its JSON text)."""
        if isinstance(spec, str):
            try:
                spec = json.loads(spec)
            except json.JSONDecodeError as exc:
                raise ProblemError(f"problem spec: not valid JSON ({exc})") from None
        if not isinstance(spec, dict) or "objective" not in spec:
            raise ProblemError(f"problem spec: expected a mapping with 'objective' and 'constraints', "
                               f"got {spec!r}")
        return cls(robot, objective_from_spec(spec["objective"]),
                   [constraint_from_spec(c) for c in spec.get("constraints", [])])

    # ------------------------------------------------------------------------------ assembly
    def assemble(self, terms, context: Context) -> QPData:
        quad = self.objective.quadratic(terms, context)
        m = terms.L.shape[0]
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
            # C order: the compiled steps of the instant read it as it is (no copy per step)
            A, b = np.ascontiguousarray(terms.L.T), -terms.tau
        else:
            A, b = np.zeros((0, m)), np.zeros(0)
        P = quad.P if getattr(self.objective, "symmetric", False) else 0.5 * (quad.P + quad.P.T)
        qp = QPData(P, quad.c, quad.r, A, b, lb, ub, cones, P_diag=quad.diag, P_factor=quad.factor)
        batch = plan["cones"]
        if batch is not None and not cones:
            qp.cones, qp._cone_arrays = batch(terms)
            qp._cone_consts = batch.consts
        elif batch is not None:
            qp.cones = batch(terms)[0] + cones
        if self.actuation is None:
            return qp
        return self.actuation.extend(qp, plan["eom"], terms.L.shape[1], terms, plan["cone_frames"])

    def _make_plan(self) -> dict:
        """What :meth:`assemble` does at every instant, decided once: the equation of motion and the
        cable bounds directly, the cones in one batch, other constraints through their methods."""
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
        # {joint: (index, frame)} of the cones (the actuators' block of a cone on a joint that carries
        # a closed loop's force)
        names = self.robot.joint_names
        cone_frames = {c.joint: (names.index(c.joint), c.frame) for c in self.cone_constraints}
        return dict(general=general, eom=eom, bounds=bounds, cone_frames=cone_frames,
                    cones=ConeBatch(cone_cons) if cone_cons else None)

    def value(self, terms, f, context: Context, qp: QPData | None = None) -> float:
        """The objective at ``f`` without smoothing terms (``qp``: the assembled problem, reused
        when there is no smoothing term)."""
        if qp is not None and not self.has_smoothing:
            return qp.objective(f)
        return self._primary.quadratic(terms, context).value(f)

    def describe(self) -> str:
        return f"minimise {self.objective!r} subject to {', '.join(map(repr, self.constraints))}"


class _Actuation:
    """The actuated joints' part of every instant's problem (module docstring): ``S``, bounds, weights."""

    def __init__(self, S, lo, hi, weight):
        self.S, self.lo, self.hi, self.weight = S, lo, hi, weight
        self.n = S.shape[1]

    @classmethod
    def of(cls, robot) -> "_Actuation | None":
        acts = tuple(getattr(robot, "actuators", ()) or ())
        if not acts:
            return None
        lo = np.concatenate([a.tau_min for a in acts]).astype(float)
        hi = np.concatenate([a.tau_max for a in acts]).astype(float)
        w = np.concatenate([np.full(len(a.idx_v), float(a.weight)) for a in acts])
        # w |tau|^2 = 1/2 tau (2 w) tau: the Hessian's diagonal is 2 w (case 1's f^T f has 2 I)
        return cls(robot.actuation, lo, hi, 2.0 * w)

    def rows(self, terms) -> np.ndarray:
        """The actuators' rows of the equation of motion at ``terms``' state: ``S`` (independent
        coordinates), or ``basis^T S`` with closed loops (``terms.actuation``)."""
        S = getattr(terms, "actuation", None)
        return self.S if S is None else S

    def extend(self, qp: QPData, eom: bool, nv: int, terms=None, cone_frames=None) -> QPData:
        """``qp`` over ``[f; tau_act]``: the equation of motion's rows gain ``-S`` (:meth:`rows`), every
        other row a zero block, every cone a zero block or, on a joint that carries a closed loop's
        force, that force's share of the torques (``terms.RT_act``); the actuators' bounds and
        ``w |tau|^2`` are added. What ``qp`` has formed already (its dense Hessian, its cones' stacked
        arrays and constants) is padded, not formed again from the structure."""
        c_ = np.ascontiguousarray
        m = qp.n
        G0, g, axis, tan, basis0 = qp.cone_arrays()
        # the dense Hessian the objective gave (a compiled Gram product) is padded too: forming it
        # again from the padded factor would cost a dense (rows, n) x (n, n) product
        dense = qp._P is not None or not qp.structured
        structured = qp.structured
        cables = (c_(qp.A, dtype=float), c_(G0, dtype=float), c_(qp.P, dtype=float) if dense else _NO_P,
                  c_(qp.P_diag, dtype=float) if structured else _NO_F,
                  c_(qp.P_factor, dtype=float).reshape(-1, m) if structured else _NO_P, c_(qp.c, dtype=float),
                  c_(qp.lb, dtype=float), c_(qp.ub, dtype=float),
                  _NO_F if qp.norm_weight is None else c_(qp.norm_weight, dtype=float))
        actuators = (c_(self.rows(terms), dtype=float), nv if eom else 0, self.lo, self.hi, self.weight)
        # (plain tuples at the kernel's boundary: solvers._structs)
        out = jit.kernels("model.actuated_kernels").actuated_arrays(cables, dense, structured, actuators)
        G = out.G
        RT_act = getattr(terms, "RT_act", None)
        if RT_act is not None:
            for i, c in enumerate(qp.cones):
                G[i, :, m:] = self._cone_block(c, terms, RT_act, cone_frames)
        cones = [ConeData(c.joint, G[i], c.g, c.axis, c.angle_deg, c.basis) for i, c in enumerate(qp.cones)]
        return QPData(out.P if dense else None, out.c, qp.r, out.A, qp.b, out.lb, out.ub, cones,
                      P_diag=out.P_diag if structured else None, P_factor=out.P_factor if structured else None,
                      norm_weight=None if qp.norm_weight is None else out.norm_weight,
                      cone_arrays=(G, g, axis, tan, basis0), cone_consts=qp.cone_consts())

    def _cone_block(self, cone, terms, RT_act, cone_frames) -> np.ndarray:
        """(rows of ``cone.G``, n_act): how the actuator torques move the cone's force."""
        zero = np.zeros((cone.G.shape[0], self.n))
        if RT_act is None:
            return zero
        if cone.joint not in (cone_frames or {}):
            raise ProblemError(f"cone on joint {cone.joint!r}: not an InteractionCone of this problem, so the "
                               f"closed loop's share of the actuator torques in its force is unknown")
        a, frame = cone_frames[cone.joint]
        block = RT_act[a, :3]
        return terms.R_socket[a] @ block if frame == "socket" else block


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
    if case not in CASES:
        raise ProblemError(f"case must be 1, 2 or 3, got {case!r}")
    if case == 1 and getattr(robot.cables, "muscles", None) is not None and cable_weights is None:
        # muscles: the activations (the biomechanics standard), the other cables' f^T f beside them
        objective = MinActivations()
        if len(robot.cables.muscle_index) < robot.m:
            w = np.ones(robot.m)
            w[robot.cables.muscle_index] = 0.0
            objective = objective + MinCableForces(w)
    elif case == 1:
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


__all__ = ["Context", "QPData", "Problem", "case_problem", "ConeData"]
