r"""Exact reference back-end: Clarabel's interior-point method on the second-order-cone program.

Each cone :math:`\|F_\perp\| \le \tan\rho^*\, a^T F` is the cone
:math:`(\tan\rho^*\,a^T F,\; e_1^T F,\; e_2^T F) \in \mathcal{Q}^3`.
Clarabel is a dependency: besides serving as the exact reference, it answers the rare instants on
which ProxQP stalls (:meth:`~mcdm_pin.solvers.proxqp_.ProxQPSolver._solve_fallback`).
"""

from __future__ import annotations

import numpy as np

from ..exceptions import SolverError
from ..problem import QPData
from .base import INACCURATE, INFEASIBLE, MAX_ITER, OPTIMAL, Solution, Solver, failure


def cone_rows(qp: QPData) -> tuple[np.ndarray, np.ndarray]:
    """Per cone, ``T (3, m)`` and ``t (3,)`` with ``s = T f + t = [tan a.F, e1.F, e2.F]``: the cone
    is ``|s[1:]| <= s[0]``. Stacked: (K, 3, m), (K, 3)."""
    if not qp.cones:
        return np.zeros((0, 3, qp.n)), np.zeros((0, 3))
    W = np.array([np.vstack([c.tan * c.axis, c.basis]) for c in qp.cones])  # (K, 3, 3)
    G, g = qp.cone_arrays()[:2]
    return W @ G, np.einsum("kab,kb->ka", W, g)


def conic_form(qp: QPData):
    """``(P, c, A, b, cones)`` of Clarabel's ``min 1/2 x^T P x + c^T x, b - A x in cones``: the
    equation of motion (zero cone), the finite bounds (non-negative cone), one second-order cone of
    dimension 3 per stability cone (:func:`cone_rows`). ``P`` is the upper triangle, sparse."""
    import clarabel
    from scipy import sparse

    n = qp.n
    blocks, rhs, cones = [], [], []
    if len(qp.b):
        blocks.append(qp.A)
        rhs.append(qp.b)
        cones.append(clarabel.ZeroConeT(len(qp.b)))
    hi, lo = np.isfinite(qp.ub), np.isfinite(qp.lb)
    if hi.any() or lo.any():
        eye = np.eye(n)
        blocks += [eye[hi], -eye[lo]]
        rhs += [qp.ub[hi], -qp.lb[lo]]
        cones.append(clarabel.NonnegativeConeT(int(hi.sum() + lo.sum())))
    if qp.cones:
        T, t = cone_rows(qp)
        blocks.append(-T.reshape(-1, n))
        rhs.append(t.reshape(-1))
        cones += [clarabel.SecondOrderConeT(3)] * len(qp.cones)
    A = sparse.csc_matrix(np.vstack(blocks)) if blocks else sparse.csc_matrix((0, n))
    b = np.concatenate(rhs) if rhs else np.zeros(0)
    return sparse.csc_matrix(np.triu(2.0 * qp.P)), qp.c, A, b, cones


class ClarabelSolver(Solver):
    """Args:
        tol: Clarabel's gap and feasibility tolerances.
        max_iter: iteration limit."""

    name = "clarabel"

    def __init__(self, tol: float = 1e-11, max_iter: int = 200):
        try:
            import clarabel  # noqa: F401
        except ImportError:
            raise SolverError("the clarabel back-end needs the clarabel package (a dependency of "
                              "mcdm-pin): pip install clarabel") from None
        self.tol, self.max_iter = tol, max_iter

    def fresh(self) -> "ClarabelSolver":
        return ClarabelSolver(self.tol, self.max_iter)

    def solve(self, qp: QPData) -> Solution:
        import clarabel

        n = qp.n
        P, c, A, b, cones = conic_form(qp)
        settings = clarabel.DefaultSettings()
        settings.verbose = False
        settings.max_iter = self.max_iter
        settings.tol_gap_abs = settings.tol_gap_rel = self.tol
        settings.tol_feas = self.tol
        settings.tol_ktratio = 1e-8
        solver = clarabel.DefaultSolver(P, c, A, b, cones, settings)
        sol = solver.solve()
        status = str(sol.status)
        if status == "Solved":
            f = np.array(sol.x)
            return Solution(f, OPTIMAL, qp.objective(f), int(sol.iterations))
        if status in ("PrimalInfeasible", "AlmostPrimalInfeasible"):
            return failure(n, INFEASIBLE, "no cable forces satisfy the constraints (Clarabel: "
                                          f"{status})", int(sol.iterations))
        if status == "MaxIterations":
            return failure(n, MAX_ITER, "Clarabel reached its iteration limit", int(sol.iterations))
        if status == "AlmostSolved":
            # reduced accuracy: returned as a candidate; the runner checks every constraint and
            # downgrades it to "inaccurate" if one is broken beyond tolerance
            f = np.array(sol.x)
            return Solution(f, OPTIMAL, qp.objective(f), int(sol.iterations),
                            message="Clarabel: solved to reduced accuracy (AlmostSolved)")
        return failure(n, INACCURATE, f"Clarabel: {status}", int(sol.iterations))
