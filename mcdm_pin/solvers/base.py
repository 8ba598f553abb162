"""What every back-end returns, and the one signature they share: ``solver.solve(qp) -> Solution``.

Back-ends may keep state between calls (workspaces, warm starts, cone cuts); ``reset()`` forgets it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..problem import QPData

OPTIMAL = "optimal"
INFEASIBLE = "infeasible"
MAX_ITER = "max_iter"
SOFTENED = "softened"
INACCURATE = "inaccurate"
ERROR = "error"
STATUSES = (OPTIMAL, INFEASIBLE, MAX_ITER, SOFTENED, INACCURATE, ERROR)


@dataclass
class Solution:
    """A back-end's answer.

    Attributes:
        f: the cable forces (m,), or NaN where there is no valid answer.
        status: one of :data:`STATUSES`.
        objective: the QP's objective value at ``f`` (NaN when not solved).
        iterations: inner solver iterations, summed over cone rounds.
        rounds: QP solves (1 + cone cut rounds) for cutting planes, 1 otherwise.
        message: what cannot be met, for infeasible or failed instants.
    """

    f: np.ndarray
    status: str
    objective: float
    iterations: int = 0
    rounds: int = 1
    message: str = ""

    @property
    def found(self) -> bool:
        return self.status in (OPTIMAL, SOFTENED)


class Solver:
    """A back-end. Subclasses implement :meth:`solve`."""

    name = "base"

    def solve(self, qp: QPData) -> Solution:
        raise NotImplementedError

    def reset(self) -> None:
        """Forget warm-start state."""

    def fresh(self) -> "Solver":
        """A new back-end with the same settings and no state (for side problems)."""
        raise NotImplementedError


def cone_violation_deg(qp: QPData, f) -> np.ndarray:
    """Per cone, how far (degrees) the force lies outside the cone (0 inside)."""
    if not qp.cones:
        return np.zeros(0)
    G, g, axis, _, _ = qp.cone_arrays()
    F = g + G @ np.asarray(f, dtype=float)
    along = np.einsum("ka,ka->k", axis, F)
    perp = F - along[:, None] * axis
    angle = np.degrees(np.arctan2(np.sqrt(np.einsum("ka,ka->k", perp, perp)), along))
    return np.maximum(angle - np.array([c.angle_deg for c in qp.cones]), 0.0)


def failure(m: int, status: str, message: str, iterations: int = 0, rounds: int = 1) -> Solution:
    return Solution(np.full(m, np.nan), status, float("nan"), iterations, rounds, message)
