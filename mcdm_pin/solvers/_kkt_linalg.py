r"""The small dense solves of the compiled active-set solver (:mod:`._kkt`): the KKT system of one
active set by LU, at a vertex through its rows alone, with dependent rows by a Cholesky of the
normal matrix, and by least squares otherwise.

At these sizes (a KKT system of ~50 unknowns on the neck) plain loops beat calls into LAPACK or
BLAS, whose copies and per-call overhead cost more than the arithmetic.
"""

from __future__ import annotations

import numpy as np
from ..jit import njit

from ._ipm_linalg import chol_inplace, chol_solve_inplace, dot


@njit(cache=True, nogil=True)
def lu_solve(K, rhs):
    """``K x = rhs`` by LU with partial pivoting (:func:`lu_factor`, then :func:`lu_apply`): LAPACK's
    ``dgesv`` without the copies to Fortran order that ``np.linalg.solve`` makes, 3x faster at these
    sizes. Returns ``(x, ok)``; ``ok`` false when a pivot is exactly zero or not finite."""
    LU, perm, ok = lu_factor(K)
    if not ok:
        return rhs.copy(), False
    return lu_apply(LU, perm, rhs), True


@njit(cache=True, nogil=True)
def kkt_solve(K, rhs, nf, square):
    """``K x = rhs`` (``K = [[Hxx, R^T], [R, 0]]``, ``nf`` unknowns before the rows ``R``) by LU when
    ``square``; otherwise, or where the LU meets an exactly zero pivot, NaNs when
    :func:`rows_inconsistent` finds the rows inconsistent beyond what least squares passes, else
    least squares (:func:`lstsq_solve`: NaNs unless its residual is at rounding level, a singular,
    inconsistent system)."""
    if square:
        sol, ok = lu_solve(K, rhs)
        if ok:
            ok = np.all(np.isfinite(sol))
        if ok:
            return sol
    if rows_inconsistent(K, rhs, nf):
        return np.full(K.shape[0], np.nan)
    return lstsq_solve(K, rhs)


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _row_gram(K, nf):
    """The lower triangle of ``R^T R`` for the rows ``R = K[nf:, :nf]``."""
    Nm = np.zeros((nf, nf))
    for i in range(K.shape[0] - nf):
        Ri = K[nf + i]
        for a in range(nf):
            ra = Ri[a]
            if ra != 0.0:
                for b in range(a + 1):
                    Nm[a, b] += ra * Ri[b]
    return Nm


@njit(cache=True, nogil=True)
def _beyond_lstsq(worst, m, rhs):
    """Whether ``m`` rows whose least-squares point misses one by ``worst`` are inconsistent beyond
    what :func:`lstsq_solve` passes: no ``x'`` meets every row within ``1e-10 max(1, max|rhs|)``
    then (``|R x' - r_c|_inf >= |R x - r_c|_2 / sqrt(m) >= worst / sqrt(m)``)."""
    full = 1.0
    for i in range(rhs.shape[0]):
        full = max(full, abs(rhs[i]))
    return worst > np.sqrt(m) * 1e-10 * full


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def rows_inconsistent(K, rhs, nf):
    """Whether the rows ``R x = r_c`` of ``K = [[Hxx, R^T], [R, 0]]`` (``R = K[nf:, :nf]``) are
    inconsistent beyond what :func:`lstsq_solve` passes (:func:`_rows_miss`), from a Cholesky of
    ``R^T R`` that drops a pivot at or below ``1e-12`` of the largest diagonal entry (a dependent
    column: :func:`chol_lower`). A singular KKT system of a wrong active-set guess (a crossover's,
    on large chains: docs/speed.md) is rejected so without an SVD of ``K``, whose cost is several
    of its LUs."""
    if K.shape[0] == nf:
        return False
    Nm = _row_gram(K, nf)
    keep = np.ones(nf, dtype=np.bool_)
    chol_lower(Nm, nf, 1e-12 * _max_diagonal(Nm), keep)
    return _rows_miss(K, rhs, nf, Nm, keep)


