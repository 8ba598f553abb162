r"""The search direction of one interior-point iteration (:mod:`._ipm`): the cones' Nesterov-Todd
scalings (:func:`cone_scalings`), the bounds' barrier terms (:func:`barrier`), the scaled Newton
system's solution for a right-hand side (:func:`newton_step`, through :mod:`._ipm_newton`), and
Mehrotra's predictor-corrector with Gondzio's centrality correctors and the longest step that keeps
every slack and multiplier in its cone (:func:`direction`).
"""

from __future__ import annotations

import numpy as np
from ..jit import njit

from . import _ipm_linalg as la
from . import _ipm_newton as newton

_FM = {"reassoc", "contract"}  # reassociation lets numba vectorise the dot products; no NaN/inf flags
_dot = la.dot


@njit(cache=True, nogil=True, error_model="numpy")
def _soc_scaling(s, z, W, Winv, W2, lam):
    """Nesterov-Todd scaling of one 3-dimensional second-order cone, in place: ``W`` and ``W^-1`` (3x3,
    symmetric) with ``W z = W^-1 s``, ``W2 = W W`` and ``lambda = W z``."""
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
    for a in range(3):
        lam[a] = W[a, 0] * z[0] + W[a, 1] * z[1] + W[a, 2] * z[2]
    for e in range(3):  # W symmetric: row e of W W
        for a in range(3):
            W2[e, a] = W[a, 0] * W[e, 0] + W[a, 1] * W[e, 1] + W[a, 2] * W[e, 2]


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
def _slack_step(dx, rzu, rzl, rzc, iu, il, T, dsu, dsl, dsc):
    """The slacks' step from the linearised constraints ``G dx + ds = -r_z`` (exact to rounding, so
    primal feasibility improves with every step even when the cones' scaling is ill-conditioned
    and ``W^2 W^-2`` is far from the identity), written into ``dsu, dsl, dsc``."""
    for q in range(iu.shape[0]):
        dsu[q] = -rzu[q] - dx[iu[q]]
    for q in range(il.shape[0]):
        dsl[q] = -rzl[q] + dx[il[q]]
    K = T.shape[0]
    la.rows_dot(T.reshape((3 * K, dx.shape[0])), np.int64(0), 3 * K, dx, dsc.reshape(3 * K), np.int64(0))
    for k in range(K):
        for e in range(3):
            dsc[k, e] -= rzc[k, e]


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
def barrier(d0, iu, il, su, zu, sl, zl, floor, dbar, dinv, ru, rl):
    """In place: ``D = d0 +`` the bounds' ``z/s`` (``dbar``; ``ru, rl`` the bounds' ``z/s``), and
    ``dinv = 1 / max(D, floor)`` (a variable without bounds or weight: refinement against the exact
    ``D`` corrects the floor)."""
    for i in range(d0.shape[0]):
        dbar[i] = d0[i]
    for q in range(iu.shape[0]):
        ru[q] = zu[q] / su[q]
        dbar[iu[q]] += ru[q]
    for q in range(il.shape[0]):
        rl[q] = zl[q] / sl[q]
        dbar[il[q]] += rl[q]
    for i in range(d0.shape[0]):
        dinv[i] = 1.0 / max(dbar[i], floor)


@njit(cache=True, nogil=True, error_model="numpy")
def newton_step(rhs_in, system, scaling, iu, il, refine, ws, out):
    """The scaled Newton system's ``out = (dx, dy, dzu, dzl, dzc)`` (in place) for the right-hand sides
    ``rhs_in = (bx, by, bzu, bzl, bzc)`` of ``P dx + A^T dy + G^T dz = bx, A dx = by,
    G dx - W^2 dz = bz``: the bounds' ``dz`` eliminated (``dz = (z/s) (G dx - bz)``, ``z/s`` from
    ``scaling``, a :class:`._structs.Scaling`), the cones' kept (:func:`._ipm_newton.solve` on
    ``system``, a :class:`._structs.NewtonSystem`: no ``W^-2`` is ever formed, whose entries grow like
    ``1/mu`` on an active cone). ``ws = (r1, u, rhs, wq)``: work arrays."""
    bx, by, bzu, bzl, bzc = rhs_in
    dx, dy, dzu, dzl, dzc = out
    ru, rl = scaling.ru, scaling.rl
    r1, u, rhs, wq = ws
    for i in range(bx.shape[0]):
        r1[i] = bx[i]
    for q in range(iu.shape[0]):
        r1[iu[q]] += ru[q] * bzu[q]
    for q in range(il.shape[0]):
        r1[il[q]] -= rl[q] * bzl[q]
    newton.solve(system, scaling.dinv, r1, bzc, by, u, rhs, wq, dx, dy, dzc)
    if refine:
        newton.refine(system, scaling, r1, bzc, by, dx, dy, dzc, refine, u, rhs, wq)
    for q in range(iu.shape[0]):
        dzu[q] = ru[q] * (dx[iu[q]] - bzu[q])
    for q in range(il.shape[0]):
        dzl[q] = rl[q] * (-dx[il[q]] - bzl[q])


