r"""The least-norm problem on the optimal face's own coordinates (:func:`face_least_norm`).

The least-norm stage (:mod:`mcdm_pin.solvers.least_norm`) pins the coordinates ``S`` of the optimal
face and leaves the others, ``rest``, free along the face's directions: the rows of ``N`` (``k`` of
them, orthonormal, over ``rest``). Its problem is then one in ``t`` (``k`` unknowns, a handful):

.. math:: \min_t\ \tfrac12 \sum_{i \in rest} w_i (x_i + (N^T t)_i)^2 \quad
          \text{s.t.}\ lb_i \le x_i + (N^T t)_i \le ub_i,

strictly convex (``H = N W N^T`` is positive definite: ``N`` has orthonormal rows, ``w > 0``), and
``t = 0`` (the first stage's answer) is feasible. A primal active-set method from there (Nocedal and
Wright, *Numerical Optimization*, algorithm 16.3) solves it in a few ``k``-sized KKT systems: each
step minimises over the bounds held, the first bound it would cross joins them, and at a minimiser
of the bounds held the one with the most negative multiplier leaves. The cones on the face are
among its rows (held on their surface); a cone not held is an inequality this problem leaves out:
where the point meets it, it is the answer all the same (the least-norm point of a larger set that
lies in the smaller one), and where not, the stage's chain solves the problem with the cone.
"""

from __future__ import annotations

import numpy as np

from ..jit import njit
from ._ipm_linalg import inf_norm
from ._kkt_eq import cone_force
from ._kkt_linalg import lu_solve


@njit(cache=True, nogil=True)
def face_least_norm(x, w, rest, N, lb, ub, held, G, gc, ax, tn):
    """The least-norm point ``x + N^T t`` of the face (module docstring; ``N``'s rows placed on
    ``rest``), its bounds held at their values exactly, and whether it answers the least-norm
    problem: the active-set method converged within its limit, and every cone not ``held`` (an
    inequality of the problem that this one leaves out: force ``G_k x + gc_k``, axis ``ax_k``,
    ``tan`` of its angle ``tn_k``) is met there, so that the point, the least-norm one of a larger
    set, lies in the problem's own. Returns ``(x_face, answers, steps)``, ``steps`` the KKT systems
    solved; where it does not answer, the least-norm stage's chain solves the problem."""
    xf = x.copy()
    k, m = N.shape
    if k == 0:
        return xf, _within_bounds(xf, rest, lb, ub), 0
    H = np.zeros((k, k))
    g = np.zeros(k)
    for a in range(m):
        i = rest[a]
        for p in range(k):
            wn = w[i] * N[p, a]
            g[p] += wn * x[i]
            for q in range(p + 1):
                H[p, q] += wn * N[q, a]
    for p in range(k):
        for q in range(p):
            H[q, p] = H[p, q]
    # the finite bounds as rows c_j^T t >= d_j: c_j = +-N[:, a], d_j = lb_i - x_i or x_i - ub_i
    rows = np.empty(2 * m, dtype=np.int64)
    sign = np.empty(2 * m)
    d = np.empty(2 * m)
    nc = 0
    for a in range(m):
        i = rest[a]
        if np.isfinite(lb[i]):
            rows[nc], sign[nc], d[nc] = a, 1.0, lb[i] - x[i]
            nc += 1
        if np.isfinite(ub[i]):
            rows[nc], sign[nc], d[nc] = a, -1.0, x[i] - ub[i]
            nc += 1
    t, held_rows, n_held, ok, steps = _active_set(H, g, N, rows[:nc], sign[:nc], d[:nc], 4 * (k + nc) + 8)
    if not ok:
        return xf, False, steps
    for a in range(m):
        s = 0.0
        for p in range(k):
            s += N[p, a] * t[p]
        xf[rest[a]] += s
    for h in range(n_held):  # a bound held is met exactly (rounding leaves it 1e-16 off)
        j = held_rows[h]
        i = rest[rows[j]]
        xf[i] = lb[i] if sign[j] > 0.0 else ub[i]
    if not _within_bounds(xf, rest, lb, ub):
        return xf, False, steps
    for c in range(held.shape[0]):
        if not held[c]:
            _, _, _, along, p0, p1, p2 = cone_force(G, gc, ax, c, xf)
            if not np.sqrt(p0 * p0 + p1 * p1 + p2 * p2) <= tn[c] * along:
                return xf, False, steps
    return xf, True, steps


