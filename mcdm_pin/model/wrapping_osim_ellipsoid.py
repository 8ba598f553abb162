r"""OpenSim's wrapping of one path segment over a ``WrapEllipsoid`` (``WrapEllipsoid::wrapLine`` with
``findClosestPoint``, ``closestPointToEllipse``, ``calcTangentPoint`` and ``CalcDistanceOnEllipsoid``,
read in opensim-core's sources and written again from their description); the conventions of
:mod:`mcdm_pin.model.wrapping_osim` (points in the ellipsoid's frame, ``(code, r1, r2, length)``).

OpenSim scales the problem by ``3 / (a + b + c)``, intersects the segment with the ellipsoid, picks a
point ``c1`` on the surface (``hybrid``: the closest point to the segment's point on its dominant axis,
blended with a fan of 300 closest points when the segment is not along an axis; ``midpoint``: the
closest point to the chord's middle; ``axial``: the dominant axis only), flips it to the active side
for a quadrant, then moves both tangent points by damped Gauss-Newton steps until they lie in the plane
through the segment and ``c1``, on the surface, with tangent lines to the end points (squared residual
<= 1e-8, at most 50 rounds), and measures the path over the surface as a polyline of about 1 mm
segments in that plane (at most 499), the far way round when a quadrant asks for it. We take the same
iterations and the same polyline, so the agreement with OpenSim is to rounding, not to these
tolerances.
"""

from __future__ import annotations

import math

import numpy as np

from .wrapping_osim import (EPS, INSIDE_RADIUS, MANDATORY_WRAP, NO_WRAP, ROUNDOFF, _ZERO, _acos, _add, _cross, _dot,
                            _dsign, _mul, _norm, _sub, _unit, register_jitable)

ELLIPSOID_TINY = 1e-8  # calcTangentPoint stops at this squared residual
MU_BLEND_MIN, MU_BLEND_MAX = 0.7073, 0.9
NUM_FAN_SAMPLES = 300
SV_BOUNDARY_BLEND = 0.3
HYBRID, MIDPOINT, AXIAL = 0, 1, 2  # PathWrap methods


@register_jitable
def _sqrt(x):
    """C's sqrt: NaN below zero (Python's raises)."""
    return math.sqrt(x) if x >= 0.0 else math.nan


@register_jitable
def _div(a, b):
    """IEEE division (a zero denominator gives inf or nan, as in C)."""
    if b != 0.0:
        return a / b
    if a == 0.0 or a != a:
        return math.nan
    return math.inf if (a > 0) == (math.copysign(1.0, b) > 0) else -math.inf


@register_jitable
def _closest_on_ellipse(a, b, u, v, x, y):
    """WrapEllipsoid::closestPointToEllipse: ``(x, y)`` on the ellipse of semi-axes ``a``, ``b`` nearest
    ``(u, v)``."""
    a2, b2 = a * a, b * b
    a2u2, b2v2 = a2 * u * u, b2 * v * v
    near_x, near_y = abs(u) <= ROUNDOFF, abs(v) <= ROUNDOFF
    if near_x and near_y:
        if a < b:
            return (-a if u < 0.0 else a), v
        return u, (-b if v < 0.0 else b)
    if near_x:
        if a >= b or abs(v) >= b - a2 / b:
            return u, (b if v >= 0 else -b)
        yy = b2 * v / (b2 - a2)
        ydb = yy / b
        return a * math.sqrt(abs(1 - ydb * ydb)), yy
    if near_y:
        if b >= a or abs(u) >= a - b2 / a:
            return (a if u >= 0 else -a), v
        xx = a2 * u / (a2 - b2)
        xda = xx / a
        return xx, b * math.sqrt(abs(1 - xda * xda))
    if (u / a) ** 2 + (v / b) ** 2 < 1.0:
        t = 0.0
    else:
        t = max(a, b) * math.sqrt(u * u + v * v)
    P, Q = t + a2, t + b2
    for _ in range(64):
        P, Q = t + a2, t + b2
        f = P * P * Q * Q - a2u2 * Q * Q - b2v2 * P * P
        if abs(f) < 1e-09:
            break
        fp = 2.0 * (P * Q * (P + Q) - a2u2 * Q - b2v2 * P)
        t -= f / fp
    return a2 * u / P, b2 * v / Q


