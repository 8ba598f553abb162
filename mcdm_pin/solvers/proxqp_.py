r"""Default back-end: ProxSuite's dense ProxQP, with the stability cones by cutting planes.

A cone :math:`K = \{F : \|F_\perp\| \le t\, a^T F\}` (:math:`t = \tan\rho^*`) is convex, so for any unit
vector :math:`n \perp a` the half-space

.. math:: n^T F \le t\, a^T F \qquad (\text{since } n^T F \le \|F_\perp\|)

contains it: a valid *outer cut*, linear in :math:`f` because :math:`F = g + G f`.

1. **Cutting planes.** Solve the QP with the cuts at hand; while some force :math:`F_k` lies outside
   its cone by more than ``cone_tol_deg``, add the cut with :math:`n = F_{k,\perp}/\|F_{k,\perp}\|`
   (it separates :math:`F_k`) and re-solve, warm-started. Every relaxation contains the true feasible
   set, so its optimum is a lower bound, and a relaxation that is infeasible *proves* the instant
   infeasible. Cuts are only dropped when inactive, so the bounds increase monotonically.
2. **SQP polish.** Near the optimum the new cuts become nearly parallel to the old ones, which makes
   the QP degenerate (ProxQP then stalls or misreports infeasibility) and Kelley's method converges
   only linearly. When a new cut is nearly parallel to an existing one, the back-end switches to
   sequential quadratic programming from the current point: one tangent row per active cone (the
   linearisation of :math:`c(F) = \|F_\perp\| - t\,a^T F`, itself a valid cut through the apex) and
   the cone's curvature :math:`z_k\,G^T (I - aa^T - \hat n\hat n^T) G/\|F_\perp\|` (positive
   semidefinite) added to the Hessian, centred at the current point. Its fixed point satisfies the
   KKT conditions of the convex problem, hence is the global optimum; convergence is quadratic (2-3
   extra solves). It stops when every cone holds and the step is below 1e-9 relative.

ProxQP's own infeasibility test is a heuristic; whenever ProxQP does not report SOLVED, HiGHS (scipy)
decides the relaxation's linear feasibility exactly, and a feasible relaxation is re-solved from
HiGHS's point with ProxQP's infeasibility test off. Cut directions that bind are kept for the next
instant (they remain valid cuts whatever the state).

Bounds are written as rows of ``C`` (not ProxQP's box), so that warm starts with ``(x, y, z)`` are
safe (see ``shared/PITFALLS.md``).
"""

from __future__ import annotations

import numpy as np
from proxsuite import proxqp

from ..problem import QPData
from .active_set import ActiveSet, try_active_set
from .base import INACCURATE, INFEASIBLE, MAX_ITER, OPTIMAL, Solution, Solver, failure

_STATUS = proxqp.QPSolverOutput
# cut rows (in f) more parallel than this are merged (see ProxQPSolver.solve)
_SAME_CUT_COS = 1.0 - 1e-5


