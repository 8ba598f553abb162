r"""Clarabel's interior-point method on the exact second-order-cone program (stage ``clarabel``): the
reference back-end, and the last resort of the default chain.

Each cone :math:`\|F_\perp\| \le \tan\rho^*\, a^T F` is the cone
:math:`(\sin\rho^*\,a^T F,\; \cos\rho^*\,e_1^T F,\; \cos\rho^*\,e_2^T F) \in \mathcal{Q}^3`
(:meth:`~mcdm_pin.qp.QPData.cone_rows`: rows of norm at most one for any half-angle; with
``tan`` in the first row a cone of 89.99 degrees had rows 5730 times larger than the others).
Clarabel's duals are returned in :mod:`.base`'s convention.
"""

from __future__ import annotations

import numpy as np

from ..exceptions import SolverError
from ..qp import QPData
from ..settings import DEFAULT, Settings
from .base import BUDGET, INACCURATE, INFEASIBLE, MAX_ITER, OPTIMAL, Solution, Stage, failure, now


def cone_rows(qp: QPData) -> tuple[np.ndarray, np.ndarray]:
    """:meth:`QPData.cone_rows` (kept for the benchmark's peers)."""
    return qp.cone_rows()


def conic_form(qp: QPData):
    """``(P, c, A, b, cones, layout)`` of Clarabel's ``min 1/2 x^T P x + c^T x, b - A x in cones``:
    the equations (zero cone), the finite bounds (non-negative cone: upper rows then lower rows),
    one second-order cone of dimension 3 per stability cone. ``P`` is the upper triangle, sparse;
    ``layout`` = (k_eq, upper indices, lower indices) to read the duals back."""
    import clarabel
    from scipy import sparse

    n = qp.n
    blocks, rhs, cones = [], [], []
    rows = independent_rows(qp.A, qp.b)
    if len(rows):
        blocks.append(qp.A[rows])
        rhs.append(qp.b[rows])
        cones.append(clarabel.ZeroConeT(len(rows)))
    hi, lo = np.flatnonzero(np.isfinite(qp.ub)), np.flatnonzero(np.isfinite(qp.lb))
    if len(hi) or len(lo):
        eye = np.eye(n)
        blocks += [eye[hi], -eye[lo]]
        rhs += [qp.ub[hi], -qp.lb[lo]]
        cones.append(clarabel.NonnegativeConeT(int(len(hi) + len(lo))))
    if qp.cones:
        T, t = qp.cone_rows()
        blocks.append(-T.reshape(-1, n))
        rhs.append(t.reshape(-1))
        cones += [clarabel.SecondOrderConeT(3)] * len(qp.cones)
    A = sparse.csc_matrix(np.vstack(blocks)) if blocks else sparse.csc_matrix((0, n))
    b = np.concatenate(rhs) if rhs else np.zeros(0)
    return sparse.csc_matrix(np.triu(qp.P)), qp.c, A, b, cones, (rows, hi, lo)


def independent_rows(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Indices of a maximal set of independent, consistent equations of ``A x = b`` (all of them when
    ``A`` has full row rank, or when the dependent ones contradict the others: then the problem is
    infeasible and Clarabel shall say so). Where the equation of motion loses rank (the 2-link arm at
    rest at q = 0: rank 3 of 4) the dependent row made Clarabel stop with ``InsufficientProgress``."""
    m = A.shape[0]
    if m == 0:
        return np.arange(0)
    from scipy.linalg import qr

    _, R, piv = qr(A.T, mode="economic", pivoting=True)
    d = np.abs(np.diag(R))
    rank = int((d > 1e-12 * max(float(d.max(initial=0.0)), 1e-300)).sum())
    if rank == m:
        return np.arange(m)
    keep = np.sort(piv[:rank])
    x = np.linalg.lstsq(A[keep], b[keep], rcond=None)[0]
    scale = max(float(np.abs(b).max(initial=0.0)), float((np.abs(A) @ np.abs(x)).max(initial=0.0)), 1e-300)
    if np.abs(A @ x - b).max(initial=0.0) > 1e-9 * scale:
        return np.arange(m)
    return keep


def clarabel_solve(qp: QPData, settings: Settings = DEFAULT, time_limit: float | None = None) -> Solution:
    """Solve ``qp`` with Clarabel (tolerances and iteration limit: ``settings``' ``clarabel_*``); the
    answer with its duals."""
    import clarabel

    n = qp.n
    P, c, A, b, cones, (rows, hi, lo) = conic_form(qp)
    neq = len(rows)
    opts = clarabel.DefaultSettings()
    opts.verbose = False
    opts.max_iter = settings.clarabel_max_iter
    opts.tol_gap_abs = opts.tol_gap_rel = settings.clarabel_tol
    opts.tol_feas = settings.clarabel_tol
    opts.tol_ktratio = settings.clarabel_ktratio
    if time_limit is not None and np.isfinite(time_limit):
        opts.time_limit = max(float(time_limit), 1e-3)
    sol = clarabel.DefaultSolver(P, c, A, b, cones, opts).solve()
    status = str(sol.status)
    it = int(sol.iterations)
    if status in ("Solved", "AlmostSolved"):
        x = np.array(sol.x)
        zz = np.array(sol.z)
        y = np.zeros(len(qp.b))  # a dropped (dependent) equation's multiplier is zero
        y[rows] = zz[:neq]
        z = np.zeros(n)
        z[hi] += zz[neq:neq + len(hi)]
        z[lo] -= zz[neq + len(hi):neq + len(hi) + len(lo)]
        z_cone = zz[neq + len(hi) + len(lo):].reshape(len(qp.cones), 3)
        # reduced accuracy is returned as a candidate: the check stage flags it if it fails the KKT test
        note = "" if status == "Solved" else "Clarabel: solved to reduced accuracy (AlmostSolved)"
        return Solution(x, OPTIMAL, qp.objective(x), y=y, z=z, z_cone=z_cone, iterations=it, message=note,
                        stage="clarabel")
    if status in ("PrimalInfeasible", "AlmostPrimalInfeasible"):
        return failure(n, INFEASIBLE, f"no point satisfies the constraints (Clarabel: {status})", it,
                       stage="clarabel")
    if status == "MaxIterations":
        return failure(n, MAX_ITER, "Clarabel reached its iteration limit", it, stage="clarabel")
    if status == "MaxTime":
        return failure(n, BUDGET, "Clarabel: budget exhausted", it, stage="clarabel")
    return failure(n, INACCURATE, f"Clarabel: {status}", it, stage="clarabel")


class ClarabelStage(Stage):
    """Answering stage: :func:`clarabel_solve` (``settings`` as there)."""

    name = "clarabel"

    def __init__(self, settings: Settings = DEFAULT):
        try:
            import clarabel  # noqa: F401
        except ImportError:
            raise SolverError("the clarabel back-end needs the clarabel package (a dependency of "
                              "mcdm-pin): pip install clarabel") from None
        self.settings = settings

    def run(self, qp, sol, deadline):
        out = clarabel_solve(qp, self.settings, deadline - now())
        if sol is not None and not out.final and sol.message:
            out = out.but(message=f"{sol.message}; {out.message}")
        elif sol is not None and out.status == OPTIMAL and sol.stage and sol.stage != self.name:
            out = out.but(message=f"{sol.stage} failed ({sol.message}); answered by Clarabel")
        return out