@njit(cache=True, nogil=True)
def _within_bounds(x, rest, lb, ub):
    """Whether every coordinate of ``rest`` lies within its bounds, one within rounding of a bound
    (1e-12 of its size) put on it; a larger miss is a failure, which the stage's chain then answers."""
    for a in range(rest.shape[0]):
        i = rest[a]
        if x[i] < lb[i]:
            if lb[i] - x[i] > 1e-12 * (1.0 + abs(lb[i])):
                return False
            x[i] = lb[i]
        elif x[i] > ub[i]:
            if x[i] - ub[i] > 1e-12 * (1.0 + abs(ub[i])):
                return False
            x[i] = ub[i]
        elif not (x[i] == x[i]):
            return False
    return True


@njit(cache=True, nogil=True)
def _active_set(H, g, N, rows, sign, d, max_steps):
    """``min 1/2 t^T H t + g^T t`` subject to ``sign_j N[:, rows_j]^T t >= d_j`` from ``t = 0`` (feasible:
    every ``d_j <= 0``) by the primal active-set method. Returns ``(t, held, n_held, ok, steps)``: the
    minimiser, the rows held at it (``held[:n_held]``), whether it converged within ``max_steps``
    KKT solves (a singular system or the limit: ``ok`` false) and the solves made."""
    k = H.shape[0]
    nc = rows.shape[0]
    t = np.zeros(k)
    held = np.empty(k, dtype=np.int64)
    n_held = 0
    in_set = np.zeros(nc, dtype=np.bool_)
    for steps in range(1, max_steps + 1):
        p, lam, ok = _step(H, g, N, rows, sign, held, n_held, t)
        if not ok:
            return t, held, n_held, False, steps
        if n_held == k:  # k independent rows fix t: the step is zero but for rounding
            p[:] = 0.0
        # the first row the step would cross (a row held, or one the step leaves, never blocks)
        alpha, block = 1.0, -1
        for j in range(nc):
            if in_set[j]:
                continue
            cp = 0.0
            ct = 0.0
            for q in range(k):
                cp += N[q, rows[j]] * p[q]
                ct += N[q, rows[j]] * t[q]
            cp *= sign[j]
            ct *= sign[j]
            if cp < -1e-14 * inf_norm(p):  # (a step along the row's surface, to rounding, crosses nothing)
                a = max((d[j] - ct) / cp, 0.0)
                if a < alpha:
                    alpha, block = a, j
        for q in range(k):
            t[q] += alpha * p[q]
        if block >= 0:
            held[n_held] = block
            n_held += 1
            in_set[block] = True
            continue
        # a minimiser of the rows held: done when no multiplier is negative, else the most negative leaves
        worst, at = 0.0, -1
        scale = max(inf_norm(lam), inf_norm(g))  # (lam: the n_held rows' multipliers)
        for h in range(n_held):
            if lam[h] < worst and lam[h] < -1e-12 * scale:
                worst, at = lam[h], h
        if at < 0:
            return t, held, n_held, True, steps
        in_set[held[at]] = False
        for h in range(at, n_held - 1):
            held[h] = held[h + 1]
        n_held -= 1
    return t, held, n_held, False, max_steps


@njit(cache=True, nogil=True)
def _step(H, g, N, rows, sign, held, n_held, t):
    """The step ``p`` to the minimiser over the rows held (``H p - C^T lam = -(H t + g)``, ``C p = 0``:
    ``C`` the rows held) and their multipliers ``lam``; ``ok`` false for a singular system."""
    k = H.shape[0]
    n = k + n_held
    K = np.zeros((n, n))
    rhs = np.zeros(n)
    for p in range(k):
        acc = g[p]
        for q in range(k):
            K[p, q] = H[p, q]
            acc += H[p, q] * t[q]
        rhs[p] = -acc
    for h in range(n_held):
        j = held[h]
        for q in range(k):
            c = sign[j] * N[q, rows[j]]
            K[k + h, q] = c
            K[q, k + h] = -c
    sol, ok = lu_solve(K, rhs)
    if not (ok and np.all(np.isfinite(sol))):
        return np.zeros(k), np.zeros(n_held), False
    return sol[:k].copy(), sol[k:].copy(), True