class ProxQPSolver(Solver):
    """Args:
        eps_abs, eps_rel: ProxQP's absolute and relative tolerances on the primal and dual
            residuals. The relative part matters when forces reach hundreds of newtons: the dual
            residual then has a rounding floor near 1e-10 that eps_abs = 1e-11 alone never meets.
        max_iter: ProxQP's iteration limit per QP (first attempt).
        cone_tol_deg: largest accepted cone violation, degrees.
        max_rounds: largest number of QP solves per instant (cut rounds + 1).
        cuts_per_cone: cuts kept per cone; beyond it, cuts with zero multiplier are dropped.
        warm_start: warm-start each QP from the previous solution (same dimensions).
        keep_cuts: keep cut directions from one instant to the next.
        active_set: first try the previous instant's active set (see :mod:`.active_set`); its
            answer is used only when it passes the full KKT check, ProxQP is run otherwise.
        eps_infeasible: ProxQP's primal/dual infeasibility tolerances (first attempt).
        max_iter_retry: iteration limit of the re-run from a feasible point (see ``_solve_qp``).
        fallback: when ProxQP stalls or its answer is inaccurate, solve the exact cone program with
            Clarabel (``_solve_fallback``).
    """

    name = "proxqp"

    def __init__(self, eps_abs: float = 1e-11, eps_rel: float = 1e-12, max_iter: int = 1000, cone_tol_deg: float = 1e-7,
                 max_rounds: int = 200, cuts_per_cone: int = 24, warm_start: bool = True,
                 keep_cuts: bool = True, eps_infeasible: float = 1e-7, max_iter_retry: int = 5_000,
                 active_set: bool = True, fallback: bool = True):
        self.active_set = active_set
        self.fallback = fallback
        self.eps_abs, self.eps_rel = eps_abs, eps_rel
        self.max_iter, self.max_iter_retry = max_iter, max_iter_retry
        self.eps_infeasible = eps_infeasible
        self.cone_tol_deg, self.max_rounds = cone_tol_deg, max_rounds
        self.cuts_per_cone, self.warm_start, self.keep_cuts = cuts_per_cone, warm_start, keep_cuts
        self.reset()

    def fresh(self) -> "ProxQPSolver":
        return ProxQPSolver(self.eps_abs, self.eps_rel, self.max_iter, self.cone_tol_deg, self.max_rounds,
                            self.cuts_per_cone, self.warm_start, self.keep_cuts, self.eps_infeasible,
                            self.max_iter_retry, self.active_set, self.fallback)

    def reset(self) -> None:
        self._warm = None
        self._guess: ActiveSet | None = None
        self._last_z = None
        self._cuts: dict[str, list[np.ndarray]] = {}

    # ------------------------------------------------------------------------------------------
    def _new_qp(self, H, g, A, b, C, l, u, eps_infeasible: float, max_iter: int):
        qp = proxqp.dense.QP(H.shape[0], A.shape[0], C.shape[0])
        s = qp.settings
        s.eps_abs, s.eps_rel, s.max_iter = self.eps_abs, self.eps_rel, max_iter
        s.verbose = False
        s.eps_primal_inf = s.eps_dual_inf = eps_infeasible
        # residuals alone do not bound the objective's error on degenerate problems (an LP whose
        # optimum is a vertex stopped 1.5e-5 above it): require a small duality gap too
        s.check_duality_gap = True
        s.eps_duality_gap_abs, s.eps_duality_gap_rel = self.eps_abs, self.eps_rel
        qp.init(H, g, A, b, C, l, u)
        return qp

    def _solve_qp(self, H, g, A, b, C, l, u):
        """Solve one relaxation. Returns (x, z, status, iterations); status ``None`` means proven
        infeasible.

        ProxQP's own infeasibility test is a heuristic that misfires on nearly parallel rows and
        after some warm starts (seen on the 2-link arm), and its iterations can stall on nearly
        infeasible problems. So when it does not report SOLVED, HiGHS (scipy) decides the
        relaxation's feasibility exactly (it is a linear feasibility problem); if feasible, ProxQP
        is re-run from HiGHS's point with its infeasibility test off and a larger iteration limit.
        """
        qp = self._new_qp(H, g, A, b, C, l, u, self.eps_infeasible, self.max_iter)
        warm = self._warm
        if self.warm_start and warm is not None and warm[0].shape == (H.shape[0],) \
                and warm[1].shape == (A.shape[0],):
            z = warm[2]
            if z.shape != (C.shape[0],):  # cut rows changed: keep the bounds' multipliers only
                z0 = np.zeros(C.shape[0])
                z0[:H.shape[0]] = z[:H.shape[0]]
                z = z0
            qp.solve(warm[0], warm[1], z)
        else:
            qp.solve()
        iterations = int(qp.results.info.iter)
        if qp.results.info.status != _STATUS.PROXQP_SOLVED:
            x0 = _feasible_point(A, b, C, l, u)
            if x0 is None:
                self._warm = None
                return None, None, None, iterations
            qp = self._new_qp(H, g, A, b, C, l, u, 0.0, self.max_iter_retry)
            qp.solve(x0, np.zeros(A.shape[0]), np.zeros(C.shape[0]))
            iterations += int(qp.results.info.iter)
        res = qp.results
        x, y, z = res.x.copy(), res.y.copy(), res.z.copy()
        status = res.info.status
        self._warm = (x, y, z) if status == _STATUS.PROXQP_SOLVED else None
        self._last_z = z
        return x, z, status, iterations

    def solve(self, qp: QPData) -> Solution:
        if self.active_set and self._guess is not None:
            hit = try_active_set(qp, self._guess)
            if hit is not None:
                f, mult, bound_mult, self._guess = hit
                # warm start for a later ProxQP solve: the point and the bounds' multipliers
                self._warm = (f.copy(), np.zeros(len(qp.b)), -bound_mult)
                return Solution(f, OPTIMAL, qp.objective(f), 0, 0, "")
        self._guess = None
        sol, mult = self._solve_proxqp(qp)
        if sol.status in (MAX_ITER, INACCURATE) and self.fallback:
            sol, mult = self._solve_fallback(qp, sol)
        if self.active_set and self._guess is None and sol.status == OPTIMAL:
            # ProxQP's multipliers of the bound rows: z > 0 at an upper, z < 0 at a lower bound
            z = self._last_z[:qp.n] if self._last_z is not None else None
            self._guess = ActiveSet.from_solution(qp, sol.f, mult, None if z is None else -z)
            # polish: the exact KKT point of ProxQP's active set (bounds and the equation of motion
            # then hold to rounding instead of to ProxQP's tolerance), if it verifies
            hit = try_active_set(qp, self._guess, max_pivots=2)
            if hit is not None:
                f, mult, bound_mult, self._guess = hit
                sol = Solution(f, OPTIMAL, qp.objective(f), sol.iterations, sol.rounds, sol.message)
        if sol.status == OPTIMAL:
            # ProxQP meets the bounds to its tolerance, relative to the problem's scale (1e-9 N at
            # forces of 1e6 N is beyond it): project onto the bounds when the miss is that small; the
            # runner re-checks the equation of motion (and cones) on the projected forces
            f = sol.f
            slack = 1e-7 * (1.0 + np.maximum(np.abs(qp.lb), np.abs(qp.ub)))
            if np.any(f < qp.lb) or np.any(f > qp.ub):
                if np.all(f >= qp.lb - slack) and np.all(f <= qp.ub + slack):
                    f = np.clip(f, qp.lb, qp.ub)
                    sol = Solution(f, OPTIMAL, qp.objective(f), sol.iterations, sol.rounds, sol.message)
        return sol

    def _solve_fallback(self, qp: QPData, failed: Solution):
        """ProxQP stalled (seen on ~1 in 100 generated robots: its iteration limit after 51k
        iterations on a positive semidefinite objective with a large flat subspace): solve the exact
        cone program with Clarabel's interior-point method instead. The answer is then polished and
        checked like any other."""
        from .clarabel_ import ClarabelSolver

        sol = ClarabelSolver().solve(qp)
        why = f"ProxQP failed ({failed.message}); answered by Clarabel"
        if sol.status != OPTIMAL:
            return Solution(sol.f, sol.status, sol.objective, failed.iterations + sol.iterations,
                            failed.rounds, f"{why}: {sol.message}"), {}
        # the polish guess: cables by position only (the stalled run's multipliers mean nothing),
        # cones that ActiveSet.from_solution finds on their surface
        self._last_z = None
        mult = {c.joint: 1.0 for c in qp.cones}
        return Solution(sol.f, OPTIMAL, sol.objective, failed.iterations + sol.iterations,
                        failed.rounds, why), mult

    def _solve_proxqp(self, qp: QPData):
        n = qp.n
        H, g = 2.0 * qp.P, qp.c
        cones = qp.cones
        if not self.keep_cuts:
            self._cuts = {}
        if self._warm is not None:
            # a new instant: keep the previous forces as the starting point but not the previous
            # instant's multipliers. Next to a singular instant (2-link arm, q = 0 at t = 0.5 s) they
            # are huge and sent ProxQP into ~1e6 inner iterations (4 s) or a false "infeasible".
            x, y, z = self._warm
            self._warm = (x, np.zeros_like(y), np.zeros_like(z))
        cuts = [list(self._cuts.get(c.joint, [])) for c in cones]
        iterations, rounds = 0, 0
        polish = False  # False: cutting planes; True: SQP polish (see the module docstring)
        sqp_dirs: list = [None] * len(cones)
        sqp_mult = np.zeros(len(cones))
        x_prev = None
        for rounds in range(1, self.max_rounds + 1):
            Hk, gk = H, g
            if polish:
                # SQP subproblem: the objective plus, per cone, its curvature weighted by its
                # multiplier, centred at the current point: 1/2 (f - x)^T (z_k D_k) (f - x)
                rows = [(k, [d]) if d is not None else (k, []) for k, d in enumerate(sqp_dirs)]
                Hk, gk = H.copy(), g.copy()
                for k, cone in enumerate(cones):
                    if sqp_dirs[k] is not None and sqp_mult[k] > 0:
                        D = sqp_mult[k] * _cone_curvature(cone, x_prev)
                        Hk += D
                        gk -= D @ x_prev
            else:
                rows = list(enumerate(cuts))
            C, l, u, owner = _rows(qp, cones, rows)
            x, z, status, it = self._solve_qp(Hk, gk, qp.A, qp.b, C, l, u)
            iterations += it
            if status is None:
                if polish:  # an SQP subproblem is not a relaxation: no proof, fall back
                    return failure(n, INACCURATE, "SQP polish subproblem infeasible", iterations, rounds), {}
                what = "the cones' outer approximation" if cones else "the cable bounds"
                return failure(n, INFEASIBLE, f"no cable forces satisfy the equation of motion and "
                                              f"{what} (decided by HiGHS)", iterations, rounds), {}
            if status == _STATUS.PROXQP_MAX_ITER_REACHED:
                return failure(n, MAX_ITER, "ProxQP reached its iteration limit", iterations, rounds), {}
            if status != _STATUS.PROXQP_SOLVED:
                return failure(n, INACCURATE, f"ProxQP: {status.name}", iterations, rounds), {}
            zc = z[n:]
            violated = []
            for k, cone in enumerate(cones):
                F = cone.force(x)
                along = float(cone.axis @ F)
                perp_vec = F - along * cone.axis
                perp = float(np.linalg.norm(perp_vec))
                if np.degrees(np.arctan2(perp, along)) > cone.angle_deg + self.cone_tol_deg:
                    violated.append((k, perp_vec / perp if perp > 1e-300 else cone.basis[0]))
            if polish:
                step = np.linalg.norm(x - x_prev) / (1.0 + np.linalg.norm(x))
                if not violated and step <= 1e-9:
                    mult = {c.joint: float(zc[owner == k].sum()) for k, c in enumerate(cones)}
                    return Solution(x, OPTIMAL, qp.objective(x), iterations, rounds), mult
                for k, cone in enumerate(cones):
                    mult = float(zc[owner == k].sum())
                    F = cone.force(x)
                    perp_vec = F - float(cone.axis @ F) * cone.axis
                    perp = float(np.linalg.norm(perp_vec))
                    if (sqp_dirs[k] is not None or any(v[0] == k for v in violated)) and perp > 1e-300:
                        sqp_dirs[k] = perp_vec / perp
                        sqp_mult[k] = mult
                x_prev = x
                continue
            duals = [zc[owner == k] for k in range(len(cones))]
            if not violated:
                if self.keep_cuts:  # keep the binding cuts (non-zero multiplier) for the next instant
                    for cone, ck, zk in zip(cones, cuts, duals):
                        self._cuts[cone.joint] = [d for d, zi in zip(ck, zk) if zi != 0.0]
                mult = {c.joint: float(dk.sum()) for c, dk in zip(cones, duals)}
                return Solution(x, OPTIMAL, qp.objective(x), iterations, rounds), mult
            if self.active_set and rounds == 1:
                # the relaxation's solution tells which cables and cones bind: Newton on that active
                # set (verified by the full KKT check) usually finishes without more rounds
                mult = {c.joint: max(float(dk.sum()), 1e-9) for c, dk in zip(cones, duals)}
                for k, _ in violated:
                    mult[cones[k].joint] = max(mult[cones[k].joint], 1e-9)
                guess = ActiveSet.from_solution(qp, x, mult, -z[:n])
                hit = try_active_set(qp, guess)
                if hit is not None:
                    f, mult, bound_mult, self._guess = hit
                    return Solution(f, OPTIMAL, qp.objective(f), iterations, rounds), mult
            for k, d in violated:
                if _parallel_cuts(cones[k], cuts[k], d):
                    polish = True
                if len(cuts[k]) >= self.cuts_per_cone:
                    # drop inactive cuts only: the relaxation never loosens where it binds, so the
                    # optimal values of successive relaxations increase and cannot cycle
                    cuts[k] = [c for c, zi in zip(cuts[k], duals[k]) if zi != 0.0]
                cuts[k].append(d)
            if polish:
                # the cuts now crowd around the optimum: nearly parallel rows are degenerate for
                # ProxQP, so finish with SQP from this point (one tangent row per cone plus the
                # cone's curvature, weighted by its multiplier: quadratic convergence)
                x_prev = x
                for k, cone in enumerate(cones):
                    F = cone.force(x)
                    perp_vec = F - float(cone.axis @ F) * cone.axis
                    perp = float(np.linalg.norm(perp_vec))
                    mult = float(duals[k].sum())
                    if (mult > 0 or any(v[0] == k for v in violated)) and perp > 1e-300:
                        sqp_dirs[k], sqp_mult[k] = perp_vec / perp, mult
                self._warm = None
                if self.keep_cuts:
                    for cone, ck, zk in zip(cones, cuts, duals):
                        self._cuts[cone.joint] = [d for d, zi in zip(ck, zk) if zi != 0.0]
        return failure(n, MAX_ITER, f"the cone cuts did not converge in {self.max_rounds} rounds",
                       iterations, rounds), {}


