r"""The equations' rank through a pivot of the active-set solver (:func:`._kkt.active_set_run`).

A pivot fixes at their bounds the free cables that left them. Where the equations need such a
cable's column (no other free cable pulls along the direction it gives them), the free columns stop
spanning the equations: the next KKT system is singular, its solution a point of 1e25 or none, and
the exchanges that follow wander among sets of the same deficient rank: on large chains most warm
starts that failed had lost the rank this way (docs/speed.md, "The equations' rank through a
pivot").

:func:`restore_rank` keeps the rank: after a pivot that fixed cables, where the free columns no
longer span the equations, it frees, for each direction lost, one fixed cable that pulls along it:
of those whose move off their bound closes the residual the fixed cables leave along that
direction, the one with the least multiplier for its pull (a dual simplex ratio test). The cables the
pivot fixed stay fixed.

The held cones' surfaces are rows too: a pivot that takes a cone beside the equations can leave
their rows dependent over the free cables (on a chain, a cone taken beside a held one at its tip
made the next KKT system singular).
"""

from __future__ import annotations

import numpy as np

from ..jit import njit
from ._kkt_linalg import chol_apply, chol_lower


@njit(cache=True, nogil=True)
def restore_rank(qp, cones, before, state, grad, held_before, held, dirs):
    """``state`` (in place, the active set after a pivot from ``before``) with fixed cables freed
    where the free columns no longer span the equations of ``qp`` (a :class:`._structs.QP`) and the
    surfaces of the cones ``held`` after it (of ``cones``, along their surface directions ``dirs``;
    ``held_before`` those held before it): module docstring. ``grad``: the bounds' multipliers at the
    set before (> 0 binds a cable at its lower bound). Returns the number of cables freed.

    Tested only after a pivot that fixed cables or took a cone and left at most ``4 k + 4`` free
    columns to spare beyond the rows (``k`` the cables it fixed and the cones it took: the rank is
    lost where few are left, and the test costs a share of a KKT solve): the rows' Gram matrix on
    the free columns, factored with its dependent rows dropped (a pivot at or below 1e-13 of its
    largest diagonal entry: a dependent row's is of rounding size, about 1e-16 of the largest)."""
    n = state.shape[0]
    k, nf, na = 0, 0, 0
    for i in range(n):
        k += before[i] == 0 and state[i] != 0
        nf += state[i] == 0
    for c in range(held.shape[0]):
        k += held[c] and not held_before[c]
        na += held[c]
    neq = qp.A.shape[0] + na
    if neq == 0 or k == 0 or nf - neq > 4 * k + 4:
        return 0
    R, r = equation_rows(qp.A, qp.b, cones, held, dirs, na)
    return _restore(R, r, qp.lb, qp.ub, before, state, grad)


@njit(cache=True, nogil=True)
def equation_rows(A, b, cones, held, dirs, na):
    """The equations and the ``na`` held cones' surfaces as rows ``(R, r)`` (``R f = r``): a cone's
    surface along its direction ``d`` is ``w^T (G_k f + g_k) = 0``, ``w = d - tan(rho) a`` (its
    gradient at a force on the surface whose part across the axis points along ``d``). The rows of
    the ratio test's basis too (:func:`._kkt._ratio_test`)."""
    neq, n = A.shape
    R = np.empty((neq + na, n))
    r = np.empty(neq + na)
    R[:neq] = A
    r[:neq] = b
    s = neq
    for c in range(held.shape[0]):
        if not held[c]:
            continue
        w0 = dirs[c, 0] - cones.tn[c] * cones.ax[c, 0]
        w1 = dirs[c, 1] - cones.tn[c] * cones.ax[c, 1]
        w2 = dirs[c, 2] - cones.tn[c] * cones.ax[c, 2]
        for i in range(n):
            R[s, i] = w0 * cones.G[c, 0, i] + w1 * cones.G[c, 1, i] + w2 * cones.G[c, 2, i]
        r[s] = -(w0 * cones.gc[c, 0] + w1 * cones.gc[c, 1] + w2 * cones.gc[c, 2])
        s += 1
    return R, r


