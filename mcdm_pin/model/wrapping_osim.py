r"""OpenSim's wrapping of one path segment over a ``WrapSphere`` or a ``WrapCylinder``, as OpenSim 4
computes it (``WrapSphere::wrapLine``, ``WrapCylinder::wrapLine`` and ``_make_spiral_path``, read in
opensim-core's sources and written again from their description).

Every point is in the wrap object's own frame (centre at the origin; the cylinder's axis is the local
``z`` axis, its ``length`` centred on ``z = 0``). Lengths in metres. Each function returns
``(code, r1, r2, length)``: the code is OpenSim's ``WrapAction`` (:data:`NO_WRAP` 0,
:data:`INSIDE_RADIUS` 1, :data:`WRAPPED` 2, :data:`MANDATORY_WRAP` 3), ``r1``/``r2`` the tangent
points (3-tuples, meaningful for codes 2 and 3) and ``length`` the path length on the surface
between them (OpenSim's ``wrap_path_length``).

**Quadrant.** ``axis`` (0, 1, 2) and ``sign`` (+1, -1; 0 for ``all``) are OpenSim's ``_wrapAxis`` and
``_wrapSign``; ``DSIGN(x)`` is +1 for ``x >= 0`` and -1 otherwise. Unconstrained, a segment wraps when
the straight line meets the object (sphere: both intersections strictly between the end points;
cylinder: the line's closest approach to the axis segment of ``length`` is within the radius,
strictly between the end points), and the shorter way round. Constrained, when an end point lies on
the active side the wrap is *mandatory* if the line meets the object, else a candidate (code 2)
only when the end points straddle the axis plane and the line's closest point lies on the inactive
side; the tangent points are then the pair on the active side, and a wrap whose tangent points face
away from the end points is a far-side wrap (OpenSim: a *negative* arc ``-(2 pi - angle) r`` for the
sphere, the long way ``2 pi - theta`` for the cylinder).

**Cylinder path.** The tangent points found in the plane normal to the axis are slid along the
surface to the plane through both end points and the apex line; the path on the surface is the
helix from ``r1`` to ``r2``: ``length = sqrt((r theta)^2 + dz^2)``. A cylinder whose both tangent
points lie beyond its ``length`` does not wrap. When the path has more than one wrap
(``single`` False), OpenSim moves ``r1`` and ``r2`` along the axis until each straight piece meets
the helix within 0.1 degree (``_adjust_tangent_point``, at most 100 rounds, on the helix sampled every
2 mm); with a single wrap it does not.

Departures: where OpenSim reuses the previous instant's tangent points (a sphere segment passing
within 1e-5 rad of the centre) we report no wrap; ``acos`` arguments are clamped to [-1, 1]. The
path's tangent points are then treated as points fixed on the wrap object's body at the instant, as
OpenSim's ``produceForces`` (and so ``computeMomentArm``) does.

The functions are ``register_jitable``: plain Python when called from Python, compiled inline into the
route kernel (:mod:`mcdm_pin.model.route_kernels`).
"""

from __future__ import annotations

import math

import numpy as np

from numba import extending

register_jitable = extending.register_jitable

NO_WRAP, INSIDE_RADIUS, WRAPPED, MANDATORY_WRAP = 0, 1, 2, 3
EPS = 2.220446049250313e-16  # SimTK::Eps: NormalizeOrZero's threshold
ROUNDOFF = 2e-13  # SIMM's ROUNDOFF_ERROR (EQUAL_WITHIN_ERROR)
LINE_EPS = 1e-5  # WrapMath's LINE_EPSILON
TANGENCY = 0.1 * math.pi / 180.0  # WrapCylinder's TANGENCY_THRESHOLD
MAX_ADJUST = 100  # WrapCylinder's MAX_ITERATIONS
_ZERO = (0.0, 0.0, 0.0)


@register_jitable
def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@register_jitable
def _add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@register_jitable
def _mul(a, k):
    return (a[0] * k, a[1] * k, a[2] * k)


@register_jitable
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@register_jitable
def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@register_jitable
def _norm(a):
    return math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


