r"""Compiled kernels of the active-set solver (:mod:`.active_set`): the equality-constrained solve of
one active set and the KKT check of the full problem.

The arithmetic is small (a KKT system of ~50 unknowns on the neck); written with numpy its cost was
the per-call overhead of ~100 array operations per try, so the whole pivoting loop runs compiled.
The state of a cable is an int8 code: 0 free, 1 at its lower bound, 2 at its upper bound.
"""

from __future__ import annotations

import numpy as np
from ..jit import njit

from ._ipm_linalg import dot

# eq_solve codes
OK, SINGULAR, NO_CONVERGENCE, DROP, VANISHED = 0, 1, 2, 3, 5
# verify codes
KKT_OPTIMAL, KKT_PIVOT, KKT_EOM, KKT_STATIONARY, KKT_SURFACE = 0, 1, -1, -3, -4
# active_set_solve codes (besides OPTIMAL = 0 and the eq_solve / verify failures, shifted)
FOUND, CYCLE, PIVOT_LIMIT = 0, 10, 11
REASONS = {SINGULAR: "singular KKT system", NO_CONVERGENCE: "Newton steps on the cone surfaces did not converge",
           VANISHED: "a cone's force vanished", 20 + KKT_EOM: "equation of motion not met",
           20 + KKT_STATIONARY: "not stationary",
           20 + KKT_SURFACE: "a held cone's force off its surface",
           CYCLE: "the active set cycles", PIVOT_LIMIT: "no verified point within the pivot limit"}


@njit(cache=True, nogil=True)
def _lu_solve(K, rhs):
    """``K x = rhs`` by LU with partial pivoting (:func:`_lu_factor`, then :func:`_lu_apply`): LAPACK's
    ``dgesv`` without the copies to Fortran order that ``np.linalg.solve`` makes, 3x faster at these
    sizes. Returns ``(x, ok)``; ``ok`` false when a pivot is exactly zero or not finite."""
    LU, perm, ok = _lu_factor(K)
    if not ok:
        return rhs.copy(), False
    return _lu_apply(LU, perm, rhs), True


@njit(cache=True, nogil=True)
def _kkt_solve(K, rhs, square):
    """``K x = rhs`` by LU; least squares when ``K`` is not square-solvable (then the residual must be
    at rounding level, else NaNs: a singular, inconsistent system)."""
    if square:
        sol, ok = _lu_solve(K, rhs)
        if ok:
            ok = np.all(np.isfinite(sol))
        if ok:
            return sol
    sol = np.linalg.lstsq(K, rhs)[0]
    scale = 1.0
    for i in range(rhs.shape[0]):
        scale = max(scale, abs(rhs[i]))
    r = K @ sol - rhs
    for i in range(rhs.shape[0]):
        if not abs(r[i]) <= 1e-10 * scale:
            sol[:] = np.nan
            break
    return sol


@njit(cache=True, nogil=True)
def _vertex_solve(K, rhs, nf, square):
    """``K = [[Hxx, R^T], [R, 0]]`` with a square ``R`` (nf x nf: at a vertex, as many free variables
    as equations and held cone surfaces, the usual warm instant): ``x`` is fixed by the rows alone,
    ``R x = r_c``, and the multipliers by ``R^T l = r_x - Hxx x``: one LU of ``R`` (nf unknowns)
    instead of one of ``K`` (2 nf: 8x the arithmetic). Falls back to :func:`_kkt_solve` when ``R``
    is singular (then so is ``K``)."""
    return _vertex_solve_lu(K, rhs, nf, square)[0]


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _vertex_solve_lu(K, rhs, nf, square):
    """:func:`_vertex_solve`, also returning ``R``'s factors ``(LU, perm, ok)`` (:func:`_lu_factor`;
    ``ok`` false when the solution did not come from them): the ratio test of the next pivot solves
    with ``R^T`` again (:func:`_ratio_test`)."""
    N = K.shape[0]
    R = np.empty((nf, nf))
    for i in range(nf):
        for j in range(nf):
            R[i, j] = K[nf + i, j]
    LU, perm, ok = _lu_factor(R)
    if not ok:
        return _kkt_solve(K, rhs, square), LU, perm, False
    x = _lu_apply(LU, perm, rhs[nf:])
    w = np.empty(nf)
    for a in range(nf):
        acc = rhs[a]
        for b in range(nf):
            acc -= K[a, b] * x[b]
        w[a] = acc
    lam = _lu_apply_t(LU, perm, w)
    sol = np.empty(N)
    for i in range(nf):
        sol[i] = x[i]
        sol[nf + i] = lam[i]
    for i in range(N):
        if not np.isfinite(sol[i]):
            return _kkt_solve(K, rhs, square), LU, perm, False
    return sol, LU, perm, True


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _lu_factor(R):
    """``R[perm] = L U`` by partial pivoting (L unit lower, both in one array). Returns
    ``(LU, perm, ok)``; ``ok`` false when a pivot is exactly zero or not finite."""
    n = R.shape[0]
    M = R.copy()
    perm = np.arange(n)
    for k in range(n):
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
        Mk = M[k, k + 1:]
        for i in range(k + 1, n):
            l = M[i, k] * inv
            M[i, k] = l
            if l != 0.0:
                _axpy(-l, Mk, M[i, k + 1:])
    return M, perm, True


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"}, inline="always")
def _axpy(a, x, y):
    """``y += a x`` over slices (a loop from 0 over ``range(len)``: numba then knows the index is not
    negative and vectorises it; the loop ``for j in range(k + 1, n)`` it replaces did not, 2x slower
    for the 49 x 49 KKT systems of the crossover). Inlined, unlike :func:`._ipm_linalg.axpy`: called
    once per row, that one made the 49 x 49 factor 24 us instead of 14."""
    for t in range(x.shape[0]):
        y[t] += a * x[t]