@njit(cache=True, nogil=True)
def _max_diagonal(M):
    scale = 1e-300
    for a in range(M.shape[0]):
        scale = max(scale, M[a, a])
    return scale


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _rows_miss(K, rhs, nf, L, keep):
    """Whether the rows of ``K`` (:func:`rows_inconsistent`) miss beyond what :func:`lstsq_solve`
    passes at their least-squares point: ``R^T R x = R^T r_c`` through ``L``, the factor of ``R^T R``
    with the dependent columns dropped (``keep`` false: their unknowns zero, the others' point still
    a least-squares one), with one step of refinement (:func:`_beyond_lstsq`)."""
    m = K.shape[0] - nf
    x = np.zeros(nf)
    res = rhs[nf:].copy()
    worst = 0.0
    for _ in range(2):  # the point, then one step of refinement on its residual
        v = np.zeros(nf)
        for i in range(m):
            ri = res[i]
            for a in range(nf):
                v[a] += K[nf + i, a] * ri
        for a in range(nf):
            if not keep[a]:
                v[a] = 0.0  # (chol_apply passes a dropped unknown through: zero)
        x += chol_apply(L, v)
        worst = 0.0
        for i in range(m):
            acc = rhs[nf + i]
            for a in range(nf):
                acc -= K[nf + i, a] * x[a]
            res[i] = acc
            worst = max(worst, abs(acc))
    return _beyond_lstsq(worst, m, rhs)


@njit(cache=True, nogil=True)
def schur_solve(K, rhs, nf):
    """``K x = rhs`` for ``K = [[D, C^T], [C, 0]]`` whose block ``D`` of the ``nf`` free variables is
    diagonal (a separable objective such as ``f^T f`` or the activations', without a held cone's
    curvature): the rows' multipliers from the Schur complement ``S = C D^-1 C^T`` by Cholesky, then
    ``x_F = D^-1 (r_1 - C^T lam)``, and one step of iterative refinement on the whole system. For
    ``m`` rows that is ``m^2 nf / 2 + m^3 / 6`` multiply-adds where an LU of the whole system takes
    ``(nf + m)^3 / 3``: at 96 DoF and 288 cables about 20 times fewer.

    A dependent row (a pivot of ``S`` at or below ``1e-12`` of its diagonal entry) has its multiplier
    set to zero; the system is then consistent only if the residual of every row is at rounding
    level (:func:`_nan_unless_consistent`, the test :func:`lstsq_solve` makes too), and otherwise
    ``x`` is NaN (a singular, inconsistent system).

    Returns ``(x, ok)``; ``ok`` false (the caller then solves the whole system by LU) when ``D`` has
    an entry off its diagonal or a diagonal entry not above ``1e-8`` of the largest."""
    N = K.shape[0]
    m = N - nf
    x = np.empty(N)
    dmax = 0.0
    for i in range(nf):
        for j in range(nf):
            if j != i and K[i, j] != 0.0:
                return x, False
        dmax = max(dmax, K[i, i])
    if not dmax > 0.0:
        return x, False
    dinv = np.empty(nf)
    for i in range(nf):
        if not K[i, i] > 1e-8 * dmax:
            return x, False
        dinv[i] = 1.0 / K[i, i]
    C = np.empty((m, nf))
    W = np.empty((m, nf))  # C D^-1
    for r in range(m):
        for p in range(nf):
            C[r, p] = K[nf + r, p]
            W[r, p] = K[nf + r, p] * dinv[p]
    L = np.zeros((m, m))
    for r in range(m):
        for q in range(r + 1):
            L[r, q] = dot(W[r], C[q])
    chol_inplace(L, 1e-12, np.int64(0))
    for j in range(m):  # (chol_solve_inplace takes the pivots' inverses)
        L[j, j] = 1.0 / L[j, j]
    _schur_apply(C, W, dinv, L, rhs, nf, x)
    res = rhs.copy()
    for i in range(N):
        res[i] -= dot(K[i], x)
    dx = np.empty(N)
    _schur_apply(C, W, dinv, L, res, nf, dx)
    for i in range(N):
        x[i] += dx[i]
    _nan_unless_consistent(K, x, rhs)
    return x, True