@njit(cache=True, nogil=True, error_model="numpy")
def _step(su, dsu, sl, dsl, sc, dsc, zu, dzu, zl, dzl, zc, dzc):
    return min(_max_step(su, dsu, sl, dsl, sc, dsc), _max_step(zu, dzu, zl, dzl, zc, dzc))


@njit(cache=True, nogil=True, error_model="numpy")
def _centring(s, ds, z, dz, a, lo, hi, rs):
    """Gondzio's correction of the bounds' complementarity targets ``rs`` (in place): the products
    ``s_i z_i`` a longer step ``a`` would reach, pulled back into ``[lo, hi]``."""
    for q in range(s.shape[0]):
        v = (s[q] + a * ds[q]) * (z[q] + a * dz[q])
        if v < lo:
            rs[q] += lo - v
        elif v > hi:
            rs[q] += max(hi - v, -hi)


@njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _gap_at(s, ds, z, dz, a):
    """``(s + a ds)^T (z + a dz)`` without temporaries."""
    g = 0.0
    for i in range(s.shape[0]):
        g += (s[i] + a * ds[i]) * (z[i] + a * dz[i])
    return g


@njit(cache=True, nogil=True, error_model="numpy")
def _cone_corrector(lamc, Winv, Wm, dsc, dzc, rzc, smu, bzc):
    """The cones' corrector right-hand side ``bz = -r_z - W (lam \\ rs)`` (into ``bzc``) with
    ``rs = -lam o lam - (W^-1 ds_a) o (W dz_a) + sigma mu e`` (scalar code: no small arrays)."""
    K = lamc.shape[0]
    for k in range(K):
        Wi, Wk, ds, dz, lam = Winv[k], Wm[k], dsc[k], dzc[k], lamc[k]
        u0 = Wi[0, 0] * ds[0] + Wi[0, 1] * ds[1] + Wi[0, 2] * ds[2]
        u1 = Wi[1, 0] * ds[0] + Wi[1, 1] * ds[1] + Wi[1, 2] * ds[2]
        u2 = Wi[2, 0] * ds[0] + Wi[2, 1] * ds[1] + Wi[2, 2] * ds[2]
        v0 = Wk[0, 0] * dz[0] + Wk[0, 1] * dz[1] + Wk[0, 2] * dz[2]
        v1 = Wk[1, 0] * dz[0] + Wk[1, 1] * dz[1] + Wk[1, 2] * dz[2]
        v2 = Wk[2, 0] * dz[0] + Wk[2, 1] * dz[1] + Wk[2, 2] * dz[2]
        l0, l1, l2 = lam[0], lam[1], lam[2]
        # rs = -(lam o lam) - (u o v) + smu e
        r0 = -(l0 * l0 + l1 * l1 + l2 * l2) - (u0 * v0 + u1 * v1 + u2 * v2) + smu
        r1 = -2.0 * l0 * l1 - (u0 * v1 + v0 * u1)
        r2 = -2.0 * l0 * l2 - (u0 * v2 + v0 * u2)
        # x = lam \ rs
        det = l0 * l0 - l1 * l1 - l2 * l2
        x0 = (l0 * r0 - l1 * r1 - l2 * r2) / det
        x1 = (r1 - x0 * l1) / l0
        x2 = (r2 - x0 * l2) / l0
        for e in range(3):
            bzc[k, e] = -rzc[k, e] - (Wk[e, 0] * x0 + Wk[e, 1] * x1 + Wk[e, 2] * x2)