@njit(cache=True, nogil=True)
def _lu_apply(LU, perm, b):
    """``R^-1 b`` from :func:`_lu_factor`."""
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
def _lu_apply_t(LU, perm, c):
    """``R^-T c`` from :func:`_lu_factor` (``R^T = U^T L^T P``)."""
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
def _determined_solve(K, rhs, nf):
    """``K = [[Hxx, R^T], [R, 0]]`` with fewer unknowns ``nf`` than rows of ``R`` (at a vertex whose
    equations are dependent: the neck at its optimum has 16 free cables for 24 equations). When
    ``R`` has full column rank, ``x`` is fixed by the (consistent) rows alone, ``x = (R^T R)^-1 R^T
    r_c``, and the multipliers are the least-norm solution of ``R^T l = r_x - Hxx x``: what least
    squares on the whole system gives, from one Cholesky of ``R^T R`` instead of an SVD of ``K``
    (10x faster). Rows inconsistent beyond what least squares could pass (a wrong guess of the
    active set) give NaNs at once, as :func:`_kkt_solve` would after its SVD. Falls back to
    :func:`_kkt_solve` otherwise."""
    N = K.shape[0]
    m = N - nf
    Nm = np.zeros((nf, nf))
    for i in range(m):
        Ri = K[nf + i]
        for a in range(nf):
            ra = Ri[a]
            if ra != 0.0:
                for b in range(a + 1):
                    Nm[a, b] += ra * Ri[b]
    scale = 1e-300
    for a in range(nf):
        scale = max(scale, Nm[a, a])
    if not chol_lower(Nm, nf, 1e-12 * scale)[0]:
        return _kkt_solve(K, rhs, False)
    # x = N^-1 R^T r_c
    v = np.zeros(nf)
    for i in range(m):
        ri = rhs[nf + i]
        for a in range(nf):
            v[a] += K[nf + i, a] * ri
    x = _chol_apply(Nm, v)
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
        # 1e-10 max|rhs| then (|R x' - r_c|_inf >= |R x - r_c|_2 / sqrt(m)). Said without the SVD
        # (~250 us on the neck: a wrong crossover guess cost more than its instant's iterations)
        full = 1.0
        for i in range(N):
            full = max(full, abs(rhs[i]))
        if worst > np.sqrt(m) * 1e-10 * full:
            out = np.empty(N)
            out[:] = np.nan
            return out
        return _kkt_solve(K, rhs, False)
    # l = R N^-1 (r_x - Hxx x)
    w = np.empty(nf)
    for a in range(nf):
        acc = rhs[a]
        for b in range(nf):
            acc -= K[a, b] * x[b]
        w[a] = acc
    u = _chol_apply(Nm, w)
    sol = np.empty(N)
    sol[:nf] = x
    for i in range(m):
        acc = 0.0
        for a in range(nf):
            acc += K[nf + i, a] * u[a]
        sol[nf + i] = acc
    return sol


@njit(cache=True, nogil=True)
def chol_lower(M, n, floor):
    """The Cholesky factor of ``M[:n, :n]``'s lower triangle, in place (column by column): ``(True,
    its smallest pivot)``, or ``(False, 0)`` at the first pivot (before its square root) at or below
    ``floor`` (then ``M`` is partly overwritten). Shared by the small factors of the active-set and
    uniqueness tests (:func:`_determined_solve`, :func:`mcdm_pin.solvers._fast.unique_test`,
    :func:`mcdm_pin.solvers._fast.definite_beyond`)."""
    dmin = np.inf
    for j in range(n):
        acc = M[j, j]
        for k in range(j):
            acc -= M[j, k] * M[j, k]
        if not acc > floor:
            return False, 0.0
        d = np.sqrt(acc)
        M[j, j] = d
        dmin = min(dmin, d)
        for i in range(j + 1, n):
            t = M[i, j]
            for k in range(j):
                t -= M[i, k] * M[j, k]
            M[i, j] = t / d
    return True, dmin


