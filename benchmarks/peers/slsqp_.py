"""scipy's SLSQP as a peer (``bench_id.py --peers slsqp``): cones as nonlinear inequalities
``tan(rho) a.F - |F_perp| >= 0`` with exact Jacobians, started from the previous instant's solution
(``ftol = 1e-8``: absolute on the objective; tighter values make SLSQP stop with 'Positive directional
derivative' on the neck's case 3)."""

from __future__ import annotations

import warnings

import numpy as np

from mcdm_pin.solvers.clarabel_ import cone_rows

from .base import Peer


def _cone_values(T, t, f):
    """Cone constraint values ``s0 - |s12|`` (K,) and Jacobian (K, m); also s12 and |s12|."""
    s = T @ f + t  # (K, 3)
    nrm = np.linalg.norm(s[:, 1:], axis=1)
    u = s[:, 1:] / np.maximum(nrm, 1e-300)[:, None]
    jac = T[:, 0, :] - np.einsum("ka,kam->km", u, T[:, 1:, :])
    return s[:, 0] - nrm, jac, s[:, 1:], nrm


def _start(qp, f_prev):
    if f_prev is not None:
        return np.clip(f_prev, qp.lb, qp.ub)
    f0 = np.linalg.lstsq(qp.A, qp.b, rcond=None)[0] if len(qp.b) else np.zeros(qp.n)
    return np.clip(f0, qp.lb, qp.ub)


class SlsqpPeer(Peer):
    name = "slsqp"
    cones = True
    label = "scipy SLSQP (warm start)"

    def __init__(self):
        self.f_prev = None

    def reset(self):
        self.f_prev = None

    def solve(self, qp):
        from scipy.optimize import Bounds, minimize

        P, c = qp.P, qp.c
        cons = []
        if len(qp.b):
            A, b = qp.A, qp.b
            cons.append(dict(type="eq", fun=lambda f: A @ f - b, jac=lambda f: A))
        if qp.cones:
            T, t = cone_rows(qp)
            cons.append(dict(type="ineq", fun=lambda f: _cone_values(T, t, f)[0],
                             jac=lambda f: _cone_values(T, t, f)[1]))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = minimize(lambda f: (0.5 * f @ P @ f + c @ f, P @ f + c), _start(qp, self.f_prev),
                           jac=True, method="SLSQP", bounds=Bounds(qp.lb, qp.ub), constraints=cons,
                           options=dict(ftol=1e-8, maxiter=1000))
        if not res.success:
            self.message = res.message
            return None
        self.f_prev = res.x
        return np.array(res.x)
