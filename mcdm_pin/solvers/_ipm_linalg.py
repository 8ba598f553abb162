r"""The linear algebra of the compiled interior-point method (:mod:`._ipm`): its Newton system solved
through the problem's structure.

Each Newton step solves, with the bounds' multipliers eliminated and the cones' ``dz_c`` kept,

.. math:: (D + F^T F)\,dx + A^T dy - T^T dz_c = r_1, \qquad A\,dx = r_2, \qquad
          -T\,dx - W^2 dz_c = r_3,

``D`` diagonal (the objective's diagonal ``d0`` plus the bounds' barrier terms ``z/s``), ``F`` the
objective's factor (``P = diag(d0) + F^T F``: the interaction objective's weighted wrench rows), ``T``
the cones' rows and ``W^2 = blockdiag(W_k^2)`` their Nesterov-Todd scaling.

**Once per solve** (:func:`structure`): modified Gram-Schmidt with pivoting turns the rows of ``F``
into an orthonormal basis ``Q`` (``rf`` rows; a row whose part outside the span of the rows before it
is below ``rank_tol`` times ``F``'s largest row counts as dependent) with ``F = C Q``, and
``M_0 = C^T C``.

**Per iteration** (:func:`factor`, :func:`solve`): with ``w_F = M_0 Q dx`` and ``w_T = -dz_c``,
eliminating ``dx = D^{-1} (r_1 - Q^T w_F - T^T w_T - A^T dy)`` leaves

.. math::

    \left( \begin{bmatrix} M_0^{-1} & & \\ & W^2 & \\ & & 0 \end{bmatrix} + B D^{-1} B^T \right)
    \begin{bmatrix} w_F \\ w_T \\ dy \end{bmatrix} =
    B D^{-1} r_1 + \begin{bmatrix} 0 \\ r_3 \\ -r_2 \end{bmatrix}, \qquad B = [Q; T; A],

symmetric positive definite, of size ``rf + 3K + k_eq`` (the neck: 24, 48, 72 in cases 1, 2, 3; 48 in
case 3 with the cones folded into their groups, below). Its
condition number grows like ``1/mu`` only: ``W_k^2`` is small on an active cone but every direction
that ``B^T`` annihilates has its ``Q`` part weighted by ``M_0^{-1}`` (bounded). A form with
``M = M_0 + T^T W^{-2} T`` folded into one ``rf``-sized block (48 unknowns in case 3) needs
``M^{-1}``, whose error grows with ``cond(M) ~ 1/mu^2`` (2e-4 absolute at a relative gap of 1e-5 on
the neck: the iteration then breaks down).

When every cone row lies in the span of ``Q`` (the neck: each cone's rows are a rotation of its
joint's force rows), ``T = C_t Q`` and only ``[Q; A]`` meets ``D^{-1}``: the products of the ``T`` rows
follow from those of ``Q`` (:func:`_expand`), 24 x 24 work instead of 24 x 76.

**The block basis** (:func:`_grouped`, tried first): when ``F``'s rows come in groups of three (the
neck: each joint's weighted force rows) that are each of full rank by the test above, ``Q`` is made
orthonormal *within* each group only, so ``C`` and ``M_0`` are block diagonal (3 x 3) and, when each
cone's rows lie in one group's span, ``C_t`` is one 3 x 3 block per cone: the cones' part of the
reduced matrix costs ~6k multiply-adds instead of ~35k (:func:`_expand_blocks`) and the basis ~4x
less than the global Gram-Schmidt. Nothing above needs ``Q`` orthonormal as a whole: ``P = Q^T M_0 Q``
holds for any ``F = C Q`` with ``C`` invertible, ``M_0^{-1}`` stays bounded (each group of full rank)
and the reduced matrix stays positive definite even when rows of different groups are dependent
(it is the global basis' matrix transformed by ``diag(R, I, I)``, ``Q_block = R Q``). The price is
``R``'s condition (~18 on the neck's groups: the joints' force directions are far from orthogonal),
which the Cholesky factor's rounding sees; on the neck the iterates, iteration counts and crossover
answers are those of the global basis (to 1e-11). A group that is not of full rank, rows not in
groups of three or a cone outside every group fall back to the global basis and its rank handling.

**Cones folded into their groups** (:func:`_fold_blocks`, :func:`_fold_factor`, :func:`_fold_solve`):
with the block basis, when each group holds at most one cone and each cone's block ``X_k`` of ``C_t``
is invertible (the neck's case 3: ``T_k = X_k Q_j``, ``X_k`` the cone's rotation of its joint's force
rows), the cone's unknowns share their group's three directions: with ``w' = X^T w_T`` only
``s = w_F + w'`` reaches ``dx``, and the difference of a group's force and cone rows,
``E w_F - V w' = -X^-1 r_3`` (``E`` the group's block of ``M_0^{-1}``, ``V = X^-1 W^2 X^-T``), leaves

.. math:: w' = (E + V)^{-1} (E s + X^{-1} r_3), \qquad
          S = E (E + V)^{-1} V \ \text{in place of}\ E \ \text{on the group's diagonal block},

a system in ``(s, dy)`` of size ``rf + k_eq`` (48 instead of 72 on the neck: its Cholesky factor ~3x
cheaper, the solves' triangular parts ~2x, no products of the cone rows to form; 41 -> 32 us per
case-3 iteration). No ``W^-2`` is formed: ``S`` is the
parallel sum of ``E`` and ``V``, bounded by both, small where the cone is active (``V`` small), and
``E + V >= E`` is as well conditioned as ``M_0``. The directions equal the expanded system's to 1e-9
(``tests/test_warm_fast.py::test_folded_cones_give_the_expanded_systems_directions``, down to a cone
held at a gap of 1e-10).

A dependent equation (``A`` losing rank: the 2-link arm at q = 0) shows as a pivot at rounding level
and is dropped (its multiplier set to zero); :func:`refine` then corrects against the exact operators.
Rounding level is judged row by row, against the row's own diagonal entry (:func:`chol_inplace`), and
only the equations' rows are ever dropped. Against the largest diagonal entry of the whole matrix
(as before), the ``M_0^{-1}`` block decided: where ``F`` is nearly rank deficient (generated robots
without a diagonal weight, ``d_0 = 0``: ``F``'s singular values from 4 down to 5e-7, or rounding
noise of 1e-16 taken for a direction) its entries reach 1e12-1e36, and every equation's pivot (of
order ``A (D + P)^{-1} A^T``) fell below 1e-14 of that: all equations dropped, ``dy = 0``, the
primal residual never fell, and the step vanished after 6-7 iterations or the iterations ran out
(9 of the 100 instants of the property test; Clarabel answered them).
"""

