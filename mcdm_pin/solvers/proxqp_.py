r"""ProxSuite's dense ProxQP, with the stability cones by cutting planes (stage ``proxqp``) and an SQP
polish once the cuts crowd (stage ``sqp_polish``).

A cone :math:`K = \{F : \|F_\perp\| \le t\, a^T F\}` (:math:`t = \tan\rho^*`) is convex, so for any unit
vector :math:`n \perp a` the half-space

.. math:: n^T F \le t\, a^T F \qquad (\text{since } n^T F \le \|F_\perp\|)

contains it: a valid *outer cut*, linear in :math:`x` because :math:`F = g + G x`.

1. **Cutting planes** (:class:`ProxQPStage`). Solve the QP with the cuts at hand; while some force
   :math:`F_k` lies outside its cone by more than ``cut_cone_deg`` (a setting), add the cut with
   :math:`n = F_{k,\perp}/\|F_{k,\perp}\|` (it separates :math:`F_k`) and re-solve, warm-started. Every
   relaxation contains the true feasible set, so its optimum is a lower bound, and a relaxation that
   is infeasible *proves* the instant infeasible. Cuts are only dropped when inactive, so the bounds
   increase monotonically. Cut directions that bind are kept for the next instant.
2. **SQP polish** (:class:`SQPPolish`). Near the optimum the new cuts become nearly parallel to the old
   ones, which makes the QP degenerate (ProxQP then stalls or misreports infeasibility) and Kelley's
   method converges only linearly. When a new cut is nearly parallel to an existing one, the cutting
   planes hand over their point and multipliers; SQP continues from there: one tangent row per
   active cone (the linearisation of :math:`c(F) = \|F_\perp\| - t\,a^T F`, itself a valid cut through
   the apex) and the cone's curvature :math:`\mu_k\,G^T (I - aa^T - \hat n\hat n^T) G/\|F_\perp\|`
   (positive semidefinite) added to the Hessian, centred at the current point. Its fixed point
   satisfies the KKT conditions of the convex problem, hence is the global optimum; convergence is
   quadratic (2-3 extra solves).

ProxQP's own infeasibility test is a heuristic; whenever ProxQP does not report SOLVED, HiGHS (scipy)
decides the relaxation's linear feasibility exactly, and a feasible relaxation is re-solved from
HiGHS's point with ProxQP's infeasibility test off.

Bounds are written as rows of ``C`` (not ProxQP's box), so that warm starts with ``(x, y, z)`` are
safe (see ``shared/PITFALLS.md``). The duals are returned in :mod:`.base`'s convention (a cut's
multiplier becomes the matching second-order-cone dual).
"""

from __future__ import annotations

import numpy as np
from proxsuite import proxqp

from ..qp import QPData
from ..settings import DEFAULT, Settings
from .base import BUDGET, INACCURATE, INFEASIBLE, MAX_ITER, OPTIMAL, Solution, Stage, failure, now

_STATUS = proxqp.QPSolverOutput


