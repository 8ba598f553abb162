r"""Compiled (numba) kernels of the per-instant hot path.

The numpy formulation of the cable terms (:func:`mcdm_pin.model.geometry.cable_geometry` and the products in
:class:`mcdm_pin.model.terms.TermsEvaluator`) is a few dozen array operations on arrays of a few hundred
elements: its cost is numpy's per-call overhead, not arithmetic (0.13 ms of the neck's 0.18 ms terms,
``benchmarks/bench_id.py``). The kernel below does the same arithmetic in one compiled pass over the
route points and segments. It is the only place with explicit loops over cables; the numpy path
stays as the reference it is tested against (``tests/test_kernels.py``).

Compiled once per install by ``mcdm-pin compile`` and cached on disk (numba ``cache=True``:
``__pycache__`` beside this file, or ``NUMBA_CACHE_DIR``); until then the same functions run as plain
Python (:mod:`mcdm_pin.jit`), so every run gives the same answers.
"""

from __future__ import annotations

import numpy as np
from ..jit import njit
from .kernel_structs import CableTerms, KeyMaps, Route


@njit(cache=True, nogil=True)
def cable_terms(oM, Jt, route, maps):
    """Cable geometry, ``L`` and the cables' part of the interaction wrenches in one pass.

    Args:
        oM: (K, 4, 4) world placements (homogeneous) of the key bodies.
        Jt: (nv, 6) the world Jacobian, transposed: row v is column v's spatial velocity at the
            world origin (Pinocchio's column-major ``data.J`` transposed: a C-ordered view).
        route: the routes at this instant (a :class:`~mcdm_pin.model.kernel_structs.Route`'s fields, as
            a plain tuple: :mod:`mcdm_pin.solvers._structs`; a segment whose ``seg_scale`` is 0 adds
            neither length nor wrench).
        maps: what the key bodies move and carry (a :class:`~mcdm_pin.model.kernel_structs.KeyMaps`'
            fields, as a plain tuple).

    Returns a :class:`~mcdm_pin.model.kernel_structs.CableTerms`.
    """
    point_local, point_key, seg_a, seg_b, seg_cable, seg_active, seg_scale = route
    v_ptr, v_idx, a_ptr, a_idx, child_key, parent_key, R_sp, n_cables, n_joints = maps
    oR = oM[:, :3, :3]
    op = oM[:, :3, 3]
    nv = Jt.shape[0]
    X = _world_points(oR, op, point_local, point_key)
    seg_len, lengths, L, Ww, bad = _segment_terms(X, Jt, point_key, seg_a, seg_b, seg_cable, seg_active, seg_scale,
                                                  v_ptr, v_idx, a_ptr, a_idx, n_cables, n_joints)
    RT = _joint_wrenches(Ww, oR, op, child_key)
    R_socket = _socket_rotations(oR, parent_key, child_key, R_sp)
    if bad < 0:
        for c in range(n_cables):
            for v in range(nv):
                if not np.isfinite(L[c, v]):
                    bad = -2
    return CableTerms(X, seg_len, lengths, L, RT, R_socket, bad)


@njit(cache=True, nogil=True)
def _world_points(oR, op, point_local, point_key):
    """The route points in the world frame (P, 3), from their bodies' placements ``(oR, op)``."""
    n_pts = point_local.shape[0]
    X = np.empty((n_pts, 3))
    for p in range(n_pts):
        k = point_key[p]
        for i in range(3):
            X[p, i] = (oR[k, i, 0] * point_local[p, 0] + oR[k, i, 1] * point_local[p, 1]
                       + oR[k, i, 2] * point_local[p, 2] + op[k, i])
    return X