from __future__ import annotations

import numpy as np
from ..jit import njit

from ..model.kernels import gram_lower

_FM = {"reassoc", "contract"}  # reassociation lets numba vectorise the dot products; no NaN/inf flags


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def dot(a, b):
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
    n = A.shape[1]
    neq = A.shape[0]
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
        W = Fm.copy()
        cg = np.empty(0, dtype=np.int64)
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
        # the cones' rows in the basis Q, when they lie in its span (the neck: each cone's rows are a
        # rotation of its joint's force rows): then only [Q; A] enters the products with D^-1
        Ct = np.empty((3 * K, rf))
        inside = K > 0
        rrow = np.empty(n)
        for k in range(K):
            for e in range(3):
                if not _in_span(T[k, e], Q, 0, rf, Ct[3 * k + e], rrow, rank_tol):
                    inside = False
        if not inside:
            Ct = np.empty((0, rf))
    nB = rf + neq if inside else rf + 3 * K + neq
    # columns padded with zeros to a multiple of 8: the Gram products' loops then have no remainder
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
    M0inv = np.zeros((rf, rf))
    if ok:  # C block diagonal: so are M0 and its inverse (eight 3 x 3 blocks on the neck, not 24 x 24)
        X = np.empty((3, 3))
        for j in range(rf // 3):
            o = 3 * j
            # (C_j^T C_j)^-1 = C_j^-1 C_j^-T: no temporaries, and C_j's condition, not its square
            if _inv3(C[o:o + 3, o:o + 3], X) != 0.0:
                for a in range(3):
                    for b in range(3):
                        M0inv[o + a, o + b] = X[a, 0] * X[b, 0] + X[a, 1] * X[b, 1] + X[a, 2] * X[b, 2]
            else:
                _gram_inverse(C[o:o + 3, o:o + 3], 3, 3, M0inv[o:o + 3, o:o + 3])
    else:
        _gram_inverse(C, r, rf, M0inv)
    fold = _fold_blocks(ok and inside, rf, K, M0inv, Ct, cg)
    return B, rf, M0inv, Ct, cg, fold


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _inv3(M, out):
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
        det = _inv3(X, Cti[k])
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


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _gram(B, dinv, W, Km):
    """``Km <- B diag(dinv) B^T`` (lower triangle): two rows of ``B diag(dinv)`` (in ``W`` (2, nb), its
    padding columns zero) against four rows of ``B`` at a time (eight sums share six loads)."""
    rb, nb = B.shape
    n = dinv.shape[0]
    R0, R1 = W[0], W[1]
    for t in range(n, nb):
        R0[t] = 0.0
        R1[t] = 0.0
    i = 0
    while i < rb:
        two = i + 1 < rb
        Bi = B[i]
        for t in range(n):
            R0[t] = Bi[t] * dinv[t]
        if two:
            Bi1 = B[i + 1]
            for t in range(n):
                R1[t] = Bi1[t] * dinv[t]
        else:
            for t in range(n):
                R1[t] = 0.0
        j = 0
        while j + 3 <= i:
            B0, B1, B2, B3 = B[j], B[j + 1], B[j + 2], B[j + 3]
            s0, s1, s2, s3 = 0.0, 0.0, 0.0, 0.0
            u0, u1, u2, u3 = 0.0, 0.0, 0.0, 0.0
            for t in range(nb):
                a = R0[t]
                b = R1[t]
                x0, x1, x2, x3 = B0[t], B1[t], B2[t], B3[t]
                s0 += a * x0
                s1 += a * x1
                s2 += a * x2
                s3 += a * x3
                u0 += b * x0
                u1 += b * x1
                u2 += b * x2
                u3 += b * x3
            Km[i, j], Km[i, j + 1], Km[i, j + 2], Km[i, j + 3] = s0, s1, s2, s3
            if two:
                Km[i + 1, j], Km[i + 1, j + 1], Km[i + 1, j + 2], Km[i + 1, j + 3] = u0, u1, u2, u3
            j += 4
        while j <= i:
            Bj = B[j]
            s0, u0 = 0.0, 0.0
            for t in range(nb):
                s0 += R0[t] * Bj[t]
                u0 += R1[t] * Bj[t]
            Km[i, j] = s0
            if two:
                Km[i + 1, j] = u0
            j += 1
        if two:
            Bj = B[i + 1]
            u0 = 0.0
            for t in range(nb):
                u0 += R1[t] * Bj[t]
            Km[i + 1, i + 1] = u0
        i += 2


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy", inline="always")
def _qq_block(Kb, rf, KFF, Km):
    """``Q D^-1 Q^T`` from ``Kb``'s lower triangle into ``KFF`` (both triangles) and ``Km``'s."""
    for a in range(rf):
        for b in range(a + 1):
            KFF[a, b] = Kb[a, b]
            KFF[b, a] = Kb[a, b]
            Km[a, b] = Kb[a, b]


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _expand(Kb, rf, Ct, KFF, G1, Km):
    """``Km <-`` the reduced matrix's products for ``B = [Q; T; A]`` from those of ``[Q; A]`` in ``Kb``
    (``T = Ct Q``): ``T D^-1 Q^T = Ct (Q D^-1 Q^T)`` etc. (lower triangle; ``KFF`` (rf, rf) and ``G1``
    (3K, rf) work)."""
    m = Ct.shape[0]
    neq = Kb.shape[0] - rf
    _qq_block(Kb, rf, KFF, Km)
    for i in range(m):  # G1 = Ct KFF
        for b in range(rf):
            G1[i, b] = dot(Ct[i], KFF[b])
        for b in range(rf):
            Km[rf + i, b] = G1[i, b]
        for j in range(i + 1):
            Km[rf + i, rf + j] = dot(G1[i], Ct[j])
    for a in range(neq):
        KA = Kb[rf + a, :rf]
        for b in range(rf):
            Km[rf + m + a, b] = KA[b]
        for j in range(m):
            Km[rf + m + a, rf + j] = dot(KA, Ct[j])
        for b in range(a + 1):
            Km[rf + m + a, rf + m + b] = Kb[rf + a, rf + b]


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _expand_blocks(Kb, rf, Ct, cg, KFF, G1, Km):
    """:func:`_expand` for a block ``Ct`` (:func:`_grouped`: cone ``k``'s rows a 3x3 block ``X_k`` at
    columns ``cg[k]``): ``T D^-1 Q^T`` row by row as ``X_k`` times three rows of ``Q D^-1 Q^T``, and the
    cones' products with each other and with ``A`` through the 3x3 blocks (~6k multiply-adds on the
    neck's case 3 instead of ~35k)."""
    m = Ct.shape[0]
    K = m // 3
    neq = Kb.shape[0] - rf
    _qq_block(Kb, rf, KFF, Km)
    for k in range(K):  # G1 = Ct KFF
        g = cg[k]
        K0, K1, K2 = KFF[g], KFF[g + 1], KFF[g + 2]
        for e in range(3):
            i = 3 * k + e
            x0, x1, x2 = Ct[i, g], Ct[i, g + 1], Ct[i, g + 2]
            Gi = G1[i]
            Ki = Km[rf + i]
            for b in range(rf):
                v = x0 * K0[b] + x1 * K1[b] + x2 * K2[b]
                Gi[b] = v
                Ki[b] = v
    for i in range(m):  # Ct KFF Ct^T
        Gi = G1[i]
        Ki = Km[rf + i]
        for l in range((i // 3) + 1):
            g = cg[l]
            g0, g1, g2 = Gi[g], Gi[g + 1], Gi[g + 2]
            for f in range(3):
                j = 3 * l + f
                if j > i:
                    break
                Ki[rf + j] = g0 * Ct[j, g] + g1 * Ct[j, g + 1] + g2 * Ct[j, g + 2]
    for a in range(neq):
        KA = Kb[rf + a]
        Ka = Km[rf + m + a]
        for b in range(rf):
            Ka[b] = KA[b]
        for l in range(K):
            g = cg[l]
            k0, k1, k2 = KA[g], KA[g + 1], KA[g + 2]
            for f in range(3):
                j = 3 * l + f
                Ka[rf + j] = k0 * Ct[j, g] + k1 * Ct[j, g + 1] + k2 * Ct[j, g + 2]
        for b in range(a + 1):
            Ka[rf + m + b] = KA[rf + b]


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def factor(B, rf, M0inv, Ct, cg, fold, W2, dinv, drop_rel, work, Kb, Km, KFF, G1):
    """The Cholesky factor (lower) of the reduced matrix of the module docstring, in place in ``Km``
    ((p, p)); whether an equation was dropped. ``Kb`` ((rf + k_eq)^2 when the cones' rows are
    expanded, else ``Km`` itself), ``work`` (2, B's columns), ``KFF``, ``G1``: work arrays (made once
    per solve). ``fold``: :func:`_fold_blocks` (non-empty: the cones folded into their groups, ``Km``
    (rf + k_eq)^2, :func:`_fold_factor`)."""
    K = W2.shape[0]
    if fold[0].shape[0]:
        _gram(B, dinv, work, Km)
        _fold_factor(fold, W2, Km)
        dropped = chol_inplace(Km, drop_rel, rf)
        _invert_diagonal(Km)
        return dropped
    if Ct.shape[0]:
        _gram(B, dinv, work, Kb)
        if cg.shape[0]:
            _expand_blocks(Kb, rf, Ct, cg, KFF, G1, Km)
        else:
            _expand(Kb, rf, Ct, KFF, G1, Km)
    else:
        _gram(B, dinv, work, Km)
    for a in range(rf):
        for b in range(a + 1):
            Km[a, b] += M0inv[a, b]
    for k in range(K):
        o = rf + 3 * k
        for a in range(3):
            for b in range(a + 1):
                Km[o + a, o + b] += W2[k, a, b]
    dropped = chol_inplace(Km, drop_rel, rf + 3 * K)
    _invert_diagonal(Km)
    return dropped


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy", inline="always")
def _invert_diagonal(L):
    """``L``'s diagonal replaced by its inverse (what :func:`chol_solve_inplace` reads)."""
    for i in range(L.shape[0]):
        L[i, i] = 1.0 / L[i, i]


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _fold_factor(fold, W2, Km):
    """Add the groups' blocks of the folded system to ``Km``'s lower triangle: ``E_j`` (group ``j``'s
    block of ``M0^-1``) for a group without a cone, ``S_k = E_j (E_j + V_k)^-1 V_k`` with
    ``V_k = X_k^-1 W_k^2 X_k^-T`` (``X_k`` cone ``k``'s block of ``Ct``) for the group of cone ``k``;
    ``(E_j + V_k)^-1`` kept in ``fold[2][k]`` for :func:`solve`."""
    Cti, gk, Fk, Eb = fold
    V = np.empty((3, 3))
    Y = np.empty((3, 3))
    S = np.empty((3, 3))
    Z = np.empty((3, 3))
    for j in range(gk.shape[0]):
        o = 3 * j
        k = gk[j]
        E = Eb[j]
        if k < 0:
            for a in range(3):
                for b in range(a + 1):
                    Km[o + a, o + b] += E[a, b]
            continue
        X, W = Cti[k], W2[k]
        for a in range(3):  # Y = X^-1 W^2, V = Y X^-T
            for b in range(3):
                Y[a, b] = X[a, 0] * W[0, b] + X[a, 1] * W[1, b] + X[a, 2] * W[2, b]
        for a in range(3):
            for b in range(3):
                V[a, b] = Y[a, 0] * X[b, 0] + Y[a, 1] * X[b, 1] + Y[a, 2] * X[b, 2]
        for a in range(3):
            for b in range(3):
                Z[a, b] = E[a, b] + V[a, b]
        G = Fk[k]
        _inv3(Z, G)
        for a in range(3):  # Y = E (E + V)^-1, S = Y V
            for b in range(3):
                Y[a, b] = E[a, 0] * G[0, b] + E[a, 1] * G[1, b] + E[a, 2] * G[2, b]
        for a in range(3):
            for b in range(3):
                S[a, b] = Y[a, 0] * V[0, b] + Y[a, 1] * V[1, b] + Y[a, 2] * V[2, b]
        for a in range(3):
            for b in range(a + 1):
                Km[o + a, o + b] += 0.5 * (S[a, b] + S[b, a])


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _fold_solve(B, rf, cg, fold, LK, dinv, r1, r3, r2, u, rhs, dx, dy, dzc):
    """:func:`solve` for the folded system: ``[s; dy]`` from the reduced system with the right-hand
    side ``[Q D^-1 r1 + E (E + V)^-1 X^-1 r3; A D^-1 r1 - r2]``, then ``dx = D^-1 (r1 - Q^T s - A^T dy)``
    and each cone's ``dz_c = -X^-T (E + V)^-1 (E s_j + X^-1 r3)``."""
    Cti, gk, Fk, Eb = fold
    n = r1.shape[0]
    K = r3.shape[0]
    p = LK.shape[0]
    neq = p - rf
    for t in range(n):
        u[t] = dinv[t] * r1[t]
    rows_dot(B, 0, p, u, rhs, 0)
    for a in range(neq):
        rhs[rf + a] -= r2[a]
    for k in range(K):
        g = cg[k]
        X, G, E = Cti[k], Fk[k], Eb[g // 3]
        t0 = X[0, 0] * r3[k, 0] + X[0, 1] * r3[k, 1] + X[0, 2] * r3[k, 2]
        t1 = X[1, 0] * r3[k, 0] + X[1, 1] * r3[k, 1] + X[1, 2] * r3[k, 2]
        t2 = X[2, 0] * r3[k, 0] + X[2, 1] * r3[k, 1] + X[2, 2] * r3[k, 2]
        h0 = G[0, 0] * t0 + G[0, 1] * t1 + G[0, 2] * t2
        h1 = G[1, 0] * t0 + G[1, 1] * t1 + G[1, 2] * t2
        h2 = G[2, 0] * t0 + G[2, 1] * t1 + G[2, 2] * t2
        for a in range(3):
            rhs[g + a] += E[a, 0] * h0 + E[a, 1] * h1 + E[a, 2] * h2
    chol_solve_inplace(LK, rhs)
    for t in range(n):
        dx[t] = r1[t]
    rows_axpy(B, 0, p, rhs, 0, -1.0, dx)
    for t in range(n):
        dx[t] *= dinv[t]
    for a in range(neq):
        dy[a] = rhs[rf + a]
    for k in range(K):
        g = cg[k]
        X, G, E = Cti[k], Fk[k], Eb[g // 3]
        s0, s1, s2 = rhs[g], rhs[g + 1], rhs[g + 2]
        r0, r1_, r2_ = r3[k, 0], r3[k, 1], r3[k, 2]
        v0 = E[0, 0] * s0 + E[0, 1] * s1 + E[0, 2] * s2 + X[0, 0] * r0 + X[0, 1] * r1_ + X[0, 2] * r2_
        v1 = E[1, 0] * s0 + E[1, 1] * s1 + E[1, 2] * s2 + X[1, 0] * r0 + X[1, 1] * r1_ + X[1, 2] * r2_
        v2 = E[2, 0] * s0 + E[2, 1] * s1 + E[2, 2] * s2 + X[2, 0] * r0 + X[2, 1] * r1_ + X[2, 2] * r2_
        w0 = G[0, 0] * v0 + G[0, 1] * v1 + G[0, 2] * v2
        w1 = G[1, 0] * v0 + G[1, 1] * v1 + G[1, 2] * v2
        w2 = G[2, 0] * v0 + G[2, 1] * v1 + G[2, 2] * v2
        for e in range(3):  # dz_c = -X^-T w'
            dzc[k, e] = -(X[0, e] * w0 + X[1, e] * w1 + X[2, e] * w2)


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def solve(B, rf, Ct, cg, fold, LK, dinv, r1, r3, r2, u, rhs, wq, dx, dy, dzc):
    """``(dx, dy, dzc)`` (written in place) of ``(D + F^T F) dx + A^T dy - T^T dzc = r1``,
    ``A dx = r2``, ``-T dx - W^2 dzc = r3`` (``r3`` (K, 3)) from :func:`factor`'s factor; ``u`` (n,),
    ``rhs`` (p,), ``wq`` (rf,): work arrays."""
    if fold[0].shape[0]:
        _fold_solve(B, rf, cg, fold, LK, dinv, r1, r3, r2, u, rhs, dx, dy, dzc)
        return
    n = r1.shape[0]
    K = r3.shape[0]
    m = 3 * K
    p = LK.shape[0]
    nw = rf + m
    neq = p - nw
    for t in range(n):
        u[t] = dinv[t] * r1[t]
    inside = Ct.shape[0] > 0
    if inside:  # B = [Q; A]
        rows_dot(B, 0, rf, u, rhs, 0)
        rows_dot(B, rf, rf + neq, u, rhs, nw)
        if cg.shape[0]:
            for i in range(m):
                g = cg[i // 3]
                rhs[rf + i] = Ct[i, g] * rhs[g] + Ct[i, g + 1] * rhs[g + 1] + Ct[i, g + 2] * rhs[g + 2]
        else:
            for i in range(m):
                rhs[rf + i] = dot(Ct[i], rhs[:rf])
    else:  # B = [Q; T; A]: its rows are the unknowns'
        rows_dot(B, 0, p, u, rhs, 0)
    for a in range(neq):
        rhs[nw + a] -= r2[a]
    for k in range(K):
        for e in range(3):
            rhs[rf + 3 * k + e] += r3[k, e]
    chol_solve_inplace(LK, rhs)
    for t in range(n):
        dx[t] = r1[t]
    if inside:
        for i in range(rf):
            wq[i] = rhs[i]
        if cg.shape[0]:
            for i in range(m):
                g = cg[i // 3]
                si = rhs[rf + i]
                wq[g] += si * Ct[i, g]
                wq[g + 1] += si * Ct[i, g + 1]
                wq[g + 2] += si * Ct[i, g + 2]
        else:
            for i in range(m):
                axpy(rhs[rf + i], Ct[i], wq)
        rows_axpy(B, 0, rf, wq, 0, -1.0, dx)
        rows_axpy(B, rf, rf + neq, rhs, nw, -1.0, dx)
    else:
        rows_axpy(B, 0, p, rhs, 0, -1.0, dx)
    for t in range(n):
        dx[t] *= dinv[t]
    for k in range(K):
        for e in range(3):
            dzc[k, e] = -rhs[rf + 3 * k + e]
    for a in range(neq):
        dy[a] = rhs[nw + a]


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def apply_P(x, d0, Fm, out, fx):
    """``out <- P x = d0 x + F^T F x`` (``fx`` (r,): work, ``F x``)."""
    for t in range(x.shape[0]):
        out[t] = d0[t] * x[t]
    rows_dot(Fm, 0, Fm.shape[0], x, fx, 0)
    rows_axpy(Fm, 0, Fm.shape[0], fx, 0, 1.0, out)


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def refine(B, rf, Ct, cg, fold, LK, dinv, dbar, Fm, T, W2, A, r1, r3, r2, dx, dy, dzc, steps, u, rhs, wq):
    """``steps`` rounds of iterative refinement of ``(dx, dy, dzc)`` against the exact operators of
    :func:`solve`'s system (``dbar``: ``d0`` plus the barrier diagonal, without the floor; ``u``,
    ``rhs``, ``wq``: :func:`solve`'s work arrays)."""
    K = T.shape[0]
    Pdx = np.empty(dx.shape[0])
    fx = np.empty(Fm.shape[0])
    cx = np.empty(dx.shape[0])
    cy = np.empty(dy.shape[0])
    cz = np.empty((K, 3))
    for _ in range(steps):
        apply_P(dx, dbar, Fm, Pdx, fx)
        e1 = r1 - Pdx
        for a in range(A.shape[0]):
            if dy[a] != 0.0:
                axpy(-dy[a], A[a], e1)
        e3 = r3.copy()
        for k in range(K):
            for e in range(3):
                axpy(dzc[k, e], T[k, e], e1)
                e3[k, e] += dot(T[k, e], dx) + W2[k, e, 0] * dzc[k, 0] + W2[k, e, 1] * dzc[k, 1] + \
                    W2[k, e, 2] * dzc[k, 2]
        e2 = r2.copy()
        for a in range(A.shape[0]):
            e2[a] -= dot(A[a], dx)
        solve(B, rf, Ct, cg, fold, LK, dinv, e1, e3, e2, u, rhs, wq, cx, cy, cz)
        axpy(1.0, cx, dx)
        axpy(1.0, cy, dy)
        for k in range(K):
            for e in range(3):
                dzc[k, e] += cz[k, e]