class ProxQPRunner:
    """One ProxQP solve of ``min 1/2 x^T H x + g^T x, A x = b, l <= C x <= u`` with the fallbacks of the
    module docstring. Args: ``settings``, the tolerances and iteration limits (``proxqp_*``);
    ``reuse``: keep the last ProxQP workspace and pass a problem of the same shape (variables,
    equations, rows of ``C``) to it through ProxQP's ``update``, the proximal parameters reset to
    their defaults, instead of allocating a new workspace per solve. The preconditioner (Ruiz
    scaling) is kept while ``C`` holds the bounds alone (its scaling barely moves between instants)
    and recomputed when cone cuts are among its rows (a stale one slowed the cutting planes
    tenfold, docs/speed.md)."""

    def __init__(self, settings: Settings = DEFAULT, reuse: bool = True):
        self.eps_abs, self.eps_rel = settings.proxqp_eps_abs, settings.proxqp_eps_rel
        self.max_iter, self.max_iter_retry = settings.proxqp_max_iter, settings.proxqp_max_iter_retry
        self.eps_infeasible = settings.proxqp_eps_infeasible
        self.reuse = reuse
        self.workspace = None  # (shape and settings, the ProxQP object) of the last solve
        self.created = 0  # ProxQP workspaces allocated (the others were updated)

    def __getstate__(self):
        # a copy (Cascade.fresh, a batch worker's solver) starts without the ProxQP workspace, which
        # is native memory and holds nothing but the last problem
        return {**self.__dict__, "workspace": None}

    def _workspace(self, H, g, A, b, C, l, u, eps_infeasible, max_iter):
        """A ProxQP object holding this problem: the last one updated when its shape and settings
        match (``reuse``), else a new one."""
        key = (H.shape[0], A.shape[0], C.shape[0], eps_infeasible)
        if self.reuse and self.workspace is not None and self.workspace[0] == key:
            qp = self.workspace[1]
            s = qp.settings
            s.max_iter, s.max_iter_in = max_iter, self._max_iter_in  # (_solve_until changes both)
            qp.update(H, g, A, b, C, l, u, update_preconditioner=C.shape[0] > H.shape[0], rho=s.default_rho,
                      mu_eq=s.default_mu_eq, mu_in=s.default_mu_in)
            return qp
        qp = self._new_qp(H, g, A, b, C, l, u, eps_infeasible, max_iter)
        self.created += 1
        self._max_iter_in = qp.settings.max_iter_in
        if self.reuse:
            self.workspace = (key, qp)
        return qp

    def _new_qp(self, H, g, A, b, C, l, u, eps_infeasible, max_iter):
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

    def solve(self, H, g, A, b, C, l, u, warm=None, deadline: float = float("inf")):
        """Returns ``(x, y, z, status, iterations)``; ``status`` ``None``: proven infeasible (HiGHS);
        :data:`OUT_OF_TIME`: ``deadline`` (:func:`~.base.now`) passed inside the solve."""
        qp = self._workspace(H, g, A, b, C, l, u, self.eps_infeasible, self.max_iter)
        n = H.shape[0]
        start = None
        if warm is not None and warm[0].shape == (n,) and warm[1].shape == (A.shape[0],):
            z = warm[2]
            if z.shape != (C.shape[0],):  # cut rows changed: keep the bounds' multipliers only
                z0 = np.zeros(C.shape[0])
                z0[:n] = z[:n] if z.shape[0] >= n else 0.0
                z = z0
            start = (warm[0], warm[1], z)
        status, iterations = _solve_until(qp, start, self.max_iter, deadline)
        if status == _STATUS.PROXQP_MAX_ITER_REACHED and now() > deadline:
            return None, None, None, OUT_OF_TIME, iterations
        if status != _STATUS.PROXQP_SOLVED:
            x0 = feasible_point(A, b, C, l, u)
            if x0 is None:
                return None, None, None, None, iterations
            qp = self._workspace(H, g, A, b, C, l, u, 0.0, self.max_iter_retry)
            start = (x0, np.zeros(A.shape[0]), np.zeros(C.shape[0]))
            status, it = _solve_until(qp, start, self.max_iter_retry, deadline)
            iterations += it
            if status == _STATUS.PROXQP_MAX_ITER_REACHED and now() > deadline:
                return None, None, None, OUT_OF_TIME, iterations
        res = qp.results
        return res.x.copy(), res.y.copy(), res.z.copy(), res.info.status, iterations


OUT_OF_TIME = "out of time"  # ProxQPRunner.solve's status when the deadline passed inside a solve
SLICE_OUTER = 25  # outer ProxQP iterations between two looks at the clock (seen: at most 19 per solve)
SLICE_INNER = 100  # inner iterations per outer one under a deadline (ProxQP: 1500; seen: at most 3)