@register_jitable
def _unit(a):
    """WrapMath::NormalizeOrZero: ``a/|a|``, zeros below machine epsilon."""
    n = _norm(a)
    if n >= EPS:
        return (a[0] / n, a[1] / n, a[2] / n)
    return _ZERO


@register_jitable
def _dsign(x):
    return 1 if x >= 0.0 else -1


@register_jitable
def _acos(x):
    return math.acos(min(1.0, max(-1.0, x)))


@register_jitable
def _closest_on_line(pt, line_pt, line):
    """WrapMath::GetClosestPointOnLineToPoint: ``(closest, t)``, ``t`` in units of ``|line|``."""
    v1 = _sub(pt, line_pt)
    mag = _norm(v1)
    v1 = _unit(v1)
    mag2 = _norm(line)
    v2 = _unit(line)
    t = _dot(v1, v2) * mag
    return _add(line_pt, _mul(v2, t)), t / mag2


@register_jitable
def _det3(r0, r1, r2):
    return _dot(r0, _cross(r1, r2))


@register_jitable
def _intersect_lines(p1, p2, p3, p4):
    """WrapMath::IntersectLines: ``(ok, pInt1, s, pInt2, t)``, ``s``/``t`` fractions of each segment."""
    vec1 = _sub(p2, p1)
    mag1 = _norm(vec1)
    vec1 = _unit(vec1)
    vec2 = _sub(p4, p3)
    mag2 = _norm(vec2)
    vec2 = _unit(vec2)
    cp = _cross(vec1, vec2)
    denom = _dot(cp, cp)
    if abs(denom) <= ROUNDOFF:
        return False, _ZERO, math.nan, _ZERO, math.nan
    d31 = _sub(p3, p1)
    t = _det3(d31, vec1, cp) / denom
    s = _det3(d31, vec2, cp) / denom
    return True, _add(p1, _mul(vec1, s)), s / mag1, _add(p3, _mul(vec2, t)), t / mag2


@register_jitable
def _intersect_seg_plane(pt1, pt2, normal, d):
    """WrapMath::IntersectLineSegPlane: ``(ok, point)``."""
    vec = _sub(pt2, pt1)
    dp = _dot(vec, normal)
    if abs(dp) < LINE_EPS:
        return False, _ZERO
    t = (-d - _dot(normal, pt1)) / dp
    if t < -LINE_EPS or t > 1.0 + LINE_EPS:
        return False, _ZERO
    return True, _add(pt1, _mul(vec, t))


@register_jitable
def _sphere_candidates(p, n, radius):
    """The two tangent points from ``p`` in the plane of normal ``n`` through the centre."""
    y = _unit(_mul(p, -1.0))
    z = _cross(n, y)
    pn = _norm(p)
    a = math.asin(radius / pn)
    k = pn * math.cos(a)
    ca, sa = math.cos(a), math.sin(a)
    ra = (p[0] + k * (ca * y[0] - sa * z[0]), p[1] + k * (ca * y[1] - sa * z[1]),
          p[2] + k * (ca * y[2] - sa * z[2]))
    rb = (p[0] + k * (ca * y[0] + sa * z[0]), p[1] + k * (ca * y[1] + sa * z[1]),
          p[2] + k * (ca * y[2] + sa * z[2]))
    return ra, rb


@register_jitable
def _best_pair(r1a, r1b, r2a, r2b, c1, c2):
    """The pair of candidates whose directions from ``c1``/``c2`` agree most (OpenSim's j1..j4
    choice): ``(r1, r2, other1, other2)``."""
    u1a, u1b = _unit(_sub(r1a, c1)), _unit(_sub(r1b, c1))
    u2a, u2b = _unit(_sub(r2a, c2)), _unit(_sub(r2b, c2))
    j1, j2, j3, j4 = _dot(u1a, u2a), _dot(u1a, u2b), _dot(u1b, u2a), _dot(u1b, u2b)
    if j1 > j2 and j1 > j3 and j1 > j4:
        return r1a, r2a, r1b, r2b
    if j2 > j3 and j2 > j4:
        return r1a, r2b, r1b, r2a
    if j3 > j4:
        return r1b, r2a, r1a, r2b
    return r1b, r2b, r1a, r2a