@njit(cache=True, nogil=True)
def _segment_terms(X, Jt, point_key, seg_a, seg_b, seg_cable, seg_active, seg_scale, v_ptr, v_idx, a_ptr, a_idx,
                   n_cables, n_joints):
    """Every segment's length and its ends' unit forces summed per cable (:func:`cable_terms`'
    arguments): ``(seg_len, lengths, L, Ww, bad)`` with ``Ww`` (Jn, 6, m) the cables' wrenches on
    each physical joint's subtree, in the world frame about the origin, and ``bad`` the first
    spanning segment of zero length (-1 when none)."""
    nv = Jt.shape[0]
    n_seg = seg_a.shape[0]
    seg_len = np.empty(n_seg)
    lengths = np.zeros(n_cables)
    L = np.zeros((n_cables, nv))
    Ww = np.zeros((n_joints, 6, n_cables))  # world, about the origin
    bad = -1
    for s in range(n_seg):
        a, b, c = seg_a[s], seg_b[s], seg_cable[s]
        sc = seg_scale[s]
        d0 = X[b, 0] - X[a, 0]
        d1 = X[b, 1] - X[a, 1]
        d2 = X[b, 2] - X[a, 2]
        ln = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        seg_len[s] = ln
        if sc == 0.0:
            continue
        lengths[c] += sc * ln
        if not seg_active[s]:
            continue
        if not ln > 1e-12:
            if bad < 0:
                bad = s
            continue
        u0, u1, u2 = sc * d0 / ln, sc * d1 / ln, sc * d2 / ln
        for end in range(2):
            e = b if end == 0 else a
            sg = 1.0 if end == 0 else -1.0
            x0, x1, x2 = X[e, 0], X[e, 1], X[e, 2]
            # the end's Pluecker vector w (six scalars: as a small array, each column's product is a
            # loop of six dependent adds)
            w0, w1, w2 = sg * u0, sg * u1, sg * u2
            w3 = sg * (x1 * u2 - x2 * u1)
            w4 = sg * (x2 * u0 - x0 * u2)
            w5 = sg * (x0 * u1 - x1 * u0)
            k = point_key[e]
            Lc = L[c]
            for t in range(v_ptr[k], v_ptr[k + 1]):
                v = v_idx[t]
                Jv = Jt[v]
                Lc[v] += (w0 * Jv[0] + w1 * Jv[1] + w2 * Jv[2]) + (w3 * Jv[3] + w4 * Jv[4] + w5 * Jv[5])
            for t in range(a_ptr[k], a_ptr[k + 1]):
                Wj = Ww[a_idx[t]]
                Wj[0, c] += w0
                Wj[1, c] += w1
                Wj[2, c] += w2
                Wj[3, c] += w3
                Wj[4, c] += w4
                Wj[5, c] += w5
    return seg_len, lengths, L, Ww, bad


@njit(cache=True, nogil=True)
def _joint_wrenches(Ww, oR, op, child_key):
    """The world wrenches ``Ww`` (overwritten: their moments moved to the joint points) in each
    joint's child frame at the joint point, ``RT`` (Jn, 6, m)."""
    n_joints, n_cables = Ww.shape[0], Ww.shape[2]
    # to each joint's child frame at the joint point: F = R^T F_w, M = R^T (M_w - t x F_w)
    RT = np.empty((n_joints, 6, n_cables))
    for j in range(n_joints):
        k = child_key[j]
        t0, t1, t2 = op[k, 0], op[k, 1], op[k, 2]
        F0, F1, F2, M0, M1, M2 = Ww[j, 0], Ww[j, 1], Ww[j, 2], Ww[j, 3], Ww[j, 4], Ww[j, 5]
        for c in range(n_cables):  # the moments about the joint point, in place (rows of Ww)
            f0, f1, f2 = F0[c], F1[c], F2[c]
            M0[c] = M0[c] - (t1 * f2 - t2 * f1)
            M1[c] = M1[c] - (t2 * f0 - t0 * f2)
            M2[c] = M2[c] - (t0 * f1 - t1 * f0)
        for i in range(3):  # row by row of RT: contiguous, where a cable at a time wrote six rows
            r0, r1, r2 = oR[k, 0, i], oR[k, 1, i], oR[k, 2, i]
            Rf, Rm = RT[j, i], RT[j, 3 + i]
            for c in range(n_cables):
                Rf[c] = r0 * F0[c] + r1 * F1[c] + r2 * F2[c]
                Rm[c] = r0 * M0[c] + r1 * M1[c] + r2 * M2[c]
    return RT