def _solve_until(qp, start, max_iter: int, deadline: float):
    """``qp.solve`` in slices of :data:`SLICE_OUTER` outer iterations, each continuing from the last
    (x, y, z), until solved, ``max_iter`` outer iterations in all, or ``deadline``: ProxQP has no
    time limit of its own, and bounds of 1e-300..1e-290 N took 1.5 million inner iterations (58 s)
    in one call. A slice costs at most ``SLICE_OUTER * SLICE_INNER`` inner iterations (~0.1 s at
    n = 8). Without a deadline: one call, as ProxQP runs it. Returns (status, inner iterations)."""
    s = qp.settings
    if not np.isfinite(deadline):
        qp.solve(*start) if start is not None else qp.solve()
        return qp.results.info.status, int(qp.results.info.iter)
    s.max_iter_in = min(int(s.max_iter_in), SLICE_INNER)
    outer = iterations = 0
    while True:
        s.max_iter = min(SLICE_OUTER, max_iter - outer)
        qp.solve(*start) if start is not None else qp.solve()
        info = qp.results.info
        outer += max(int(info.iter_ext), 1)
        iterations += int(info.iter)
        if info.status != _STATUS.PROXQP_MAX_ITER_REACHED or outer >= max_iter or now() > deadline:
            return info.status, iterations
        res = qp.results
        start = (res.x.copy(), res.y.copy(), res.z.copy())


def _cone_dual(cone, dirs, mults) -> np.ndarray:
    """The second-order-cone dual of cut multipliers ``mults`` on cut directions ``dirs``:
    ``(sum z_j, -sum z_j d_j.e1, -sum z_j d_j.e2) / cos(rho)``."""
    out = np.zeros(3)
    cosr = np.cos(np.radians(cone.angle_deg))
    for d, zj in zip(dirs, mults):
        out += zj * np.array([1.0, -d @ cone.basis[0], -d @ cone.basis[1]])
    return out / cosr


def _duals(qp, y, z, owner, dirs_per_cone):
    """(y, z_box, z_cone) of a ProxQP answer on rows [bounds; cuts of each cone in order]."""
    n = qp.n
    zc = z[n:]
    z_cone = np.zeros((len(qp.cones), 3))
    for k, cone in enumerate(qp.cones):
        z_cone[k] = _cone_dual(cone, dirs_per_cone[k], np.maximum(zc[owner == k], 0.0))
    return y, z[:n].copy(), z_cone


