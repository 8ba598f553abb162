r"""The rows of the interior-point method's reduced Newton system, made once per solve
(:func:`structure`): an orthonormal basis ``Q`` of the objective's factor ``F = C Q`` (a block basis
when ``F``'s rows come in groups of three, :func:`_grouped`), ``M_0^{-1} = (C^T C)^{-1}``, the cones'
rows in that basis when they lie in its span, and whether each cone folds into its group
(:func:`_fold_blocks`). Why each form, and how :mod:`._ipm_newton` uses them: that module's docstring.
"""

from __future__ import annotations

import numpy as np
from ..jit import njit

from ..model.kernels import gram_lower
from ._ipm_linalg import add_inverse, axpy, chol_inplace, dot, inv3

_FM = {"reassoc", "contract"}  # reassociation lets numba vectorise the dot products; no NaN/inf flags


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _in_span(row, Q, lo, hi, coef, rest, rank_tol):
    """Whether ``row`` lies in the span of the orthonormal rows ``Q[lo:hi]``: its part outside them
    (left in ``rest``, (n,) work) at most ``rank_tol`` times its norm; its coefficients are written
    into ``coef[lo:hi]``."""
    for t in range(row.shape[0]):
        rest[t] = row[t]
    for a in range(lo, hi):
        cc = dot(row, Q[a])
        coef[a] = cc
        axpy(-cc, Q[a], rest)
    return not dot(rest, rest) > rank_tol * rank_tol * max(dot(row, row), 1e-300)


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _grouped(Fm, T, rank_tol, keep):
    """The block basis of :func:`structure` when each cone's rows lie in the span of one group of
    three consecutive rows of ``F`` (the neck's case 3: a cone's rows are a rotation of its joint's
    weighted force rows): ``(ok, Q, C, Ct, cg)`` with ``Q`` orthonormal within each group (modified
    Gram-Schmidt with pivoting inside the group), ``F = C Q`` (``C`` block diagonal), cone ``k``'s rows
    ``T_k = Ct[3k:3k+3, cg[k]:cg[k]+3] Q[cg[k]:cg[k]+3]`` (``Ct`` zero elsewhere). ``ok`` is false
    (and the rest unusable) when ``F``'s rows are not in groups of three, a group has a row whose part
    outside the span of the group's other rows is below ``keep`` (then the global basis of
    :func:`structure` with its rank handling is used), or a cone lies in no group's span."""
    r, n = Fm.shape
    K = T.shape[0]
    ng = r // 3
    Q = np.empty((r, n))
    C = np.zeros((r, r))
    Ct = np.zeros((3 * K, r))
    cg = np.empty(K, dtype=np.int64)
    if r == 0 or r % 3 != 0:
        return False, Q, C, Ct, cg
    W = np.empty((3, n))
    res = np.empty(3)
    used = np.empty(3, dtype=np.bool_)
    for j in range(ng):
        o = 3 * j
        for i in range(3):
            W[i] = Fm[o + i]
            res[i] = dot(W[i], W[i])
            used[i] = False
        for c_ in range(3):
            best, piv = 0.0, -1
            for i in range(3):
                if not used[i] and res[i] > keep and res[i] > best:
                    best, piv = res[i], i
            if piv < 0:
                return False, Q, C, Ct, cg
            used[piv] = True
            nrm = np.sqrt(dot(W[piv], W[piv]))
            q = Q[o + c_]
            for t in range(n):
                q[t] = W[piv, t] / nrm
            C[o + piv, o + c_] = nrm
            for i in range(3):
                if not used[i]:
                    cc = dot(W[i], q)
                    C[o + i, o + c_] = cc
                    axpy(-cc, q, W[i])
                    res[i] = dot(W[i], W[i])
    rrow = np.empty(n)
    for k in range(K):
        found = -1
        for jj in range(ng):
            j = (k + jj) % ng  # the k-th group first (the cones in the order of their joints)
            o = 3 * j
            fits = True
            for e in range(3):
                if not _in_span(T[k, e], Q, o, o + 3, Ct[3 * k + e], rrow, rank_tol):
                    fits = False
                    break
            if fits:
                found = j
                break
            for e in range(3):
                for a in range(3):
                    Ct[3 * k + e, o + a] = 0.0
        if found < 0:
            return False, Q, C, Ct, cg
        cg[k] = 3 * found
    return True, Q, C, Ct, cg


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def structure(Fm, T, A, rank_tol):
    """The rows of the reduced system (module docstring): ``(B, rf, M0inv, Ct, cg)`` with ``B = [Q;
    T_1; ...; T_K; A]`` (its columns padded with zeros to a multiple of 8), ``M0inv = (C^T C)^{-1}``
    (full, ``rf x rf``) for ``F = C Q``; when every cone row lies in the span of ``Q``, ``T = Ct Q``
    and ``B = [Q; A]`` (else ``Ct`` is empty). ``Q`` is the block basis of :func:`_grouped` when it
    applies (then ``cg`` holds each cone's group offset, ``Ct`` is block sparse), else the global one
    (``cg`` empty)."""
    r = Fm.shape[0]
    K = T.shape[0]
    res = np.empty(r)
    big = 0.0
    for i in range(r):
        res[i] = dot(Fm[i], Fm[i])
        big = max(big, res[i])
    # a row's part outside the span of the rows before it is judged against F's largest row (a
    # direction of F weaker than rank_tol |F| adds below rounding to P; judged against the row's
    # own norm, the rounding left of a dependent row passed: M0 with eigenvalues of 1e-33, M0^-1 of
    # 1e36, generated robots)
    keep = rank_tol * rank_tol * big
    ok, Q, C, Ct, cg = _grouped(Fm, T, rank_tol, keep)
    if ok:
        rf = r
        inside = K > 0
    else:
        cg = np.empty(0, dtype=np.int64)
        Q, C, rf = _global_basis(Fm, res, keep)
        # the cones' rows in the basis Q, when they lie in its span (the neck: each cone's rows are a
        # rotation of its joint's force rows): then only [Q; A] enters the products with D^-1
        Ct, inside = _cones_in_basis(T, Q, rf, rank_tol)
    B = _stacked_rows(Q, T, A, rf, inside)
    M0inv = _m0_inverse(C, rf, ok)
    fold = _fold_blocks(ok and inside, rf, K, M0inv, Ct, cg)
    return B, rf, M0inv, Ct, cg, fold


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _fold_blocks(possible, rf, K, M0inv, Ct, cg):
    """The cones folded into the force rows (module docstring, "Cones folded into their groups"):
    ``(Cti, gk, Fk, Eb)`` with ``Cti[k]`` the inverse of cone ``k``'s 3 x 3 block of ``Ct``, ``gk[j]`` the
    cone of group ``j`` (-1: none), ``Fk`` (K, 3, 3) work for :func:`factor`'s ``(E + V_k)^-1`` and
    ``Eb[j]`` group ``j``'s block of ``M0^-1``; all empty (the expanded system is used) unless
    ``possible`` (the block basis with every cone's rows in its group's span), each group holds at most
    one cone and every cone's block is invertible (its determinant above 1e-12 of the product of its
    rows' norms)."""
    ng = rf // 3
    none = (np.empty((0, 3, 3)), np.empty(0, dtype=np.int64), np.empty((0, 3, 3)), np.empty((0, 3, 3)))
    if not possible or K == 0:
        return none
    gk = np.full(ng, -1, dtype=np.int64)
    Cti = np.empty((K, 3, 3))
    X = np.empty((3, 3))
    for k in range(K):
        j = cg[k] // 3
        if gk[j] >= 0:
            return none
        gk[j] = k
        nrm = 1.0
        for e in range(3):
            re = 0.0
            for a in range(3):
                X[e, a] = Ct[3 * k + e, cg[k] + a]
                re += X[e, a] * X[e, a]
            nrm *= np.sqrt(re)
        det = inv3(X, Cti[k])
        if not abs(det) > 1e-12 * nrm:
            return none
    Eb = np.empty((ng, 3, 3))
    for j in range(ng):
        for a in range(3):
            for b in range(3):
                Eb[j, a, b] = M0inv[3 * j + a, 3 * j + b]
    return Cti, gk, np.empty((K, 3, 3)), Eb


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _gram_inverse(C, rows, cols, out):
    """``out <- (C^T C)^{-1}`` (both triangles) for ``C[:rows, :cols]`` of full column rank."""
    M0 = np.zeros((cols, cols))
    gram_lower(C, rows, cols, M0)
    chol_inplace(M0, 1e-300, cols)
    add_inverse(M0, out)
    for a in range(cols):
        for b in range(a):
            out[b, a] = out[a, b]


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _global_basis(Fm, res, keep):
    """Modified Gram-Schmidt with pivoting on the rows of ``Fm`` (``res``: their squared norms, then
    what is left of them; a row left with ``keep`` or less counts as dependent): ``(Q, C, rf)`` with
    ``Fm = C Q[:rf]``, ``Q``'s first ``rf`` rows orthonormal."""
    r = Fm.shape[0]
    n = Fm.shape[1]
    W = Fm.copy()
    C = np.zeros((r, r))
    used = np.zeros(r, dtype=np.bool_)
    Q = np.empty((r, n))
    rf = 0
    for _ in range(r):
        best, piv = 0.0, -1
        for i in range(r):
            if not used[i] and res[i] > keep and res[i] > best:
                best, piv = res[i], i
        if piv < 0:
            break
        used[piv] = True
        Wp = W[piv]
        nrm = np.sqrt(dot(Wp, Wp))
        q = Q[rf]
        for t in range(n):
            q[t] = Wp[t] / nrm
        C[piv, rf] = nrm
        for i in range(r):
            if not used[i] and res[i] > 0.0:
                Wi = W[i]
                cc = dot(Wi, q)
                C[i, rf] = cc
                acc = 0.0
                for t in range(n):  # the projection removed and the rest's norm in one pass
                    w = Wi[t] - cc * q[t]
                    Wi[t] = w
                    acc += w * w
                res[i] = acc
        rf += 1
    return Q, C, rf


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _cones_in_basis(T, Q, rf, rank_tol):
    """The cones' rows in the basis ``Q[:rf]``, ``T = Ct Q``, when every one lies in its span:
    ``(Ct, True)``; else ``(Ct with no rows, False)``."""
    K = T.shape[0]
    n = T.shape[2]
    Ct = np.empty((3 * K, rf))
    inside = K > 0
    rrow = np.empty(n)
    for k in range(K):
        for e in range(3):
            if not _in_span(T[k, e], Q, np.int64(0), rf, Ct[3 * k + e], rrow, rank_tol):
                inside = False
    if not inside:
        Ct = np.empty((0, rf))
    return Ct, inside


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _stacked_rows(Q, T, A, rf, inside):
    """``B = [Q; T_1; ...; T_K; A]`` (without the cones' rows when they lie ``inside`` the basis),
    its columns padded with zeros to a multiple of 8: the Gram products' loops then have no
    remainder."""
    K = T.shape[0]
    n = A.shape[1]
    neq = A.shape[0]
    nB = rf + neq if inside else rf + 3 * K + neq
    B = np.zeros((nB, (n + 7) // 8 * 8))
    for i in range(rf):
        B[i, :n] = Q[i]
    o = rf
    if not inside:
        for k in range(K):
            for e in range(3):
                B[rf + 3 * k + e, :n] = T[k, e]
        o = rf + 3 * K
    for a in range(neq):
        B[o + a, :n] = A[a]
    return B


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _m0_inverse(C, rf, ok):
    """``M_0^{-1} = (C^T C)^{-1}`` (``rf x rf``); with the block basis (``ok``: :func:`_grouped`)
    ``C``, and so ``M_0`` and its inverse, are block diagonal (3 x 3 blocks)."""
    r = C.shape[0]
    M0inv = np.zeros((rf, rf))
    if ok:  # C block diagonal: so are M0 and its inverse (eight 3 x 3 blocks on the neck, not 24 x 24)
        X, Cj, Mj = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
        three = np.int64(3)  # typed, not a literal: the specialisation the other calls use
        for j in range(rf // 3):
            o = 3 * j
            Cj[:, :] = C[o:o + 3, o:o + 3]  # contiguous: one specialisation of the kernels below
            # (C_j^T C_j)^-1 = C_j^-1 C_j^-T: no temporaries, and C_j's condition, not its square
            if inv3(Cj, X) != 0.0:
                for a in range(3):
                    for b in range(3):
                        M0inv[o + a, o + b] = X[a, 0] * X[b, 0] + X[a, 1] * X[b, 1] + X[a, 2] * X[b, 2]
            else:
                Mj[:, :] = 0.0
                _gram_inverse(Cj, three, three, Mj)
                M0inv[o:o + 3, o:o + 3] = Mj
    else:
        _gram_inverse(C, r, rf, M0inv)
    return M0inv
