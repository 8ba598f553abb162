r"""Default back-end: ProxSuite's dense ProxQP, with the stability cones by cutting planes.

A cone :math:`K = \{F : \|F_\perp\| \le t\, a^T F\}` (:math:`t = \tan\rho^*`) is convex, so for any unit
vector :math:`n \perp a` the half-space

.. math:: n^T F \le t\, a^T F \qquad (\text{since } n^T F \le \|F_\perp\|)

contains it: a valid *outer cut*, linear in :math:`f` because :math:`F = g + G f`. The back-end solves
the QP with the cuts it has, and while some force :math:`F_k` lies outside its cone by more than
``cone_tol_deg``, adds the cut with :math:`n = F_{k,\perp}/\|F_{k,\perp}\|` (it separates :math:`F_k`)
and re-solves, warm-started. Every relaxation contains the true feasible set, so (i) its optimum
never exceeds the true optimum and the limit point, being feasible, is the global optimum, and
(ii) a relaxation that is infeasible proves the true problem infeasible. Cut directions are kept for
the next instant (they remain valid cuts whatever the state).

Bounds are written as rows of ``C`` (not ProxQP's box), so that warm starts with ``(x, y, z)`` are
safe (see ``shared/PITFALLS.md``).
"""

from __future__ import annotations

import numpy as np
from proxsuite import proxqp

from ..problem import QPData
from .base import INACCURATE, INFEASIBLE, MAX_ITER, OPTIMAL, Solution, Solver, failure

_STATUS = proxqp.QPSolverOutput
# cut rows (in f) more parallel than this make ProxQP misreport infeasibility: a new cut replaces such
# a neighbour instead of joining it
_SAME_CUT_COS = 1.0 - 1e-5


