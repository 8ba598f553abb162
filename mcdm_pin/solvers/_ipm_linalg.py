r"""Small dense kernels of the compiled interior-point method (:mod:`._ipm`, :mod:`._ipm_structure`,
:mod:`._ipm_newton`), also used by the active-set kernels: vectorised dot products and updates, the
Cholesky factor that drops dependent equations' pivots (:func:`chol_inplace`) and its solves, the
products with a block of rows, 3 x 3 inverses and the largest magnitude of a vector.

Kernels call them with typed integers (``np.int64(0)``) and contiguous arrays, not literals or
slices: numba compiles a kernel once per argument type, and a literal ``0`` or an ``A``-ordered
slice is a type of its own (docs/speed.md, "Third pass").
"""
from __future__ import annotations

import numpy as np
from ..jit import njit


_FM = {"reassoc", "contract"}  # reassociation lets numba vectorise the dot products; no NaN/inf flags


@njit(cache=True, nogil=True, error_model="numpy")
def inf_norm(v):
    """``max |v_i|`` (0 for an empty ``v``)."""
    m = 0.0
    for i in range(v.shape[0]):
        m = max(m, abs(v[i]))
    return m


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def dot(a, b):
    s = 0.0
    for i in range(a.shape[0]):
        s += a[i] * b[i]
    return s