@njit(cache=True, nogil=True)
def _chol_apply(L, r):
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
def _matvec(M, x):
    """``M x`` by rows (:func:`._ipm_linalg.dot`): at these sizes numba's ``@`` (a BLAS call) costs
    more than the arithmetic."""
    out = np.empty(M.shape[0])
    for i in range(M.shape[0]):
        out[i] = dot(M[i], x)
    return out


@njit(cache=True, nogil=True, inline="always")
def cone_force(G, gc, ax, k, x):
    """Cone ``k``'s force ``F = g_k + G_k x`` at ``x``, its component along the axis and the part
    perpendicular to it: ``(F0, F1, F2, along, p0, p1, p2)``."""
    F0, F1, F2 = gc[k, 0], gc[k, 1], gc[k, 2]
    for i in range(x.shape[0]):
        xi = x[i]
        F0 += G[k, 0, i] * xi
        F1 += G[k, 1, i] * xi
        F2 += G[k, 2, i] * xi
    al = ax[k, 0] * F0 + ax[k, 1] * F1 + ax[k, 2] * F2
    return F0, F1, F2, al, F0 - al * ax[k, 0], F1 - al * ax[k, 1], F2 - al * ax[k, 2]


@njit(cache=True, nogil=True)
def _on_surfaces(f, G, gc, ax, tn, act, tol):
    """Every cone of ``act`` has ``| |F_perp| - tan a.F | <= tol |F|`` at ``f``."""
    for s in range(act.shape[0]):
        k = act[s]
        F = gc[k] + G[k] @ f
        al = ax[k, 0] * F[0] + ax[k, 1] * F[1] + ax[k, 2] * F[2]
        p0, p1, p2 = F[0] - al * ax[k, 0], F[1] - al * ax[k, 1], F[2] - al * ax[k, 2]
        perp = np.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
        if not abs(perp - tn[k] * al) <= tol * np.sqrt(F[0] * F[0] + F[1] * F[1] + F[2] * F[2]):
            return False
    return True