@register_jitable
def osim_sphere(p1, p2, radius, axis, sign):
    """OpenSim's ``WrapSphere::wrapLine`` (module docstring): ``(code, r1, r2, length)``."""
    if _norm(p1) < radius or _norm(p2) < radius:
        return INSIDE_RADIUS, _ZERO, _ZERO, 0.0
    ri = _sub(p1, p2)
    mp = _mul(p2, -1.0)
    a = _dot(ri, ri)
    b = -2.0 * _dot(mp, ri)
    c = _dot(mp, mp) - radius * radius
    disc = b * b - 4.0 * a * c
    if disc < 0.0:
        return NO_WRAP, _ZERO, _ZERO, 0.0
    l1 = (-b + math.sqrt(disc)) / (2.0 * a)
    l2 = (-b - math.sqrt(disc)) / (2.0 * a)
    if not (0.0 < l1 < 1.0) or not (0.0 < l2 < 1.0) or l1 < l2:
        return NO_WRAP, _ZERO, _ZERO, 0.0
    p1p2 = _unit(ri)
    hp2 = _cross(p1p2, _unit(p2))
    if _norm(hp2) < 0.00001:
        return NO_WRAP, _ZERO, _ZERO, 0.0  # OpenSim reuses the previous instant's wrap here
    n = _unit(hp2)
    r1a, r1b = _sphere_candidates(p1, n, radius)
    r2a, r2b = _sphere_candidates(p2, n, radius)
    r1, r2, r11, r22 = _best_pair(r1a, r1b, r2a, r2b, _ZERO, _ZERO)
    code = WRAPPED
    far = False
    if sign != 0:
        s1, s2 = _dsign(p1[axis]), _dsign(p2[axis])
        if s1 == sign or s2 == sign:
            mm, tt = _closest_on_line(_ZERO, p1, p1p2)
            tt = -tt
            if _dot(mm, mm) < radius * radius and 0.0 < tt < 1.0:
                code = MANDATORY_WRAP
            elif s1 != s2 and _dsign(mm[axis]) != sign:
                code = WRAPPED
            else:
                return NO_WRAP, _ZERO, _ZERO, 0.0
        if s1 != sign or s2 != sign:
            wrapaxis = (float(sign) if axis == 0 else 0.0, float(sign) if axis == 1 else 0.0,
                        float(sign) if axis == 2 else 0.0)
            musc = _unit(_add(_mul(p1, -1.0), _mul(p2, -1.0)))
            u1a, u1b = _unit(r1a), _unit(r1b)
            u2a, u2b = _unit(r2a), _unit(r2b)
            if _dot(u1a, musc) > _dot(u1b, musc):
                r1, r11 = r1a, r1b
            else:
                r1, r11 = r1b, r1a
            if _dot(u2a, musc) > _dot(u2b, musc):
                r2, r22 = r2a, r2b
            else:
                r2, r22 = r2b, r2a
            musc = _unit(_add(_sub(r1, p1), _sub(r2, p2)))
            if _dot(musc, wrapaxis) < 0.0:
                r1, r2 = r11, r22
            musc = _add(_sub(r1, p1), _sub(r2, p2))
            if _dot(_add(r1, r2), musc) < 0.0:
                far = True
    angle = _acos(_dot(_unit(r1), _unit(r2)))
    if far:
        angle = -(2.0 * math.pi - angle)
    return code, r1, r2, radius * angle


_AXIS_P0 = (0.0, 0.0, -1.0)  # WrapCylinder's p0 and dn: the axis through the origin along z
_AXIS_DN = (0.0, 0.0, 1.0)


@register_jitable
def _cylinder_candidates(p, radius):
    """The tangent points from ``p`` to the circle of the cylinder in the plane normal to the axis
    through ``p``'s foot ``c`` on the axis: ``(ra, rb, c, |p - c|)``."""
    c, _ = _closest_on_line(p, _AXIS_P0, _AXIS_DN)
    vv = _sub(p, c)
    dist_c = _norm(vv)
    vv = _unit(vv)
    d = radius * (radius / dist_c)
    pp = _add(c, _mul(vv, d))
    d = math.sqrt(radius * radius - d * d)
    uu = _cross(_AXIS_DN, vv)
    return _add(pp, _mul(uu, d)), _sub(pp, _mul(uu, d)), c, dist_c


