"""DAQP (dual active-set, dense; Arnström, Bemporad, Axehill 2022) as a peer: cases 1 and 2 (no cones).

``min 1/2 f^T P f + c^T f`` with the bounds as DAQP's simple bounds (the first ``m`` entries of
``bupper``/``blower``) and ``A f = b`` as rows flagged equality (``sense`` 5). DAQP's defaults
otherwise (primal tolerance 1e-6: 1e-9 made one instant of the neck's case 2 cycle, ``exitflag``
-2), but for the proximal regularisation: ``eps_prox`` 0 for a definite ``P`` (case 1), 1e-6 forced
for a singular one (case 2's interaction objective is positive semidefinite of low rank).

Cold (the first instant after ``reset()``): ``daqp.solve`` (empty working set; 25 % faster than
setting up a ``daqp.Model`` on the neck's case 2). Warm: from the second instant on, one
``daqp.Model``, set up from the previous answer (``primal_start``) and then given each instant through
``update``: the workspace (no new allocation) and its working set, the previous instant's active
constraints, carry over.
"""

from __future__ import annotations

import numpy as np

from .base import Peer, fail, finite_bounds

EQUALITY = 5
SETTINGS = dict()
PROX = 1e-6  # eps_prox for a singular P


class DaqpPeer(Peer):
    name = "daqp"
    label = "DAQP (dense active set)"
    warm = "one daqp.Model, data through update (working set kept)"

    def __init__(self):
        import daqp  # noqa: F401
        self.reset()

    def reset(self):
        self.model, self.shape, self.x_prev = None, None, None

    def solve(self, qp):
        import daqp

        n, me = qp.n, len(qp.b)
        lb, ub = finite_bounds(qp)
        data = dict(H=np.ascontiguousarray(qp.P), f=np.ascontiguousarray(qp.c), A=np.ascontiguousarray(qp.A),
                    bupper=np.concatenate([ub, qp.b]), blower=np.concatenate([lb, qp.b]))
        if self.shape != (n, me) or self.x_prev is None:  # cold
            self.model = None
            x, _, flag, _ = daqp.solve(sense=_sense(n, me), **data, **SETTINGS, **_prox(qp))
        elif self.model is None:  # the second instant: a workspace from the previous answer
            m = daqp.Model()
            m.settings = {**m.settings, **SETTINGS, **_prox(qp)}
            m.setup(sense=_sense(n, me), primal_start=self.x_prev, **data)
            self.model = m
            x, _, flag, _ = m.solve()
        else:
            self.model.update(**data)
            x, _, flag, _ = self.model.solve()
        self.shape = (n, me)
        if flag != 1:
            self.model, self.x_prev = None, None
            return fail(self, f"exitflag {flag}")
        self.x_prev = np.array(x)
        return self.x_prev.copy()


def _sense(n: int, me: int) -> np.ndarray:
    """DAQP's constraint flags: ``n`` bounds (inequalities, 0), then ``me`` equalities (5)."""
    sense = np.zeros(n + me, dtype=np.int32)
    sense[n:] = EQUALITY
    return sense


def _prox(qp) -> dict:
    """``eps_prox``: 0 for a definite ``P``, ``PROX`` (forced proximal iterations) for a singular one."""
    return {"eps_prox": 0.0 if _definite(qp) else PROX}


def _definite(qp) -> bool:
    """Whether ``P`` is positive definite beyond rounding: ``P = diag(P_diag) + F^T F`` with a positive
    diagonal, else its Cholesky pivots above 1e-10 of its largest diagonal entry (a numerically
    singular ``P`` can pass a plain Cholesky, and DAQP then stops with ``exitflag`` -5, not convex)."""
    if qp.structured and np.min(qp.P_diag) > 0.0:
        return True
    try:
        L = np.linalg.cholesky(qp.P)
    except np.linalg.LinAlgError:
        return False
    return bool((np.diag(L) ** 2).min() > 1e-10 * np.diag(qp.P).max())
