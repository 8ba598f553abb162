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
route kernel (:mod:`mcdm_pin.model.route_kernels`). ``WrapEllipsoid`` is
:mod:`mcdm_pin.model.wrapping_osim_ellipsoid`.
"""

from __future__ import annotations

import math

from ..jit import extending

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