@njit(cache=True, nogil=True)
def _socket_rotations(oR, parent_key, child_key, R_sp):
    """Each joint's rotation child frame -> socket frame (Jn, 3, 3): ``(R_parent R_sp)^T R_child``."""
    n_joints = child_key.shape[0]
    R_socket = np.empty((n_joints, 3, 3))
    for j in range(n_joints):
        kp, kc = parent_key[j], child_key[j]
        for a in range(3):
            for b in range(3):
                acc = 0.0
                for t in range(3):
                    # (R_parent R_sp)[t, a] = sum_s R_parent[t, s] R_sp[s, a]
                    rps = oR[kp, t, 0] * R_sp[j, 0, a] + oR[kp, t, 1] * R_sp[j, 1, a] + oR[kp, t, 2] * R_sp[j, 2, a]
                    acc += rps * oR[kc, t, b]
                R_socket[j, a, b] = acc
    return R_socket


@njit(cache=True, nogil=True)
def noise_floor(A):
    """``1e3`` machine epsilons of the largest ``|A_ij|``: an entry at or below it is the rounding of
    a zero (a cable's moment arm about an axis its line meets, -4e-19 beside arms of 0.06 m), and the
    scaling treats it as zero. Equilibrated as a column of its own, that entry made the column's
    factor 2e18 and the variable's curvature 1e30 in the scaled problem, whose interior-point answer
    was 18 % above the optimum
    (tests/test_properties.py::test_a_rounding_zero_in_the_equations_does_not_scale_the_answer_away)."""
    amax = 0.0
    for i in range(A.shape[0]):
        for j in range(A.shape[1]):
            amax = max(amax, abs(A[i, j]))
    return 1e3 * 2.220446049250313e-16 * amax


@njit(cache=True, nogil=True)
def spread(A, b):
    """The largest ratio between the largest and smallest non-zero row maxima, column maxima and
    right-hand-side entries of ``|A|``, ``|b|`` (1 when all are zero): how badly scaled ``A x = b``
    is. Entries of ``A`` at its rounding (:func:`noise_floor`) count as zero."""
    n_r, n_c = A.shape
    tiny = noise_floor(A)
    cols = np.zeros(n_c)
    rmin, rmax = np.inf, 0.0
    for r in range(n_r):
        m = 0.0
        for c in range(n_c):
            v = abs(A[r, c])
            if v <= tiny:
                continue
            if v > m:
                m = v
            if v > cols[c]:
                cols[c] = v
        if m > 0.0:
            rmin = min(rmin, m)
            rmax = max(rmax, m)
    cmin, cmax = np.inf, 0.0
    for c in range(n_c):
        if cols[c] > 0.0:
            cmin = min(cmin, cols[c])
            cmax = max(cmax, cols[c])
    bmin, bmax = np.inf, 0.0
    for r in range(b.shape[0]):
        v = abs(b[r])
        if v > 0.0:
            bmin = min(bmin, v)
            bmax = max(bmax, v)
    if rmax == 0.0 or cmax == 0.0:
        return 1.0
    out = max(rmax / rmin, cmax / cmin)
    if bmax > 0.0:
        out = max(out, bmax / bmin)
    return out