@njit(cache=True, nogil=True)
def _schur_apply(C, W, dinv, L, rhs, nf, out):
    """:func:`schur_solve`'s solution for the right-hand side ``rhs`` into ``out`` (``L`` the
    complement's Cholesky factor with its pivots' inverses on the diagonal, ``W = C D^-1``)."""
    m = C.shape[0]
    lam = np.empty(m)
    for r in range(m):
        t = -rhs[nf + r]
        for p in range(nf):
            t += W[r, p] * rhs[p]
        lam[r] = t
    chol_solve_inplace(L, lam)
    for p in range(nf):
        t = rhs[p]
        for r in range(m):
            t -= C[r, p] * lam[r]
        out[p] = dinv[p] * t
    for r in range(m):
        out[nf + r] = lam[r]


@njit(cache=True, nogil=True)
def lstsq_solve(K, rhs):
    """``K x = rhs`` by least squares; NaNs unless the residual is at rounding level (a singular,
    inconsistent system)."""
    sol = np.linalg.lstsq(K, rhs)[0]
    _nan_unless_consistent(K, sol, rhs)
    return sol


@njit(cache=True, nogil=True)
def _nan_unless_consistent(K, sol, rhs):
    """``sol`` set to NaN (in place) unless every residual of ``K sol = rhs`` is at rounding level:
    below ``1e-10`` of the right-hand side's largest entry, at least 1 (a singular, inconsistent
    system otherwise)."""
    scale = 1.0
    for i in range(rhs.shape[0]):
        scale = max(scale, abs(rhs[i]))
    r = K @ sol - rhs
    for i in range(rhs.shape[0]):
        if not abs(r[i]) <= 1e-10 * scale:
            sol[:] = np.nan
            break


@njit(cache=True, nogil=True)
def vertex_solve(K, rhs, nf, square):
    """``K = [[Hxx, R^T], [R, 0]]`` with a square ``R`` (nf x nf: at a vertex, as many free variables
    as equations and held cone surfaces, the usual warm instant): ``x`` is fixed by the rows alone,
    ``R x = r_c``, and the multipliers by ``R^T l = r_x - Hxx x``: one LU of ``R`` (nf unknowns)
    instead of one of ``K`` (2 nf: 8x the arithmetic). Falls back to :func:`kkt_solve` when ``R``
    is singular (then so is ``K``)."""
    return vertex_solve_lu(K, rhs, nf, square)[0]


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def vertex_solve_lu(K, rhs, nf, square):
    """:func:`vertex_solve`, also returning ``R``'s factors ``(LU, perm, ok)`` (:func:`lu_factor`;
    ``ok`` false when the solution did not come from them): the ratio test of the next pivot solves
    with ``R^T`` again (:func:`._kkt._ratio_test`)."""
    N = K.shape[0]
    R = np.empty((nf, nf))
    for i in range(nf):
        for j in range(nf):
            R[i, j] = K[nf + i, j]
    LU, perm, ok = lu_factor(R)
    if not ok:
        return kkt_solve(K, rhs, nf, square), LU, perm, False
    if _rounding_pivot(LU):
        # rows dependent but for rounding (free cables along one line: the neck's pitch, case 1, at
        # its optimum's own active set): the vertex's point is noise and fails the check at the
        # right active set. Where the free block is diagonal, the rows' Schur complement drops the
        # dependent rows and solves the system, or finds it inconsistent; then, and where the block
        # is not diagonal, the vertex's point stands (a wrong guess's noise still says which cables
        # to exchange: docs/speed.md, "A vertex's dependent rows")
        alt, diagonal = schur_solve(K, rhs, nf)
        if diagonal and np.all(np.isfinite(alt)):
            return alt, LU, perm, False
    x = lu_apply(LU, perm, rhs[nf:])
    w = np.empty(nf)
    for a in range(nf):
        acc = rhs[a]
        for b in range(nf):
            acc -= K[a, b] * x[b]
        w[a] = acc
    lam = lu_apply_t(LU, perm, w)
    sol = np.empty(N)
    for i in range(nf):
        sol[i] = x[i]
        sol[nf + i] = lam[i]
    for i in range(N):
        if not np.isfinite(sol[i]):
            return kkt_solve(K, rhs, nf, square), LU, perm, False
    return sol, LU, perm, True