@register_jitable
def _constrained_pair(r1a, r1b, r2a, r2b, c1, c2, axis, sign):
    """OpenSim's choice of the tangent points on the active side: ``(r1, r2, far_side)``."""
    u1a, u1b, u2a, u2b = _sub(r1a, c1), _sub(r1b, c1), _sub(r2a, c2), _sub(r2b, c2)
    alpha = _acos(_dot(u1a, u2b) / (_norm(u1a) * _norm(u2b)))
    beta = _acos(_dot(u1b, u2a) / (_norm(u1b) * _norm(u2a)))
    on1a, on1b = _dsign(r1a[axis]) == sign, _dsign(r1b[axis]) == sign
    on2a, on2b = _dsign(r2a[axis]) == sign, _dsign(r2b[axis]) == sign
    if (on1a and on1b and on2a) or (not on1a and on1b) or (not on1a and not on1b and on2a):
        return r1b, r2a, not alpha > beta
    if (on1a and on1b) or (on1a and not on1b) or on2b:
        return r1a, r2b, alpha > beta
    if alpha > beta:  # none of the four is on the active side
        return r1a, r2b, True
    return r1b, r2a, True


@register_jitable
def _rotate_z(v, angle):
    c, s = math.cos(angle), math.sin(angle)
    return (c * v[0] - s * v[1], s * v[0] + c * v[1], v[2])


@register_jitable
def _adjust_tangent(pt, r, w):
    """WrapCylinder::_adjust_tangent_point: ``(moved, r)``, ``r`` slid along the axis when the line
    ``pt -> r`` and the helix ``r -> w`` differ in slope by more than 0.1 degree."""
    alpha = _acos(_dot(_unit(_sub(r, pt)), _AXIS_DN))
    omega = _acos(_dot(_unit(_sub(w, r)), _AXIS_DN))
    if abs(alpha - omega) <= TANGENCY:
        return False, r
    pa, _ = _closest_on_line(pt, r, _AXIS_DN)
    wa, _ = _closest_on_line(w, r, _AXIS_DN)
    ok, _, _, hit, _ = _intersect_lines(pt, w, pa, wa)
    if not ok:
        return True, r
    return True, _add(r, _mul(_sub(hit, r), 1.5))


@register_jitable
def _spiral(p1, p2, r1, r2, radius, long_wrap, single):
    """WrapCylinder::_make_spiral_path without the drawing points: ``(r1, r2, length)``."""
    sense = -1.0 if long_wrap else 1.0
    for rounds in range(MAX_ADJUST + 1):
        a1, _t = _closest_on_line(r1, _AXIS_P0, _AXIS_DN)
        a2, _t = _closest_on_line(r2, _AXIS_P0, _AXIS_DN)
        axial = _dot(_sub(a2, a1), _AXIS_DN)
        uu, vv = _sub(r1, a1), _sub(r2, a2)
        theta = math.atan2(_dot(_cross(uu, vv), _AXIS_DN), _dot(uu, vv))
        if long_wrap:
            theta = 2.0 * math.pi - theta
        length = math.sqrt((radius * theta) ** 2 + axial * axial)
        n_seg = int(length / 0.002)
        if single or n_seg < 2 or rounds == MAX_ADJUST:
            return r1, r2, length
        t = 1.0 / n_seg
        w = _add(_rotate_z(r1, sense * t * theta), _mul(_AXIS_DN, t * axial))
        moved1, r1 = _adjust_tangent(p1, r1, w)
        w = _add(_rotate_z(r1, sense * (1.0 - t) * theta), _mul(_AXIS_DN, (1.0 - t) * axial))
        moved2, r2 = _adjust_tangent(p2, r2, w)
        if not (moved1 or moved2):
            return r1, r2, length
    return r1, r2, 0.0  # not reached: the last round returns above