@register_jitable
def _closest_on_ellipsoid(dims, a, b, c, u, v, w, axis, prev):
    """WrapEllipsoid::findClosestPoint: the point of the ellipsoid ``a, b, c`` (scaled semi-axes;
    ``dims`` the unscaled ones pick the special case) nearest ``(u, v, w)``; ``axis`` -1 lets it find a
    zero coordinate; ``prev`` is returned when Newton's method does not converge (OpenSim leaves its
    output untouched then)."""
    if axis < 0:
        best = math.inf
        uvw = (u, v, w)
        for i in range(3):
            if abs(uvw[i]) <= ROUNDOFF:
                s = dims[0] + dims[1] + dims[2] - dims[i]
                if best > s:
                    axis, best = i, s
    if axis == 0:
        y, z = _closest_on_ellipse(b, c, v, w, prev[1], prev[2])
        return (u, y, z)
    if axis == 1:
        z, x = _closest_on_ellipse(c, a, w, u, prev[2], prev[0])
        return (x, v, z)
    if axis == 2:
        x, y = _closest_on_ellipse(a, b, u, v, prev[0], prev[1])
        return (x, y, w)
    a2, b2, c2 = a * a, b * b, c * c
    a2u2, b2v2, c2w2 = a2 * u * u, b2 * v * v, c2 * w * w
    t = _newton_start(a, b, c, u, v, w)
    for _ in range(64):
        P, Q, R, f, fp = _newton_terms(t, a2, b2, c2, a2u2, b2v2, c2w2)
        if abs(f) < 1e-09:
            return (a2 * u / P, b2 * v / Q, c2 * w / R)
        t -= f / fp
    return prev


@register_jitable
def _newton_start(a, b, c, u, v, w):
    """findClosestPoint's start for ``t``: 0 inside the ellipsoid, ``max(a, b, c) |(u, v, w)|``
    outside."""
    if (u / a) ** 2 + (v / b) ** 2 + (w / c) ** 2 < 1.0:
        return 0.0
    return max(a, b, c) * math.sqrt(u * u + v * v + w * w)


@register_jitable
def _newton_terms(t, a2, b2, c2, a2u2, b2v2, c2w2):
    """findClosestPoint's Newton step at ``t``: ``(P, Q, R, f, f')`` with ``P = t + a^2``,
    ``Q = t + b^2``, ``R = t + c^2`` and ``f(t) = P^2 Q^2 R^2 - a^2 u^2 Q^2 R^2 - b^2 v^2 P^2 R^2 -
    c^2 w^2 P^2 Q^2`` (OpenSim's order of operations, so the same bits)."""
    P, Q, R = t + a2, t + b2, t + c2
    f = P * P * Q * Q * R * R - a2u2 * Q * Q * R * R - b2v2 * P * P * R * R - c2w2 * P * P * Q * Q
    PQ, PR, QR, PQR = P * Q, P * R, Q * R, P * Q * R
    fp = 2.0 * (PQR * (QR + PR + PQ) - a2u2 * QR * (Q + R) - b2v2 * PR * (P + R) - c2w2 * PQ * (P + Q))
    return P, Q, R, f, fp


@register_jitable
def _solve4(M, rhs, A, x):
    """``x = M^-1 rhs`` for a 4x4 ``M`` (Gauss-Jordan with partial pivoting), ``A`` (4, 4) its work
    array: both given, so the damped steps' loop allocates nothing."""
    for i in range(4):
        x[i] = rhs[i]
        for k in range(4):
            A[i, k] = M[i, k]
    for col in range(4):
        piv = col
        for r in range(col + 1, 4):
            if abs(A[r, col]) > abs(A[piv, col]):
                piv = r
        if piv != col:
            for k in range(4):
                A[col, k], A[piv, k] = A[piv, k], A[col, k]
            x[col], x[piv] = x[piv], x[col]
        d = A[col, col]
        for k in range(4):
            A[col, k] /= d
        x[col] /= d
        for r in range(4):
            if r != col:
                g = A[r, col]
                for k in range(4):
                    A[r, k] -= g * A[col, k]
                x[r] -= g * x[col]