@njit(cache=True, nogil=True)
def eq_solve(H, g, A, b, lb, ub, state, G, gc, ax, tn, cact, cdir, max_newton, step_tol, reg):
    """Minimise ``1/2 f^T H f + g^T f`` with ``A f = b``, the cables of ``state`` fixed at their
    bounds and the cones of ``cact`` held on their surface (Newton steps with the cones' curvature
    weighted by their multipliers).

    ``reg`` (n,) > 0 is added to the free cables' diagonal (a Tikhonov term ``1/2 sum reg_i f_i^2``):
    with a positive semidefinite objective whose optimum is a flat ridge (case 2 with ``beta = 0``)
    the system is otherwise singular and its solution arbitrary along the ridge; with it, the point
    of the ridge nearest the origin in that weighted norm. The KKT check of the original problem
    decides whether the point is accepted (its stationarity residual ``reg_i f_i``: ~1e-12 of the
    gradient's scale, :func:`tikhonov`).

    Returns ``(code, f, y, mus, dirs, solves, LU, perm, lu_ok)``: ``mus`` (nc,) the active cones'
    multipliers (0 elsewhere), ``dirs`` (nc, 3) their surface directions at ``f``, ``solves`` the
    linear KKT systems solved (1 without active cones; one per Newton step with them); at a vertex,
    ``(LU, perm)`` the factors of the last solve's rows on the free cables (:func:`_vertex_solve_lu`;
    ``lu_ok`` false otherwise).
    """
    n = H.shape[0]
    neq = A.shape[0]
    nc = G.shape[0]
    f = np.zeros(n)
    nf = 0
    for i in range(n):
        if state[i] == 1:
            f[i] = lb[i]
        elif state[i] == 2:
            f[i] = ub[i]
        else:
            nf += 1
    free = np.empty(nf, dtype=np.int64)
    t = 0
    for i in range(n):
        if state[i] == 0:
            free[t] = i
            t += 1
    na = 0
    for k in range(nc):
        if cact[k]:
            na += 1
    act = np.empty(na, dtype=np.int64)
    t = 0
    for k in range(nc):
        if cact[k]:
            act[t] = k
            t += 1
    mus = np.zeros(nc)
    dirs = cdir.copy()
    # fewer free cables than equations is fine when the equations are dependent (e.g. the 2-link
    # arm at q = 0): the KKT system is then solved in the least-squares sense (and verified)
    square = nf >= neq + na
    N = nf + neq + na
    # fixed part of the gradient and of the equations (f is zero on the free cables here)
    Hf = _matvec(H, f)
    Af = _matvec(A, f)
    f_cur = f.copy()
    x_prev = np.zeros(nf)
    have_cur = False
    have_prev = False
    y = np.zeros(neq)
    iters = max_newton if na > 0 else 1
    converged = False
    solves = 0
    LU = np.empty((0, 0))
    perm = np.empty(0, dtype=np.int64)
    lu_ok = False
    for _ in range(iters):
        K = np.zeros((N, N))
        rhs = np.empty(N)
        for p in range(nf):
            i = free[p]
            for q in range(nf):
                K[p, q] = H[i, free[q]]
            K[p, p] += reg[i]
            for r in range(neq):
                K[p, nf + r] = A[r, i]
                K[nf + r, p] = A[r, i]
            rhs[p] = -(g[i] + Hf[i])
        for r in range(neq):
            rhs[nf + r] = b[r] - Af[r]
        for s in range(na):
            k = act[s]
            d0, d1, d2 = dirs[k, 0], dirs[k, 1], dirs[k, 2]
            if have_cur:
                F = gc[k] + G[k] @ f_cur
                al = ax[k, 0] * F[0] + ax[k, 1] * F[1] + ax[k, 2] * F[2]
                p0, p1, p2 = F[0] - al * ax[k, 0], F[1] - al * ax[k, 1], F[2] - al * ax[k, 2]
                nrm = np.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
                if nrm <= 1e-300:
                    return VANISHED, f, y, mus, dirs, solves, LU, perm, False
                d0, d1, d2 = p0 / nrm, p1 / nrm, p2 / nrm
                dirs[k, 0], dirs[k, 1], dirs[k, 2] = d0, d1, d2
                mu = mus[k]
                if mu > 0.0:
                    # curvature mu G^T (I - a a^T - d d^T) G / |F_perp| = mu/|F_perp| v v^T with
                    # v = G^T e, e = a x d (the projector is rank one: e e^T)
                    e0 = ax[k, 1] * d2 - ax[k, 2] * d1
                    e1 = ax[k, 2] * d0 - ax[k, 0] * d2
                    e2 = ax[k, 0] * d1 - ax[k, 1] * d0
                    v = e0 * G[k, 0] + e1 * G[k, 1] + e2 * G[k, 2]
                    sc = mu / nrm
                    # centred at f_cur: + 1/2 (f - f_cur)^T D (f - f_cur); on the free cables the
                    # gradient gains D (f_fixed - f_cur) restricted to free rows
                    vdf = 0.0
                    for i in range(n):
                        if state[i] != 0:
                            vdf += v[i] * (f[i] - f_cur[i])
                        else:
                            vdf -= v[i] * f_cur[i]
                    for p in range(nf):
                        vp = sc * v[free[p]]
                        for q in range(nf):
                            K[p, q] += vp * v[free[q]]
                        rhs[p] -= vp * vdf
            w0 = d0 - tn[k] * ax[k, 0]
            w1 = d1 - tn[k] * ax[k, 1]
            w2 = d2 - tn[k] * ax[k, 2]
            row = w0 * G[k, 0] + w1 * G[k, 1] + w2 * G[k, 2]
            rr = -(w0 * gc[k, 0] + w1 * gc[k, 1] + w2 * gc[k, 2])
            for i in range(n):
                if state[i] != 0:
                    rr -= row[i] * f[i]
            for p in range(nf):
                K[p, nf + neq + s] = row[free[p]]
                K[nf + neq + s, p] = row[free[p]]
            rhs[nf + neq + s] = rr
        if nf == neq + na:
            sol, LU, perm, lu_ok = _vertex_solve_lu(K, rhs, nf, square)
        else:
            lu_ok = False
            sol = _kkt_solve(K, rhs, square) if square else _determined_solve(K, rhs, nf)
        solves += 1
        for i in range(N):
            if not np.isfinite(sol[i]):
                return SINGULAR, f, y, mus, dirs, solves, LU, perm, False
        for p in range(nf):
            f[free[p]] = sol[p]
        y = sol[nf:nf + neq].copy()
        for s in range(na):
            mus[act[s]] = sol[nf + neq + s]
        if na == 0:
            converged = True
            break
        if have_cur:
            for s in range(na):
                if mus[act[s]] < 0.0:
                    return DROP, f, y, mus, dirs, solves, LU, perm, lu_ok
        if have_prev:
            dx = 0.0
            xx = 0.0
            for p in range(nf):
                dx += (sol[p] - x_prev[p]) ** 2
                xx += sol[p] ** 2
            step = np.sqrt(dx) / (1.0 + np.sqrt(xx))
            # converged: a step below step_tol, or, on an ill-conditioned system whose rounding floor
            # is above it, a step below 1e-8 with every held cone on its surface to 1e-11 of |F|
            # (the KKT check that follows decides in both cases)
            if step <= step_tol or (step <= 1e-8 and _on_surfaces(f, G, gc, ax, tn, act, 1e-11)):
                converged = True
                break
        for p in range(nf):
            x_prev[p] = sol[p]
        have_prev = True
        f_cur[:] = f
        have_cur = True
    if not converged:
        return NO_CONVERGENCE, f, y, mus, dirs, solves, LU, perm, lu_ok
    return OK, f, y, mus, dirs, solves, LU, perm, lu_ok


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def verify(H, g, A, b, lb, ub, state, f, y, G, gc, ax, tn, basis0, cact, mus, primal_tol, dual_tol,
           eom_tol):
    """KKT conditions of the full problem at ``f`` (multipliers ``y`` of ``A f = b``, ``mus`` of the
    active cones).

    Returns ``(code, to_lower, to_upper, release, cone_in, cone_dir, cone_out, grad, worst_kind,
    worst_idx)``; ``code`` is :data:`KKT_OPTIMAL`, :data:`KKT_PIVOT` (the flags say what to change;
    ``worst_kind`` 1 lower, 2 upper, 0 release, -1 none) or a negative reason.
    """
    n = f.shape[0]
    nc = G.shape[0]
    to_lower = np.zeros(n, dtype=np.bool_)
    to_upper = np.zeros(n, dtype=np.bool_)
    release = np.zeros(n, dtype=np.bool_)
    cone_in = np.zeros(nc, dtype=np.bool_)
    cone_out = np.zeros(nc, dtype=np.bool_)
    cone_dir = np.zeros((nc, 3))
    grad = np.zeros(n)
    for i in range(n):
        if f[i] < lb[i] - primal_tol * (1.0 + abs(lb[i])) and state[i] != 1:
            to_lower[i] = True
        if f[i] > ub[i] + primal_tol * (1.0 + abs(ub[i])) and state[i] != 2:
            to_upper[i] = True
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
            return KKT_EOM, to_lower, to_upper, release, cone_in, cone_dir, cone_out, grad, -1, -1
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
    off_surface = False
    for k in range(nc):
        F0, F1, F2, al, p0, p1, p2 = cone_force(G, gc, ax, k, f)
        perp = np.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
        if cact[k]:
            if al <= 0.0:  # held on the wrong nappe (F pulls the ball out): let the cone go
                cone_out[k] = True
                continue
            if not abs(perp - tn[k] * al) <= 1e-10 * np.sqrt(F0 * F0 + F1 * F1 + F2 * F2):
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
        elif perp > tn[k] * al * (1 + 1e-12) or al < 0.0:
            cone_in[k] = True
            if perp > 0.0:
                cone_dir[k, 0], cone_dir[k, 1], cone_dir[k, 2] = p0 / perp, p1 / perp, p2 / perp
            else:
                cone_dir[k] = basis0[k]
    stationary = True
    for i in range(n):
        if state[i] == 0 and abs(grad[i]) > 1e-8 * gscale:
            stationary = False
    any_change = False
    worst_kind, worst_idx, worst = -1, -1, -np.inf
    for i in range(n):
        if (state[i] == 1 and grad[i] < -dual_tol * gscale) or \
                (state[i] == 2 and grad[i] > dual_tol * gscale):
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