@njit(cache=True, nogil=True, error_model="numpy")
def direction(res, slacks, mu, system, scaling, iu, il, refine, ncorr, ws, rb, D):
    """Mehrotra's predictor-corrector direction with Gondzio's centrality correctors on the bounds
    (at most ``ncorr``, each kept only when it lengthens the step) at the iterate whose residuals are
    ``res = (rx, ry, rzu, rzl, rzc)`` and slacks ``slacks`` (:class:`._structs.Slacks`), with the
    Newton ``system`` and ``scaling`` (:class:`._structs.NewtonSystem`, :class:`._structs.Scaling`).
    ``rb = (bx, by, bzu, bzl, rsu, rsl, bzc)``: right-hand-side work arrays;
    ``D = (DX, DY, DZU, DZL, DZC, DSU, DSL, DSC)`` two slots of directions. Returns the slot of the
    direction and its largest step."""
    rx, ry, rzu, rzl, rzc = res
    su, zu, sl, zl, sc, zc = slacks
    T = system.T
    Wm, Winv, lamc = scaling.Wm, scaling.Winv, scaling.lamc
    K = T.shape[0]
    nu, nl = su.shape[0], sl.shape[0]
    gap = mu * (nu + nl + K)
    bx, by, bzu, bzl, rsu, rsl, bzc = rb
    DX, DY, DZU, DZL, DZC, DSU, DSL, DSC = D
    for i in range(rx.shape[0]):
        bx[i] = -rx[i]
    for a in range(ry.shape[0]):
        by[a] = -ry[a]
    # predictor (affine scaling): bz = -rz + s
    for q in range(nu):
        bzu[q] = -rzu[q] + su[q]
    for q in range(nl):
        bzl[q] = -rzl[q] + sl[q]
    for k in range(K):
        for e in range(3):
            bzc[k, e] = -rzc[k, e] + sc[k, e]
    dx, dy, dzu, dzl, dzc, dsu, dsl, dsc = DX[0], DY[0], DZU[0], DZL[0], DZC[0], DSU[0], DSL[0], DSC[0]
    rhs_in = (bx, by, bzu, bzl, bzc)
    newton_step(rhs_in, system, scaling, iu, il, refine, ws, (dx, dy, dzu, dzl, dzc))
    _slack_step(dx, rzu, rzl, rzc, iu, il, T, dsu, dsl, dsc)
    a_p = min(1.0, _step(su, dsu, sl, dsl, sc, dsc, zu, dzu, zl, dzl, zc, dzc))
    gap_aff = _gap_at(su, dsu, zu, dzu, a_p) + _gap_at(sl, dsl, zl, dzl, a_p)
    for k in range(K):
        for e in range(3):
            gap_aff += (sc[k, e] + a_p * dsc[k, e]) * (zc[k, e] + a_p * dzc[k, e])
    sigma = min(1.0, max(0.0, gap_aff / max(gap, 1e-300))) ** 3
    smu = sigma * mu
    # corrector: rs = -lam o lam - (W^-1 ds_a) o (W dz_a) + sigma mu e
    for q in range(nu):
        lq = np.sqrt(su[q] * zu[q])
        rsu[q] = -lq * lq - dsu[q] * dzu[q] + smu
    for q in range(nl):
        lq = np.sqrt(sl[q] * zl[q])
        rsl[q] = -lq * lq - dsl[q] * dzl[q] + smu
    _cone_corrector(lamc, Winv, Wm, dsc, dzc, rzc, smu, bzc)
    best, best_a = 0, 0.0
    cur = 0  # the predictor's slot is free again
    for j in range(ncorr + 1):
        # W (lam \ rs) = rs / z on the bounds
        for q in range(nu):
            bzu[q] = -rzu[q] - rsu[q] / zu[q]
        for q in range(nl):
            bzl[q] = -rzl[q] - rsl[q] / zl[q]
        dx, dy, dzu, dzl, dzc = DX[cur], DY[cur], DZU[cur], DZL[cur], DZC[cur]
        dsu, dsl, dsc = DSU[cur], DSL[cur], DSC[cur]
        newton_step(rhs_in, system, scaling, iu, il, refine, ws, (dx, dy, dzu, dzl, dzc))
        _slack_step(dx, rzu, rzl, rzc, iu, il, T, dsu, dsl, dsc)
        a = _step(su, dsu, sl, dsl, sc, dsc, zu, dzu, zl, dzl, zc, dzc)
        if not np.isfinite(_dot(dx, dx) + _dot(dy, dy)):
            a = 0.0
        if j > 0 and not a > 1.01 * best_a:
            break
        best, best_a = cur, a
        if a >= 0.9:  # long enough: a corrector would cost more than it gains
            break
        at = min(1.0, a + 0.5)
        _centring(su, dsu, zu, dzu, at, 0.1 * smu, 10.0 * smu, rsu)
        _centring(sl, dsl, zl, dzl, at, 0.1 * smu, 10.0 * smu, rsl)
        cur = 1 - cur
    return best, best_a


@njit(cache=True, nogil=True, error_model="numpy")
def cone_scalings(sc, zc, Wm, Winv, Wc2, lamc):
    """Every cone's Nesterov-Todd ``W``, ``W^-1``, ``W^2`` and ``lambda = W z``, in place."""
    for k in range(sc.shape[0]):
        _soc_scaling(sc[k], zc[k], Wm[k], Winv[k], Wc2[k], lamc[k])
