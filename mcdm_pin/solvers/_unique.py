r"""The compiled uniqueness test of an optimum (:func:`unique_test`):
:func:`mcdm_pin.solvers.least_norm.is_unique` after its first test, the same steps and thresholds
(the strongly active constraints, their rows' rank on the free variables, the Hessian of the
Lagrangian made definite along those rows); the numpy code stays the reference. The
answer kernels of :mod:`._fast` call it, and :mod:`.least_norm` calls it through :mod:`._fast`.
Also the optimal face that the least-norm stage pins (:func:`face_setup`: the same strongly active
set, the face's rows, :func:`face_rows`, and a basis of them), which :mod:`.least_norm` calls
directly.
"""

from __future__ import annotations

import numpy as np
from ..jit import njit

from ..model.kernels import gram_lower
from ._ipm_linalg import dot
from ._kkt_eq import cone_force
from ._face_qp import face_least_norm
from ._kkt_linalg import chol_lower
from ._structs import QP, Cones, Face, Limits


@njit(cache=True, nogil=True)
def definite_beyond(H, J, rows, thr, hscale, penalty):
    """Whether ``H + gamma J^T J - thr I`` has a Cholesky factor (``J = J[:rows]``, ``gamma =
    penalty hscale / max |J^T J|``, ``penalty``:
    :attr:`~mcdm_pin.settings.Settings.unique_penalty`): then ``z^T H z > thr |z|^2`` for every ``z`` with
    ``J z = 0``, the uniqueness test's conclusion without the null space
    (:mod:`mcdm_pin.solvers.least_norm`, "Skipped when unique")."""
    nf = H.shape[0]
    M = np.zeros((nf, nf))
    gram_lower(J, rows, nf, M)
    big = 0.0
    for a in range(nf):
        for b in range(a + 1):
            big = max(big, abs(M[a, b]))
    gam = penalty * hscale / big if big > 0.0 else 0.0
    for a in range(nf):
        for b in range(a + 1):
            M[a, b] = H[a, b] + gam * M[a, b]
        M[a, a] -= thr
    return chol_lower(M, nf, 0.0)[0]


@njit(cache=True, nogil=True, inline="always")
def unique_test(x, z, zc, qp, cones, limits):
    """:func:`mcdm_pin.solvers.least_norm.is_unique` of ``x`` (duals ``z``, ``zc``) on ``qp`` and
    ``cones`` (:class:`._structs.QP`, :class:`._structs.Cones`) after its first test (its
    ``_strongly_active``, the Cholesky of ``J^T J``, then the Cholesky of ``H + gamma J^T J - thr I``,
    :func:`definite_beyond`), with the thresholds ``limits.near``, ``unique_rel``, ``penalty``: 1
    unique, 0 not proven unique."""
    c, lb, ub, A, P = qp.c, qp.lb, qp.ub, qp.A, qp.H
    G, gc, ax, tn, cosr = cones.G, cones.gc, cones.ax, cones.tn, cones.cosr
    near, unique_rel, penalty = limits.near, limits.unique_rel, limits.penalty
    gscale = _gradient_scale(x, c, P)
    thr = unique_rel * gscale
    free, nf = _not_strongly_active(x, z, lb, ub, near, thr)
    if nf == 0:
        return 1
    crow, nr, cv, cs, ncv, _ = _held_cone_rows(G, gc, ax, tn, cosr, zc, x, thr)
    m = A.shape[0]
    rows = m + nr
    J = np.empty((rows, nf))
    for r in range(rows):
        for a in range(nf):
            J[r, a] = A[r, free[a]] if r < m else crow[r - m, free[a]]
    # the usual case (a vertex): J has full column rank, the null space is empty
    if rows >= nf and _full_column_rank(J, rows, nf):
        return 1
    H, hscale = _reduced_hessian(P, free, nf, cv, cs, ncv)
    return 1 if definite_beyond(H, J, rows, unique_rel * hscale, hscale, penalty) else 0


@njit(cache=True, nogil=True)
def _gradient_scale(x, c, P):
    """The scale of the objective's gradient ``P x + c``: the largest entry of it and of ``c``."""
    n = x.shape[0]
    grad = c.copy()  # the objective's gradient P x + c
    for i in range(n):
        grad[i] += dot(P[i], x)  # (vectorised: a plain loop's sum waits on each product)
    gscale = 1e-300
    for i in range(n):
        gscale = max(gscale, abs(grad[i]), abs(c[i]))
    return gscale


@njit(cache=True, nogil=True)
def _not_strongly_active(x, z, lb, ub, near, thr):
    """The variables not at a bound (within ``near``) with a multiplier beyond ``thr``: ``(free,
    nf)``, their indices in ``free[:nf]``."""
    n = x.shape[0]
    free = np.empty(n, dtype=np.int64)
    nf = 0
    for i in range(n):
        at_l = (x[i] - lb[i] <= near * (1.0 + abs(lb[i]))) and (z[i] < -thr)
        at_u = (ub[i] - x[i] <= near * (1.0 + abs(ub[i]))) and (z[i] > thr)
        if not (at_l or at_u):
            free[nf] = i
            nf += 1
    return free, nf