@register_jitable
def _tangent_residual(r1, d1, p1, a, vs, vs4):
    """calcTangentPoint's residuals: in the plane, on the ellipsoid, tangent plane through ``r1`` and
    ``p1`` (a tuple); and their sum of squares."""
    nr1 = (2.0 * r1[0] / (a[0] * a[0]), 2.0 * r1[1] / (a[1] * a[1]), 2.0 * r1[2] / (a[2] * a[2]))
    e0 = vs[0] * r1[0] + vs[1] * r1[1] + vs[2] * r1[2] + vs4
    e1 = -1.0 + (r1[0] / a[0]) ** 2 + (r1[1] / a[1]) ** 2 + (r1[2] / a[2]) ** 2
    e2 = _dot(nr1, r1) + d1
    e3 = _dot(nr1, p1) + d1
    return (e0, e1, e2, e3), e0 * e0 + e1 * e1 + e2 * e2 + e3 * e3


@register_jitable
def _tangent_point(pe, r1, p1, a, vs, vs4):
    """WrapEllipsoid::calcTangentPoint (centre at the origin): ``r1`` moved, by OpenSim's damped
    Gauss-Newton steps, until it lies in the plane ``vs . x + vs4 = 0``, on the ellipsoid and on a line
    from ``p1`` tangent to it (squared residual <= 1e-8, at most 50 rounds). Its arrays are made once
    per call, not per step."""
    if abs(pe) < 0.0001:
        return p1
    r = np.array([r1[0], r1[1], r1[2]])
    nr1 = (2.0 * r[0] / (a[0] * a[0]), 2.0 * r[1] / (a[1] * a[1]), 2.0 * r[2] / (a[2] * a[2]))
    d1 = -(nr1[0] * r[0] + nr1[1] * r[1] + nr1[2] * r[2])
    ee, ssq = _tangent_residual((r[0], r[1], r[2]), d1, p1, a, vs, vs4)
    ssqo = ssq
    alpha = 0.01
    D = np.zeros((4, 4))
    D2 = np.empty((4, 4))
    work = np.empty((4, 4))
    v, diag, vt, x = np.empty(4), np.empty(4), np.empty(4), np.empty(4)
    for _ in range(50):
        if not ssq > ELLIPSOID_TINY:
            break
        for i in range(3):
            D[i, 0] = vs[i]
            D[i, 1] = 2.0 * r[i] / (a[i] * a[i])
            D[i, 2] = 2.0 * (2.0 * r[i]) / (a[i] * a[i])
            D[i, 3] = 2.0 * p1[i] / (a[i] * a[i])
        D[3, 0], D[3, 1], D[3, 2], D[3, 3] = 0.0, 0.0, 1.0, 1.0
        pr = _unit(_sub(p1, (r[0], r[1], r[2])))
        pm = _unit(p1)
        pcos = _dot(pr, pm)
        dd = 1.0 - pcos ** 100 if pcos > 0.1 else 1.0
        for i in range(4):
            v[i] = 0.0
            vt[i] = 0.0
            for j in range(4):
                D2[i, j] = 0.0
        for i in range(4):
            for j in range(4):
                v[i] -= D[i, j] * ee[j]
                for k in range(4):
                    D2[i, j] += D[i, k] * D[j, k]
        for i in range(4):
            diag[i] = D2[i, i]
        n2 = 0
        while ssq >= ssqo and n2 < 1000:
            for i in range(4):
                D2[i, i] = diag[i] * (1.0 + alpha)
            _solve4(D2, v, work, x)
            for i in range(4):
                vt[i] = dd * x[i] / 16.0
            r[0] += vt[0]
            r[1] += vt[1]
            r[2] += vt[2]
            d1 += vt[3]
            ssqo = ssq
            ee, ssq = _tangent_residual((r[0], r[1], r[2]), d1, p1, a, vs, vs4)
            alpha *= 4.0
            n2 += 1
        alpha /= 8.0
        fakt = 0.5
        n2 = 0
        while ssq <= ssqo and n2 < 1000:
            fakt *= 2.0
            r[0] += vt[0] * fakt
            r[1] += vt[1] * fakt
            r[2] += vt[2] * fakt
            d1 += vt[3] * fakt
            ssqo = ssq
            ee, ssq = _tangent_residual((r[0], r[1], r[2]), d1, p1, a, vs, vs4)
            n2 += 1
        r[0] -= vt[0] * fakt
        r[1] -= vt[1] * fakt
        r[2] -= vt[2] * fakt
        d1 -= vt[3] * fakt
        ee, ssq = _tangent_residual((r[0], r[1], r[2]), d1, p1, a, vs, vs4)
        ssqo = ssq
    return (r[0], r[1], r[2])