class ProxQPStage(Stage):
    """Answering stage: ProxQP with the cones by cutting planes (module docstring).

    Args:
        cuts_per_cone: cuts kept per cone; beyond it, cuts with zero multiplier are dropped.
        max_rounds: largest number of QP solves per instant (cut rounds + 1).
        warm_start: start from the previous instant's answer.
        keep_cuts: keep the binding cut directions from one instant to the next.
        settings: the tolerances (``proxqp_*``, ``cut_cone_deg``, ``same_cut_cos``).
        reuse: :class:`ProxQPRunner`'s.
    """

    name = "proxqp"

    def __init__(self, settings: Settings = DEFAULT, cuts_per_cone: int = 24, max_rounds: int = 200,
                 warm_start: bool = True, keep_cuts: bool = True, reuse: bool = True):
        self.settings = settings
        self.runner = ProxQPRunner(settings, reuse)
        self.cuts_per_cone, self.max_rounds = cuts_per_cone, max_rounds
        self.warm_start, self.keep_cuts = warm_start, keep_cuts
        self.reset()

    def reset(self):
        self._warm = None
        self._cuts: dict[str, list[np.ndarray]] = {}
        self.runner.workspace = None  # a reset chain answers as a new one

    def learn(self, qp, sol):
        # the previous forces as the starting point but not the previous multipliers: next to a
        # singular instant (2-link arm, q = 0 at t = 0.5 s) they are huge and sent ProxQP into
        # ~1e6 inner iterations (4 s) or a false "infeasible". Kept as they are (an optimal answer's
        # forces are finite): copied by the solve that uses them (most instants have none)
        if self.warm_start:
            self._warm = sol.x

    def seed(self, hint):
        if np.isfinite(hint.x).all():
            self._warm = hint.x

    def _start(self, qp):
        """The warm start ``(x, y, z)`` for ``qp`` (``None``: none)."""
        x = self._warm if self.warm_start else None
        if x is None or not np.all(np.isfinite(x)):
            return None
        return x.copy(), np.zeros(len(qp.b)), np.zeros(len(x))

    def run(self, qp, sol, deadline):
        n, cones = qp.n, qp.cones
        if not self.keep_cuts:
            self._cuts = {}
        cuts = [list(self._cuts.get(c.joint, [])) for c in cones]
        warm = self._start(qp)
        iterations = 0
        for rounds in range(1, self.max_rounds + 1):
            if rounds > 1 and now() > deadline:
                return failure(n, BUDGET, f"ProxQP cutting planes: budget exhausted after {rounds - 1} "
                                          f"rounds", iterations, rounds - 1, self.name)
            C, l, u, owner = cut_rows(qp, list(enumerate(cuts)))
            x, y, z, status, it = self.runner.solve(qp.P, qp.c, qp.A, qp.b, C, l, u, warm, deadline)
            iterations += it
            if status is OUT_OF_TIME:
                return failure(n, BUDGET, f"ProxQP: budget exhausted inside round {rounds}", iterations,
                               rounds, self.name)
            if status is None:
                what = "the cones' outer approximation" if cones else "the bounds"
                return failure(n, INFEASIBLE, f"no point satisfies the equation of motion and {what} "
                                              f"(decided by HiGHS)", iterations, rounds, self.name)
            if status == _STATUS.PROXQP_MAX_ITER_REACHED:
                return failure(n, MAX_ITER, "ProxQP reached its iteration limit", iterations, rounds, self.name)
            if status != _STATUS.PROXQP_SOLVED:
                return failure(n, INACCURATE, f"ProxQP: {status.name}", iterations, rounds, self.name)
            warm = (x, y, z)
            zc = z[n:]
            violated = [(k, d) for k, d in ((k, _violation(cone, x, self.settings.cut_cone_deg)) for k, cone in enumerate(cones))
                        if d is not None]
            duals = [zc[owner == k] for k in range(len(cones))]
            ys, zb, z_cone = _duals(qp, y, z, owner, cuts)
            if not violated:
                if self.keep_cuts:  # the binding cuts (non-zero multiplier) start the next instant
                    for cone, ck, zk in zip(cones, cuts, duals):
                        self._cuts[cone.joint] = [d for d, zi in zip(ck, zk) if zi != 0.0]
                return Solution(x, OPTIMAL, qp.objective(x), y=ys, z=zb, z_cone=z_cone,
                                iterations=iterations, rounds=rounds, stage=self.name)
            crowded = False
            for k, d in violated:
                if _parallel_cuts(cones[k], cuts[k], d, self.settings.same_cut_cos):
                    crowded = True
                if len(cuts[k]) >= self.cuts_per_cone:
                    # drop inactive cuts only: the relaxation never loosens where it binds, so the
                    # optimal values of successive relaxations increase and cannot cycle
                    cuts[k] = [c for c, zi in zip(cuts[k], duals[k]) if zi != 0.0]
                cuts[k].append(d)
            if crowded:
                if self.keep_cuts:
                    for cone, ck, zk in zip(cones, cuts, duals):
                        self._cuts[cone.joint] = [d for d, zi in zip(ck[:len(zk)], zk) if zi != 0.0]
                # hand over to the SQP polish: the point, and which cones bind (violated or with a
                # positive multiplier) with their multipliers
                return Solution(x, INACCURATE, qp.objective(x), y=ys, z=zb, z_cone=z_cone,
                                iterations=iterations, rounds=rounds, stage=self.name,
                                message=SQP_HANDOVER)
        return failure(n, MAX_ITER, f"the cone cuts did not converge in {self.max_rounds} rounds",
                       iterations, self.max_rounds, self.name)


SQP_HANDOVER = "cone cuts crowd: SQP polish takes over"


