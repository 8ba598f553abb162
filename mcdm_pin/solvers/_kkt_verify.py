r"""The KKT check of the full problem at the point of one active set (:func:`verify`, for
:mod:`._kkt`'s pivoting loop): the equations of motion, the bounds, the multipliers' signs, the
cones, and which exchange the violations ask for.
"""

from __future__ import annotations

import numpy as np
from ..jit import njit

from ._kkt_eq import cone_force

# verify codes
KKT_OPTIMAL, KKT_PIVOT, KKT_EOM, KKT_STATIONARY, KKT_SURFACE = 0, 1, -1, -3, -4


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def verify(qp, cones, state, f, y, cact, mus, limits):
    """KKT conditions of the full problem (``qp`` and ``cones``: :class:`._structs.QP`,
    :class:`._structs.Cones`) at ``f`` (multipliers ``y`` of ``A f = b``, ``mus`` of the active
    cones), to the tolerances of ``limits`` (a :class:`._structs.Limits`: ``primal_tol``,
    ``dual_tol``, ``eom_tol``, ``stationary_tol``, ``surface_tol``, ``cone_tol``).

    Returns ``(code, to_lower, to_upper, release, cone_in, cone_dir, cone_out, grad, worst_kind,
    worst_idx)``; ``code`` is :data:`KKT_OPTIMAL`, :data:`KKT_PIVOT` (the flags say what to change;
    ``worst_kind`` 1 lower, 2 upper, 0 release, -1 none) or a negative reason.
    """
    H, g, A, b, lb, ub = qp.H, qp.c, qp.A, qp.b, qp.lb, qp.ub
    G, gc, ax, tn, basis0 = cones.G, cones.gc, cones.ax, cones.tn, cones.basis0
    n = f.shape[0]
    nc = G.shape[0]
    release = np.zeros(n, dtype=np.bool_)
    cone_in = np.zeros(nc, dtype=np.bool_)
    cone_out = np.zeros(nc, dtype=np.bool_)
    cone_dir = np.zeros((nc, 3))
    grad = np.zeros(n)
    to_lower, to_upper = _bound_violations(f, lb, ub, state, limits.primal_tol)
    if not _eom_met(A, b, f, limits.eom_tol):
        return KKT_EOM, to_lower, to_upper, release, cone_in, cone_dir, cone_out, grad, -1, -1
    grad, gscale = _lagrangian_gradient(H, g, A, f, y)
    off_surface = _cone_conditions(G, gc, ax, tn, basis0, cact, mus, f, grad, cone_in, cone_out, cone_dir,
                                   limits.surface_tol, limits.cone_tol)
    stationary = True
    for i in range(n):
        if state[i] == 0 and abs(grad[i]) > limits.stationary_tol * gscale:
            stationary = False
    any_change, worst_kind, worst_idx = _worst_violation(state, f, lb, ub, grad, gscale, limits.dual_tol, to_lower,
                                                         to_upper, release)
    for k in range(nc):
        if cone_in[k] or cone_out[k]:
            any_change = True
    if not any_change:
        # nothing to exchange: a KKT point if stationary on the free cables (a pending exchange
        # comes first: far from the optimum a regularised solve is not stationary)
        code = KKT_OPTIMAL if stationary else KKT_STATIONARY
        if off_surface:
            code = KKT_SURFACE
        return code, to_lower, to_upper, release, cone_in, cone_dir, cone_out, grad, -1, -1
    return KKT_PIVOT, to_lower, to_upper, release, cone_in, cone_dir, cone_out, grad, worst_kind, worst_idx


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _bound_violations(f, lb, ub, state, primal_tol):
    """The cables below their lower bound and above their upper bound beyond ``primal_tol`` (relative
    to ``1 + |bound|``) that ``state`` does not hold there: ``(to_lower, to_upper)``."""
    n = f.shape[0]
    to_lower = np.zeros(n, dtype=np.bool_)
    to_upper = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        if f[i] < lb[i] - primal_tol * (1.0 + abs(lb[i])) and state[i] != 1:
            to_lower[i] = True
        if f[i] > ub[i] + primal_tol * (1.0 + abs(ub[i])) and state[i] != 2:
            to_upper[i] = True
    return to_lower, to_upper


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _eom_met(A, b, f, eom_tol):
    """Whether ``A f = b`` holds to ``eom_tol`` relative to the largest of ``|b|`` and the rows'
    ``sum |A_ri| |f_i|``."""
    n = f.shape[0]
    # plain loops: at these sizes BLAS calls and temporaries cost more than the arithmetic
    neq = A.shape[0]
    res = np.empty(neq)
    scale = 1e-300
    for r in range(neq):
        scale = max(scale, abs(b[r]))
        acc = 0.0
        sacc = 0.0
        for i in range(n):
            acc += A[r, i] * f[i]
            sacc += abs(A[r, i]) * abs(f[i])
        res[r] = acc - b[r]
        scale = max(scale, sacc)
    for r in range(neq):
        if abs(res[r]) > eom_tol * scale:
            return False
    return True


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _lagrangian_gradient(H, g, A, f, y):
    """The gradient of the Lagrangian without the cones, ``H f + g + A^T y``, and the scale it is
    judged by (the largest entry of ``H f + g`` and of ``A^T y``): ``(grad, gscale)``."""
    n = f.shape[0]
    neq = A.shape[0]
    grad = np.zeros(n)
    obj_grad = g.copy()
    for i in range(n):
        acc = 0.0
        for j in range(n):
            acc += H[i, j] * f[j]
        obj_grad[i] += acc
    Aty = np.zeros(n)
    for r in range(neq):
        yr = y[r]
        for i in range(n):
            Aty[i] += A[r, i] * yr
    gscale = 1e-300
    for i in range(n):
        gscale = max(gscale, abs(obj_grad[i]), abs(Aty[i]))
        grad[i] = obj_grad[i] + Aty[i]
    return grad, gscale


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _cone_conditions(G, gc, ax, tn, basis0, cact, mus, f, grad, cone_in, cone_out, cone_dir, surface_tol, cone_tol):
    """The cones' KKT conditions at ``f``: a held cone (``cact``) lets go (``cone_out``) on the wrong
    nappe or with a negative multiplier, and adds ``mu d|F_perp|/df - mu tan a.G`` to ``grad``; a
    free cone whose force leaves it comes in (``cone_in``, with its surface direction in
    ``cone_dir``; broken: ``|F_perp| > tan(rho) a.F (1 + cone_tol)``). Returns whether a held cone's
    force is off its surface by more than ``surface_tol |F|`` (Newton did not settle)."""
    n = f.shape[0]
    nc = G.shape[0]
    off_surface = False
    for k in range(nc):
        F0, F1, F2, al, p0, p1, p2 = cone_force(G, gc, ax, k, f)
        perp = np.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
        if cact[k]:
            if al <= 0.0:  # held on the wrong nappe (F pulls the ball out): let the cone go
                cone_out[k] = True
                continue
            if not abs(perp - tn[k] * al) <= surface_tol * np.sqrt(F0 * F0 + F1 * F1 + F2 * F2):
                off_surface = True  # Newton did not settle: exchanges still apply, no acceptance
            if mus[k] < 0.0:
                cone_out[k] = True
            # d/df |F_perp| = n^T G with n = F_perp / |F_perp| (the caller never holds a cone
            # whose force vanished: eq_solve reports it)
            w0 = p0 / perp - tn[k] * ax[k, 0]
            w1 = p1 / perp - tn[k] * ax[k, 1]
            w2 = p2 / perp - tn[k] * ax[k, 2]
            mu = mus[k]
            for i in range(n):
                grad[i] += mu * (w0 * G[k, 0, i] + w1 * G[k, 1, i] + w2 * G[k, 2, i])
        elif perp > tn[k] * al * (1 + cone_tol) or al < 0.0:
            cone_in[k] = True
            if perp > 0.0:
                cone_dir[k, 0], cone_dir[k, 1], cone_dir[k, 2] = p0 / perp, p1 / perp, p2 / perp
            else:
                cone_dir[k] = basis0[k]
    return off_surface


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _worst_violation(state, f, lb, ub, grad, gscale, dual_tol, to_lower, to_upper, release):
    """The fixed cables whose multiplier has the wrong sign beyond ``dual_tol`` (``release``, set
    here; a variable with ``lb == ub`` is at both bounds, so its multiplier may have either sign) and
    the worst of every violation, bounds included: ``(any_change, worst_kind, worst_idx)``
    (``worst_kind`` 1 lower, 2 upper, 0 release, -1 none)."""
    n = f.shape[0]
    any_change = False
    worst_kind, worst_idx, worst = -1, -1, -np.inf
    for i in range(n):
        if lb[i] != ub[i] and ((state[i] == 1 and grad[i] < -dual_tol * gscale) or
                               (state[i] == 2 and grad[i] > dual_tol * gscale)):
            release[i] = True
            any_change = True
            v = abs(grad[i]) / gscale
            if v > worst:
                worst, worst_kind, worst_idx = v, 0, i
        if to_lower[i]:
            any_change = True
            v = (lb[i] - f[i]) / (1.0 + abs(lb[i]))
            if v > worst:
                worst, worst_kind, worst_idx = v, 1, i
        if to_upper[i]:
            any_change = True
            v = (f[i] - ub[i]) / (1.0 + abs(ub[i]))
            if v > worst:
                worst, worst_kind, worst_idx = v, 2, i
    return any_change, worst_kind, worst_idx