@register_jitable
def _ellipsoid_arc(r1, r2, a, vs, vs4, far, factor):
    """WrapEllipsoid::CalcDistanceOnEllipsoid (centre at the origin, scaled coordinates): the length of
    OpenSim's polyline over the surface from ``r1`` to ``r2`` in the plane ``(vs, vs4)`` (segments of
    about 1 mm unscaled, at most 499), and its second and second-last points (for the far-side test)."""
    chord = _norm(_sub(r1, r2)) / factor
    if chord < 0.001:
        return chord * factor, r2, r1, 1
    n_seg = min(int(chord / 0.001), 499)
    imax = 0
    for i in range(1, 3):
        if abs(vs[i]) > abs(vs[imax]):
            imax = i
    mu = -vs4 / vs[imax]
    a0 = (mu if imax == 0 else 0.0, mu if imax == 1 else 0.0, mu if imax == 2 else 0.0)
    ar1 = _unit(_sub(r1, a0))
    ar2 = _unit(_sub(r2, a0))
    phi0 = _acos(_dot(ar1, ar2))
    dphi = -(2 * math.pi - phi0) / n_seg if far else phi0 / n_seg
    vsz = _unit(_cross(ar1, ar2))
    vsy = _cross(vsz, ar1)
    f2 = (a0[0] / a[0], a0[1] / a[1], a0[2] / a[2])
    cc = _dot(f2, f2) - 1.0
    total, prev = 0.0, r1
    first, last = r2, r1
    for i in range(n_seg - 1):
        phi = (i + 1) * dphi
        cp, sp = math.cos(phi), math.sin(phi)
        r = (ar1[0] * cp + vsy[0] * sp, ar1[1] * cp + vsy[1] * sp, ar1[2] * cp + vsy[2] * sp)
        f1 = (r[0] / a[0], r[1] / a[1], r[2] / a[2])
        aa, bb = _dot(f1, f1), 2.0 * _dot(f1, f2)
        mu3 = (-bb + _sqrt(bb * bb - 4.0 * aa * cc)) / (2.0 * aa)
        s = _add(a0, _mul(r, mu3))
        total += _norm(_sub(s, prev))
        if i == 0:
            first = s
        last = s
        prev = s
    total += _norm(_sub(r2, prev))
    return total, first, last, n_seg + 1


N_FAN = NUM_FAN_SAMPLES - 2  # the fan's samples, i = 1 .. 298


@register_jitable
def _fan_samples(r1, r1r2, a):
    """The fan's samples ``s_i = r1 + (i / 300) r1r2`` as ``(u, v, w)``, the products ``(a^2 u^2,
    b^2 v^2, c^2 w^2)``, Newton's start ``t`` (0 inside the ellipsoid, ``max(a, b, c) |s_i|``
    outside) and ``live``: 1 for a sample in the general case of :func:`_closest_on_ellipsoid`, 0 for
    one with a coordinate within ``ROUNDOFF`` of zero. One array each (a sweep over separate arrays
    compiles to vector instructions; rows of one array, which the compiler cannot tell apart, run
    at half that speed)."""
    A, B, C = a[0], a[1], a[2]
    a2, b2, c2 = A * A, B * B, C * C
    su, sv, sw = np.empty(N_FAN), np.empty(N_FAN), np.empty(N_FAN)
    k0, k1, k2, t = np.empty(N_FAN), np.empty(N_FAN), np.empty(N_FAN), np.empty(N_FAN)
    live = np.empty(N_FAN, np.int64)
    for j in range(N_FAN):
        s = (j + 1) / NUM_FAN_SAMPLES
        u, v, w = r1[0] + r1r2[0] * s, r1[1] + r1r2[1] * s, r1[2] + r1r2[2] * s
        su[j], sv[j], sw[j] = u, v, w
        live[j] = 0 if abs(u) <= ROUNDOFF or abs(v) <= ROUNDOFF or abs(w) <= ROUNDOFF else 1
        k0[j], k1[j], k2[j] = a2 * u * u, b2 * v * v, c2 * w * w
        t[j] = _newton_start(A, B, C, u, v, w)
    return su, sv, sw, k0, k1, k2, t, live