@njit(cache=True, nogil=True, fastmath={"nnan", "ninf"})
def ruiz(A, sweeps):
    """:func:`mcdm_pin.scaling.equilibrate`: ``sweeps`` Ruiz sweeps on ``|A|`` (each row and column
    divided by the square root of its largest entry; an all-zero one left alone), then each factor
    rounded to the nearest power of two. Returns ``(r, d)``, the rows' and columns' factors.

    (``A`` is finite: an assembled problem's equations. The fastmath flags only let the maxima
    compile to vector instructions; no sum is reassociated, so the bits are the uncompiled code's.)"""
    n_r, n_c = A.shape
    tiny = noise_floor(A)
    # the entries above the noise floor, row by row (compressed rows): a zero never raises a maximum,
    # so the sweeps walk these alone (the equations of a muscle arm are about a tenth full)
    start = np.empty(n_r + 1, dtype=np.int64)
    cols = np.empty(n_r * n_c, dtype=np.int64)
    vals = np.empty(n_r * n_c)
    k = 0
    for i in range(n_r):
        start[i] = k
        for j in range(n_c):
            v = abs(A[i, j])
            if v > tiny:
                cols[k] = j
                vals[k] = v
                k += 1
    start[n_r] = k
    r = np.ones(n_r)
    d = np.ones(n_c)
    row = np.empty(n_r)
    col = np.empty(n_c)
    for _ in range(sweeps):
        col[:] = 0.0
        for i in range(n_r):
            ri = r[i]
            m = 0.0
            for k in range(start[i], start[i + 1]):  # this row's maximum, and the columns' so far
                j = cols[k]
                v = ri * vals[k] * d[j]
                col[j] = v if v > col[j] else col[j]
                m = v if v > m else m
            row[i] = m
        for i in range(n_r):
            r[i] /= np.sqrt(row[i] if row[i] != 0.0 else 1.0)
        for j in range(n_c):
            d[j] /= np.sqrt(col[j] if col[j] != 0.0 else 1.0)
    for i in range(n_r):
        r[i] = np.exp2(np.round(np.log2(r[i])))
    for j in range(n_c):
        d[j] = np.exp2(np.round(np.log2(d[j])))
    return r, d


@njit(cache=True, nogil=True)
def cone_batch(RT, u, R_socket, axes, index, socket):
    """Every cone's force map at once (:class:`mcdm_pin.constraints.cone.ConeBatch`, whose numpy
    ``arrays`` is the reference): cone ``k`` on physical joint ``j = index[k]`` has ``F = g + G f``
    with ``G = R^T[j, :3]``, ``g = u[j, :3]``, both turned into the socket frame by ``R_socket[j]``
    when ``socket[k]``; returns ``(G (K, 3, m), g (K, 3), axes (K, 3))``."""
    K = index.shape[0]
    m = RT.shape[2]
    G = np.empty((K, 3, m))
    g = np.empty((K, 3))
    ax = np.empty((K, 3))
    for k in range(K):
        j = index[k]
        for a in range(3):
            ax[k, a] = axes[j, a]
        if socket[k]:
            for a in range(3):
                r0, r1, r2 = R_socket[j, a, 0], R_socket[j, a, 1], R_socket[j, a, 2]
                g[k, a] = r0 * u[j, 0] + r1 * u[j, 1] + r2 * u[j, 2]
                for c in range(m):
                    G[k, a, c] = r0 * RT[j, 0, c] + r1 * RT[j, 1, c] + r2 * RT[j, 2, c]
        else:
            for a in range(3):
                g[k, a] = u[j, a]
                for c in range(m):
                    G[k, a, c] = RT[j, a, c]
    return G, g, ax


@njit(cache=True, nogil=True)
def gram_lower(X, rows, cols, out):
    """Add the lower triangle (diagonal included) of ``X[:rows, :cols]^T X[:rows, :cols]`` to ``out``
    (cols x cols), row by row, skipping zero entries: the Gram matrices of the interaction objective
    (:func:`interaction_quadratic`), the uniqueness test (:func:`mcdm_pin.solvers._unique.unique_test`)
    and the interior-point method's reduced system (:func:`mcdm_pin.solvers._ipm_structure.structure`)."""
    for t in range(rows):
        Xt = X[t]
        for a in range(cols):
            xa = Xt[a]
            if xa != 0.0:
                for b in range(a + 1):
                    out[a, b] += xa * Xt[b]