@njit(cache=True, nogil=True)
def _held_cone_rows(G, gc, ax, tn, cosr, zc, x, thr):
    """The rows the cones held at ``x`` (multiplier beyond ``thr``) add to the active constraints'
    Jacobian, ``crow[:nr]`` (every row of ``G`` for a cone held at its apex, else its surface's
    normal and its tangent across the axis), their curvature ``sum_k cs[k] cv[k] cv[k]^T``
    (``k < ncv``) and which cones are held: ``(crow, nr, cv, cs, ncv, held)``."""
    n = x.shape[0]
    K = G.shape[0]
    held = np.zeros(K, dtype=np.bool_)
    crow = np.empty((3 * K, n))
    cv = np.empty((K, n))  # the held cones' curvature: sum_k cs[k] cv[k] cv[k]^T
    cs = np.empty(K)
    ncv = 0
    nr = 0
    for k in range(K):
        mu = zc[k, 0] * cosr[k]
        if not mu > thr:
            continue
        held[k] = True
        F0, F1, F2, al, p0, p1, p2 = cone_force(G, gc, ax, k, x)
        p = np.array([p0, p1, p2])
        perp = np.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
        nF = np.sqrt(F0 * F0 + F1 * F1 + F2 * F2)
        if perp <= 1e-12 * max(nF, 1e-300):  # held at the apex: every row of G
            for a in range(3):
                crow[nr] = G[k, a]
                nr += 1
            continue
        h = p / perp
        w = h - tn[k] * ax[k]
        e0 = ax[k, 1] * h[2] - ax[k, 2] * h[1]
        e1 = ax[k, 2] * h[0] - ax[k, 0] * h[2]
        e2 = ax[k, 0] * h[1] - ax[k, 1] * h[0]
        crow[nr] = w[0] * G[k, 0] + w[1] * G[k, 1] + w[2] * G[k, 2]
        crow[nr + 1] = e0 * G[k, 0] + e1 * G[k, 1] + e2 * G[k, 2]
        nr += 2
        # curvature mu G^T (I - a a^T - h h^T) G / |F_perp| = mu/|F_perp| v v^T, v = G^T (a x h)
        cv[ncv] = crow[nr - 1]
        cs[ncv] = mu / perp
        ncv += 1
    return crow, nr, cv, cs, ncv, held


@njit(cache=True, nogil=True)
def _full_column_rank(J, rows, nf):
    """Whether ``J[:rows]`` (``nf`` columns) has full column rank: the Cholesky factor of ``J^T J``
    exists with its smallest pivot squared above 1e-10 of ``J^T J``'s largest entry."""
    JtJ = np.zeros((nf, nf))
    gram_lower(J, rows, nf, JtJ)
    big = 1e-300
    for a in range(nf):
        for bb in range(a + 1):
            JtJ[bb, a] = JtJ[a, bb]
            big = max(big, abs(JtJ[a, bb]))
    ok, dmin = chol_lower(JtJ, nf, 0.0)
    return ok and dmin * dmin > 1e-10 * big


@njit(cache=True, nogil=True)
def _reduced_hessian(P, free, nf, cv, cs, ncv):
    """The Hessian of the Lagrangian on the free variables, ``P_FF`` plus the held cones'
    curvature, and the scale of ``P`` (its largest entry): ``(H, hscale)``."""
    n = P.shape[0]
    H = np.empty((nf, nf))
    hscale = 1e-300
    for i in range(n):
        for j in range(n):
            hscale = max(hscale, abs(P[i, j]))
    for a in range(nf):
        for bb in range(nf):
            hab = P[free[a], free[bb]]
            for k in range(ncv):
                hab += cs[k] * cv[k, free[a]] * cv[k, free[bb]]
            H[a, bb] = hab
    return H, hscale