@njit(cache=True, nogil=True)
def active_set_solve(H, g, A, b, lb, ub, state0, G, gc, ax, tn, basis0, cact0, cdir0, max_pivots,
                     max_newton, step_tol, primal_tol, dual_tol, eom_tol, reg_rel):
    """:func:`active_set_run` without its counts: ``(code, f, mus, grad, state, cact, dirs,
    next_state, y)`` (the signature the interior-point method's crossover uses)."""
    out = active_set_run(H, g, A, b, lb, ub, state0, G, gc, ax, tn, basis0, cact0, cdir0, max_pivots,
                         max_newton, step_tol, primal_tol, dual_tol, eom_tol, reg_rel)
    return out[0], out[1], out[2], out[3], out[4], out[5], out[6], out[7], out[8]


@njit(cache=True, nogil=True)
def next_guess(state, grad):
    """The next instant's guess of the bounds from a verified answer's: a variable whose multiplier
    (``grad``, > 0 at a lower bound) is below 1e-12 of the largest is guessed free."""
    gmx = 0.0
    for i in range(grad.shape[0]):
        gmx = max(gmx, abs(grad[i]))
    thr = 1e-12 * max(gmx, 1e-300)
    nxt = state.copy()
    for i in range(state.shape[0]):
        if (state[i] == 1 and not grad[i] > thr) or (state[i] == 2 and not grad[i] < -thr):
            nxt[i] = 0
    return nxt