@njit(cache=True, nogil=True)
def interaction_quadratic(RT, u, keep, sw):
    """:meth:`mcdm_pin.objectives.MinInteractions.quadratic` (the numpy reference) in one pass: with
    ``K = sw R^T[keep]`` and ``k = sw u[keep]`` (rows of the flattened (J*6, m) and (J*6,) arrays),
    ``F = sqrt(2) K``, ``P = F^T F``, ``c = 2 K^T k``, ``r = k . k``; returns ``(P, c, r, F)``."""
    m = RT.shape[2]
    nk = keep.shape[0]
    R = RT.reshape(RT.shape[0] * 6, m)
    uf = u.reshape(u.shape[0] * 6)
    s2 = np.sqrt(2.0)
    F = np.empty((nk, m))
    c = np.zeros(m)
    r = 0.0
    for t in range(nk):
        row = keep[t]
        kt = sw[t] * uf[row]
        r += kt * kt
        for j in range(m):
            Kj = sw[t] * R[row, j]
            F[t, j] = s2 * Kj
            c[j] += kt * Kj
    for j in range(m):
        c[j] = 2.0 * c[j]
    P = np.zeros((m, m))
    gram_lower(F, nk, m, P)
    for a in range(m):
        for b in range(a):
            P[b, a] = P[a, b]
    return P, c, r, F


def csr(lists, n):
    """(ptr, idx) int64 arrays of a list of index lists."""
    ptr = np.zeros(n + 1, dtype=np.int64)
    ptr[1:] = np.cumsum([len(x) for x in lists])
    idx = np.array([i for x in lists for i in x], dtype=np.int64)
    return ptr, idx


@njit(cache=True, nogil=True)
def _outside(v, limit):
    return not (1.0 / limit <= v <= limit)


@njit(cache=True, nogil=True)
def bound_unit(lb, ub, d):
    """The variables' unit from their bounds in the units ``d`` (:func:`mcdm_pin.scaling.scaling_factors`,
    whose comments say why): the largest positive lower bound (a force a cable must carry), raised
    to the geometric middle with the smallest limit where that is larger. A limit is a nonzero
    upper bound, or a negative lower bound: an actuator's ``-U <= tau <= U`` says how large it may
    get, not how large it is (the thoracoscapular model's reserves have ``U`` up to 5e6 N m, and as
    a unit that put the muscles' forces at 1e-5 and the objective's factor at 2^31)."""
    unit = 0.0
    limit = np.inf
    for j in range(lb.shape[0]):
        lo, hi = lb[j] / d[j], ub[j] / d[j]
        if np.isfinite(lo) and lo > 0.0:
            unit = max(unit, lo)
        elif np.isfinite(lo) and lo < 0.0:
            limit = min(limit, -lo)
        if np.isfinite(hi) and hi != 0.0:
            limit = min(limit, abs(hi))
    if unit > 0.0 and np.isfinite(limit) and limit > unit:
        unit = np.sqrt(unit * limit)
    return unit


@njit(cache=True, nogil=True)
def needs_scaling(A, b, lb, ub, P_diag, P_factor, c, G, g, limit):
    """Whether :func:`mcdm_pin.scaling.scaling_factors` would scale this structured problem
    (``P = diag(P_diag) + P_factor^T P_factor``) at all: the same tests in one pass, for the usual
    well-scaled instant (then no copy is made). ``False`` means: every factor would be one; ``True``
    that some may not be, or that ``P_diag`` has a negative (or NaN) entry, which these tests do
    not cover (the caller then computes the factors)."""
    m, n = A.shape
    for j in range(n):
        if not P_diag[j] >= 0.0:
            return True
    if m and spread(A, np.zeros(0)) > limit:
        return True
    unit = bound_unit(lb, ub, np.ones(n))
    for r in range(m):
        row = 0.0
        for j in range(n):
            row = max(row, abs(A[r, j]))
        if row > 0.0:
            if _outside(row, limit):
                return True
            unit = max(unit, abs(b[r]) / row)
    if unit > 0.0 and _outside(unit, limit):
        return True
    # |P|'s largest entry: P = diag(P_diag) + P_factor^T P_factor (P_diag >= 0) is positive
    # semidefinite, so it is its largest diagonal entry
    size = 0.0
    for j in range(n):
        col = abs(P_diag[j])
        for r in range(P_factor.shape[0]):
            col += P_factor[r, j] * P_factor[r, j]
        size = max(size, col, abs(c[j]))
    if _outside(max(size, 1e-300), limit):
        return True
    for k in range(G.shape[0]):
        sz = 1e-300
        for e in range(3):
            sz = max(sz, abs(g[k, e]))
            for j in range(n):
                sz = max(sz, abs(G[k, e, j]))
        if _outside(sz, limit):
            return True
    return False


