r"""Compiled primal-dual interior-point method for the instant's cone program, specialised to its
structure (the kernels of :mod:`.ipm`).

.. math::

    \min\ \tfrac12 x^T P x + c^T x \ \text{ s.t. }\ A x = b,\ \ x_i + s^u_i = u_i,\ -x_i + s^l_i = -l_i,
    \ \ -T_k x + s^c_k = t_k,\ \ s^u, s^l \ge 0,\ s^c_k \in \mathcal Q^3,

with ``P = diag(d) + F^T F`` (``F`` of few rows: the interaction objective's weighted wrench rows).
Mehrotra's predictor-corrector with Nesterov-Todd scaling (Vandenberghe, "The CVXOPT linear and
quadratic cone program solvers", 2010, sections 3-4; the same steps as CVXOPT's ``coneqp``).

**The structure.** Each Newton step solves ``H dx + A^T dy = r1, A dx = r2`` with
``H = D + U^T S U``: ``D`` diagonal (``d`` plus the bounds' barrier terms ``z/s``), ``U = [F; T_1;
...; T_K]`` (``r + 3K`` rows) and ``S = blockdiag(I, V_1, ..., V_K)`` (``V_k`` the cones' 3x3 scaling
terms). Eliminating ``dx`` (Woodbury) leaves one symmetric positive definite system of size
``r + 3K + k_eq`` instead of the ``n + k_eq`` KKT system:

.. math::

    \begin{bmatrix} S^{-1} + U D^{-1} U^T & U D^{-1} A^T \\ A D^{-1} U^T & A D^{-1} A^T + \delta I
    \end{bmatrix} \begin{bmatrix} w \\ dy \end{bmatrix} =
    \begin{bmatrix} U D^{-1} r_1 \\ A D^{-1} r_1 - r_2 \end{bmatrix}, \qquad
    dx = D^{-1} (r_1 - U^T w - A^T dy),

with ``S^{-1} = blockdiag(I, W_1^2, ..., W_K^2)`` (no inverse needed). On the neck (76 cables, 24
equations) that is 24 (case 1), 48 (case 2) or 72 (case 3) unknowns instead of 100. ``delta`` (1e-13
of the matrix's scale) keeps it definite when ``A`` loses rank (the 2-link arm at q = 0); one step of
iterative refinement on the unregularised system removes its effect.

**Crossover.** Once the relative duality gap is below ``crossover_gap``, the active set read off the
iterate (bounds whose slack is below their multiplier, cones whose slack is nearer the cone's
boundary than its multiplier is to zero: Tapia's indicators) is handed to the compiled active-set
solver (:func:`._kkt.active_set_solve`), whose point is accepted only if it passes the full KKT check.
That turns an interior point accurate to ~1e-6 into the exact optimum (to rounding) a few
iterations early.

**Infeasibility.** A primal infeasibility certificate (``y``, ``z`` in the dual cone with
``A^T y + G^T z = 0`` and ``b^T y + h^T z < 0``, relative residual below ``eps``) ends the run with
``INFEASIBLE``; the iterates of an infeasible-start method tend to one when the problem is infeasible.
Otherwise the run ends at the iteration limit and the caller falls back to another stage.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from . import _kkt

# return codes
SOLVED, CROSSOVER, INFEASIBLE_CERT, MAX_ITER, NUMERICAL = 0, 1, 2, 3, 4

_FM = {"reassoc", "contract"}  # reassociation lets numba vectorise the dot products; no NaN/inf flags


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _dot(a, b):
    s = 0.0
    for i in range(a.shape[0]):
        s += a[i] * b[i]
    return s


@njit(cache=True, nogil=True, error_model="numpy")
def _soc_scaling(s, z, W, Winv):
    """Nesterov-Todd scaling of one 3-dimensional second-order cone: ``W`` and ``W^-1`` (3x3,
    symmetric) with ``W z = W^-1 s``; returns ``lambda = W z``."""
    ns = np.sqrt(max(s[0] * s[0] - s[1] * s[1] - s[2] * s[2], 1e-300))
    nz = np.sqrt(max(z[0] * z[0] - z[1] * z[1] - z[2] * z[2], 1e-300))
    sb0, sb1, sb2 = s[0] / ns, s[1] / ns, s[2] / ns
    zb0, zb1, zb2 = z[0] / nz, z[1] / nz, z[2] / nz
    gam = np.sqrt(max(0.5 * (1.0 + sb0 * zb0 + sb1 * zb1 + sb2 * zb2), 1e-300))
    w0 = (sb0 + zb0) / (2.0 * gam)
    w1 = (sb1 - zb1) / (2.0 * gam)
    w2 = (sb2 - zb2) / (2.0 * gam)
    eta = np.sqrt(ns / nz)
    # v with v^T J v = 1 and W = eta (2 v v^T - J): v = (w + e) / sqrt(2 (w0 + 1))
    nv = np.sqrt(2.0 * (w0 + 1.0))
    v = ((w0 + 1.0) / nv, w1 / nv, w2 / nv)
    J = (1.0, -1.0, -1.0)
    for a in range(3):
        for b in range(3):
            jab = J[a] if a == b else 0.0
            W[a, b] = eta * (2.0 * v[a] * v[b] - jab)
            # W^-1 = (2 J v v^T J - J) / eta
            Winv[a, b] = (2.0 * J[a] * v[a] * v[b] * J[b] - jab) / eta
    lam = np.empty(3)
    for a in range(3):
        lam[a] = W[a, 0] * z[0] + W[a, 1] * z[1] + W[a, 2] * z[2]
    return lam


@njit(cache=True, nogil=True, error_model="numpy")
def _soc_prod(u, v):
    """The Jordan product of the second-order cone: ``(u.v, u0 v1 + v0 u1, u0 v2 + v0 u2)``."""
    out = np.empty(3)
    out[0] = u[0] * v[0] + u[1] * v[1] + u[2] * v[2]
    out[1] = u[0] * v[1] + v[0] * u[1]
    out[2] = u[0] * v[2] + v[0] * u[2]
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def _soc_div(lam, r):
    """``x`` with ``lam o x = r`` (``lam`` in the cone's interior)."""
    det = lam[0] * lam[0] - lam[1] * lam[1] - lam[2] * lam[2]
    x = np.empty(3)
    x[0] = (lam[0] * r[0] - lam[1] * r[1] - lam[2] * r[2]) / det
    x[1] = (r[1] - x[0] * lam[1]) / lam[0]
    x[2] = (r[2] - x[0] * lam[2]) / lam[0]
    return x


@njit(cache=True, nogil=True, error_model="numpy")
def _soc_step(u, d):
    """Largest ``alpha`` (capped at 1e300) with ``u + alpha d`` in the cone (``u`` inside)."""
    a = d[0] * d[0] - d[1] * d[1] - d[2] * d[2]
    b = 2.0 * (u[0] * d[0] - u[1] * d[1] - u[2] * d[2])
    c = max(u[0] * u[0] - u[1] * u[1] - u[2] * u[2], 0.0)
    best = 1e300
    if d[0] < 0.0:
        best = -u[0] / d[0]
    disc = b * b - 4.0 * a * c
    if a == 0.0:
        if b < 0.0:
            best = min(best, -c / b)
        return best
    if disc < 0.0:
        return best
    sq = np.sqrt(disc)
    for root in ((-b - sq) / (2.0 * a), (-b + sq) / (2.0 * a)):
        if root > 0.0:
            best = min(best, root)
    return best


@njit(cache=True, nogil=True, error_model="numpy")
def _shift_into_cones(su, sl, sc):
    """Shift a point into the interior (CVXOPT's initial point): if its smallest eigenvalue ``m``
    is not positive, add ``(1 - m) e``."""
    m = 1e300
    nrm = 0.0
    for i in range(su.shape[0]):
        m = min(m, su[i])
        nrm += su[i] * su[i]
    for i in range(sl.shape[0]):
        m = min(m, sl[i])
        nrm += sl[i] * sl[i]
    for k in range(sc.shape[0]):
        m = min(m, sc[k, 0] - np.sqrt(sc[k, 1] ** 2 + sc[k, 2] ** 2))
        nrm += sc[k, 0] ** 2 + sc[k, 1] ** 2 + sc[k, 2] ** 2
    if m == 1e300:
        return
    if m <= 1e-8 * max(np.sqrt(nrm), 1.0):
        shift = 1.0 - m
        su += shift
        sl += shift
        for k in range(sc.shape[0]):
            sc[k, 0] += shift


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _factor(H0, diag, T, Vc, A, iu, il, su, zu, sl, zl):
    """Form ``H = H0 + barrier diagonal + sum_k T_k^T V_k T_k`` and factor it (Cholesky, lower, in a
    new array), then the Schur complement ``S = A H^-1 A^T = Y^T Y`` with ``Y = L^-1 A^T``.
    ``diag``: ``H0`` is diagonal and there are no cones (then ``H`` is diagonal: no dense work).
    Returns ``(L, Y, Ls, floored)``: ``floored`` when a pivot had to be replaced (a dependent
    equation, a singular ``H``): the solves then take a step of iterative refinement."""
    n = H0.shape[0]
    neq = A.shape[0]
    K = T.shape[0]
    L = np.zeros((n, n)) if not diag else np.zeros((n, 1))
    if diag:
        for i in range(n):
            L[i, 0] = H0[i, i]
    else:
        for i in range(n):
            for j in range(i + 1):
                L[i, j] = H0[i, j]
    for q in range(iu.shape[0]):
        i = iu[q]
        if diag:
            L[i, 0] += zu[q] / su[q]
        else:
            L[i, i] += zu[q] / su[q]
    for q in range(il.shape[0]):
        i = il[q]
        if diag:
            L[i, 0] += zl[q] / sl[q]
        else:
            L[i, i] += zl[q] / sl[q]
    for k in range(K):
        Tk = T[k]
        R = np.empty((3, n))
        for e in range(3):
            for i in range(n):
                R[e, i] = Vc[k, e, 0] * Tk[0, i] + Vc[k, e, 1] * Tk[1, i] + Vc[k, e, 2] * Tk[2, i]
        for i in range(n):
            t0, t1, t2 = Tk[0, i], Tk[1, i], Tk[2, i]
            Li = L[i]
            for j in range(i + 1):
                Li[j] += t0 * R[0, j] + t1 * R[1, j] + t2 * R[2, j]
    # Cholesky (row-oriented: the inner products run over contiguous rows)
    scale = 1e-300
    for i in range(n):
        scale = max(scale, L[i, 0] if diag else L[i, i])
    floor = 1e-30 * scale
    floored = False
    if diag:
        for i in range(n):
            if not L[i, 0] > floor:
                floored = True
            L[i, 0] = np.sqrt(max(L[i, 0], floor))
    else:
        floored = _chol_rows(L, floor, floor)
    # Y = L^-1 A^T, row by row (each row a combination of the previous rows: contiguous axpys)
    Y = np.empty((n, neq))
    for i in range(n):
        Yi = Y[i]
        for a in range(neq):
            Yi[a] = A[a, i]
        if not diag:
            Li = L[i]
            for k in range(i):
                lk = Li[k]
                if lk != 0.0:
                    Yk = Y[k]
                    for a in range(neq):
                        Yi[a] -= lk * Yk[a]
            inv = 1.0 / Li[i]
        else:
            inv = 1.0 / L[i, 0]
        for a in range(neq):
            Yi[a] *= inv
    # S = Y^T Y (lower), then its Cholesky; a dependent equation (A losing rank) gives a pivot at
    # rounding level: it is replaced by a huge one (the equation is dropped; refinement checks)
    Ls = np.zeros((neq, neq))
    for i in range(n):
        Yi = Y[i]
        for a in range(neq):
            ya = Yi[a]
            for b in range(a + 1):
                Ls[a, b] += ya * Yi[b]
    sscale = 1e-300
    for a in range(neq):
        sscale = max(sscale, Ls[a, a])
    if _chol_rows(Ls, 1e-13 * sscale, 1e300):
        floored = True
    return L, Y, Ls, floored


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _chol_rows(L, tiny, replace):
    """Cholesky of the lower triangle of ``L`` in place, row-oriented (the inner products run over
    contiguous rows); a pivot not above ``tiny`` becomes ``replace`` (``tiny`` itself: a singular ``H``
    kept barely definite; a huge value: a dependent equation dropped). Returns whether one did."""
    n = L.shape[0]
    replaced = False
    for j in range(n):
        Lj = L[j]
        acc = 0.0
        for k in range(j):
            acc += Lj[k] * Lj[k]
        d = Lj[j] - acc
        if not d > tiny:
            d = replace
            replaced = True
        d = np.sqrt(d)
        Lj[j] = d
        inv = 1.0 / d
        for i in range(j + 1, n):
            Li = L[i]
            acc = 0.0
            for k in range(j):
                acc += Li[k] * Lj[k]
            Li[j] = (Li[j] - acc) * inv
    return replaced


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _lsolve(L, r, diag):
    """``L^-1 r`` (``diag``: L stored as its diagonal, (n, 1))."""
    n = r.shape[0]
    u = r.copy()
    if diag:
        for i in range(n):
            u[i] /= L[i, 0]
        return u
    for i in range(n):
        Li = L[i]
        acc = 0.0
        for k in range(i):
            acc += Li[k] * u[k]
        u[i] = (u[i] - acc) / Li[i]
    return u


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _ltsolve(L, u, diag):
    """``L^-T u``."""
    n = u.shape[0]
    x = u.copy()
    if diag:
        for i in range(n):
            x[i] /= L[i, 0]
        return x
    for i in range(n - 1, -1, -1):
        xi = x[i] / L[i, i]
        x[i] = xi
        Li = L[i]
        for k in range(i):
            x[k] -= Li[k] * xi
    return x


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _dense_solve(L, Y, Ls, r1, r2, diag):
    """``H dx + A^T dy = r1, A dx = r2`` with the factors of :func:`_factor`:
    ``u = L^-1 r1``, ``S dy = Y^T u - r2``, ``dx = L^-T (u - Y dy)``."""
    n = r1.shape[0]
    neq = r2.shape[0]
    u = _lsolve(L, r1, diag)
    rhs = -r2.copy()
    for i in range(n):
        ui = u[i]
        Yi = Y[i]
        for a in range(neq):
            rhs[a] += Yi[a] * ui
    dy = _kkt._chol_apply(Ls, rhs)
    for i in range(n):
        Yi = Y[i]
        acc = 0.0
        for a in range(neq):
            acc += Yi[a] * dy[a]
        u[i] -= acc
    return _ltsolve(L, u, diag), dy


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _apply_H(v, H0, diag, T, Vc, iu, il, su, zu, sl, zl):
    """``H v`` with ``H = H0 + barrier diagonal + sum_k T_k^T V_k T_k``."""
    n = v.shape[0]
    if diag:
        out = np.empty(n)
        for i in range(n):
            out[i] = H0[i, i] * v[i]
    else:
        out = H0 @ v
    for t in range(iu.shape[0]):
        out[iu[t]] += zu[t] / su[t] * v[iu[t]]
    for t in range(il.shape[0]):
        out[il[t]] += zl[t] / sl[t] * v[il[t]]
    for k in range(T.shape[0]):
        tv = np.empty(3)
        for e in range(3):
            tv[e] = _dot(T[k, e], v)
        for e in range(3):
            s = Vc[k, e, 0] * tv[0] + Vc[k, e, 1] * tv[1] + Vc[k, e, 2] * tv[2]
            for i in range(n):
                out[i] += s * T[k, e, i]
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def _newton(bx, by, bzu, bzl, bzc, L, Y, Ls, H0, diag, T, A, Vc, iu, il, su, zu, sl, zl, refine):
    """Solve the scaled Newton system for ``(dx, dy, dzu, dzl, dzc)`` (module docstring)."""
    n = bx.shape[0]
    K = T.shape[0]
    r1 = bx.copy()
    for t in range(iu.shape[0]):
        r1[iu[t]] += zu[t] / su[t] * bzu[t]
    for t in range(il.shape[0]):
        r1[il[t]] -= zl[t] / sl[t] * bzl[t]
    for k in range(K):
        vb = np.empty(3)
        for e in range(3):
            vb[e] = Vc[k, e, 0] * bzc[k, 0] + Vc[k, e, 1] * bzc[k, 1] + Vc[k, e, 2] * bzc[k, 2]
        for e in range(3):
            for i in range(n):
                r1[i] -= vb[e] * T[k, e, i]
    dx, dy = _dense_solve(L, Y, Ls, r1, by, diag)
    for _ in range(refine):
        e1 = r1 - _apply_H(dx, H0, diag, T, Vc, iu, il, su, zu, sl, zl) - A.T @ dy
        e2 = by - A @ dx
        cx, cy = _dense_solve(L, Y, Ls, e1, e2, diag)
        dx += cx
        dy += cy
    dzu = np.empty(iu.shape[0])
    for t in range(iu.shape[0]):
        dzu[t] = zu[t] / su[t] * (dx[iu[t]] - bzu[t])
    dzl = np.empty(il.shape[0])
    for t in range(il.shape[0]):
        dzl[t] = zl[t] / sl[t] * (-dx[il[t]] - bzl[t])
    dzc = np.empty((K, 3))
    for k in range(K):
        q = np.empty(3)
        for e in range(3):
            q[e] = -_dot(T[k, e], dx) - bzc[k, e]
        for e in range(3):
            dzc[k, e] = Vc[k, e, 0] * q[0] + Vc[k, e, 1] * q[1] + Vc[k, e, 2] * q[2]
    return dx, dy, dzu, dzl, dzc


@njit(cache=True, nogil=True, error_model="numpy")
def _slack_step(dx, rzu, rzl, rzc, iu, il, T):
    """The slacks' step from the linearised constraints ``G dx + ds = -r_z`` (exact to rounding, so
    primal feasibility improves with every step even when the cones' scaling is ill-conditioned
    and ``W^2 W^-2`` is far from the identity)."""
    dsu = -rzu.copy()
    for q in range(iu.shape[0]):
        dsu[q] -= dx[iu[q]]
    dsl = -rzl.copy()
    for q in range(il.shape[0]):
        dsl[q] += dx[il[q]]
    K = T.shape[0]
    dsc = -rzc.copy()
    for k in range(K):
        for e in range(3):
            dsc[k, e] += _dot(T[k, e], dx)
    return dsu, dsl, dsc


@njit(cache=True, nogil=True, error_model="numpy")
def _max_step(su, dsu, sl, dsl, sc, dsc):
    a = 1e300
    for t in range(su.shape[0]):
        if dsu[t] < 0.0:
            a = min(a, -su[t] / dsu[t])
    for t in range(sl.shape[0]):
        if dsl[t] < 0.0:
            a = min(a, -sl[t] / dsl[t])
    for k in range(sc.shape[0]):
        a = min(a, _soc_step(sc[k], dsc[k]))
    return a


@njit(cache=True, nogil=True, error_model="numpy")
def _residuals(x, y, zu, zl, zc, su, sl, sc, H0, diag, c, A, b, iu, il, lb, ub, T, t):
    n = x.shape[0]
    if diag:
        Hx = np.empty(n)
        for i in range(n):
            Hx[i] = H0[i, i] * x[i]
    else:
        Hx = H0 @ x
    rx = Hx + c + A.T @ y
    for q in range(iu.shape[0]):
        rx[iu[q]] += zu[q]
    for q in range(il.shape[0]):
        rx[il[q]] -= zl[q]
    K = T.shape[0]
    rzc = np.empty((K, 3))
    for k in range(K):
        for e in range(3):
            tx = _dot(T[k, e], x)
            for i in range(n):
                rx[i] -= zc[k, e] * T[k, e, i]
            rzc[k, e] = -tx + sc[k, e] - t[k, e]
    ry = A @ x - b
    rzu = np.empty(iu.shape[0])
    for q in range(iu.shape[0]):
        rzu[q] = x[iu[q]] + su[q] - ub[iu[q]]
    rzl = np.empty(il.shape[0])
    for q in range(il.shape[0]):
        rzl[q] = -x[il[q]] + sl[q] + lb[il[q]]
    pobj = 0.5 * _dot(Hx, x) + _dot(c, x)
    return rx, ry, rzu, rzl, rzc, pobj


@njit(cache=True, nogil=True, error_model="numpy")
def _inf_norm(v):
    m = 0.0
    for i in range(v.shape[0]):
        m = max(m, abs(v[i]))
    return m


@njit(cache=True, nogil=True, error_model="numpy")
def ipm_solve(H, c, A, b, lb, ub, T, t, max_iter, eps, crossover_gap, G, gc, ax, tn, basis0,
              max_pivots, as_tols):
    """The interior-point method with crossover (module docstring).

    Args:
        H (n, n): ``P`` (symmetric positive semidefinite); c (n,): linear term.
        A (k, n), b (k,): equalities. lb, ub (n,): bounds (may be infinite).
        T (K, 3, n), t (K, 3): cone rows ``s = T x + t`` in the second-order cone.
        max_iter, eps: iteration limit; relative residual and gap tolerance.
        crossover_gap: try the active set once the relative gap is below this (0: never).
        G, gc, ax, tn, basis0: the cones in the active-set solver's form (``F = gc + G x``, axis,
            tan, a normal) for the crossover.
        max_pivots: pivot limit of each crossover attempt.
        as_tols (5,): the active-set solver's step, primal, dual, equation-of-motion and
            regularisation tolerances.

    Returns ``(code, x, y, zbox, zc, iterations, state, cact, mus, dirs)``: ``code`` one of SOLVED,
    CROSSOVER, INFEASIBLE_CERT (then ``y, zbox, zc`` are the certificate), MAX_ITER, NUMERICAL;
    ``zbox`` (n,) the bounds' multipliers (> 0 at an upper bound), ``zc`` (K, 3) the cones' duals;
    after a crossover ``state, cact, mus, dirs`` the verified active set (else empty).
    """
    n = c.shape[0]
    neq = A.shape[0]
    K = T.shape[0]
    diag = K == 0
    for i in range(n):
        for j in range(n):
            if i != j and H[i, j] != 0.0:
                diag = False
    nu, nl = 0, 0
    for i in range(n):
        if np.isfinite(ub[i]):
            nu += 1
        if np.isfinite(lb[i]):
            nl += 1
    iu = np.empty(nu, dtype=np.int64)
    il = np.empty(nl, dtype=np.int64)
    a_, b_ = 0, 0
    for i in range(n):
        if np.isfinite(ub[i]):
            iu[a_] = i
            a_ += 1
        if np.isfinite(lb[i]):
            il[b_] = i
            b_ += 1
    deg = nu + nl + K
    # scales of the data, for relative tests
    bscale = max(1.0, _inf_norm(b))
    hscale = 1.0
    for q in range(nu):
        hscale = max(hscale, abs(ub[iu[q]]))
    for q in range(nl):
        hscale = max(hscale, abs(lb[il[q]]))
    for k in range(K):
        for e in range(3):
            hscale = max(hscale, abs(t[k, e]))
    cscale = max(1.0, _inf_norm(c))
    empty_state = np.zeros(0, dtype=np.int8)
    empty_b = np.zeros(0, dtype=np.bool_)
    empty_f = np.zeros(0)
    empty_d = np.zeros((0, 3))

    # ---- initial point (Mehrotra's idea for LPs): the minimiser of the objective, slightly
    # regularised, on the equations alone; slacks kept at least theta inside, duals mu0 / slack. On
    # the neck (forces of ~1 N under limits of 1000 N) this saves the 4-5 iterations that CVXOPT's
    # start (the middle of the box) spends shrinking from 1000 N to 1 N.
    x, y, su, zu, sl, zl, sc, zc = _start(H, diag, c, A, b, lb, ub, T, t, iu, il)
    Wc2 = np.zeros((K, 3, 3))
    Vc = np.zeros((K, 3, 3))
    Wk = np.empty((3, 3))
    Wik = np.empty((3, 3))
    Winv = np.zeros((K, 3, 3))
    Wm = np.zeros((K, 3, 3))
    lamc = np.zeros((K, 3))
    attempts = 0
    end = MAX_ITER
    last_state = np.full(n, -1, dtype=np.int8)
    last_cact = np.zeros(K, dtype=np.bool_)
    it = 0
    for it in range(max_iter):
        rx, ry, rzu, rzl, rzc, pobj = _residuals(x, y, zu, zl, zc, su, sl, sc, H, diag, c, A, b, iu, il,
                                                 lb, ub, T, t)
        gap = _dot(su, zu) + _dot(sl, zl)
        for k in range(K):
            gap += sc[k, 0] * zc[k, 0] + sc[k, 1] * zc[k, 1] + sc[k, 2] * zc[k, 2]
        mu = gap / max(deg, 1)
        pres = _inf_norm(ry) / bscale
        for q in range(nu):
            pres = max(pres, abs(rzu[q]) / hscale)
        for q in range(nl):
            pres = max(pres, abs(rzl[q]) / hscale)
        for k in range(K):
            for e in range(3):
                pres = max(pres, abs(rzc[k, e]) / hscale)
        dres = _inf_norm(rx) / cscale
        # relative to the objective, with an absolute floor of 1e-13 (the data are of order one)
        gap_rel = gap / max(1e-13 / max(eps, 1e-300), abs(pobj))
        if pres <= eps and dres <= eps and gap_rel <= eps:
            # converged: the active set it points at, once more, for the exact point
            if crossover_gap > 0.0:
                state, cact, cdir = _read_active_set(x, su, zu, sl, zl, sc, zc, iu, il, G, gc, ax, basis0)
                if _new_guess(state, cact, last_state, last_cact):
                    code, f, mus, grad, st, ca, dirs, nxt, yy = _kkt.active_set_solve(
                        H, c, A, b, lb, ub, state, G, gc, ax, tn, basis0, cact, cdir, max_pivots, 10,
                        as_tols[0], as_tols[1], as_tols[2], as_tols[3], as_tols[4])
                    if code == _kkt.FOUND:
                        return (CROSSOVER, f, yy, -grad, zc, it, st, ca, mus, dirs)
            return (SOLVED, x, y, _zbox(zu, zl, iu, il, n), zc, it, empty_state, empty_b, empty_f,
                    empty_d)
        # primal infeasibility certificate: A^T y + G^T z = 0, b^T y + h^T z < 0
        hz = _dot(b, y)
        for q in range(nu):
            hz += ub[iu[q]] * zu[q]
        for q in range(nl):
            hz -= lb[il[q]] * zl[q]
        for k in range(K):
            hz += t[k, 0] * zc[k, 0] + t[k, 1] * zc[k, 1] + t[k, 2] * zc[k, 2]
        if hz < 0.0:
            g = A.T @ y
            for q in range(nu):
                g[iu[q]] += zu[q]
            for q in range(nl):
                g[il[q]] -= zl[q]
            for k in range(K):
                for e in range(3):
                    for i in range(n):
                        g[i] -= zc[k, e] * T[k, e, i]
            ysz = _inf_norm(y) * bscale
            for q in range(nu):
                ysz = max(ysz, abs(zu[q]) * hscale)
            for q in range(nl):
                ysz = max(ysz, abs(zl[q]) * hscale)
            if _inf_norm(g) * hscale <= eps * -hz and -hz > 1e-6 * ysz:
                return (INFEASIBLE_CERT, x, y, _zbox(zu, zl, iu, il, n), zc, it, empty_state, empty_b,
                        empty_f, empty_d)
        # ---- crossover: the active set the iterate points at, verified by the active-set solver
        if crossover_gap > 0.0 and gap_rel <= crossover_gap and pres <= 1e3 * crossover_gap \
                and attempts < 8:
            state, cact, cdir = _read_active_set(x, su, zu, sl, zl, sc, zc, iu, il, G, gc, ax, basis0)
            if _new_guess(state, cact, last_state, last_cact):
                attempts += 1
                code, f, mus, grad, st, ca, dirs, nxt, yy = _kkt.active_set_solve(
                    H, c, A, b, lb, ub, state, G, gc, ax, tn, basis0, cact, cdir, max_pivots, 10,
                    as_tols[0], as_tols[1], as_tols[2], as_tols[3], as_tols[4])
                if code == _kkt.FOUND:
                    return (CROSSOVER, f, yy, -grad, zc, it, st, ca, mus, dirs)
        # ---- scaling
        lu = np.sqrt(su * zu)
        ll = np.sqrt(sl * zl)
        for k in range(K):
            lamc[k] = _soc_scaling(sc[k], zc[k], Wk, Wik)
            Wm[k] = Wk
            Winv[k] = Wik
            Wc2[k] = Wk @ Wk
            Vc[k] = Wik @ Wik
        L, Y, Ls, floored = _factor(H, diag, T, Vc, A, iu, il, su, zu, sl, zl)
        refine = 1 if floored else 0
        # ---- predictor (affine scaling direction): bz = -rz + s
        dx, dy, dzu, dzl, dzc = _newton(-rx, -ry, -rzu + su, -rzl + sl, -rzc + sc, L, Y, Ls, H, diag, T,
                                        A, Vc, iu, il, su, zu, sl, zl, refine)
        dsu, dsl, dsc = _slack_step(dx, rzu, rzl, rzc, iu, il, T)
        a_p = min(_max_step(su, dsu, sl, dsl, sc, dsc), _max_step(zu, dzu, zl, dzl, zc, dzc))
        a_p = min(1.0, a_p)
        gap_aff = _dot(su + a_p * dsu, zu + a_p * dzu) + _dot(sl + a_p * dsl, zl + a_p * dzl)
        for k in range(K):
            gap_aff += _dot(sc[k] + a_p * dsc[k], zc[k] + a_p * dzc[k])
        sigma = min(1.0, max(0.0, gap_aff / max(gap, 1e-300))) ** 3
        smu = sigma * mu
        # ---- corrector: rs = -lam o lam - (W^-1 ds_a) o (W dz_a) + sigma mu e
        rsu = -lu * lu - dsu * dzu + smu
        rsl = -ll * ll - dsl * dzl + smu
        bzu = -rzu - np.sqrt(su / zu) * (rsu / lu)
        bzl = -rzl - np.sqrt(sl / zl) * (rsl / ll)
        bzc = np.empty((K, 3))
        divc = np.empty((K, 3))
        for k in range(K):
            rs = -_soc_prod(lamc[k], lamc[k]) - _soc_prod(Winv[k] @ dsc[k], Wm[k] @ dzc[k])
            rs[0] += smu
            divc[k] = _soc_div(lamc[k], rs)
            bzc[k] = -rzc[k] - Wm[k] @ divc[k]
        dx, dy, dzu, dzl, dzc = _newton(-rx, -ry, bzu, bzl, bzc, L, Y, Ls, H, diag, T, A, Vc, iu, il, su,
                                        zu, sl, zl, refine)
        dsu, dsl, dsc = _slack_step(dx, rzu, rzl, rzc, iu, il, T)
        a = min(_max_step(su, dsu, sl, dsl, sc, dsc), _max_step(zu, dzu, zl, dzl, zc, dzc))
        a = min(1.0, 0.99 * a)
        if not np.isfinite(_dot(dx, dx) + _dot(dy, dy)):
            a = 0.0
        if not (a > 1e-14) or not np.isfinite(a):
            end = NUMERICAL
            break
        end = MAX_ITER
        x += a * dx
        y += a * dy
        su += a * dsu
        zu += a * dzu
        sl += a * dsl
        zl += a * dzl
        sc += a * dsc
        zc += a * dzc
    # no convergence: one last crossover from where the iterations stopped
    if crossover_gap > 0.0:
        state, cact, cdir = _read_active_set(x, su, zu, sl, zl, sc, zc, iu, il, G, gc, ax, basis0)
        if _new_guess(state, cact, last_state, last_cact):
            code, f, mus, grad, st, ca, dirs, nxt, yy = _kkt.active_set_solve(
                H, c, A, b, lb, ub, state, G, gc, ax, tn, basis0, cact, cdir, max_pivots, 10,
                as_tols[0], as_tols[1], as_tols[2], as_tols[3], as_tols[4])
            if code == _kkt.FOUND:
                return (CROSSOVER, f, yy, -grad, zc, it + 1, st, ca, mus, dirs)
    return (end, x, y, _zbox(zu, zl, iu, il, n), zc, it + 1, empty_state, empty_b, empty_f, empty_d)


@njit(cache=True, nogil=True, error_model="numpy")
def _start(H, diag, c, A, b, lb, ub, T, t, iu, il):
    """The initial point (see :func:`ipm_solve`)."""
    n = c.shape[0]
    K = T.shape[0]
    nu, nl = iu.shape[0], il.shape[0]
    hmax = 0.0
    for i in range(n):
        hmax = max(hmax, abs(H[i, i]))
    cmax = _inf_norm(c)
    delta = max(1e-6 * hmax, 1e-3 * cmax, 1e-12)
    su = np.ones(nu)
    zu = np.full(nu, delta)
    sl = np.ones(nl)
    zl = np.full(nl, delta)
    Vc = np.zeros((K, 3, 3))
    for k in range(K):
        for e in range(3):
            Vc[k, e, e] = delta
    L, Y, Ls, floored = _factor(H, diag, T, Vc, A, iu, il, su, zu, sl, zl)
    x, y, _, _, _ = _newton(-c, b, np.zeros(nu), np.zeros(nl), np.zeros((K, 3)), L, Y, Ls, H, diag, T, A,
                            Vc, iu, il, su, zu, sl, zl, 1)
    xs = max(1.0, _inf_norm(x))
    theta = 1e-1 * xs
    g = H @ x + c
    mu0 = theta * max(1.0, _inf_norm(g))
    for q in range(nu):
        su[q] = max(ub[iu[q]] - x[iu[q]], theta)
        zu[q] = mu0 / su[q]
    for q in range(nl):
        sl[q] = max(x[il[q]] - lb[il[q]], theta)
        zl[q] = mu0 / sl[q]
    sc = np.empty((K, 3))
    zc = np.empty((K, 3))
    for k in range(K):
        for e in range(3):
            sc[k, e] = _dot(T[k, e], x) + t[k, e]
        nrm = np.sqrt(sc[k, 1] ** 2 + sc[k, 2] ** 2)
        if sc[k, 0] - nrm < theta:
            sc[k, 0] = nrm + theta
        det = sc[k, 0] ** 2 - nrm ** 2
        zc[k, 0] = mu0 * sc[k, 0] / det
        zc[k, 1] = -mu0 * sc[k, 1] / det
        zc[k, 2] = -mu0 * sc[k, 2] / det
    return x, y, su, zu, sl, zl, sc, zc


@njit(cache=True, nogil=True, error_model="numpy")
def _read_active_set(x, su, zu, sl, zl, sc, zc, iu, il, G, gc, ax, basis0):
    """The active set an interior iterate points at (Tapia's indicators): a bound whose slack is
    below its multiplier, a cone whose slack is nearer the cone's boundary than its multiplier is
    to zero; a cone's surface direction from its force at ``x``."""
    n = x.shape[0]
    K = sc.shape[0]
    state = np.zeros(n, dtype=np.int8)
    for q in range(il.shape[0]):
        if sl[q] < zl[q]:
            state[il[q]] = 1
    for q in range(iu.shape[0]):
        if su[q] < zu[q]:
            state[iu[q]] = 2
    cact = np.zeros(K, dtype=np.bool_)
    cdir = np.zeros((K, 3))
    for k in range(K):
        smin = sc[k, 0] - np.sqrt(sc[k, 1] ** 2 + sc[k, 2] ** 2)
        znorm = np.sqrt(zc[k, 0] ** 2 + zc[k, 1] ** 2 + zc[k, 2] ** 2)
        if smin < znorm:
            cact[k] = True
        Fk = gc[k] + G[k] @ x
        al = ax[k, 0] * Fk[0] + ax[k, 1] * Fk[1] + ax[k, 2] * Fk[2]
        p0, p1, p2 = Fk[0] - al * ax[k, 0], Fk[1] - al * ax[k, 1], Fk[2] - al * ax[k, 2]
        pn = np.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
        if pn > 0.0:
            cdir[k, 0], cdir[k, 1], cdir[k, 2] = p0 / pn, p1 / pn, p2 / pn
        else:
            cdir[k] = basis0[k]
    return state, cact, cdir


@njit(cache=True, nogil=True, error_model="numpy")
def _new_guess(state, cact, last_state, last_cact):
    """Whether ``(state, cact)`` differs from the last guess tried (then it becomes the last)."""
    same = True
    for i in range(state.shape[0]):
        if state[i] != last_state[i]:
            same = False
    for k in range(cact.shape[0]):
        if cact[k] != last_cact[k]:
            same = False
    last_state[:] = state
    last_cact[:] = cact
    return not same


@njit(cache=True, nogil=True, error_model="numpy")
def _zbox(zu, zl, iu, il, n):
    z = np.zeros(n)
    for q in range(iu.shape[0]):
        z[iu[q]] += zu[q]
    for q in range(il.shape[0]):
        z[il[q]] -= zl[q]
    return z