class SQPPolish(Stage):
    """Answering stage after :class:`ProxQPStage`'s hand-over: sequential quadratic programming from
    the cutting planes' point (module docstring). ProxQP solves each subproblem (``settings``: the
    tolerances, ``proxqp_*``, ``cut_cone_deg``, ``sqp_step``; ``reuse``: :class:`ProxQPRunner`'s)."""

    name = "sqp_polish"

    def __init__(self, settings: Settings = DEFAULT, max_rounds: int = 50, reuse: bool = True):
        self.settings = settings
        self.runner = ProxQPRunner(settings, reuse)
        self.max_rounds = max_rounds

    def applies(self, sol):
        return sol is not None and sol.message == SQP_HANDOVER and np.all(np.isfinite(sol.x))

    def run(self, qp, sol, deadline):
        n, cones = qp.n, qp.cones
        x_prev = sol.x
        cosr = np.cos(np.radians([c.angle_deg for c in cones]))
        mult = sol.z_cone[:, 0] * cosr
        dirs: list = [None] * len(cones)
        for k, cone in enumerate(cones):
            d = _perp_dir(cone, x_prev)
            if d is not None and (mult[k] > 0 or _violation(cone, x_prev, self.settings.cut_cone_deg) is not None):
                dirs[k] = d
        iterations, warm = sol.iterations, None
        obj_prev = np.inf
        for rounds in range(1, self.max_rounds + 1):
            if now() > deadline:
                return failure(n, BUDGET, "SQP polish: budget exhausted", iterations, sol.rounds + rounds - 1,
                               self.name)
            # the objective plus, per cone, its curvature weighted by its multiplier, centred at the
            # current point: 1/2 (x - x_prev)^T (mu_k D_k) (x - x_prev)
            Hk, gk = qp.P.copy(), qp.c.copy()
            for k, cone in enumerate(cones):
                if dirs[k] is not None and mult[k] > 0:
                    D = mult[k] * _cone_curvature(cone, x_prev)
                    Hk += D
                    gk -= D @ x_prev
            rows = [(k, [dirs[k]] if dirs[k] is not None else []) for k in range(len(cones))]
            C, l, u, owner = cut_rows(qp, rows)
            x, y, z, status, it = self.runner.solve(Hk, gk, qp.A, qp.b, C, l, u, warm, deadline)
            iterations += it
            if status is OUT_OF_TIME:
                return failure(n, BUDGET, "SQP polish: budget exhausted inside a subproblem", iterations,
                               sol.rounds + rounds, self.name)
            if status != _STATUS.PROXQP_SOLVED:
                return failure(n, INACCURATE, "SQP polish: a subproblem failed", iterations,
                               sol.rounds + rounds, self.name)
            warm = (x, y, z)
            zc = z[n:]
            violated = [k for k, cone in enumerate(cones) if _violation(cone, x, self.settings.cut_cone_deg) is not None]
            step = np.linalg.norm(x - x_prev) / (1.0 + np.linalg.norm(x))
            obj = qp.objective(x)
            # where the optimum is not unique (a positive semidefinite objective) the iterates may
            # slide along the optimal face: a settled objective ends the loop too (the polish and
            # least-norm stages then pick the face's point, the check stage verifies it)
            settled = rounds > 1 and abs(obj - obj_prev) <= self.settings.sqp_step * max(abs(obj), 1e-12)
            obj_prev = obj
            x_prev = x
            for k, cone in enumerate(cones):
                m = float(zc[owner == k].sum())
                d = _perp_dir(cone, x)
                if (dirs[k] is not None or k in violated) and d is not None:
                    dirs[k], mult[k] = d, m
            if not violated and (step <= self.settings.sqp_step or settled):
                ys, zb, z_cone = _duals(qp, y, z, owner, [[dirs[k]] if dirs[k] is not None else []
                                                           for k in range(len(cones))])
                return Solution(x, OPTIMAL, qp.objective(x), y=ys, z=zb, z_cone=z_cone, iterations=iterations,
                                rounds=sol.rounds + rounds, stage=self.name)
        return failure(n, MAX_ITER, "SQP polish did not converge", iterations, sol.rounds + self.max_rounds,
                       self.name)