@njit(cache=True, nogil=True)
def _pow2(x):
    return np.exp2(np.round(np.log2(x)))


@njit(cache=True, nogil=True)
def _objective_size(reach, P, P_diag, P_factor, c):
    """:func:`scale_factors`' size of the objective with each variable at ``reach``: the largest
    ``|reach_i P_ij reach_j|`` (``P`` dense), else of ``P_diag reach^2`` and the factor's columns'
    sums of squares, and of ``|c reach|``; at least 1e-300."""
    n = reach.shape[0]
    size = 0.0
    if P.shape[0] > 0:
        for i in range(n):
            for j in range(n):
                size = max(size, abs(reach[i] * P[i, j] * reach[j]))
    else:
        for j in range(n):
            size = max(size, abs(P_diag[j] * reach[j] * reach[j]))
        acc = np.zeros(n)  # each column's sum of squares, rows in order (row by row: contiguous)
        for q in range(P_factor.shape[0]):
            for j in range(n):
                x = P_factor[q, j] * reach[j]
                acc[j] += x * x
        for j in range(n):
            size = max(size, acc[j])
    for j in range(n):
        size = max(size, abs(c[j] * reach[j]))
    return max(size, 1e-300)


@njit(cache=True, nogil=True)
def _cone_scales(G, g, d, limit):
    """:func:`scale_factors`' factor of each cone: one over the power of two nearest its size (the
    largest ``|G_k d|`` and ``|g_k|``) where that lies outside ``limit``, else 1."""
    K, _, n = G.shape
    cone = np.ones(K)
    for k in range(K):
        sz = 0.0
        for e in range(3):
            for j in range(n):
                sz = max(sz, abs(G[k, e, j] * d[j]))
        for e in range(3):
            sz = max(sz, abs(g[k, e]))
        sz = max(sz, 1e-300)
        if _outside(sz, limit):
            cone[k] = 1.0 / _pow2(sz)
    return cone


@njit(cache=True, nogil=True)
def scale_factors(A, b, lb, ub, c, P, P_diag, P_factor, structured, G, g, f_scale, force, limit):
    """:func:`mcdm_pin.scaling.scaling_factors` in one pass, the same steps in the same order
    (``P`` (n, n) the dense Hessian when the problem has it, else (0, 0); ``structured``: ``P =
    diag(P_diag) + P_factor^T P_factor``; ``f_scale`` (n,) or empty: none). Returns ``(scaled, d,
    r, obj, cone)``: ``scaled`` false when every factor is one and ``force`` is false (then the
    rest is meaningless)."""
    if not force and f_scale.shape[0] == 0 and structured and not needs_scaling(A, b, lb, ub, P_diag, P_factor, c, G,
                                                                                g, limit):
        m, n = A.shape
        return False, np.ones(n), np.ones(m), 1.0, np.ones(G.shape[0])
    return factors(A, b, lb, ub, c, P, P_diag, P_factor, G, g, f_scale, force, limit)