@njit(cache=True, nogil=True, fastmath=False, error_model="numpy")  # (stated: else inherited from a caller)
def dot_in_order(a, b):
    """:func:`dot` summed in index order, without reassociation: the same to the bit as the
    uncompiled code, for a kernel whose decisions must not depend on the compile (the dual guess's
    line search: :mod:`._dual_guess`)."""
    s = 0.0
    for i in range(a.shape[0]):
        s += a[i] * b[i]
    return s


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def axpy(a, x, y):
    """``y += a x`` in place."""
    for i in range(y.shape[0]):
        y[i] += a * x[i]


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy", inline="always")
def _pivot(Lj, j, drop_rel, first_drop):
    """Row ``Lj``'s pivot (its diagonal entry less the squares before it) judged as in
    :func:`chol_inplace` and stored in ``Lj[j]``: ``(the pivot, dropped)``."""
    d = Lj[j]
    floor = drop_rel * abs(d)
    for k in range(j):
        d -= Lj[k] * Lj[k]
    dropped = not d > floor
    d = np.sqrt((1e300 if j >= first_drop else max(floor, 1e-300)) if dropped else d)
    Lj[j] = d
    return d, dropped


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def chol_inplace(L, drop_rel, first_drop):
    """Cholesky factor of the lower triangle of ``L`` in place (row-oriented, two columns at a time:
    each row's products with both pivot rows share its loads, and four rows at a time share the
    pivot rows' loads). Each pivot is judged against its own row's
    diagonal entry ``L_jj`` before the elimination (the factor does not depend on the scaling of the
    rows, nor should the test): a pivot at or below ``drop_rel L_jj`` in a row from ``first_drop`` on
    becomes 1e300 (its unknown is dropped: the solves set it to zero; a dependent equation), in a
    row before ``first_drop`` becomes ``drop_rel L_jj`` (a block that is positive definite by
    construction kept barely definite). Returns whether a pivot was dropped or raised."""
    p = L.shape[0]
    dropped = False
    j = 0
    while j + 1 < p:
        Lj, Lk = L[j], L[j + 1]
        d, dr = _pivot(Lj, j, drop_rel, first_drop)
        dropped |= dr
        inv = 1.0 / d
        s = Lk[j]
        for k in range(j):
            s -= Lk[k] * Lj[k]
        Lk[j] = s * inv
        d1, dr = _pivot(Lk, j + 1, drop_rel, first_drop)
        dropped |= dr
        inv1 = 1.0 / d1
        ljk = Lk[j]
        i = j + 2
        while i + 3 < p:
            A0, A1, A2, A3 = L[i], L[i + 1], L[i + 2], L[i + 3]
            s0, s1, s2, s3 = A0[j], A1[j], A2[j], A3[j]
            t0, t1, t2, t3 = A0[j + 1], A1[j + 1], A2[j + 1], A3[j + 1]
            for k in range(j):
                a = Lj[k]
                b = Lk[k]
                s0 -= A0[k] * a
                s1 -= A1[k] * a
                s2 -= A2[k] * a
                s3 -= A3[k] * a
                t0 -= A0[k] * b
                t1 -= A1[k] * b
                t2 -= A2[k] * b
                t3 -= A3[k] * b
            s0, s1, s2, s3 = s0 * inv, s1 * inv, s2 * inv, s3 * inv
            A0[j], A1[j], A2[j], A3[j] = s0, s1, s2, s3
            A0[j + 1] = (t0 - s0 * ljk) * inv1
            A1[j + 1] = (t1 - s1 * ljk) * inv1
            A2[j + 1] = (t2 - s2 * ljk) * inv1
            A3[j + 1] = (t3 - s3 * ljk) * inv1
            i += 4
        while i < p:
            Ai = L[i]
            s0, t0 = Ai[j], Ai[j + 1]
            for k in range(j):
                s0 -= Ai[k] * Lj[k]
                t0 -= Ai[k] * Lk[k]
            s0 *= inv
            Ai[j] = s0
            Ai[j + 1] = (t0 - s0 * ljk) * inv1
            i += 1
        j += 2
    if j < p:  # the last pivot when p is odd
        dropped |= _pivot(L[j], j, drop_rel, first_drop)[1]
    return dropped


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def add_inverse(L, out):
    """``out += (L L^T)^{-1}`` on the lower triangle (``L^{-1}`` formed row by row)."""
    p = L.shape[0]
    Li_ = np.zeros((p, p))
    for i in range(p):
        Li = L[i]
        inv = 1.0 / Li[i]
        row = Li_[i]
        row[i] = inv
        for k in range(i):
            lk = Li[k] * inv
            if lk != 0.0:
                Rk = Li_[k]
                for j in range(k + 1):
                    row[j] -= lk * Rk[j]
    # (L L^T)^-1 = L^-T L^-1: entry (a, b) = sum_i Li_[i, a] Li_[i, b]
    for i in range(p):
        row = Li_[i]
        for a in range(i + 1):
            ra = row[a]
            if ra != 0.0:
                Oa = out[a]
                for b in range(a + 1):
                    Oa[b] += ra * row[b]


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def inv3(M, out):
    """``out <- M^-1`` of a 3 x 3 matrix (adjugate over determinant); returns the determinant."""
    c00 = M[1, 1] * M[2, 2] - M[1, 2] * M[2, 1]
    c01 = M[1, 2] * M[2, 0] - M[1, 0] * M[2, 2]
    c02 = M[1, 0] * M[2, 1] - M[1, 1] * M[2, 0]
    det = M[0, 0] * c00 + M[0, 1] * c01 + M[0, 2] * c02
    if det == 0.0:
        return det
    inv = 1.0 / det
    out[0, 0] = c00 * inv
    out[1, 0] = c01 * inv
    out[2, 0] = c02 * inv
    out[0, 1] = (M[0, 2] * M[2, 1] - M[0, 1] * M[2, 2]) * inv
    out[1, 1] = (M[0, 0] * M[2, 2] - M[0, 2] * M[2, 0]) * inv
    out[2, 1] = (M[0, 1] * M[2, 0] - M[0, 0] * M[2, 1]) * inv
    out[0, 2] = (M[0, 1] * M[1, 2] - M[0, 2] * M[1, 1]) * inv
    out[1, 2] = (M[0, 2] * M[1, 0] - M[0, 0] * M[1, 2]) * inv
    out[2, 2] = (M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0]) * inv
    return det


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def rows_dot(B, lo, hi, u, out, off):
    """``out[off + i - lo] = B[i] . u`` for the rows ``lo <= i < hi`` (four rows at a time share the
    loads of ``u``)."""
    n = u.shape[0]
    i = lo
    while i + 3 < hi:
        B0, B1, B2, B3 = B[i], B[i + 1], B[i + 2], B[i + 3]
        s0, s1, s2, s3 = 0.0, 0.0, 0.0, 0.0
        for t in range(n):
            ut = u[t]
            s0 += B0[t] * ut
            s1 += B1[t] * ut
            s2 += B2[t] * ut
            s3 += B3[t] * ut
        o = off + i - lo
        out[o], out[o + 1], out[o + 2], out[o + 3] = s0, s1, s2, s3
        i += 4
    while i < hi:
        Bi = B[i]
        s0 = 0.0
        for t in range(n):
            s0 += Bi[t] * u[t]
        out[off + i - lo] = s0
        i += 1


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def rows_axpy(B, lo, hi, coef, off, scale, y):
    """``y += scale sum_i coef[off + i - lo] B[i]`` over the rows ``lo <= i < hi`` (four rows at a
    time: one pass over ``y`` per four rows)."""
    n = y.shape[0]
    i = lo
    while i + 3 < hi:
        B0, B1, B2, B3 = B[i], B[i + 1], B[i + 2], B[i + 3]
        o = off + i - lo
        c0, c1, c2, c3 = scale * coef[o], scale * coef[o + 1], scale * coef[o + 2], scale * coef[o + 3]
        for t in range(n):
            y[t] += c0 * B0[t] + c1 * B1[t] + c2 * B2[t] + c3 * B3[t]
        i += 4
    while i < hi:
        axpy(scale * coef[off + i - lo], B[i], y)
        i += 1


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def chol_solve_inplace(L, y):
    """``y <- (L L^T)^{-1} y`` for :func:`factor`'s ``L``, whose diagonal holds the pivots' inverses
    (both passes along rows of ``L``; no temporaries; each row's pivot a product, not a division:
    the next row waits on it)."""
    p = L.shape[0]
    for i in range(p):
        Li = L[i]
        s = 0.0
        for k in range(i):
            s += Li[k] * y[k]
        y[i] = (y[i] - s) * Li[i]
    for i in range(p - 1, -1, -1):
        Li = L[i]
        xi = y[i] * Li[i]
        y[i] = xi
        for k in range(i):
            y[k] -= Li[k] * xi