@njit(cache=True, nogil=True)
def _rounding_pivot(LU):
    """Whether a pivot of the factors ``LU`` (:func:`lu_factor`) is at or below ``1e-13`` of the largest
    one: the rounding of a zero, many decades below a healthy pivot (docs/speed.md, "A vertex's
    dependent rows", says where each kind sits). The pivots alone, not the matrix's entries: a pass
    over those costs about a seventh of the LU itself."""
    n = LU.shape[0]
    big = 0.0
    for k in range(n):
        big = max(big, abs(LU[k, k]))
    for k in range(n):
        if abs(LU[k, k]) <= 1e-13 * big:
            return True
    return False


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def lu_factor(R):
    """``R[perm] = L U`` by partial pivoting (L unit lower, both in one array). Returns
    ``(LU, perm, ok)``; ``ok`` false when a pivot is exactly zero or not finite.

    Right-looking, in panels of four columns: each panel is factored column by column (its updates
    kept to the panel), its rows of ``U`` right of it follow by forward substitution, and the rows
    below take the four columns' updates in one pass (:func:`_trailing4`), so each trailing entry is
    loaded and stored once per panel instead of once per column. Every entry receives the same
    operations in the same order as column-by-column elimination, so the factors are the same to
    the bit; a 59 x 59 system (a warm frame of MyoSuite's arm) factors about a fifth faster, one of
    100 to 250 unknowns about 1.7x (docs/speed.md)."""
    n = R.shape[0]
    M = R.copy()
    perm = np.arange(n)
    for k0 in range(0, n, 4):
        k1 = min(k0 + 4, n)
        for k in range(k0, k1):  # the panel: its pivots, its columns' multipliers and updates
            p = k
            big = abs(M[k, k])
            for i in range(k + 1, n):
                v = abs(M[i, k])
                if v > big:
                    big, p = v, i
            if not (big > 0.0) or not np.isfinite(big):
                return M, perm, False
            if p != k:
                for j in range(n):
                    M[k, j], M[p, j] = M[p, j], M[k, j]
                perm[k], perm[p] = perm[p], perm[k]
            inv = 1.0 / M[k, k]
            for i in range(k + 1, n):
                l = M[i, k] * inv
                M[i, k] = l
                if l != 0.0:
                    for j in range(k + 1, k1):
                        M[i, j] -= l * M[k, j]
        for k in range(k0, k1):  # the panel's rows of U right of it
            for i in range(k + 1, k1):
                l = M[i, k]
                if l != 0.0:
                    _axpy(-l, M[k, k1:], M[i, k1:])
        if k1 - k0 == 4:
            _trailing4(M, k0, k1, n)
        else:  # (the last, narrower panel)
            for i in range(k1, n):
                _columnwise(M, k0, k1, i)
    return M, perm, True


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"}, inline="always")
def _trailing4(M, k0, k1, n):
    """Rows and columns ``k1:`` of ``M`` less the four panel columns' products ``L[:, k0:k1]
    U[k0:k1, :]``, subtracted one after the other as four column eliminations would (no sum
    reassociated: each entry's differences are taken left to right). A row with a zero multiplier
    skips that column's update, as column elimination does (a zero's sign stays as it was)."""
    U0, U1, U2, U3 = M[k0, k1:], M[k0 + 1, k1:], M[k0 + 2, k1:], M[k0 + 3, k1:]
    for i in range(k1, n):
        l0, l1, l2, l3 = M[i, k0], M[i, k0 + 1], M[i, k0 + 2], M[i, k0 + 3]
        row = M[i, k1:]
        if l0 != 0.0 and l1 != 0.0 and l2 != 0.0 and l3 != 0.0:
            for j in range(row.shape[0]):
                row[j] = row[j] - l0 * U0[j] - l1 * U1[j] - l2 * U2[j] - l3 * U3[j]
        else:
            _columnwise(M, k0, k1, i)


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"}, inline="always")
def _columnwise(M, k0, k1, i):
    """Row ``i`` of ``M``, columns ``k1:``, less the panel columns' updates one column at a time, a
    zero multiplier's skipped (:func:`lu_factor`)."""
    row = M[i, k1:]
    for t in range(k0, k1):
        l = M[i, t]
        if l != 0.0:
            _axpy(-l, M[t, k1:], row)


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"}, inline="always")
def _axpy(a, x, y):
    """``y += a x`` over slices (a loop from 0 over ``range(len)``: numba then knows the index is not
    negative and vectorises it; the loop ``for j in range(k + 1, n)`` it replaces did not, 2x slower
    for the 49 x 49 KKT systems of the crossover). Inlined, unlike :func:`._ipm_linalg.axpy`: called
    once per row, a call costs about what the row's arithmetic does at these sizes."""
    for t in range(x.shape[0]):
        y[t] += a * x[t]