@njit(cache=True, nogil=True)
def tikhonov(H, g, ub, reg_rel):
    """The Tikhonov terms ``reg`` (n,) of :func:`eq_solve`: ``reg_rel`` times each variable's own
    curvature ``H_ii``, at least ``1e-8`` of the objective's scale ``s = max(max H_ii, max |g_i| /
    (1 + max |u_i|))``; ``reg_rel s`` for a variable the objective does not see (``H_ii = 0``, a
    zero row of a positive semidefinite ``H``).

    Relative to each variable's own curvature, the stationarity residual ``reg_i f_i`` stays
    ~``reg_rel`` of that variable's gradient ``H_ii f_i`` whatever the spread of the diagonal: with
    one term ``reg_rel s`` for all (MyoSuite's arm, scaled: the muscles' ``2 w / g^2`` from 4e-7 to
    381 next to the reserves' 200), the strong muscles' residual ``reg_rel s f_i`` (``s f_i`` 1e4-7e4
    times the gradient's scale) fails the check of stationarity (1e-8 of that scale) at the optimum's
    active set, and the interior-point method's crossover is refused (a fifth of the arm's instants
    with the glenohumeral cone then ran on to a numerical breakdown).
    """
    n = H.shape[0]
    hmax = 0.0  # H's largest entry: for a positive semidefinite H, its largest diagonal entry
    gmax = 0.0
    umax = 0.0
    for i in range(n):
        hmax = max(hmax, H[i, i])
        gmax = max(gmax, abs(g[i]))
        if np.isfinite(ub[i]):
            umax = max(umax, abs(ub[i]))
    scale = max(hmax, gmax / (1.0 + umax))
    reg = np.empty(n)
    for i in range(n):
        reg[i] = reg_rel * (max(H[i, i], 1e-8 * scale) if H[i, i] > 0.0 else scale)
    return reg


