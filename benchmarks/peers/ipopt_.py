"""IPOPT through cyipopt as a peer (``bench_id.py --peers ipopt``): exact Hessian, tolerance 1e-10,
MUMPS, the same cone form as SLSQP's, started from the previous instant's solution. Needs ``apt-get
install -y coinor-libipopt-dev libblas-dev liblapack-dev pkg-config`` and ``pip install cyipopt``."""

from __future__ import annotations

import numpy as np

from mcdm_pin.solvers.clarabel_ import cone_rows

from .base import Peer
from .slsqp_ import _cone_values, _start


class _IpoptNLP:
    def __init__(self, qp, T, t):
        self.qp, self.T, self.t = qp, T, t
        n, me, k = qp.n, len(qp.b), len(qp.cones)
        self.me, self.k = me, k
        self.jrows, self.jcols = np.indices((me + k, n)).reshape(2, -1)
        self.hrows, self.hcols = np.tril_indices(n)

    def objective(self, f):
        return float(0.5 * f @ self.qp.P @ f + self.qp.c @ f)

    def gradient(self, f):
        return self.qp.P @ f + self.qp.c

    def constraints(self, f):
        parts = [self.qp.A @ f]
        if self.k:
            parts.append(_cone_values(self.T, self.t, f)[0])
        return np.concatenate(parts)

    def jacobianstructure(self):
        return self.jrows, self.jcols

    def jacobian(self, f):
        parts = [self.qp.A]
        if self.k:
            parts.append(_cone_values(self.T, self.t, f)[1])
        return np.vstack(parts).ravel()

    def hessianstructure(self):
        return self.hrows, self.hcols

    def hessian(self, f, lam, obj_factor):
        H = obj_factor * self.qp.P
        if self.k:
            # d^2 (-|s12|) = -T12^T (I - u u^T) T12 / |s12|
            _, _, s12, nrm = _cone_values(self.T, self.t, f)
            for j in range(self.k):
                if nrm[j] > 1e-12:
                    u = s12[j] / nrm[j]
                    T12 = self.T[j, 1:, :]
                    Tu = u @ T12
                    H = H - lam[self.me + j] * (T12.T @ T12 - np.outer(Tu, Tu)) / nrm[j]
        return H[self.hrows, self.hcols]


class IpoptPeer(Peer):
    name = "ipopt"
    cones = True
    label = "IPOPT via cyipopt (warm start)"

    def __init__(self):
        import cyipopt  # noqa: F401
        self.f_prev = None

    def reset(self):
        self.f_prev = None

    def solve(self, qp):
        import cyipopt

        T, t = cone_rows(qp)
        me, k = len(qp.b), len(qp.cones)
        cl = np.concatenate([qp.b, np.zeros(k)])
        cu = np.concatenate([qp.b, np.full(k, 2e19)])
        lb = np.where(np.isfinite(qp.lb), qp.lb, -2e19)
        ub = np.where(np.isfinite(qp.ub), qp.ub, 2e19)
        nlp = cyipopt.Problem(n=qp.n, m=me + k, problem_obj=_IpoptNLP(qp, T, t), lb=lb, ub=ub, cl=cl, cu=cu)
        nlp.add_option("print_level", 0)
        nlp.add_option("sb", "yes")
        nlp.add_option("tol", 1e-10)
        nlp.add_option("max_iter", 500)
        x, info = nlp.solve(_start(qp, self.f_prev))
        if info["status"] not in (0, 1):  # solved, solved to acceptable level
            self.message = info["status_msg"]
            return None
        self.f_prev = x
        return np.array(x)