@register_jitable
def _fan_newton(a, k0, k1, k2, t, live):
    """Newton's iteration of :func:`_closest_on_ellipsoid`'s general case for every live sample, in
    sweeps over all of them: a sweep is one step of each sample still iterating (the same arithmetic
    in the same order, so the same roots ``t`` to the bit). A sample leaves ``live`` when
    ``|f| < 1e-9``; after 64 steps the ones still live did not converge. The sweep has no branch, so
    the compiler turns it into vector instructions: four samples per instruction instead of one."""
    a2, b2, c2 = a[0] * a[0], a[1] * a[1], a[2] * a[2]
    for _ in range(64):
        n_live = 0
        for j in range(N_FAN):
            tj = t[j]
            _, _, _, f, fp = _newton_terms(tj, a2, b2, c2, k0[j], k1[j], k2[j])
            step = live[j] if not abs(f) < 1e-09 else 0  # (a NaN f keeps stepping, as in OpenSim)
            # (f / 0 in C is inf, and the next step's f NaN: either way the sample does not converge)
            t[j] = (tj - (f / fp if fp != 0.0 else math.nan)) if step != 0 else tj
            live[j] = step
            n_live += step
        if n_live == 0:
            return


@register_jitable
def _fan_units(a, su, sv, sw, t):
    """Each sample's nearest point ``(a^2 u / (t + a^2), ...)`` at its root ``t``, and the unit
    vector to it from the sample (``_unit``: zeros below ``EPS``): ``(x, y, z, ex, ey, ez)``, one
    array each (meaningful for the samples that converged)."""
    a2, b2, c2 = a[0] * a[0], a[1] * a[1], a[2] * a[2]
    x, y, z = np.empty(N_FAN), np.empty(N_FAN), np.empty(N_FAN)
    ex, ey, ez = np.empty(N_FAN), np.empty(N_FAN), np.empty(N_FAN)
    for j in range(N_FAN):
        tj = t[j]
        xj, yj, zj = a2 * su[j] / (tj + a2), b2 * sv[j] / (tj + b2), c2 * sw[j] / (tj + c2)
        x[j], y[j], z[j] = xj, yj, zj
        dx, dy, dz = xj - su[j], yj - sv[j], zj - sw[j]
        n = math.sqrt(dx * dx + dy * dy + dz * dz)
        big = n >= EPS
        ex[j] = dx / n if big else 0.0
        ey[j] = dy / n if big else 0.0
        ez[j] = dz / n if big else 0.0
    return x, y, z, ex, ey, ez


@register_jitable
def _fan_sum(dims, a, r1, r1r2, prev):
    """The hybrid method's fan: the sum, over the samples ``s_i = r1 + (i / 300) r1r2``
    (``i = 1 .. 298``), of the unit vectors from ``s_i`` to the ellipsoid's point nearest it, each
    found by :func:`_closest_on_ellipsoid` (``prev``: the first sample's fallback, then each sample's
    point the next one's, as OpenSim passes them).

    The samples' Newton iterations are independent: :func:`_fan_samples`, :func:`_fan_newton` and
    :func:`_fan_units` run them side by side over arrays. The sum then goes through the samples in
    order, as OpenSim's loop does: a sample with a coordinate within ``ROUNDOFF`` of zero (the
    special cases) goes through :func:`_closest_on_ellipsoid` itself, and one whose iteration did not
    converge keeps the previous sample's point. The sum is OpenSim's loop's to the bit."""
    su, sv, sw, k0, k1, k2, t, live = _fan_samples(r1, r1r2, a)
    special = live == 0
    _fan_newton(a, k0, k1, k2, t, live)
    x, y, z, ex, ey, ez = _fan_units(a, su, sv, sw, t)
    s0, s1, s2 = 0.0, 0.0, 0.0
    for j in range(N_FAN):
        if special[j] or live[j] != 0:
            p = (su[j], sv[j], sw[j])
            if special[j]:
                prev = _closest_on_ellipsoid(dims, a[0], a[1], a[2], p[0], p[1], p[2], -1, prev)
            e = _unit(_sub(prev, p))
            s0, s1, s2 = s0 + e[0], s1 + e[1], s2 + e[2]
        else:
            prev = (x[j], y[j], z[j])
            s0, s1, s2 = s0 + ex[j], s1 + ey[j], s2 + ez[j]
    return (s0, s1, s2)