@njit(cache=True, nogil=True)
def active_set_run(H, g, A, b, lb, ub, state0, G, gc, ax, tn, basis0, cact0, cdir0, max_pivots,
                   max_newton, step_tol, primal_tol, dual_tol, eom_tol, reg_rel):
    """Block principal pivoting from the guess ``(state0, cact0, cdir0)`` until a verified KKT point
    (see :func:`mcdm_pin.solvers.active_set.try_active_set`).

    Every violated condition is exchanged at once (a block pivot) while the number of violations
    falls (Judice and Pires allow a few steps without progress; here none: on the neck that wandered
    off and cycled); then, or when a block pivot leaves a singular
    system (too many cables fixed for the equation of motion), only the worst violation changes
    (Judice and Pires' safeguard).

    ``reg_rel``: the Tikhonov terms of :func:`eq_solve` relative to each variable's curvature (:func:`tikhonov`).

    Returns ``(code, f, mus, grad, state, cact, dirs, next_state, y, sets, solves)``: ``code`` :data:`FOUND` or a
    key of :data:`REASONS`; at :data:`FOUND`, ``mus`` the cones' multipliers, ``grad`` the bounds'
    multipliers (> 0 at a lower bound), ``y`` the equations' multipliers, ``(state, cact, dirs)`` the optimum's active set and ``next_state`` the guess for
    the next instant (the bounds whose multiplier is not negligible, 1e-12 of the largest);
    ``sets`` the active sets tried (pivots + 1), ``solves`` the linear KKT systems solved for them
    (one per active set without cones, one per Newton step with them).
    """
    n = H.shape[0]
    reg = tikhonov(H, g, ub, reg_rel)
    neq = A.shape[0]
    nc = G.shape[0]
    state = state0.copy()
    for i in range(n):
        # a variable can only be held at a finite bound (the least-norm stage frees some bounds)
        if (state[i] == 1 and not np.isfinite(lb[i])) or (state[i] == 2 and not np.isfinite(ub[i])):
            state[i] = 0
    cact = cact0.copy()
    cdir = cdir0.copy()
    hist_s = np.zeros((max_pivots, n), dtype=np.int8)
    hist_c = np.zeros((max_pivots, nc), dtype=np.bool_)
    f = np.zeros(n)
    y = np.zeros(neq)
    mus = np.zeros(nc)
    grad = np.zeros(n)
    # the last verified-but-not-optimal point, to step back to when a block pivot fails
    have_prev = False
    prev_state = state.copy()
    prev_cact = cact.copy()
    prev_grad = np.zeros(n)
    prev_kind, prev_idx = -1, -1
    prev_dirs = cdir.copy()
    prev_cone_dir = cdir.copy()
    prev_in = np.zeros(nc, dtype=np.bool_)
    prev_out = np.zeros(nc, dtype=np.bool_)
    last_was_block = False
    best_ninf = n + nc + 1
    blocks_ok = True
    solves = 0
    for it in range(max_pivots):
        for h in range(it):
            same = True
            for i in range(n):
                if hist_s[h, i] != state[i]:
                    same = False
                    break
            if same:
                for k in range(nc):
                    if hist_c[h, k] != cact[k]:
                        same = False
                        break
            if same:
                return CYCLE, f, mus, grad, state, cact, cdir, state, y, it, solves
        hist_s[it] = state
        hist_c[it] = cact
        code, f, y, mus, dirs, ns, LU, perm, lu_ok = eq_solve(H, g, A, b, lb, ub, state, G, gc, ax, tn,
                                                              cact, cdir, max_newton, step_tol, reg)
        solves += ns
        if code == DROP:  # a cone pulls the force inwards: it is not active
            for k in range(nc):
                if cact[k] and mus[k] < 0.0:
                    cact[k] = False
            continue
        if code == SINGULAR and have_prev and last_was_block:
            # the block pivot fixed too much: step back and change only the worst violation
            state, cact = _single_pivot(prev_state, prev_cact, prev_grad, prev_kind, prev_idx,
                                        prev_in, prev_out, neq, nc, n)
            cdir = _next_dirs(prev_in, prev_cone_dir, prev_dirs, nc)
            last_was_block = False
            blocks_ok = False  # from now on one change at a time (finite for strictly convex QPs)
            continue
        if code != OK and code != NO_CONVERGENCE:
            return code, f, mus, grad, state, cact, cdir, state, y, it + 1, solves
        # Newton steps that did not settle still say which cables and cones to exchange; the point
        # itself is accepted only if it passes the full KKT check like any other
        (vcode, to_lower, to_upper, release, cone_in, cone_dir, cone_out, grad, worst_kind,
         worst_idx) = verify(H, g, A, b, lb, ub, state, f, y, G, gc, ax, tn, basis0, cact, mus,
                             primal_tol, dual_tol, eom_tol)
        if vcode == KKT_OPTIMAL:
            return FOUND, f, mus, grad, state, cact, dirs, next_guess(state, grad), y, it + 1, solves
        if vcode != KKT_PIVOT:
            return 20 + vcode, f, mus, grad, state, cact, cdir, state, y, it + 1, solves
        have_prev = True
        prev_state[:] = state
        prev_cact[:] = cact
        prev_grad[:] = grad
        prev_kind, prev_idx = worst_kind, worst_idx
        prev_dirs[:] = dirs
        prev_cone_dir[:] = cone_dir
        prev_in[:] = cone_in
        prev_out[:] = cone_out
        ninf = 0
        for i in range(n):
            ninf += release[i] + to_lower[i] + to_upper[i]
        for k in range(nc):
            ninf += cone_in[k] + cone_out[k]
        # a block pivot only while the number of violations keeps falling
        block = blocks_ok and ninf < best_ninf
        best_ninf = min(best_ninf, ninf)
        new_state = state.copy()
        n_in = 0
        n_out = 0
        n_act = 0
        for k in range(nc):
            n_in += cone_in[k]
            n_out += cone_out[k]
            n_act += cact[k]
        for i in range(n):
            if release[i]:
                new_state[i] = 0
            if to_lower[i]:
                new_state[i] = 1
            if to_upper[i]:
                new_state[i] = 2
        if block and n - np.count_nonzero(new_state) >= neq + n_act - n_out + n_in:
            state = new_state
            for k in range(nc):
                if cone_out[k]:
                    cact[k] = False
                if cone_in[k]:
                    cact[k] = True
            last_was_block = True
        else:
            enter = -1
            if (worst_kind == 1 or worst_kind == 2) and n - np.count_nonzero(state) == neq + n_act:
                # at a vertex (as many free cables as equations): a dual simplex step, the fixed
                # cable to free chosen by the ratio test (keeps the other multipliers' signs)
                enter = _ratio_test(A, G, gc, ax, tn, cact, dirs, state, grad, worst_kind, worst_idx, n,
                                    LU, perm, lu_ok)
            if enter >= 0:
                state = state.copy()
                state[worst_idx] = worst_kind
                state[enter] = 0
            else:
                state, cact = _single_pivot(state, cact, grad, worst_kind, worst_idx, cone_in, cone_out,
                                            neq, nc, n)
            last_was_block = False
        cdir = _next_dirs(cone_in, cone_dir, dirs, nc)
    return PIVOT_LIMIT, f, mus, grad, state, cact, cdir, state, y, max_pivots, solves


