r"""The Newton system of the compiled interior-point method (:mod:`._ipm`), factored and solved once per
iteration through the problem's structure (made once per solve by :mod:`._ipm_structure`).

Each Newton step solves, with the bounds' multipliers eliminated and the cones' ``dz_c`` kept,

.. math:: (D + F^T F)\,dx + A^T dy - T^T dz_c = r_1, \qquad A\,dx = r_2, \qquad
          -T\,dx - W^2 dz_c = r_3,

``D`` diagonal (the objective's diagonal ``d0`` plus the bounds' barrier terms ``z/s``), ``F`` the
objective's factor (``P = diag(d0) + F^T F``: the interaction objective's weighted wrench rows), ``T``
the cones' rows and ``W^2 = blockdiag(W_k^2)`` their Nesterov-Todd scaling.

**Once per solve** (:func:`._ipm_structure.structure`): modified Gram-Schmidt with pivoting turns the rows of ``F``
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

**The block basis** (:func:`._ipm_structure._grouped`, tried first): when ``F``'s rows come in groups of three (the
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

**Cones folded into their groups** (:func:`._ipm_structure._fold_blocks`, :func:`_fold_factor`, :func:`_fold_solve`):
with the block basis, when each group holds at most one cone and each cone's block ``X_k`` of ``C_t``
is invertible (the neck's case 3: ``T_k = X_k Q_j``, ``X_k`` the cone's rotation of its joint's force
rows), the cone's unknowns share their group's three directions: with ``w' = X^T w_T`` only
``s = w_F + w'`` reaches ``dx``, and the difference of a group's force and cone rows,
``E w_F - V w' = -X^-1 r_3`` (``E`` the group's block of ``M_0^{-1}``, ``V = X^-1 W^2 X^-T``), leaves

.. math:: w' = (E + V)^{-1} (E s + X^{-1} r_3), \qquad
          S = E (E + V)^{-1} V \ \text{in place of}\ E \ \text{on the group's diagonal block},

a system in ``(s, dy)`` of size ``rf + k_eq`` (48 instead of 72 on the neck: its Cholesky factor ~3x
cheaper, the solves' triangular parts ~2x, no products of the cone rows to form; docs/speed.md,
"Fourth pass"). No ``W^-2`` is formed: ``S`` is the
parallel sum of ``E`` and ``V``, bounded by both, small where the cone is active (``V`` small), and
``E + V >= E`` is as well conditioned as ``M_0``. The directions equal the expanded system's to 1e-9
(``tests/test_warm_fast.py::test_folded_cones_give_the_expanded_systems_directions``, down to a cone
held at a gap of 1e-10).

A dependent equation (``A`` losing rank: the 2-link arm at q = 0) shows as a pivot at rounding level
and is dropped (its multiplier set to zero); :func:`refine` then corrects against the exact operators.
Rounding level is judged row by row, against the row's own diagonal entry
(:func:`._ipm_linalg.chol_inplace`), and only the equations' rows are ever dropped. Against the largest
diagonal entry of the whole matrix (as before), the ``M_0^{-1}`` block decided: where ``F`` is nearly
rank deficient (generated robots without a diagonal weight, ``d_0 = 0``: ``F``'s singular values from 4
down to 5e-7, or rounding noise of 1e-16 taken for a direction) its entries reach 1e12-1e36, and every
equation's pivot (of order ``A (D + P)^{-1} A^T``) fell below 1e-14 of that: all equations dropped, ``dy
= 0``, the primal residual never fell, and the step vanished after 6-7 iterations or the iterations ran
out (9 of the 100 instants of the property test; Clarabel answered them). """

from __future__ import annotations

import numpy as np
from ..jit import njit

from ._ipm_linalg import axpy, chol_inplace, chol_solve_inplace, dot, inv3, rows_axpy, rows_dot