@njit(cache=True, nogil=True)
def _restore(A, b, lb, ub, before, state, grad):
    """:func:`restore_rank` on the rows ``A f = b``: the cables freed."""
    neq = A.shape[0]
    G = _free_gram(A, state)
    big = 0.0
    for r in range(neq):
        big = max(big, G[r, r])
    if big == 0.0:
        return 0
    keep = np.ones(neq, dtype=np.bool_)
    chol_lower(G, neq, 1e-13 * big, keep)
    freed = 0
    for j in range(neq):
        if not keep[j]:
            w = _lost_direction(A, state, G, keep, j)
            k = _least_binding_along(A, b, lb, ub, before, state, grad, w)
            if k >= 0:
                state[k] = 0
                freed += 1
    return freed


@njit(cache=True, nogil=True)
def _free_gram(A, state):
    """The lower triangle of ``A_F A_F^T`` over the free columns ``F`` (``state == 0``)."""
    neq, n = A.shape
    G = np.zeros((neq, neq))
    for i in range(n):
        if state[i] != 0:
            continue
        for r in range(neq):
            ar = A[r, i]
            if ar != 0.0:
                for s in range(r + 1):
                    G[r, s] += ar * A[s, i]
    return G


@njit(cache=True, nogil=True)
def _lost_direction(A, state, L, keep, j):
    """A direction ``w`` of the rows that the free columns do not reach (``w^T A_F ~ 0``): ``e_j``
    less its projection on the kept rows, ``w_kept = -(A_K A_K^T)^-1 A_K a_j`` on the free
    columns, with the kept rows' factor ``L`` (:func:`._kkt_linalg.chol_lower` with ``keep``: a
    dropped row passes through it)."""
    neq, n = A.shape
    rhs = np.zeros(neq)
    for i in range(n):
        if state[i] == 0:
            aj = A[j, i]
            if aj != 0.0:
                for r in range(neq):
                    if keep[r]:
                        rhs[r] += A[r, i] * aj
    c = chol_apply(L, rhs)
    w = np.zeros(neq)
    for r in range(neq):
        if keep[r]:
            w[r] = -c[r]
    w[j] = 1.0
    return w


@njit(cache=True, nogil=True)
def _least_binding_along(A, b, lb, ub, before, state, grad, w):
    """The fixed cable (not one the pivot has just fixed) to free along the lost direction ``w``: of
    those whose move off their bound (up from a lower, down from an upper) closes the residual the
    fixed cables leave along ``w`` (``w^T (b - A x)`` with every fixed cable at its bound), the one
    with the smallest ratio of its multiplier to its pull ``|w^T a_k|`` (a dual simplex ratio test);
    -1 when none pulls along ``w``."""
    neq, n = A.shape
    s = np.zeros(n)
    top = 0.0
    res = 0.0
    for r in range(neq):
        res += w[r] * b[r]
    for k in range(n):
        if state[k] != 0:
            acc = 0.0
            for r in range(neq):
                acc += w[r] * A[r, k]
            s[k] = acc
            res -= acc * (lb[k] if state[k] == 1 else ub[k])
            if before[k] != 0:
                top = max(top, abs(acc))
    best, best_ratio = -1, np.inf
    for k in range(n):
        if state[k] == 0 or before[k] == 0 or not abs(s[k]) > 1e-8 * top or top == 0.0:
            continue
        up = state[k] == 1  # (a cable at its lower bound moves up, one at its upper bound down)
        if res != 0.0 and (s[k] * res > 0.0) != up:
            continue
        lam = grad[k] if up else -grad[k]
        ratio = max(lam, 0.0) / abs(s[k])
        if ratio < best_ratio:
            best, best_ratio = k, ratio
    return best