@njit(cache=True, nogil=True)
def _ratio_test(A, G, gc, ax, tn, cact, dirs, state, grad, kind, r, n, LU, perm, lu_ok):
    """The fixed cable whose release lets the leaving free cable ``r`` reach its bound (``kind`` 1:
    it is below its lower bound, 2: above its upper bound) at the least dual cost: min over eligible
    j of multiplier_j / |dx_r/df_j|, with ``x_F = B^-1 (rhs - col_j f_j)`` and ``B`` the square
    matrix of the equations (and held cones' surface rows) on the free cables. -1 if none is
    eligible or ``B`` is singular. ``(LU, perm)``: ``B``'s factors when ``lu_ok`` (the vertex solve
    of this active set factored the same matrix, :func:`_vertex_solve_lu`), else ``B`` is solved
    afresh."""
    neq = A.shape[0]
    nc = G.shape[0]
    rows = np.zeros((neq + nc, n))
    m = 0
    for i in range(neq):
        rows[m] = A[i]
        m += 1
    for k in range(nc):
        if cact[k]:
            w0 = dirs[k, 0] - tn[k] * ax[k, 0]
            w1 = dirs[k, 1] - tn[k] * ax[k, 1]
            w2 = dirs[k, 2] - tn[k] * ax[k, 2]
            rows[m] = w0 * G[k, 0] + w1 * G[k, 1] + w2 * G[k, 2]
            m += 1
    free = np.flatnonzero(state == 0)
    if free.shape[0] != m:
        return -1
    pos = -1
    for q in range(m):
        if free[q] == r:
            pos = q
    if pos < 0:
        return -1
    e = np.zeros(m)
    e[pos] = 1.0
    if lu_ok and LU.shape[0] == m:
        u = _lu_apply_t(LU, perm, e)  # row pos of B^-1
    else:
        B = np.empty((m, m))
        for q in range(m):
            for i in range(m):
                B[i, q] = rows[i, free[q]]
        try:
            u = np.linalg.solve(B.T, e)  # row pos of B^-1
        except Exception:  # noqa: BLE001 (singular basis)
            return -1
    need_up = kind == 1  # x_r must rise to its lower bound
    best, enter = np.inf, -1
    for j in range(n):
        if state[j] == 0:
            continue
        d = 0.0  # dx_r / df_j = -(B^-1 col_j)_pos
        for i in range(m):
            d -= u[i] * rows[i, j]
        # f_j may only move away from its bound: up from a lower one, down from an upper one
        rate = d if state[j] == 1 else -d
        if (rate > 1e-12) if need_up else (rate < -1e-12):
            lam = grad[j] if state[j] == 1 else -grad[j]
            ratio = max(lam, 0.0) / abs(rate)
            if ratio < best:
                best, enter = ratio, j
    return enter


@njit(cache=True, nogil=True)
def _next_dirs(cone_in, cone_dir, dirs, nc):
    out = dirs.copy()
    for k in range(nc):
        if cone_in[k]:
            out[k] = cone_dir[k]
    return out


@njit(cache=True, nogil=True)
def _single_pivot(state, cact, grad, worst_kind, worst_idx, cone_in, cone_out, neq, nc, n):
    """Change only the worst violation (a bound: fix it, and no cone change; a multiplier of the
    wrong sign: free it, with the cone changes); then, if too few cables are free for the equations,
    free the least binding fixed ones (a simplex-like swap)."""
    new_state = state.copy()
    new_cact = cact.copy()
    bounds_move = worst_kind == 1 or worst_kind == 2
    if bounds_move:
        new_state[worst_idx] = worst_kind
    elif worst_kind == 0:
        new_state[worst_idx] = 0
    n_act = 0
    for k in range(nc):
        if not bounds_move:
            if cone_out[k]:
                new_cact[k] = False
            if cone_in[k]:
                new_cact[k] = True
        n_act += new_cact[k]
    need = neq + n_act
    n_fixed = 0
    for i in range(n):
        if new_state[i] != 0 and i != worst_idx:
            n_fixed += 1
    fixed = np.empty(n_fixed, dtype=np.int64)
    lam = np.empty(n_fixed)
    t = 0
    for i in range(n):
        if new_state[i] != 0 and i != worst_idx:
            fixed[t] = i
            lam[t] = grad[i] if new_state[i] == 1 else -grad[i]
            t += 1
    order = np.argsort(lam, kind="mergesort")
    for t in range(n_fixed):
        if n - np.count_nonzero(new_state) >= need:
            break
        new_state[fixed[order[t]]] = 0
    return new_state, new_cact