def _rows(qp: QPData, cones, rows):
    """Inequality rows: the cable bounds (identity) then, per cone, ``(d - t a)^T (g + G f) <= 0``
    for each direction ``d``. Returns C, l, u and the cone index owning each cut row."""
    n = qp.n
    blocks, rhs, owner = [np.eye(n)], [qp.ub], []
    for k, dirs in rows:
        if dirs:
            cone = cones[k]
            W = np.asarray(dirs) - cone.tan * cone.axis
            blocks.append(W @ cone.G)
            rhs.append(-(W @ cone.g))
            owner += [k] * len(dirs)
    C = np.vstack(blocks)
    l = np.concatenate([qp.lb, np.full(C.shape[0] - n, -np.inf)])
    return C, l, np.concatenate(rhs), np.array(owner, dtype=int)


def _cone_curvature(cone, x) -> np.ndarray:
    r"""Hessian in f of :math:`c(f) = \|F_\perp\| - t\,a^T F` at ``x``:
    :math:`G^T (P_\perp - \hat n\hat n^T) G / \|F_\perp\|` (positive semidefinite)."""
    F = cone.force(x)
    perp_vec = F - float(cone.axis @ F) * cone.axis
    perp = float(np.linalg.norm(perp_vec))
    if perp <= 1e-300:
        return np.zeros((len(x), len(x)))
    nhat = perp_vec / perp
    Pp = np.eye(3) - np.outer(cone.axis, cone.axis) - np.outer(nhat, nhat)
    return cone.G.T @ Pp @ cone.G / perp


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
