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
        from scipy import sparse

        n = qp.n
        blocks, rhs, cones = [], [], []
        if len(qp.b):
            blocks.append(qp.A)
            rhs.append(qp.b)
            cones.append(clarabel.ZeroConeT(len(qp.b)))
        hi, lo = np.isfinite(qp.ub), np.isfinite(qp.lb)
        eye = np.eye(n)
        if hi.any() or lo.any():
            blocks += [eye[hi], -eye[lo]]
            rhs += [qp.ub[hi], -qp.lb[lo]]
            cones.append(clarabel.NonnegativeConeT(int(hi.sum() + lo.sum())))
        for c in qp.cones:
            # s = b - A f = [t a.F; e1.F; e2.F] with F = g + G f
            T = np.vstack([c.tan * c.axis, c.basis])
            blocks.append(-(T @ c.G))
            rhs.append(T @ c.g)
            cones.append(clarabel.SecondOrderConeT(3))
        A = sparse.csc_matrix(np.vstack(blocks))
        b = np.concatenate(rhs)
        P = sparse.csc_matrix(np.triu(2.0 * qp.P))
        settings = clarabel.DefaultSettings()
        settings.verbose = False
        settings.max_iter = self.max_iter
        settings.tol_gap_abs = settings.tol_gap_rel = self.tol
        settings.tol_feas = self.tol
        settings.tol_ktratio = 1e-8
        solver = clarabel.DefaultSolver(P, qp.c, A, b, cones, settings)
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