class ProxQPSolver(Solver):
    """Args:
        eps_abs: ProxQP's absolute tolerance on the primal and dual residuals.
        max_iter: ProxQP's iteration limit per QP.
        cone_tol_deg: largest accepted cone violation, degrees.
        max_rounds: largest number of QP solves per instant (cut rounds + 1).
        cuts_per_cone: rows reserved per cone; when full, the slackest cut is replaced.
        warm_start: warm-start each QP from the previous solution (same dimensions).
        keep_cuts: keep cut directions from one instant to the next.
        eps_infeasible: ProxQP's primal/dual infeasibility tolerances. ProxQP's default (1e-4)
            declared feasible relaxations infeasible on the 2-link arm; 1e-9 did not.
    """

    name = "proxqp"

    def __init__(self, eps_abs: float = 1e-11, max_iter: int = 10_000, cone_tol_deg: float = 1e-7,
                 max_rounds: int = 200, cuts_per_cone: int = 24, warm_start: bool = True,
                 keep_cuts: bool = True, eps_infeasible: float = 1e-9):
        self.eps_infeasible = eps_infeasible
        self.reuse = False
        self.eps_abs, self.max_iter = eps_abs, max_iter
        self.cone_tol_deg, self.max_rounds = cone_tol_deg, max_rounds
        self.cuts_per_cone, self.warm_start, self.keep_cuts = cuts_per_cone, warm_start, keep_cuts
        self.reset()

    def fresh(self) -> "ProxQPSolver":
        return ProxQPSolver(self.eps_abs, self.max_iter, self.cone_tol_deg, self.max_rounds,
                            self.cuts_per_cone, self.warm_start, self.keep_cuts, self.eps_infeasible)

    def reset(self) -> None:
        self._qp = None
        self._dims = None
        self._warm = None
        self._cuts: dict[str, list[np.ndarray]] = {}

    # ------------------------------------------------------------------------------------------
    def _new_qp(self, dims, H, g, A, b, C, l, u):
        qp = proxqp.dense.QP(*dims)
        s = qp.settings
        s.eps_abs, s.eps_rel, s.max_iter = self.eps_abs, 0.0, self.max_iter
        s.verbose = False
        s.eps_primal_inf = s.eps_dual_inf = self.eps_infeasible
        qp.init(H, g, A, b, C, l, u)
        self._qp, self._dims = qp, dims

    def _solve_qp(self, H, g, A, b, C, l, u):
        dims = (H.shape[0], A.shape[0], C.shape[0])
        if self._qp is None or dims != self._dims or not self.reuse:
            self._new_qp(dims, H, g, A, b, C, l, u)
        else:
            self._qp.update(H, g, A, b, C, l, u, update_preconditioner=True)
        warm = self.warm_start and self._warm is not None and self._warm[0].shape[0] == dims[0] \
            and self._warm[1].shape[0] == dims[1] and self._warm[2].shape[0] == dims[2]
        if warm:
            self._qp.solve(*self._warm)
            if self._qp.results.info.status == _STATUS.PROXQP_PRIMAL_INFEASIBLE:
                # ProxQP's infeasibility test misfires after some warm starts (seen on the 2-link
                # arm, case 3): confirm with a new workspace and a cold start before believing it.
                self._new_qp(dims, H, g, A, b, C, l, u)
                self._qp.solve()
        else:
            self._qp.solve()
        res = self._qp.results
        x, y, z = res.x.copy(), res.y.copy(), res.z.copy()
        status = res.info.status
        if status == _STATUS.PROXQP_SOLVED:
            self._warm = (x, y, z)
        else:
            self._warm = None
        return x, z, status, int(res.info.iter)

    def solve(self, qp: QPData) -> Solution:
        n = qp.n
        H, g = 2.0 * qp.P, qp.c
        cones = qp.cones
        cap = self.cuts_per_cone
        if not self.keep_cuts:
            self._cuts = {}
        cuts = [list(self._cuts.get(c.joint, [])) for c in cones]
        n_in = n + cap * len(cones)
        C = np.zeros((n_in, n))
        C[:n] = np.eye(n)
        l, u = np.full(n_in, -np.inf), np.full(n_in, np.inf)
        l[:n], u[:n] = qp.lb, qp.ub
        iterations, rounds = 0, 0
        for rounds in range(1, self.max_rounds + 1):
            for k, cone in enumerate(cones):
                base = n + k * cap
                t = cone.tan
                C[base:base + cap] = 0.0
                u[base:base + cap] = np.inf
                for i, d in enumerate(cuts[k]):
                    w = d - t * cone.axis  # d . F - t a . F <= 0
                    C[base + i] = w @ cone.G
                    u[base + i] = -(w @ cone.g)
            x, z, status, it = self._solve_qp(H, g, qp.A, qp.b, C, l, u)
            iterations += it
            if status == _STATUS.PROXQP_PRIMAL_INFEASIBLE:
                # ProxQP's infeasibility test is a heuristic that misfires on thin relaxations; the
                # relaxation is a linear feasibility problem, decided exactly by HiGHS.
                x0 = _feasible_point(qp.A, qp.b, C, l, u)
                if x0 is None:
                    what = "the cones' outer approximation" if cones else "the cable bounds"
                    return failure(n, INFEASIBLE, f"no cable forces satisfy the equation of motion "
                                                  f"and {what}", iterations, rounds)
                self._new_qp(self._dims, H, g, qp.A, qp.b, C, l, u)
                self._qp.solve(x0, np.zeros(len(qp.b)), np.zeros(len(l)))
                res = self._qp.results
                iterations += int(res.info.iter)
                if res.info.status != _STATUS.PROXQP_SOLVED:
                    return failure(n, INACCURATE, "ProxQP could not solve a feasible relaxation "
                                                  f"({res.info.status.name})", iterations, rounds)
                x, z = res.x.copy(), res.z.copy()
                self._warm = (x, res.y.copy(), z)
                status = _STATUS.PROXQP_SOLVED
            if status == _STATUS.PROXQP_MAX_ITER_REACHED:
                return failure(n, MAX_ITER, "ProxQP reached its iteration limit", iterations, rounds)
            if status != _STATUS.PROXQP_SOLVED:
                return failure(n, INACCURATE, f"ProxQP: {status.name}", iterations, rounds)
            added = False
            for k, cone in enumerate(cones):
                F = cone.force(x)
                along = float(cone.axis @ F)
                perp_vec = F - along * cone.axis
                perp = float(np.linalg.norm(perp_vec))
                angle = np.degrees(np.arctan2(perp, along))
                if angle <= cone.angle_deg + self.cone_tol_deg:
                    continue
                d = perp_vec / perp if perp > 1e-300 else cone.basis[0]
                near = _parallel_cuts(cone, cuts[k], d)
                if near:
                    # a nearly identical cut makes the relaxation degenerate (ProxQP then misreports
                    # infeasibility): replace it by the exact separating cut instead
                    cuts[k][near[0]] = d
                    added = True
                    continue
                if len(cuts[k]) >= cap:
                    # replace the cut with the most slack at the current point
                    slack = [cone.tan * along - float(c @ F) for c in cuts[k]]
                    cuts[k].pop(int(np.argmax(slack)))
                cuts[k].append(d)
                added = True
            if not added:
                if self.keep_cuts:  # keep the cuts that bind (non-zero multiplier) for the next instant
                    for k, cone in enumerate(cones):
                        zk = z[n + k * cap:n + k * cap + len(cuts[k])]
                        self._cuts[cone.joint] = [d for d, zi in zip(cuts[k], zk) if zi > 0.0]
                return Solution(x, OPTIMAL, qp.objective(x), iterations, rounds)
        return failure(n, MAX_ITER, f"the cone cuts did not converge in {self.max_rounds} rounds",
                       iterations, rounds)


def _feasible_point(A, b, C, l, u):
    """A point of ``{A x = b, l <= C x <= u}`` found by HiGHS (scipy), or ``None`` if it is empty."""
    from scipy.optimize import linprog

    n = C.shape[1]
    rows_u, rows_l = np.isfinite(u), np.isfinite(l)
    box = np.zeros(len(u), dtype=bool)
    box[:n] = True  # the first n rows of C are the identity: the cable bounds
    A_ub = np.vstack([C[rows_u & ~box], -C[rows_l & ~box]])
    b_ub = np.concatenate([u[rows_u & ~box], -l[rows_l & ~box]])
    bounds = list(zip(np.where(np.isfinite(l[:n]), l[:n], None), np.where(np.isfinite(u[:n]), u[:n], None)))
    res = linprog(np.zeros(n), A_ub=A_ub if len(b_ub) else None, b_ub=b_ub if len(b_ub) else None,
                  A_eq=A if len(b) else None, b_eq=b if len(b) else None, bounds=bounds, method="highs")
    return res.x if res.status == 0 else None


def _parallel_cuts(cone, cuts, d) -> list[int]:
    """Indices of existing cuts whose rows in f are nearly parallel to the new cut's."""
    if not cuts:
        return []
    t = cone.tan
    W = (np.asarray(cuts) - t * cone.axis) @ cone.G
    w = (d - t * cone.axis) @ cone.G
    cos = W @ w / (np.linalg.norm(W, axis=1) * np.linalg.norm(w) + 1e-300)
    return [int(i) for i in np.flatnonzero(cos > _SAME_CUT_COS)]