def _perp_dir(cone, x):
    F = cone.force(x)
    perp_vec = F - float(cone.axis @ F) * cone.axis
    perp = float(np.linalg.norm(perp_vec))
    return perp_vec / perp if perp > 1e-300 else None


def _violation(cone, x, cut_cone_deg: float):
    """The separating cut direction if the cone is broken by more than ``cut_cone_deg``, else None."""
    F = cone.force(x)
    along = float(cone.axis @ F)
    perp_vec = F - along * cone.axis
    perp = float(np.linalg.norm(perp_vec))
    if np.degrees(np.arctan2(perp, along)) > cone.angle_deg + cut_cone_deg:
        return perp_vec / perp if perp > 1e-300 else cone.basis[0]
    return None


def cut_rows(qp: QPData, rows):
    """Inequality rows: the bounds (identity) then, per cone, ``(d - t a)^T (g + G x) <= 0`` for each
    direction ``d``. Returns C, l, u and the cone index owning each cut row."""
    n = qp.n
    blocks, rhs, owner = [np.eye(n)], [qp.ub], []
    for k, dirs in rows:
        if dirs:
            cone = qp.cones[k]
            W = np.asarray(dirs) - cone.tan * cone.axis
            blocks.append(W @ cone.G)
            rhs.append(-(W @ cone.g))
            owner += [k] * len(dirs)
    C = np.vstack(blocks)
    l = np.concatenate([qp.lb, np.full(C.shape[0] - n, -np.inf)])
    return C, l, np.concatenate(rhs), np.array(owner, dtype=int)


def _cone_curvature(cone, x) -> np.ndarray:
    r"""Hessian in x of :math:`c(x) = \|F_\perp\| - t\,a^T F` at ``x``:
    :math:`G^T (P_\perp - \hat n\hat n^T) G / \|F_\perp\|` (positive semidefinite)."""
    F = cone.force(x)
    perp_vec = F - float(cone.axis @ F) * cone.axis
    perp = float(np.linalg.norm(perp_vec))
    if perp <= 1e-300:
        return np.zeros((len(x), len(x)))
    nhat = perp_vec / perp
    Pp = np.eye(3) - np.outer(cone.axis, cone.axis) - np.outer(nhat, nhat)
    return cone.G.T @ Pp @ cone.G / perp


def feasible_point(A, b, C, l, u):
    """A point of ``{A x = b, l <= C x <= u}`` found by HiGHS (scipy), or ``None`` if it is empty."""
    from scipy.optimize import linprog

    n = C.shape[1]
    rows_u, rows_l = np.isfinite(u), np.isfinite(l)
    box = np.zeros(len(u), dtype=bool)
    box[:n] = True  # the first n rows of C are the identity: the bounds
    A_ub = np.vstack([C[rows_u & ~box], -C[rows_l & ~box]])
    b_ub = np.concatenate([u[rows_u & ~box], -l[rows_l & ~box]])
    bounds = list(zip(np.where(np.isfinite(l[:n]), l[:n], None), np.where(np.isfinite(u[:n]), u[:n], None)))
    res = linprog(np.zeros(n), A_ub=A_ub if len(b_ub) else None, b_ub=b_ub if len(b_ub) else None,
                  A_eq=A if len(b) else None, b_eq=b if len(b) else None, bounds=bounds, method="highs")
    return res.x if res.status == 0 else None


def _parallel_cuts(cone, cuts, d, same_cut_cos: float) -> list[int]:
    """Indices of existing cuts whose rows in x are nearly parallel to the new cut's."""
    if not cuts:
        return []
    t = cone.tan
    W = (np.asarray(cuts) - t * cone.axis) @ cone.G
    w = (d - t * cone.axis) @ cone.G
    cos = W @ w / (np.linalg.norm(W, axis=1) * np.linalg.norm(w) + 1e-300)
    return [int(i) for i in np.flatnonzero(cos > same_cut_cos)]