@register_jitable
def osim_cylinder(p1, p2, radius, length, axis, sign, single):
    """OpenSim's ``WrapCylinder::wrapLine`` (module docstring): ``(code, r1, r2, length)``;
    ``single``: the path has this one wrap only."""
    rr = radius * radius
    if p1[0] * p1[0] + p1[1] * p1[1] < rr or p2[0] * p2[0] + p2[1] * p2[1] < rr:
        return INSIDE_RADIUS, _ZERO, _ZERO, 0.0
    ok, near12, t12, near00, _ = _intersect_lines(p1, p2, (0.0, 0.0, -0.5 * length), (0.0, 0.0, 0.5 * length))
    gap = _sub(near12, near00)
    meets = ok and _dot(gap, gap) < rr and 0.0 < t12 < 1.0
    code = WRAPPED
    if sign == 0:
        if not meets:
            return NO_WRAP, _ZERO, _ZERO, 0.0
        code = MANDATORY_WRAP
    r1a, r1b, c1, d1 = _cylinder_candidates(p1, radius)
    r2a, r2b, c2, d2 = _cylinder_candidates(p2, radius)
    far, long_wrap = False, False
    if sign != 0:
        s1, s2 = _dsign(p1[axis]), _dsign(p2[axis])
        if s1 == sign or s2 == sign:
            if meets:
                code = MANDATORY_WRAP
            elif not (s1 != s2 and _dsign(near12[axis]) != sign):
                return NO_WRAP, _ZERO, _ZERO, 0.0
        r1, r2, far = _constrained_pair(r1a, r1b, r2a, r2b, c1, c2, axis, sign)
        long_wrap = _dot(_add(_sub(r1, c1), _sub(r2, c2)), _add(_sub(r1, p1), _sub(r2, p2))) < 0.0
    else:
        r1, r2, _o1, _o2 = _best_pair(r1a, r1b, r2a, r2b, c1, c2)
    # the apex line: on the cylinder, in the plane of p1, p2 and the axis point below the path
    t = d1 / (d1 + d2)
    mpt = _add(p1, _mul(_sub(p2, p1), t))
    axispt, _t = _closest_on_line(mpt, _AXIS_P0, _AXIS_DN)
    normal = _unit(_cross(_unit(_sub(p1, axispt)), _unit(_sub(p2, axispt))))
    apex1 = _add(axispt, _mul(_unit(_cross(_AXIS_DN, normal)), radius))
    apex2 = _add(axispt, _mul(_unit(_cross(normal, _AXIS_DN)), radius))
    g1, g2 = _sub(mpt, apex1), _sub(mpt, apex2)
    nearer1 = _dot(g1, g1) < _dot(g2, g2)
    apex = apex1 if nearer1 != far else apex2
    # slide r1, r2 along the axis to the plane through p1, p2 and the apex
    normal = _unit(_cross(_unit(_sub(p1, apex)), _unit(_sub(p2, apex))))
    d = -_dot(p1, normal)
    ten = _mul(_AXIS_DN, 10.0)
    hit1, r1p = _intersect_seg_plane(_sub(r1, ten), _add(r1, ten), normal, d)
    hit2, r2p = _intersect_seg_plane(_sub(r2, ten), _add(r2, ten), normal, d)
    if hit1:  # (OpenSim passes c2 as the line's direction here, not c2 - c1)
        x, _t = _closest_on_line(r1p, c1, c2)
        if _dot(_sub(x, c2), _sub(x, c2)) < _dot(_sub(c1, c2), _sub(c1, c2)):
            r1 = r1p
    if hit2:
        x, _t = _closest_on_line(r2p, c2, c1)
        if _dot(_sub(x, c1), _sub(x, c1)) < _dot(_sub(c2, c1), _sub(c2, c1)):
            r2 = r2p
    half = 0.5 * length
    if (r1[2] < -half or r1[2] > half) and (r2[2] < -half or r2[2] > half):
        return NO_WRAP, _ZERO, _ZERO, 0.0
    r1, r2, arc = _spiral(p1, p2, r1, r2, radius, long_wrap, single)
    return code, r1, r2, arc


