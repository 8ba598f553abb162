"""cvxpy with Clarabel as a peer (``bench_id.py --peers cvxpy``): a Parameter-ised (DPP) problem built
and compiled once per case, outside the timing; per instant the parameters are set (inside the timing,
including the factor ``K`` of ``P = K^T K`` by pivoted Cholesky, since ``quad_form`` of a parameter
is not DPP) and the problem is re-solved."""

from __future__ import annotations

import warnings

import numpy as np

from mcdm_pin.solvers.clarabel_ import cone_rows

from .base import Peer


class CvxpyPeer(Peer):
    name = "cvxpy"
    cones = True
    label = "cvxpy + Clarabel (DPP, built once)"

    def __init__(self):
        import cvxpy  # noqa: F401
        self.prob = None

    def prepare(self, qp):
        import cvxpy as cp

        n, me, k = qp.n, len(qp.b), len(qp.cones)
        self.hi, self.lo = np.isfinite(qp.ub), np.isfinite(qp.lb)
        f = self.f = cp.Variable(n)
        self.K, self.c = cp.Parameter((n, n)), cp.Parameter(n)
        cons = []
        if me:
            self.A, self.b = cp.Parameter((me, n)), cp.Parameter(me)
            cons.append(self.A @ f == self.b)
        if self.hi.any():
            self.ub = cp.Parameter(int(self.hi.sum()))
            cons.append(f[np.flatnonzero(self.hi)] <= self.ub)
        if self.lo.any():
            self.lb = cp.Parameter(int(self.lo.sum()))
            cons.append(f[np.flatnonzero(self.lo)] >= self.lb)
        self.T = [cp.Parameter((3, n)) for _ in range(k)]
        self.t = [cp.Parameter(3) for _ in range(k)]
        for T, t in zip(self.T, self.t):
            s = T @ f + t
            cons.append(cp.SOC(s[0], s[1:]))
        self.prob = cp.Problem(cp.Minimize(0.5 * cp.sum_squares(self.K @ f) + self.c @ f), cons)
        assert self.prob.is_dcp(dpp=True)
        self._set(qp)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            self.prob.solve(solver=cp.CLARABEL)  # compile once (cached for the re-solves)

    def _set(self, qp):
        from scipy.linalg import lapack

        # P = K^T K by pivoted Cholesky (P is PSD, possibly singular)
        U, piv, rank, info = lapack.dpstrf(qp.P, lower=0)
        U = np.triu(U)
        U[rank:] = 0.0
        K = np.empty_like(U)
        K[:, piv - 1] = U
        self.K.value, self.c.value = K, qp.c
        if len(qp.b):
            self.A.value, self.b.value = qp.A, qp.b
        if self.hi.any():
            self.ub.value = qp.ub[self.hi]
        if self.lo.any():
            self.lb.value = qp.lb[self.lo]
        if qp.cones:
            T, t = cone_rows(qp)
            for k in range(len(qp.cones)):
                self.T[k].value, self.t[k].value = T[k], t[k]

    def solve(self, qp):
        import cvxpy as cp

        self._set(qp)
        try:
            self.prob.solve(solver=cp.CLARABEL)
        except cp.error.SolverError:
            return None
        if self.prob.status in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE):
            return np.array(self.f.value)
        return None