@register_jitable
def _surface_point(dims, a, p1p2, r1, r2, axis, sign, method):
    """The surface point ``c1`` the tangent plane passes through, and the tangent points' start
    ``(c1, r1, r2)`` (OpenSim's hybrid, midpoint or axial choice, then the quadrant's flip)."""
    r1r2 = _sub(r2, r1)
    mu = _unit(p1p2)
    mu = (abs(mu[0]), abs(mu[1]), abs(mu[2]))
    t = (_div(-r1[0], r1r2[0]), _div(-r1[1], r1r2[1]), _div(-r1[2], r1r2[2]))
    sv_t = [_add(r1, _mul(r1r2, t[i])) for i in range(3)]
    c1_t = [_closest_on_ellipsoid(dims, a[0], a[1], a[2], sv_t[i][0], sv_t[i][1], sv_t[i][2], i, _ZERO)
            for i in range(3)]
    best = 0
    for i in range(1, 3):
        if mu[i] > mu[best]:
            best = i
    mub, tb = mu[best], t[best]
    c1, fan = _ZERO, -math.inf
    if method == HYBRID or method == AXIAL:
        if method == HYBRID and mub > MU_BLEND_MIN:
            s = 1.0
            if tb < 0.0 or tb > 1.0:
                s = 0.0
            elif tb < SV_BOUNDARY_BLEND:
                s = tb / SV_BOUNDARY_BLEND
            elif tb > 1.0 - SV_BOUNDARY_BLEND:
                s = (1.0 - tb) / SV_BOUNDARY_BLEND
            if s < 1.0:
                mub = MU_BLEND_MIN + s * (mub - MU_BLEND_MIN)
        if method == AXIAL or mub > MU_BLEND_MIN:
            c1 = c1_t[best]
        if method == HYBRID and mub < MU_BLEND_MAX:
            mid = _add(r1, _mul(r1r2, 0.5))
            fan_pt = _add(mid, _unit(_fan_sum(dims, a, r1, r1r2, c1_t[0])))
            if mub <= MU_BLEND_MIN:
                c1 = _closest_on_ellipsoid(dims, a[0], a[1], a[2], fan_pt[0], fan_pt[1], fan_pt[2], -1, c1)
                fan = 1.0
            else:
                tt = (mub - MU_BLEND_MIN) / (MU_BLEND_MAX - MU_BLEND_MIN)
                c1b = _closest_on_ellipsoid(dims, a[0], a[1], a[2], fan_pt[0], fan_pt[1], fan_pt[2], -1, c1_t[1])
                c2 = _add(_mul(c1, tt), _mul(c1b, 1.0 - tt))
                c1 = _closest_on_ellipsoid(dims, a[0], a[1], a[2], c2[0], c2[1], c2[2], -1, c1)
                fan = 1.0 - tt
    else:
        sv = _add(r1, _mul(_sub(r2, r1), 0.5))
        c1 = _closest_on_ellipsoid(dims, a[0], a[1], a[2], sv[0], sv[1], sv[2], -1, c1)
    if method != AXIAL or (0.0 < tb < 1.0):
        r1, r2 = c1, c1
    if sign != 0 and _dsign(c1[axis]) != sign:
        orig = c1[axis]
        c1 = (-c1[0] if axis == 0 else c1[0], -c1[1] if axis == 1 else c1[1], -c1[2] if axis == 2 else c1[2])
        r1, r2 = c1, c1
        # (OpenSim then tests EQUAL_WITHIN_ERROR(fanWeight, -inf), which is never true: an unset fan
        # weight stays -inf and the bisection below is skipped)
        fan = min(fan, 1.0)
        if fan > 0.0:
            bis = (orig + c1[axis]) / 2.0
            ca = c1[axis] + fan * (bis - c1[axis])
            tc = (ca if axis == 0 else c1[0], ca if axis == 1 else c1[1], ca if axis == 2 else c1[2])
            c1 = _closest_on_ellipsoid(dims, a[0], a[1], a[2], tc[0], tc[1], tc[2], -1, c1)
    return c1, r1, r2