# ------------------------------------------------------------------ WrapEllipsoid (OpenSim's algorithm)

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
    if (u / a) ** 2 + (v / b) ** 2 + (w / c) ** 2 < 1.0:
        t = 0.0
    else:
        t = max(a, b, c) * math.sqrt(u * u + v * v + w * w)
    for _ in range(64):
        P, Q, R = t + a2, t + b2, t + c2
        f = P * P * Q * Q * R * R - a2u2 * Q * Q * R * R - b2v2 * P * P * R * R - c2w2 * P * P * Q * Q
        if abs(f) < 1e-09:
            return (a2 * u / P, b2 * v / Q, c2 * w / R)
        PQ, PR, QR, PQR = P * Q, P * R, Q * R, P * Q * R
        fp = 2.0 * (PQR * (QR + PR + PQ) - a2u2 * QR * (Q + R) - b2v2 * PR * (P + R) - c2w2 * PQ * (P + Q))
        t -= f / fp
    return prev


@register_jitable
def _solve4(M, rhs):
    """``M^-1 rhs`` for a 4x4 ``M`` (Gauss-Jordan with partial pivoting)."""
    A = M.copy()
    x = rhs.copy()
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
    return x


@register_jitable
def _tangent_residual(r1, d1, p1, a, vs, vs4):
    """calcTangentPoint's residuals: in the plane, on the ellipsoid, tangent plane through ``r1`` and
    ``p1``; and their sum of squares."""
    nr1 = (2.0 * r1[0] / (a[0] * a[0]), 2.0 * r1[1] / (a[1] * a[1]), 2.0 * r1[2] / (a[2] * a[2]))
    e0 = vs[0] * r1[0] + vs[1] * r1[1] + vs[2] * r1[2] + vs4
    e1 = -1.0 + (r1[0] / a[0]) ** 2 + (r1[1] / a[1]) ** 2 + (r1[2] / a[2]) ** 2
    e2 = _dot(nr1, r1) + d1
    e3 = _dot(nr1, p1) + d1
    return np.array([e0, e1, e2, e3]), e0 * e0 + e1 * e1 + e2 * e2 + e3 * e3


@register_jitable
def _tangent_point(pe, r1, p1, a, vs, vs4):
    """WrapEllipsoid::calcTangentPoint (centre at the origin): ``r1`` moved, by OpenSim's damped
    Gauss-Newton steps, until it lies in the plane ``vs . x + vs4 = 0``, on the ellipsoid and on a line
    from ``p1`` tangent to it (squared residual <= 1e-8, at most 50 rounds)."""
    if abs(pe) < 0.0001:
        return p1
    r = np.array([r1[0], r1[1], r1[2]])
    nr1 = (2.0 * r[0] / (a[0] * a[0]), 2.0 * r[1] / (a[1] * a[1]), 2.0 * r[2] / (a[2] * a[2]))
    d1 = -(nr1[0] * r[0] + nr1[1] * r[1] + nr1[2] * r[2])
    ee, ssq = _tangent_residual((r[0], r[1], r[2]), d1, p1, a, vs, vs4)
    ssqo = ssq
    alpha = 0.01
    D = np.zeros((4, 4))
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
        v = -(D @ ee)
        D2 = D @ D.T
        diag = np.array([D2[0, 0], D2[1, 1], D2[2, 2], D2[3, 3]])
        vt = np.zeros(4)
        n2 = 0
        while ssq >= ssqo and n2 < 1000:
            for i in range(4):
                D2[i, i] = diag[i] * (1.0 + alpha)
            vt = dd * _solve4(D2, v) / 16.0
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
            vsum = _ZERO
            prev = c1_t[0]
            for i in range(1, NUM_FAN_SAMPLES - 1):
                sv = _add(r1, _mul(r1r2, i / NUM_FAN_SAMPLES))
                prev = _closest_on_ellipsoid(dims, a[0], a[1], a[2], sv[0], sv[1], sv[2], -1, prev)
                vsum = _add(vsum, _unit(_sub(prev, sv)))
            fan_pt = _add(mid, _unit(vsum))
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
