"""PIQP (proximal interior point, dense; Schwan, Jiang, Kuhn, Jones 2023) as a peer: cases 1 and 2.

``DenseSolver.setup(P, c, A, b, x_l=lb, x_u=ub)``: the bounds as PIQP's box, the equation of motion
as its equalities; tolerances 1e-9 (absolute and relative, PIQP's are 1e-8 / 1e-9).

Warm: PIQP has no warm start of its iterate (an interior-point method); the warm run keeps one solver
and passes each instant through ``update`` (no new allocation, the preconditioner reused); cold builds
a new solver per instant.
"""

from __future__ import annotations

import numpy as np

from .base import Peer, fail

EPS = 1e-9


class PiqpPeer(Peer):
    name = "piqp"
    label = "PIQP (dense interior point)"
    warm = "one solver, data through update (no iterate warm start)"

    def __init__(self):
        import piqp  # noqa: F401
        self.solver, self.shape = None, None

    def reset(self):
        self.solver, self.shape = None, None

    def solve(self, qp):
        import piqp

        P, A = np.asfortranarray(qp.P), np.asfortranarray(qp.A)
        shape = (qp.n, len(qp.b))
        if self.solver is None or self.shape != shape:
            s = piqp.DenseSolver()
            s.settings.verbose = False
            s.settings.eps_abs = s.settings.eps_rel = EPS
            s.setup(P, qp.c, A, qp.b, None, None, None, qp.lb, qp.ub)
            self.solver, self.shape = s, shape
        else:
            self.solver.update(P, qp.c, A, qp.b, None, None, None, qp.lb, qp.ub)
        status = self.solver.solve()
        if status != piqp.PIQP_SOLVED:
            return fail(self, str(status))
        return np.array(self.solver.result.x)