@njit(cache=True, nogil=True)
def factors(A, b, lb, ub, c, P, P_diag, P_factor, G, g, f_scale, force, limit):
    """:func:`scale_factors` without its one-pass test for the well-scaled instant (which only
    shortens: where it says "no scaling", these factors are all one as well)."""
    m, n = A.shape
    K = G.shape[0]
    ones_m, ones_n = np.ones(m), np.ones(n)
    has_f = f_scale.shape[0] > 0
    wide = m > 0 and spread(A, np.zeros(0)) > limit
    if wide:
        r, d = ruiz(A, np.int64(10))
    else:
        r, d = ones_m, ones_n.copy()
    if has_f and m > 0:
        for j in range(n):
            d[j] = d[j] * _pow2(f_scale[j])
    rows = np.zeros(m)
    for i in range(m):
        for j in range(n):
            rows[i] = max(rows[i], abs(A[i, j]) * d[j])
        rows[i] = rows[i] * r[i]
    # the variables' unit (scaling.py's comments say why)
    unit = bound_unit(lb, ub, d)
    for i in range(m):
        if rows[i] > 0.0:
            unit = max(unit, abs(b[i] * r[i]) / rows[i])
    u = _pow2(unit) if unit > 0.0 and _outside(unit, limit) else 1.0
    r = r.copy()
    for j in range(n):
        d[j] = d[j] * u
    for i in range(m):
        row = rows[i] * u
        if row > 0.0 and _outside(row, limit):
            r[i] = r[i] / _pow2(row)
    # the objective's size: each variable at its unit, or at its largest bound where that is smaller
    reach = np.empty(n)
    for j in range(n):
        bound = max(abs(lb[j]), abs(ub[j]))
        reach[j] = min(d[j], bound if np.isfinite(bound) else np.inf)
    size = _objective_size(reach, P, P_diag, P_factor, c)
    obj = _pow2(size) if _outside(size, limit) else 1.0
    cone = _cone_scales(G, g, d, limit)
    scaled = force or u != 1.0 or obj != 1.0
    for j in range(n):
        scaled = scaled or d[j] != 1.0
    for i in range(m):
        scaled = scaled or r[i] != 1.0
    for k in range(K):
        scaled = scaled or cone[k] != 1.0
    return scaled, d, r, obj, cone


def warm_calls():
    """This module's kernels with example arguments of the types the library passes (registered
    with :mod:`mcdm_pin.jit`, which loads them from numba's cache or compiles them)."""
    z = np.zeros
    i64 = np.int64
    return [(spread, (z((1, 2)), z(1))), (ruiz, (z((1, 2)), 10)),
            (scale_factors, (z((1, 2)), z(1), z(2), z(2), z(2), z((0, 0)), z(2), z((1, 2)), True, z((1, 3, 2)),
                             z((1, 3)), z(0), False, 1e3)),
            (interaction_quadratic, (z((1, 6, 2)), z((1, 6)), z(1, dtype=i64), z(1))),
            (cone_batch, (z((1, 6, 2)), z((1, 6)), z((1, 3, 3)), z((1, 3)), z(1, dtype=i64), np.ones(1, dtype=np.bool_))),
            (needs_scaling, (z((1, 2)), z(1), z(2), z(2), z(2), z((1, 2)), z(2), z((1, 3, 2)), z((1, 3)), 1e3)),
            (bound_unit, (z(2), z(2), np.ones(2))),
            # (plain tuples at the boundary: solvers._structs)
            (cable_terms, (np.tile(np.eye(4), (1, 1, 1)), z((1, 6)),
                           tuple(Route(z((2, 3)), z(2, dtype=i64), np.array([0], dtype=i64), np.array([1], dtype=i64),
                                       np.array([0], dtype=i64), np.array([False]), np.ones(1))),
                           tuple(KeyMaps(z(2, dtype=i64), z(0, dtype=i64), z(2, dtype=i64), z(0, dtype=i64),
                                         z(0, dtype=i64), z(0, dtype=i64), z((0, 3, 3)), 1, 0))))]


def warm_up() -> None:
    """Load every registered kernel from numba's cache when the compile step has stamped it
    (:func:`mcdm_pin.jit.prepare`); otherwise the kernels run uncompiled."""
    from .. import jit

    jit.prepare()


def _register() -> None:
    from .. import jit

    jit.register("mcdm_pin.model.kernels", warm_calls)


_register()
