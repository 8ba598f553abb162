"""ProxSuite's dense ProxQP (proximal augmented Lagrangian; Bambade et al. 2022) as a peer: cases 1, 2.

``proxqp.dense.QP(n, n_eq, 0, box_constraints=True)``: the bounds as ProxQP's box, the equation of
motion as its equalities; ``eps_abs`` 1e-8 (the default 1e-5 leaves bounds 5e-4 short: PITFALLS.md;
1e-9 ran into the 10,000-iteration limit on 2 of 6 instants of the 96-DoF chain of ``scaling.py``),
``eps_rel`` 0, the duality gap checked too (residuals alone do not bound the objective's error).

Warm: one QP object per run, each instant passed through ``update`` and solved from the previous
result (``initial_guess = WARM_START_WITH_PREVIOUS_RESULT``, set before ``init``: after it, it
segfaults); cold: a new QP per instant (``NO_INITIAL_GUESS``). ``results.x`` is a live view: copied.
"""

from __future__ import annotations

import numpy as np

from .base import Peer, fail

EPS = 1e-8


class ProxqpPeer(Peer):
    name = "proxqp"
    label = "ProxQP (dense, box)"
    warm = "one QP, data through update, previous result as start"

    def __init__(self):
        from proxsuite import proxqp  # noqa: F401
        self.qp, self.shape = None, None

    def reset(self):
        self.qp, self.shape = None, None

    def _new(self, qp, warm: bool):
        from proxsuite import proxqp

        q = proxqp.dense.QP(qp.n, len(qp.b), 0, box_constraints=True)
        s = q.settings
        s.eps_abs, s.eps_rel, s.verbose = EPS, 0.0, False
        s.check_duality_gap = True
        s.eps_duality_gap_abs, s.eps_duality_gap_rel = EPS, 0.0
        s.initial_guess = (proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT if warm
                           else proxqp.InitialGuess.NO_INITIAL_GUESS)
        q.init(qp.P, qp.c, qp.A, qp.b, None, None, None, l_box=qp.lb, u_box=qp.ub)
        return q

    def solve(self, qp):
        from proxsuite import proxqp

        shape = (qp.n, len(qp.b))
        if self.qp is None or self.shape != shape:
            self.qp, self.shape = self._new(qp, warm=True), shape
        else:
            self.qp.update(qp.P, qp.c, qp.A, qp.b, None, None, None, l_box=qp.lb, u_box=qp.ub)
        self.qp.solve()
        res = self.qp.results
        if res.info.status != proxqp.QPSolverOutput.PROXQP_SOLVED:
            return fail(self, str(res.info.status))
        return res.x.copy()