@njit(cache=True, nogil=True)
def lu_apply(LU, perm, b):
    """``R^-1 b`` from :func:`lu_factor`."""
    n = LU.shape[0]
    y = np.empty(n)
    for i in range(n):
        acc = b[perm[i]]
        for k in range(i):
            acc -= LU[i, k] * y[k]
        y[i] = acc
    for i in range(n - 1, -1, -1):
        acc = y[i]
        for k in range(i + 1, n):
            acc -= LU[i, k] * y[k]
        y[i] = acc / LU[i, i]
    return y


@njit(cache=True, nogil=True)
def lu_apply_t(LU, perm, c):
    """``R^-T c`` from :func:`lu_factor` (``R^T = U^T L^T P``)."""
    n = LU.shape[0]
    z = np.empty(n)
    for i in range(n):
        acc = c[i]
        for k in range(i):
            acc -= LU[k, i] * z[k]
        z[i] = acc / LU[i, i]
    for i in range(n - 1, -1, -1):
        acc = z[i]
        for k in range(i + 1, n):
            acc -= LU[k, i] * z[k]
        z[i] = acc
    out = np.empty(n)
    for i in range(n):
        out[perm[i]] = z[i]
    return out


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def determined_solve(K, rhs, nf):
    """``K = [[Hxx, R^T], [R, 0]]`` with fewer unknowns ``nf`` than rows of ``R`` (at a vertex whose
    equations are dependent: the neck at its optimum has 16 free cables for 24 equations). When
    ``R`` has full column rank, ``x`` is fixed by the (consistent) rows alone, ``x = (R^T R)^-1 R^T
    r_c``, and the multipliers are the least-norm solution of ``R^T l = r_x - Hxx x``: what least
    squares on the whole system gives, from one Cholesky of ``R^T R`` instead of an SVD of ``K``
    (10x faster). Rows inconsistent beyond what least squares could pass (a wrong guess of the
    active set) give NaNs at once, as :func:`lstsq_solve` would after its SVD. Falls back to
    :func:`lstsq_solve` otherwise."""
    N = K.shape[0]
    m = N - nf
    Nm = _row_gram(K, nf)
    keep = np.ones(nf, dtype=np.bool_)
    chol_lower(Nm, nf, 1e-12 * _max_diagonal(Nm), keep)
    if not np.all(keep):  # dependent columns: the rows judged on the kept ones' factor
        return np.full(N, np.nan) if _rows_miss(K, rhs, nf, Nm, keep) else lstsq_solve(K, rhs)
    # x = N^-1 R^T r_c
    v = np.zeros(nf)
    for i in range(m):
        ri = rhs[nf + i]
        for a in range(nf):
            v[a] += K[nf + i, a] * ri
    x = chol_apply(Nm, v)
    # the rows must be consistent (else the instant's active set is wrong: lstsq decides)
    rscale = 1.0
    for i in range(m):
        rscale = max(rscale, abs(rhs[nf + i]))
    worst = 0.0
    for i in range(m):
        acc = -rhs[nf + i]
        for a in range(nf):
            acc += K[nf + i, a] * x[a]
        if not abs(acc) <= worst:
            worst = abs(acc)
    if not worst <= 1e-10 * rscale:
        # lstsq's answer would fail its own check (NaNs) whenever this x, the rows' least-squares
        # point, misses by more than sqrt(m) times its threshold: no x' meets every row within
        # 1e-10 max|rhs| then (|R x' - r_c|_inf >= |R x - r_c|_2 / sqrt(m)). Said without the SVD,
        # which would make a wrong crossover guess cost more than its instant's iterations
        return np.full(N, np.nan) if _beyond_lstsq(worst, m, rhs) else lstsq_solve(K, rhs)
    # l = R N^-1 (r_x - Hxx x)
    w = np.empty(nf)
    for a in range(nf):
        acc = rhs[a]
        for b in range(nf):
            acc -= K[a, b] * x[b]
        w[a] = acc
    u = chol_apply(Nm, w)
    sol = np.empty(N)
    sol[:nf] = x
    for i in range(m):
        acc = 0.0
        for a in range(nf):
            acc += K[nf + i, a] * u[a]
        sol[nf + i] = acc
    return sol


