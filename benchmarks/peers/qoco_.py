"""QOCO (primal-dual interior point for SOCPs, custom KKT; Chari, Acikmese 2025) as a peer: cases 1-3.

The same conic form as Clarabel's (``mcdm_pin.solvers.clarabel_.conic_form``: equations, finite
bounds as a non-negative cone, one 3-dimensional second-order cone per stability cone), handed to
``QOCO.setup(n, m, p, P, c, A, b, G, h, l, nsoc, q)`` with ``G f + s = h``; tolerances 1e-9
(absolute and relative). ``QOCO_SOLVED_INACCURATE`` counts as an answer (as Clarabel's
``AlmostSolved`` does): the benchmark's objective check judges it.

Warm: QOCO has no warm start (an interior-point method) and updates keep only a fixed sparsity
pattern, which the per-instant matrices do not have: every instant is set up afresh, warm or cold.
"""

from __future__ import annotations

import numpy as np

from .base import Peer, fail

EPS = 1e-9


class QocoPeer(Peer):
    name = "qoco"
    label = "QOCO (SOCP interior point)"
    cones = True
    warm = "none (set up per instant)"

    def __init__(self):
        import qoco  # noqa: F401

    def solve(self, qp):
        import qoco
        from scipy import sparse

        from mcdm_pin.solvers.clarabel_ import conic_form

        P, c, AG, bh, cones, (rows, hi, lo) = conic_form(qp)
        p = len(rows)
        l_dim = len(hi) + len(lo)
        nsoc = len(qp.cones)
        A, b = (AG[:p], bh[:p]) if p else (None, None)
        G, h = (AG[p:], bh[p:]) if AG.shape[0] > p else (None, None)
        s = qoco.QOCO()
        s.setup(qp.n, AG.shape[0] - p, p, P, c, sparse.csc_matrix(A) if A is not None else None, b,
                sparse.csc_matrix(G) if G is not None else None, h, l_dim, nsoc,
                np.full(nsoc, 3, dtype=np.int32) if nsoc else None,
                verbose=False, abstol=EPS, reltol=EPS)
        res = s.solve()
        if res.status not in ("QOCO_SOLVED", "QOCO_SOLVED_INACCURATE"):
            return fail(self, str(res.status))
        return np.array(res.x)
