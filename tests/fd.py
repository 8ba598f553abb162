"""Finite differences shared by the tests."""

from __future__ import annotations

import numpy as np


def lengths_jacobian(lengths_at, q, h: float = 1e-6) -> np.ndarray:
    """Central differences of the cable lengths, ``(m, nv)``: ``lengths_at(q)`` returns the lengths.

    The error is O(h^2 |l'''|) ~ 1e-12 from truncation plus ~ eps |l| / h ~ 1e-10 from rounding."""
    q = np.asarray(q, dtype=float)
    columns = []
    for i in range(len(q)):
        e = np.zeros(len(q))
        e[i] = h
        columns.append((lengths_at(q + e) - lengths_at(q - e)) / (2 * h))
    return np.stack(columns, axis=1)


def bounds_lp_feasible(robot, q, qd=None, qdd=None) -> bool:
    """Whether ``L^T f = -(M qdd + h)`` has a solution with ``f_min <= f <= f_max``: an LP decided by
    HiGHS (scipy), sharing nothing with the solvers under test but the model terms (RNEA from
    Pinocchio, ``L`` checked against finite differences elsewhere). The reference for instants that
    the default chain's Clarabel stage calls infeasible (comparing them with Clarabel would compare
    Clarabel with itself)."""
    from scipy.optimize import linprog

    from mcdm_pin import compute_terms

    t = compute_terms(robot, q, qd, qdd)
    res = linprog(np.zeros(robot.m), A_eq=t.L.T, b_eq=-t.tau, bounds=list(zip(robot.f_min, robot.f_max)),
                  method="highs")
    if res.status not in (0, 2):
        raise RuntimeError(f"HiGHS could not decide the bounds LP: {res.message}")
    return res.status == 0