@njit(cache=True, nogil=True, inline="always")  # (inlined: each caller's fastmath applies)
def chol_lower(M, n, floor, keep=None):
    """The Cholesky factor of ``M[:n, :n]``'s lower triangle, in place (column by column): ``(True,
    its smallest pivot)``, or ``(False, 0)`` at the first pivot (before its square root) at or below
    ``floor`` (then ``M`` is partly overwritten). Shared by the small factors of the active-set and
    uniqueness tests (:func:`determined_solve`, :func:`mcdm_pin.solvers._unique.unique_test`,
    :func:`mcdm_pin.solvers._unique.definite_beyond`).

    With ``keep`` ((n,) bools, true), such a pivot drops its column instead (a dependent one):
    ``keep[j]`` false, the factor's row and column ``j`` zero and its diagonal 1, so that
    :func:`chol_apply` passes that unknown through and the others are the factor of the kept
    columns alone; the factor then always completes.

    Inlined into each caller, so that the caller's ``fastmath`` applies: numba's callees otherwise
    take the flags of whichever caller compiled them first, and the dual guess
    (:mod:`._dual_guess`) needs it exact where :func:`determined_solve` wants it vectorised."""
    dmin = np.inf
    for j in range(n):
        acc = M[j, j]
        for k in range(j):
            acc -= M[j, k] * M[j, k]
        if not acc > floor:
            if keep is None:
                return False, 0.0
            keep[j] = False
            for k in range(j):
                M[j, k] = 0.0
            M[j, j] = 1.0
            for i in range(j + 1, n):
                M[i, j] = 0.0
            continue
        d = np.sqrt(acc)
        M[j, j] = d
        dmin = min(dmin, d)
        for i in range(j + 1, n):
            t = M[i, j]
            for k in range(j):
                t -= M[i, k] * M[j, k]
            M[i, j] = t / d
    return True, dmin


@njit(cache=True, nogil=True, inline="always")  # (inlined: each caller's fastmath applies)
def chol_apply(L, r):
    """``(L L^T)^-1 r``."""
    n = L.shape[0]
    y = r.copy()
    for i in range(n):
        t = y[i]
        for k in range(i):
            t -= L[i, k] * y[k]
        y[i] = t / L[i, i]
    for i in range(n - 1, -1, -1):
        t = y[i]
        for k in range(i + 1, n):
            t -= L[k, i] * y[k]
        y[i] = t / L[i, i]
    return y


@njit(cache=True, nogil=True)
def matvec(M, x):
    """``M x`` by rows (:func:`._ipm_linalg.dot`): at these sizes numba's ``@`` (a BLAS call) costs
    more than the arithmetic."""
    out = np.empty(M.shape[0])
    for i in range(M.shape[0]):
        out[i] = dot(M[i], x)
    return out
