"""Clarabel (interior point for cone programs; Goulart, Chen 2024) as a peer: cases 1-3.

The library's conic form (``mcdm_pin.solvers.clarabel_.conic_form``), built inside the timed region
as a user would; Clarabel's default settings (``tight``: 1e-11 gaps and feasibility, the reference
optimum of the benchmark's check).

Warm: Clarabel has no warm start of its iterate (an interior-point method), and its data updates need
a fixed sparsity pattern, which the per-instant matrices do not have: set up per instant, warm or cold.
"""

from __future__ import annotations

import numpy as np

from .base import Peer, fail


class ClarabelPeer(Peer):
    name = "clarabel"
    label = "Clarabel (direct SOCP)"
    cones = True
    warm = "none (set up per instant)"

    def __init__(self, tight: bool = False):
        import clarabel  # noqa: F401
        self.tight = tight

    def solve(self, qp):
        import clarabel

        from mcdm_pin.solvers.clarabel_ import conic_form

        P, c, A, b, cones, _ = conic_form(qp)
        settings = clarabel.DefaultSettings()
        settings.verbose = False
        if self.tight:
            settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = 1e-11
            settings.tol_ktratio = 1e-8
        sol = clarabel.DefaultSolver(P, c, A, b, cones, settings).solve()
        if str(sol.status) in ("Solved", "AlmostSolved"):
            return np.array(sol.x)
        return fail(self, str(sol.status))