@register_jitable
def osim_ellipsoid(p1, p2, dims, axis, sign, method):
    """OpenSim's ``WrapEllipsoid::wrapLine`` with the ``PathWrap`` method ``method`` (:data:`HYBRID`,
    :data:`MIDPOINT`, :data:`AXIAL`): ``(code, r1, r2, length)``; points in the ellipsoid's frame,
    ``dims`` its semi-axes (m). OpenSim's own iterations, so its own tolerances: the tangent points
    solve their equations to a squared residual of 1e-8 (scaled units) and the surface path is a
    polyline of ~1 mm segments."""
    factor = 3.0 / (dims[0] + dims[1] + dims[2])
    p1 = _mul(p1, factor)
    p2 = _mul(p2, factor)
    a = _mul(dims, factor)
    p1e = -1.0 + (p1[0] / a[0]) ** 2 + (p1[1] / a[1]) ** 2 + (p1[2] / a[2]) ** 2
    p2e = -1.0 + (p2[0] / a[0]) ** 2 + (p2[1] / a[1]) ** 2 + (p2[2] / a[2]) ** 2
    if p1e < -0.0001 or p2e < -0.0001:
        return INSIDE_RADIUS, _ZERO, _ZERO, 0.0
    p1p2 = _sub(p1, p2)
    if abs(_dot(_unit(p1), _unit(p2)) - 1.0) < 0.0001:
        return NO_WRAP, _ZERO, _ZERO, 0.0
    f1 = (p1p2[0] / a[0], p1p2[1] / a[1], p1p2[2] / a[2])
    f2 = (p2[0] / a[0], p2[1] / a[1], p2[2] / a[2])
    aa, bb, cc = _dot(f1, f1), 2.0 * _dot(f1, f2), _dot(f2, f2) - 1.0
    disc = bb * bb - 4.0 * aa * cc
    if disc < 0.0:
        return NO_WRAP, _ZERO, _ZERO, 0.0
    l1 = (-bb + math.sqrt(disc)) / (2.0 * aa)
    l2 = (-bb - math.sqrt(disc)) / (2.0 * aa)
    if not (0.0 < l1 < 1.0) or not (0.0 < l2 < 1.0):
        return NO_WRAP, _ZERO, _ZERO, 0.0
    r1 = _add(p2, _mul(p1p2, l1))
    r2 = _add(p2, _mul(p1p2, l2))
    c1, r1, r2 = _surface_point(dims, a, p1p2, r1, r2, axis, sign, method)
    vs = _unit(_cross(p1p2, _sub(p1, c1)))
    vs4 = -_dot(vs, c1)
    r1 = _tangent_point(p1e, r1, p1, a, vs, vs4)
    r2 = _tangent_point(p2e, r2, p2, a, vs, vs4)
    far = False
    length, w1, w2, n_pts = _ellipsoid_arc(r1, r2, a, vs, vs4, far, factor)
    if sign != 0 and n_pts > 2:
        if _dot(_unit(_sub(p1, r1)), _unit(_sub(w1, r1))) > 0.0 or _dot(_unit(_sub(p2, r2)),
                                                                           _unit(_sub(w2, r2))) > 0.0:
            far = True
            length, w1, w2, n_pts = _ellipsoid_arc(r1, r2, a, vs, vs4, far, factor)
    return MANDATORY_WRAP, _mul(r1, 1.0 / factor), _mul(r2, 1.0 / factor), length / factor
