r"""What every stage and back-end returns, and the one signature they share.

A :class:`Solution` is modelled on qpsolvers' ``Solution``: the point, the duals, the objective, the
status. Duals follow one convention for every back-end (the Lagrangian of :class:`~mcdm_pin.qp.QPData`):

.. math::

    P x + c + A^T y + z - \sum_k T_k^T z^{cone}_k = 0,

with ``z_i > 0`` only where ``x_i`` is at its upper bound, ``z_i < 0`` only at its lower bound, and
``z^cone_k`` in the second-order cone, dual to ``s_k = T_k x + t_k`` (:meth:`QPData.cone_rows`).

A :class:`Stage` is one step of a solve (a warm active set, the compiled interior-point method,
ProxQP with cone cuts, ...). Every stage has the same signature, ``stage(qp, sol, deadline) ->
Solution | None``: ``sol`` is the answer so far (``None`` at first); a stage that *answers* runs only
while there is no final answer yet, a stage that *refines* runs only on an optimal answer.
:class:`~mcdm_pin.solvers.cascade.Cascade` runs a list of stages; it is a :class:`Solver`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, fields

import numpy as np

OPTIMAL = "optimal"
INFEASIBLE = "infeasible"
MAX_ITER = "max_iter"
SOFTENED = "softened"
INACCURATE = "inaccurate"
BUDGET = "budget"
ERROR = "error"
STATUSES = (OPTIMAL, INFEASIBLE, MAX_ITER, SOFTENED, INACCURATE, BUDGET, ERROR)
FINAL = (OPTIMAL, INFEASIBLE)  # statuses after which no stage tries to answer again


@dataclass
class Solution:
    """An answer (see the module docstring for the duals' convention).

    Attributes:
        x: the variables (n,), NaN where there is no valid answer.
        status: one of :data:`STATUSES`.
        objective: ``1/2 x^T P x + c^T x + r`` at ``x`` (NaN when not solved).
        y: (k,) multipliers of ``A x = b``; z: (n,) of the bounds; z_cone: (K, 3) of the cones
            (``None`` when the stage has none).
        iterations: inner iterations, summed over the stages that ran: the active-set stages count
            linear KKT solves (one per active set tried and per Newton step on held cones), the
            others their method's iterations (interior-point, ProxQP, Clarabel).
        rounds: QP solves (cone cut rounds + 1) for cutting planes, 1 otherwise.
        message: what cannot be met, for infeasible or failed instants; notes otherwise.
        stage: the stage that produced ``x`` (``first>refiner`` when a refining stage moved it).
        unique: whether the first-stage optimum is provably unique (``None``: not decided).
        unique_tested: the uniqueness test (:func:`~mcdm_pin.solvers.least_norm.is_unique`) ran on
            ``x`` already (a compiled answer), so ``unique`` ``None`` means *not proven* and the
            least-norm stage does not test again.
        active: the optimum's active set, when the stage knows it
            (:class:`~mcdm_pin.solvers.active_set.ActiveSet`).
        verified: the point and its duals passed the compiled active-set solver's KKT check (tighter
            than :mod:`.check`'s), so the check stage does not repeat it.
    """

    x: np.ndarray
    status: str
    objective: float = float("nan")
    y: np.ndarray | None = None
    z: np.ndarray | None = None
    z_cone: np.ndarray | None = None
    iterations: int = 0
    rounds: int = 1
    message: str = ""
    stage: str = ""
    unique: bool | None = None
    active: object = field(default=None, repr=False)
    verified: bool = False
    unique_tested: bool = False

    @property
    def f(self) -> np.ndarray:
        """``x`` (the name the cable-only code used)."""
        return self.x

    @property
    def found(self) -> bool:
        return self.status in (OPTIMAL, SOFTENED)

    @property
    def final(self) -> bool:
        return self.status in FINAL

    def but(self, **changes) -> "Solution":
        """A copy with some fields changed (``dataclasses.replace`` without its per-field checks: a
        few microseconds less on every stage of every instant)."""
        for name in changes:
            if name not in _FIELDS:
                raise TypeError(f"Solution has no field {name!r}")
        new = object.__new__(Solution)
        new.__dict__.update(self.__dict__)
        new.__dict__.update(changes)
        return new


_FIELDS = frozenset(f.name for f in fields(Solution))


def failure(n: int, status: str, message: str, iterations: int = 0, rounds: int = 1,
            stage: str = "") -> Solution:
    return Solution(np.full(n, np.nan), status, float("nan"), iterations=iterations, rounds=rounds,
                    message=message, stage=stage)


class Stage:
    """One step of a solve. Subclasses set ``name`` and ``refines`` and implement :meth:`run`."""

    name = "stage"
    refines = False  # False: answers when no final answer exists yet; True: improves an optimal one

    def applies(self, sol: Solution | None) -> bool:
        if self.refines:
            return sol is not None and sol.status == OPTIMAL
        return sol is None or not sol.final

    def __call__(self, qp, sol: Solution | None = None, deadline: float = float("inf")) -> Solution | None:
        """Run the stage on ``qp`` given the answer so far; ``None``: nothing to say."""
        return self.run(qp, sol, deadline)

    def run(self, qp, sol: Solution | None, deadline: float) -> Solution | None:
        raise NotImplementedError

    def learn(self, qp, sol: Solution) -> None:
        """Called with the final answer of each solve (warm starts for the next instant)."""

    def seed(self, hint: Solution) -> None:
        """A hint for the next solve only (the least-norm stage seeds its inner solve with the
        first stage's optimum)."""

    def reset(self) -> None:
        """Forget every warm start."""


class Solver:
    """A back-end: ``solve(qp) -> Solution``. Subclasses implement :meth:`solve`."""

    name = "base"

    def solve(self, qp) -> Solution:
        raise NotImplementedError

    def reset(self) -> None:
        """Forget warm-start state."""

    def fresh(self) -> "Solver":
        """A new back-end with the same settings and no state (for side problems)."""
        raise NotImplementedError


def now() -> float:
    return time.perf_counter()


def cone_violation_deg(qp, x) -> np.ndarray:
    """Per cone, how far (degrees) the force lies outside the cone (0 inside)."""
    if not qp.cones:
        return np.zeros(0)
    G, g, axis, _, _ = qp.cone_arrays()
    F = g + G @ np.asarray(x, dtype=float)
    along = np.einsum("ka,ka->k", axis, F)
    perp = F - along[:, None] * axis
    angle = np.degrees(np.arctan2(np.sqrt(np.einsum("ka,ka->k", perp, perp)), along))
    return np.maximum(angle - np.array([c.angle_deg for c in qp.cones]), 0.0)