@njit(cache=True, nogil=True)
def face_setup(x, z, zc, qp, cones, limits, F, d, w):
    """The least-norm stage's optimal face through ``x`` (:func:`mcdm_pin.solvers.least_norm.stage2_problem`)
    in one pass: the strongly active set of :func:`unique_test` (the duals ``z``, ``zc``; zero: none;
    thresholds ``limits.near``, ``unique_rel``), the rows :func:`face_rows` gathers over it (``P =
    diag(d) + F^T F``) and an orthonormal basis of their parts on ``rest`` (:func:`_row_basis`), the
    least-norm problem's bounds and rows made from them, and the least-norm point of the face in
    its own coordinates (:func:`._face_qp.face_least_norm`, weights ``w``). Returns a
    :class:`._structs.Face`."""
    qp, cones, limits = QP(*qp), Cones(*cones), Limits(*limits)  # (plain tuples at the boundary: ._structs)
    n = x.shape[0]
    thr = limits.unique_rel * _gradient_scale(x, qp.c, qp.H)
    idx, nf = _not_strongly_active(x, z, qp.lb, qp.ub, limits.near, thr)
    free = np.zeros(n, dtype=np.bool_)
    for a in range(nf):
        free[idx[a]] = True
    crow, nr, _, _, _, held = _held_cone_rows(cones.G, cones.gc, cones.ax, cones.tn, cones.cosr, zc, x, thr)
    S, rest, R = face_rows(F, d, qp.A, qp.c, np.ascontiguousarray(crow[:nr]), free)
    Vt, N = _row_basis(R)
    # the least-norm problem's bounds: a strongly active bound drops (the face holds it), x_i pins S
    lb, ub = np.empty(n), np.empty(n)
    for i in range(n):
        lb[i] = qp.lb[i] if free[i] else -np.inf
        ub[i] = qp.ub[i] if free[i] else np.inf
    for a in range(S.shape[0]):
        lb[S[a]] = ub[S[a]] = x[S[a]]
    E = np.zeros((Vt.shape[0], n))
    for r in range(Vt.shape[0]):
        for a in range(rest.shape[0]):
            E[r, rest[a]] = Vt[r, a]
    x_face, direct, steps = face_least_norm(x, w, rest, N, lb, ub, held, cones.G, cones.gc, cones.ax, cones.tn)
    return Face(free, held, S, rest, Vt, lb, ub, E, x_face, direct, steps)


@njit(cache=True, nogil=True)
def _row_basis(R):
    """An orthonormal basis of the rows of ``R`` (its right singular vectors whose singular value
    is above ``1e-10`` of the largest, or of 1 when the largest is smaller: rows of unit norm,
    :func:`face_rows`), and one of their null space (the other right singular vectors): ``(Vt,
    N)``, both over ``R``'s columns."""
    m = R.shape[1]
    if m == 0:
        return np.zeros((0, 0)), np.zeros((0, 0))
    if R.shape[0] == 0:
        return np.zeros((0, m)), np.eye(m)
    # (every right singular vector: the thin SVD gives them all when the rows are at least the columns)
    _, sv, Vt = np.linalg.svd(R, full_matrices=R.shape[0] < m)
    top = 1.0
    for i in range(sv.shape[0]):
        top = max(top, sv[i])
    r = 0
    for i in range(sv.shape[0]):  # (in decreasing order)
        if sv[i] > 1e-10 * top:
            r += 1
    return np.ascontiguousarray(Vt[:r]), np.ascontiguousarray(Vt[r:])


@njit(cache=True, nogil=True)
def face_rows(F, d, A, c, C, free):
    """The rows of :func:`face_setup`'s face before their basis: the objective's
    rows ``F`` (``P = diag(d) + F^T F``) whose curvature ``|F_i|^2`` is above ``1e-12`` of the largest
    curvature (theirs and ``|d_j|``), the equations ``A``, ``c^T`` and the strongly active cones' rows
    ``C``. The coordinates ``S`` whose unit rows are among them (``|d_j|`` above the same threshold,
    or a strongly active bound: not ``free``) split off, each other row's part on the remaining
    coordinates ``rest``, divided by the whole row's norm (rows of norm zero dropped), stacked into
    ``R``. Returns ``(S, rest, R)``."""
    n = c.shape[0]
    curv = np.empty(F.shape[0])
    top = 1e-300
    for i in range(F.shape[0]):
        curv[i] = dot(F[i], F[i])
        top = max(top, curv[i])
    for j in range(n):
        top = max(top, abs(d[j]))
    unit = np.empty(n, dtype=np.bool_)
    n_unit = 0
    for j in range(n):
        unit[j] = abs(d[j]) > 1e-12 * top or not free[j]
        if unit[j]:
            n_unit += 1
    S = np.empty(n_unit, dtype=np.int64)
    rest = np.empty(n - n_unit, dtype=np.int64)
    a = b = 0
    for j in range(n):
        if unit[j]:
            S[a] = j
            a += 1
        else:
            rest[b] = j
            b += 1
    R = np.empty((F.shape[0] + A.shape[0] + 1 + C.shape[0], n - n_unit))
    t = 0
    for i in range(F.shape[0]):
        if curv[i] > 1e-12 * top:
            t = _face_row(F[i], np.sqrt(curv[i]), rest, R, t)
    for i in range(A.shape[0]):
        t = _face_row(A[i], np.sqrt(dot(A[i], A[i])), rest, R, t)
    t = _face_row(c, np.sqrt(dot(c, c)), rest, R, t)
    for i in range(C.shape[0]):
        t = _face_row(C[i], np.sqrt(dot(C[i], C[i])), rest, R, t)
    return S, rest, R[:t]


@njit(cache=True, nogil=True, inline="always")
def _face_row(row, norm, rest, R, t):
    """``row``'s part on ``rest`` over ``norm`` into ``R[t]`` unless ``norm`` is zero; the next row."""
    if not norm > 0.0:
        return t
    for k in range(rest.shape[0]):
        R[t, k] = row[rest[k]] / norm
    return t + 1