_FM = {"reassoc", "contract"}  # reassociation lets numba vectorise the dot products; no NaN/inf flags


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def gram_plan(B, n):
    """How :func:`_gram` reads ``B`` (the reduced system's rows over ``n`` variables, its columns
    padded with zeros): ``(Bg, cols, srow, scol, sval)``, made once per solve. A column of ``B`` with
    one nonzero entry adds to one diagonal entry of ``B D^-1 B^T`` only (an actuator's torque,
    weighted on its own, in its coordinate's row of the equation of motion: 22 of the 85 variables
    of MyoSuite's arm), a zero column adds nothing. ``Bg`` holds the other columns (``cols``: their
    indices in ``B``), padded with zero columns to a multiple of 8, and ``(srow, scol, sval)`` the
    single entries' rows, columns and values. ``Bg`` is ``B`` itself when every column has two
    nonzero entries or more."""
    rb = B.shape[0]
    nnz = np.zeros(n, dtype=np.int64)
    for i in range(rb):
        Bi = B[i]
        for t in range(n):
            nnz[t] += 1 if Bi[t] != 0.0 else 0
    nd, ns = 0, 0
    for t in range(n):
        if nnz[t] >= 2:
            nd += 1
        elif nnz[t] == 1:
            ns += 1
    srow, scol, sval = np.empty(ns, dtype=np.int64), np.empty(ns, dtype=np.int64), np.empty(ns)
    if nd == n:
        return B, np.arange(n), srow, scol, sval
    Bg = np.zeros((rb, (nd + 7) // 8 * 8))
    cols = np.empty(nd, dtype=np.int64)
    d, s = 0, 0
    for t in range(n):
        if nnz[t] >= 2:
            cols[d] = t
            for i in range(rb):
                Bg[i, d] = B[i, t]
            d += 1
        elif nnz[t] == 1:
            for i in range(rb):
                if B[i, t] != 0.0:
                    srow[s], scol[s], sval[s] = i, t, B[i, t]
            s += 1
    return Bg, cols, srow, scol, sval


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _gram(plan, dinv, W, Km):
    """``Km <- B diag(dinv) B^T`` (lower triangle) from :func:`gram_plan`'s ``plan``: two rows of
    ``Bg diag(dinv)`` (in ``W`` (2, at least Bg's columns), its padding columns zero) against four
    rows of ``Bg`` at a time (eight sums share six loads), then the single entries on the diagonal."""
    Bg, cols, srow, scol, sval = plan
    rb, nb = Bg.shape
    n = cols.shape[0]
    R0, R1 = W[0], W[1]
    for t in range(n, nb):
        R0[t] = 0.0
        R1[t] = 0.0
    i = 0
    while i < rb:
        two = i + 1 < rb
        Bi = Bg[i]
        for t in range(n):
            R0[t] = Bi[t] * dinv[cols[t]]
        if two:
            Bi1 = Bg[i + 1]
            for t in range(n):
                R1[t] = Bi1[t] * dinv[cols[t]]
        else:
            for t in range(n):
                R1[t] = 0.0
        j = 0
        while j + 3 <= i:
            B0, B1, B2, B3 = Bg[j], Bg[j + 1], Bg[j + 2], Bg[j + 3]
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
            Bj = Bg[j]
            s0, u0 = 0.0, 0.0
            for t in range(nb):
                s0 += R0[t] * Bj[t]
                u0 += R1[t] * Bj[t]
            Km[i, j] = s0
            if two:
                Km[i + 1, j] = u0
            j += 1
        if two:
            Bj = Bg[i + 1]
            u0 = 0.0
            for t in range(nb):
                u0 += R1[t] * Bj[t]
            Km[i + 1, i + 1] = u0
        i += 2
    for q in range(srow.shape[0]):
        Km[srow[q], srow[q]] += sval[q] * sval[q] * dinv[scol[q]]


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
def factor(gram, rf, M0inv, Ct, cg, fold, W2, dinv, drop_rel, work, Kb, Km, KFF, G1):
    """The Cholesky factor (lower) of the reduced matrix of the module docstring, in place in ``Km``
    ((p, p)); whether an equation was dropped. ``gram``: :func:`gram_plan` of the rows ``B``. ``Kb``
    ((rf + k_eq)^2 when the cones' rows are expanded, else ``Km`` itself), ``work`` (2, B's columns),
    ``KFF``, ``G1``: work arrays (made once per solve). ``fold``: :func:`_fold_blocks` (non-empty: the
    cones folded into their groups, ``Km`` (rf + k_eq)^2, :func:`_fold_factor`)."""
    K = W2.shape[0]
    if fold[0].shape[0]:
        _gram(gram, dinv, work, Km)
        _fold_factor(fold, W2, Km)
        dropped = chol_inplace(Km, drop_rel, rf)
        _invert_diagonal(Km)
        return dropped
    if Ct.shape[0]:
        _gram(gram, dinv, work, Kb)
        if cg.shape[0]:
            _expand_blocks(Kb, rf, Ct, cg, KFF, G1, Km)
        else:
            _expand(Kb, rf, Ct, KFF, G1, Km)
    else:
        _gram(gram, dinv, work, Km)
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
        inv3(Z, G)
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
    rows_dot(B, np.int64(0), p, u, rhs, np.int64(0))
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
    rows_axpy(B, np.int64(0), p, rhs, np.int64(0), -1.0, dx)
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
def solve(system, dinv, r1, r3, r2, u, rhs, wq, dx, dy, dzc):
    """``(dx, dy, dzc)`` (written in place) of ``(D + F^T F) dx + A^T dy - T^T dzc = r1``,
    ``A dx = r2``, ``-T dx - W^2 dzc = r3`` (``r3`` (K, 3)) from :func:`factor`'s factor (``system``:
    a :class:`._structs.NewtonSystem`); ``u`` (n,), ``rhs`` (p,), ``wq`` (rf,): work arrays."""
    B, rf, Ct, cg, fold, LK = system.B, system.rf, system.Ct, system.cg, system.fold, system.LK
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
        rows_dot(B, np.int64(0), rf, u, rhs, np.int64(0))
        rows_dot(B, rf, rf + neq, u, rhs, nw)
        if cg.shape[0]:
            for i in range(m):
                g = cg[i // 3]
                rhs[rf + i] = Ct[i, g] * rhs[g] + Ct[i, g + 1] * rhs[g + 1] + Ct[i, g + 2] * rhs[g + 2]
        else:
            for i in range(m):
                rhs[rf + i] = dot(Ct[i], rhs[:rf])
    else:  # B = [Q; T; A]: its rows are the unknowns'
        rows_dot(B, np.int64(0), p, u, rhs, np.int64(0))
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
        rows_axpy(B, np.int64(0), rf, wq, np.int64(0), -1.0, dx)
        rows_axpy(B, rf, rf + neq, rhs, nw, -1.0, dx)
    else:
        rows_axpy(B, np.int64(0), p, rhs, np.int64(0), -1.0, dx)
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
    rows_dot(Fm, np.int64(0), Fm.shape[0], x, fx, np.int64(0))
    rows_axpy(Fm, np.int64(0), Fm.shape[0], fx, np.int64(0), 1.0, out)


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def refine(system, scaling, r1, r3, r2, dx, dy, dzc, steps, u, rhs, wq):
    """``steps`` rounds of iterative refinement of ``(dx, dy, dzc)`` against the exact operators of
    :func:`solve`'s ``system`` (``scaling``: a :class:`._structs.Scaling`, whose ``dbar`` is ``d0``
    plus the barrier diagonal, without the floor; ``u``, ``rhs``, ``wq``: :func:`solve`'s work
    arrays)."""
    Fm, T, A = system.F, system.T, system.A
    dinv, dbar, W2 = scaling.dinv, scaling.dbar, scaling.W2
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
        solve(system, dinv, e1, e3, e2, u, rhs, wq, cx, cy, cz)
        axpy(1.0, cx, dx)
        axpy(1.0, cy, dy)
        for k in range(K):
            for e in range(3):
                dzc[k, e] += cz[k, e]
