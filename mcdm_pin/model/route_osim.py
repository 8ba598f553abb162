r"""OpenSim's path of a muscle at one instant (``GeometryPath::computePath``), as rows of the route
pass's path arrays.

For each cable whose route follows OpenSim's rules (:data:`mcdm_pin.model.cables.OPENSIM_WRAPS`,
:class:`~mcdm_pin.model.cables.ConditionalPoint`, :class:`~mcdm_pin.model.cables.MovingPoint`), at the
configuration ``q``:

1. the route's points that are active (a conditional point while its coordinate is within its range
   +- 1e-5), a moving point at ``f(clamp(q_c))`` in its frame;
2. the wraps, as ``GeometryPath::applyWrapObjects`` does: in order, each wrap first removes its own
   tangent points, then tries every segment of the current path between the first and the last active
   point of its ``span`` (skipping a pair of tangent points of one wrap object) with
   :mod:`mcdm_pin.model.wrapping_osim`; a *mandatory* wrap takes its segment at once, otherwise the
   candidate that lengthens the path least wins, and its two tangent points are inserted in that
   segment. With two or more wraps this repeats (at most 8 rounds) until the length changes by less
   than 0.5 mm; after the first round, when the first wrap did not wrap and the second found an end
   point inside its object, the two swap order (OpenSim's rule, kept as is);
3. the straight pieces become the cable's segments (slots: its own ``n - 1`` segments, then one per
   wrap; unused slots get scale 0), each wrap's surface length is added to the cable's arc length;
4. a moving point ``P`` on a segment spanning two bodies adds its own motion to ``L``:
   ``dl/dq_c += s u^T R_b dP/dq_c`` with ``u`` the segment's unit direction (world), ``s`` +1 when
   ``P`` ends the segment and -1 when it starts it, ``R_b`` the world rotation of ``P``'s body and
   ``dP/dq_c`` the functions' slopes at the unclamped coordinate (OpenSim's ``produceForces``, which
   ``computeMomentArm`` uses; a segment within one body adds no such term there either). OpenSim
   applies this term as a generalized force on the coordinate, not as a force on a body: it is in
   ``L`` (so in the equation of motion) but in no body wrench, so the interaction wrenches
   (``Terms.RT``) do not carry it; a joint whose coordinate drives a moving point then sees
   ``S^T p = (M qdd + h + L^T f)`` less that term.

Tangent points are written into their slots in the frame of the wrap's body: the cable-terms kernel
then treats them as points fixed on that body at the instant, as OpenSim's ``produceForces`` does.

**OpenSim's cached ground positions.** OpenSim reads a point's ground position through a cache that
is filled at its first read in an instant (``Point::getLocationInGround``) and that a wrap moving
its tangent point later in the same instant does not refresh (``PathWrapPoint::setLocation``). Its
lengths (the rounds' convergence test, the candidates' length change, the final length) and its
forces' directions use those cached positions, its wrap geometry and the points where its forces
act use the refreshed ones. We keep the same cache (``_ground``; the tangent points left in the slots
are the cached ones) and report, in ``lever``, each path tangent point's refreshed position less its
cached one: :func:`mcdm_pin.model.routes.add_levers` adds the moments of those levers to ``L`` and to
the interaction wrenches. With one wrap, or wraps that settle in their first round, the lever is 0.

Departures from OpenSim: the previous instant's wrap is never reused (OpenSim reuses it only for a
sphere segment through the centre). A wrap whose span has no active point ends the wrapping of the
path, as OpenSim's ``return`` does.

The functions here are ``register_jitable`` (compiled inline into
:func:`mcdm_pin.model.route_kernels.osim_route_pass`, plain Python before ``mcdm-pin compile``);
:class:`OsimTables` builds their tables once per cable set.
"""

from __future__ import annotations

import math

import numpy as np
from ..jit import extending

from .wrapping_osim import INSIDE_RADIUS, MANDATORY_WRAP, NO_WRAP, WRAPPED, osim_cylinder, osim_sphere
from .wrapping_osim_ellipsoid import osim_ellipsoid
from .kernel_structs import OsimPaths

register_jitable = extending.register_jitable

# columns of route_int
R_CABLE, R_P0, R_N, R_S0, R_W0, R_NW, R_E0, R_T0 = range(8)
N_ROUTE = 8
# columns of wrap_int (OpenSim wraps)
O_KEY, O_CYL, O_AXIS, O_SIGN, O_START, O_END, O_OBJECT, O_METHOD = range(8)
N_OINT = 8
SPHERE, CYLINDER, ELLIPSOID = 0, 1, 2  # values of the O_CYL column (the wrap object's kind)
# columns of wrap_float (OpenSim wraps): R_w (row-major), p_w, radius, length, the ellipsoid's radii
O_R, O_P, O_RADIUS, O_LENGTH, O_DIMS = 0, 9, 12, 13, 14
N_OFLOAT = 17
# point kinds and columns of pt_float: the range (conditional) or clamp (moving), the frame's
# placement in its joint (R_f row-major, p_f)
FIXED, CONDITIONAL, MOVING = 0, 1, 2
F_LO, F_HI, F_R, F_P = 0, 1, 2, 11
N_PFLOAT = 14
CONDITIONAL_SLACK = 1e-5  # ConditionalPathPoint::isActive widens the range by this
ROUND_TOL = 0.0005  # applyWrapObjects: rounds stop when the length changes by less (m)
MAX_ROUNDS = 8


@register_jitable
def _spline(knots, lo, hi, x):
    """Value and slope of the piecewise cubic ``knots[lo:hi]`` (columns x, y, b, c, d) at ``x``."""
    if x < knots[lo, 0]:
        return knots[lo, 1] + (x - knots[lo, 0]) * knots[lo, 2], knots[lo, 2]
    last = hi - 1
    if x > knots[last, 0]:
        return knots[last, 1] + (x - knots[last, 0]) * knots[last, 2], knots[last, 2]
    k = lo
    while k + 1 < last and knots[k + 1, 0] <= x:
        k += 1
    dx = x - knots[k, 0]
    y, b, c, d = knots[k, 1], knots[k, 2], knots[k, 3], knots[k, 4]
    return y + dx * (b + dx * (c + dx * d)), b + dx * (2.0 * c + 3.0 * d * dx)


@register_jitable
def _world(oM, key, x):
    return (oM[key, 0, 0] * x[0] + oM[key, 0, 1] * x[1] + oM[key, 0, 2] * x[2] + oM[key, 0, 3],
            oM[key, 1, 0] * x[0] + oM[key, 1, 1] * x[1] + oM[key, 1, 2] * x[2] + oM[key, 1, 3],
            oM[key, 2, 0] * x[0] + oM[key, 2, 1] * x[1] + oM[key, 2, 2] * x[2] + oM[key, 2, 3])


@register_jitable
def _node_world(oM, point_key, point_local, p):
    return _world(oM, point_key[p], (point_local[p, 0], point_local[p, 1], point_local[p, 2]))


@register_jitable
def _ground(oM, point_key, point_local, p, t0, cache):
    """OpenSim's ``getLocationInGround`` of path node ``p``: a tangent point's (slot ``t0 <= p``) is
    cached at its first read in the instant and kept, even when the wrap moves it later (module
    docstring); ``cache`` (2W, 4): the cached position in the wrap body's frame and a flag."""
    j = p - t0
    if j < 0:
        return _node_world(oM, point_key, point_local, p)
    if cache[j, 3] == 0.0:
        cache[j, 0], cache[j, 1], cache[j, 2], cache[j, 3] = point_local[p, 0], point_local[p, 1], point_local[p, 2], 1.0
    return _world(oM, point_key[p], (cache[j, 0], cache[j, 1], cache[j, 2]))


@register_jitable
def _dist(a, b):
    return math.sqrt((a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2 + (a[2] - b[2]) ** 2)


@register_jitable
def _row(oM, k, i, R):
    """Row ``i`` of ``oR_k R`` (R a nested tuple)."""
    return (oM[k, i, 0] * R[0][0] + oM[k, i, 1] * R[1][0] + oM[k, i, 2] * R[2][0],
            oM[k, i, 0] * R[0][1] + oM[k, i, 1] * R[1][1] + oM[k, i, 2] * R[2][1],
            oM[k, i, 0] * R[0][2] + oM[k, i, 1] * R[1][2] + oM[k, i, 2] * R[2][2])


@register_jitable
def _wrap_frame(oM, wi, wf):
    """The wrap object's world rotation (nested tuple, rows) and origin."""
    k = wi[O_KEY]
    R = ((wf[O_R], wf[O_R + 1], wf[O_R + 2]), (wf[O_R + 3], wf[O_R + 4], wf[O_R + 5]),
         (wf[O_R + 6], wf[O_R + 7], wf[O_R + 8]))
    return (_row(oM, k, 0, R), _row(oM, k, 1, R), _row(oM, k, 2, R)), _world(oM, k, (wf[O_P], wf[O_P + 1],
                                                                                      wf[O_P + 2]))


@register_jitable
def _to(R, p, x):
    dx, dy, dz = x[0] - p[0], x[1] - p[1], x[2] - p[2]
    return (R[0][0] * dx + R[1][0] * dy + R[2][0] * dz, R[0][1] * dx + R[1][1] * dy + R[2][1] * dz,
            R[0][2] * dx + R[1][2] * dy + R[2][2] * dz)


@register_jitable
def _place_points(q, p0, n, pt_kind, pt_q, pt_float, pt_fun, fun_ptr, knots, point_local, pt_dP, active):
    """Step 1: ``active`` (n,) and, for moving points, ``point_local`` and ``pt_dP`` (joint frame)."""
    for i in range(n):
        p = p0 + i
        kind = pt_kind[p]
        f = pt_float[p]
        active[i] = True
        if kind == CONDITIONAL:
            c = q[pt_q[p]]
            active[i] = f[F_LO] - CONDITIONAL_SLACK <= c <= f[F_HI] + CONDITIONAL_SLACK
        elif kind == MOVING:
            c = q[pt_q[p]]
            cc = min(max(c, f[F_LO]), f[F_HI])
            loc = [0.0, 0.0, 0.0]
            der = [0.0, 0.0, 0.0]
            for a in range(3):
                g = pt_fun[p, a]
                loc[a] = _spline(knots, fun_ptr[g], fun_ptr[g + 1], cc)[0]
                der[a] = _spline(knots, fun_ptr[g], fun_ptr[g + 1], c)[1]
            for i2 in range(3):
                r = F_R + 3 * i2
                point_local[p, i2] = f[r] * loc[0] + f[r + 1] * loc[1] + f[r + 2] * loc[2] + f[F_P + i2]
                pt_dP[p, i2] = f[r] * der[0] + f[r + 1] * der[1] + f[r + 2] * der[2]


@register_jitable
def _same_object(owner, wrap_int, w0, path_a, path_b):
    """Both path nodes are tangent points of one wrap object."""
    oa, ob = owner[path_a], owner[path_b]
    return oa >= 0 and ob >= 0 and wrap_int[w0 + oa, O_OBJECT] == wrap_int[w0 + ob, O_OBJECT]


@register_jitable
def _path_length(oM, point_key, point_local, path, owner, plen, wrap_int, w0, wrap_len, t0, cache):
    """``calcLengthAfterPathComputation``: straight pieces between the nodes' (cached) ground
    positions, wrap lengths between a wrap's tangent points."""
    total = 0.0
    x0 = _ground(oM, point_key, point_local, path[0], t0, cache)
    for j in range(plen - 1):
        x1 = _ground(oM, point_key, point_local, path[j + 1], t0, cache)
        if _same_object(owner, wrap_int, w0, j, j + 1):
            total += wrap_len[w0 + owner[j + 1]]
        else:
            total += _dist(x0, x1)
        x0 = x1
    return total


@register_jitable
def _remove_wrap(path, owner, plen, w):
    """Remove wrap ``w``'s two tangent points from the path; the new length."""
    for j in range(plen):
        if owner[j] == w:
            for k in range(j, plen - 2):
                path[k] = path[k + 2]
                owner[k] = owner[k + 2]
            return plen - 2
    return plen


@register_jitable
def _wrap_one(oM, route, paths, path, owner, plen, w0, w, p0, active, single, slot, t0, cache):
    """One wrap's turn in a round (step 2): ``(code, plen, stop, length)``; on success its tangent points are
    in ``point_local[slot]``, ``point_local[slot + 1]`` (wrap body frame) and inserted in the path;
    ``stop``: no active point in its span (OpenSim then ends the wrapping)."""
    point_local, point_key, wrap_int = route.point_local, route.point_key, paths.wrap_int
    wi, wf = wrap_int[w0 + w], paths.wrap_float[w0 + w]
    plen = _remove_wrap(path, owner, plen, w)
    jf = wi[O_START]
    while jf <= wi[O_END] and not active[jf]:
        jf += 1
    jr = wi[O_END]
    while jr >= wi[O_START] and not active[jr]:
        jr -= 1
    if jf > wi[O_END] or jr < wi[O_START]:
        return NO_WRAP, plen, True, 0.0
    start, end = -1, -1
    for j in range(plen):
        if owner[j] < 0 and path[j] == p0 + jf:
            start = j
        if owner[j] < 0 and path[j] == p0 + jr:
            end = j
    Rg, pg = _wrap_frame(oM, wi, wf)
    code, best, best_change = NO_WRAP, -1, math.inf
    r1b, r2b, lb = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0.0
    for pt1 in range(start, end):
        if _same_object(owner, wrap_int, w0, pt1, pt1 + 1):
            continue
        x1 = _to(Rg, pg, _node_world(oM, point_key, point_local, path[pt1]))
        x2 = _to(Rg, pg, _node_world(oM, point_key, point_local, path[pt1 + 1]))
        if wi[O_CYL] == CYLINDER:
            code, r1, r2, wl = osim_cylinder(x1, x2, wf[O_RADIUS], wf[O_LENGTH], wi[O_AXIS], wi[O_SIGN], single)
        elif wi[O_CYL] == ELLIPSOID:
            code, r1, r2, wl = osim_ellipsoid(x1, x2, (wf[O_DIMS], wf[O_DIMS + 1], wf[O_DIMS + 2]), wi[O_AXIS],
                                              wi[O_SIGN], wi[O_METHOD])
        else:
            code, r1, r2, wl = osim_sphere(x1, x2, wf[O_RADIUS], wi[O_AXIS], wi[O_SIGN])
        if code == MANDATORY_WRAP:
            best, r1b, r2b, lb = pt1, r1, r2, wl
            break
        if code == WRAPPED:  # calcPathLengthChange reads the ends' (cached) ground positions
            g1 = _to(Rg, pg, _ground(oM, point_key, point_local, path[pt1], t0, cache))
            g2 = _to(Rg, pg, _ground(oM, point_key, point_local, path[pt1 + 1], t0, cache))
            change = _dist(g1, r1) + wl + _dist(r2, g2) - _dist(g1, g2)
            if change < best_change:
                best, r1b, r2b, lb, best_change = pt1, r1, r2, wl, change
    if best < 0:
        return code, plen, False, 0.0
    R = ((wf[O_R], wf[O_R + 1], wf[O_R + 2]), (wf[O_R + 3], wf[O_R + 4], wf[O_R + 5]),
         (wf[O_R + 6], wf[O_R + 7], wf[O_R + 8]))
    for i in range(3):
        point_local[slot, i] = R[i][0] * r1b[0] + R[i][1] * r1b[1] + R[i][2] * r1b[2] + wf[O_P + i]
        point_local[slot + 1, i] = R[i][0] * r2b[0] + R[i][1] * r2b[1] + R[i][2] * r2b[2] + wf[O_P + i]
    for k in range(plen - 1, best, -1):
        path[k + 2] = path[k]
        owner[k + 2] = owner[k]
    path[best + 1], path[best + 2] = slot, slot + 1
    owner[best + 1], owner[best + 2] = w, w
    return code, plen + 2, False, lb


@register_jitable
def _apply_wraps(oM, route, paths, path, owner, plen, r, active, cache):
    """Step 2 for route row ``r`` (``GeometryPath::applyWrapObjects``) on ``route`` with the tables
    ``paths`` (:mod:`~mcdm_pin.model.kernel_structs`): the new path length."""
    point_local, point_key, wrap_int, wrap_len = route.point_local, route.point_key, paths.wrap_int, paths.wrap_len
    p0, w0, nw, t0 = r[R_P0], r[R_W0], r[R_NW], r[R_T0]
    order = np.arange(nw)
    result = np.zeros(nw, dtype=np.int64)
    last = math.inf
    for kk in range(1 if nw < 2 else MAX_ROUNDS):
        for i in range(nw):
            w = order[i]
            code, plen, stop, wl = _wrap_one(oM, route, paths, path, owner, plen, w0, w, p0, active, nw == 1,
                                             t0 + 2 * w, t0, cache)
            if stop:
                return plen
            result[i] = code
            wrap_len[w0 + w] = wl
        length = _path_length(oM, point_key, point_local, path, owner, plen, wrap_int, w0, wrap_len, t0, cache)
        if abs(length - last) < ROUND_TOL:
            break
        last = length
        if kk == 0 and nw > 1 and result[0] == NO_WRAP and result[1] == INSIDE_RADIUS:
            order[0], order[1] = 1, 0
            plen = _remove_wrap(path, owner, plen, 0)
    return plen


@register_jitable
def _write_segments(oM, paths, route, path, owner, plen, r, arc_length, L_extra):
    """Steps 3 and 4 for route row ``r`` (of ``paths``, an
    :class:`~mcdm_pin.model.kernel_structs.OsimPaths`): the straight pieces into the cable's segment
    slots of ``route``, the arcs into its arc length, the moving points' own terms into ``L_extra``."""
    point_local, point_key, seg_a, seg_b, _, seg_active, seg_scale = route
    wrap_int, wrap_len, pt_kind, pt_v, pt_dP = paths.wrap_int, paths.wrap_len, paths.pt_kind, paths.pt_v, paths.pt_dP
    c, s0, n, w0, nw, e0 = r[R_CABLE], r[R_S0], r[R_N], r[R_W0], r[R_NW], r[R_E0]
    n_slots = n - 1 + nw
    k = 0
    for j in range(plen - 1):
        if _same_object(owner, wrap_int, w0, j, j + 1):
            arc_length[c] += wrap_len[w0 + owner[j + 1]]
            continue
        s = s0 + k if k < n - 1 else e0 + k - (n - 1)
        k += 1
        a, b = path[j], path[j + 1]
        seg_a[s], seg_b[s], seg_scale[s] = a, b, 1.0
        seg_active[s] = point_key[a] != point_key[b]
        if not seg_active[s] or (pt_kind[a] != MOVING and pt_kind[b] != MOVING):
            continue
        xa = _node_world(oM, point_key, point_local, a)
        xb = _node_world(oM, point_key, point_local, b)
        ln = _dist(xa, xb)
        if not ln > 0.0:
            continue
        u = ((xb[0] - xa[0]) / ln, (xb[1] - xa[1]) / ln, (xb[2] - xa[2]) / ln)
        for e, sg in ((b, 1.0), (a, -1.0)):
            if pt_kind[e] == MOVING:
                kk = point_key[e]
                acc = 0.0
                for i in range(3):
                    acc += u[i] * (oM[kk, i, 0] * pt_dP[e, 0] + oM[kk, i, 1] * pt_dP[e, 1]
                                   + oM[kk, i, 2] * pt_dP[e, 2])
                L_extra[c, pt_v[e]] += sg * acc
    for k2 in range(k, n_slots):
        s = s0 + k2 if k2 < n - 1 else e0 + k2 - (n - 1)
        seg_scale[s] = 0.0
        seg_active[s] = False


@register_jitable
def osim_routes(oM, q, paths, route, arc_length, L_extra, lever):
    """Every OpenSim route at configuration ``q`` (steps 1-4 of the module docstring), in place:
    ``paths`` the tables (:class:`~mcdm_pin.model.kernel_structs.OsimPaths`), ``route`` the route
    pass's points and segments (:class:`~mcdm_pin.model.kernel_structs.Route`) rewritten.
    ``L_extra`` (m, nv) is zeroed first; ``arc_length`` is added to (the MuJoCo wraps' pass zeroes
    it); ``lever`` (P, 3): for a tangent point whose cached position (``point_local``) differs from
    where its wrap last put it, that difference (its body's frame), else 0."""
    route_int, pt_kind, pt_q, pt_v, pt_fun, pt_float, fun_ptr, knots, wrap_int, wrap_float, wrap_len, pt_dP = paths
    point_local, point_key, seg_a, seg_b, _, seg_active, seg_scale = route
    L_extra[:, :] = 0.0
    for ri in range(route_int.shape[0]):
        r = route_int[ri]
        p0, n, nw = r[R_P0], r[R_N], r[R_NW]
        active = np.zeros(n, dtype=np.bool_)
        _place_points(q, p0, n, pt_kind, pt_q, pt_float, pt_fun, fun_ptr, knots, point_local, pt_dP, active)
        path = np.empty(n + 2 * nw, dtype=np.int64)
        owner = np.empty(n + 2 * nw, dtype=np.int64)
        plen = 0
        for i in range(n):
            if active[i]:
                path[plen], owner[plen] = p0 + i, -1
                plen += 1
        if nw > 0:
            t0 = r[R_T0]
            cache = np.zeros((2 * nw, 4))
            plen = _apply_wraps(oM, route, paths, path, owner, plen, r, active, cache)
            # computePath's last length: every node's ground position read (and cached); the path's
            # tangent points are then where OpenSim's lengths and forces see them
            _path_length(oM, point_key, point_local, path, owner, plen, wrap_int, r[R_W0], wrap_len, t0, cache)
            for j in range(2 * nw):
                for i in range(3):
                    lever[t0 + j, i] = 0.0
            for j in range(plen):
                k = path[j] - t0
                if k >= 0:  # lever: the refreshed position less the cached one (forces act there)
                    for i in range(3):
                        lever[path[j], i] = point_local[path[j], i] - cache[k, i]
                        point_local[path[j], i] = cache[k, i]
        _write_segments(oM, paths, route, path, owner, plen, r, arc_length, L_extra)


_QUADRANT = {"all": (0, 0), "+x": (0, 1), "-x": (0, -1), "+y": (1, 1), "-y": (1, -1), "+z": (2, 1), "-z": (2, -1)}


class OsimTables:
    """The tables of :func:`osim_routes` for a cable set (built once; see the module docstring).

    Args:
        cables: the :class:`~mcdm_pin.model.cables.CableSet`.
        wrap_keys: (W,) the key body of each OpenSim wrap (``cables.osim_wraps``).
        n_all: the number of points of the route pass's layout (the set's points, the MuJoCo wraps'
            slots, then two slots per OpenSim wrap from ``slot0``).
        slot0, seg0: the first OpenSim tangent slot and the first OpenSim extra segment.
    """

    def __init__(self, cables, wrap_keys, n_all: int, slot0: int, seg0: int):
        from .cables import ConditionalPoint, MovingPoint, OPENSIM_WRAPS, Wrap

        self.pt_kind = np.zeros(n_all, dtype=np.int64)
        self.pt_q = np.zeros(n_all, dtype=np.int64)
        self.pt_v = np.zeros(n_all, dtype=np.int64)
        self.pt_fun = np.zeros((n_all, 3), dtype=np.int64)
        self.pt_float = np.zeros((n_all, N_PFLOAT))
        self.pt_dP = np.zeros((n_all, 3))
        rows, knots, fun_ptr, wint, wflt, objects = [], [], [0], [], [], {}
        w0 = 0
        for k in cables.osim_cables:
            cable = cables.cables[k]
            pts = np.flatnonzero(cables.point_cable == k)
            p0, n = int(pts[0]), len(pts)
            s0 = int(np.flatnonzero(cables.seg_cable == k)[0])
            for i, rp in enumerate(cable.route_points):
                p = p0 + i
                f = self.pt_float[p]
                f[F_R:F_R + 9] = cables.point_frame_rotation[p].reshape(9)
                f[F_P:F_P + 3] = cables.point_frame_translation[p]
                if isinstance(rp, ConditionalPoint):
                    self.pt_kind[p], self.pt_q[p] = CONDITIONAL, rp.q_index
                    f[F_LO], f[F_HI] = rp.range
                elif isinstance(rp, MovingPoint):
                    self.pt_kind[p], self.pt_q[p], self.pt_v[p] = MOVING, rp.q_index, rp.v_index
                    f[F_LO], f[F_HI] = rp.clamp
                    for a, fn in enumerate(rp.functions):
                        self.pt_fun[p, a] = len(fun_ptr) - 1
                        knots.extend(zip(fn.x, fn.y, fn.b, fn.c, fn.d))
                        fun_ptr.append(len(knots))
            elems = [e for e in cable.route if isinstance(e, Wrap) and e.kind in OPENSIM_WRAPS]
            resolved = [w for w in cables.osim_wraps if w.cable == k]
            for e, rw in zip(elems, resolved):
                start = e.span[0] - 1 if e.span[0] >= 1 else 0
                end = e.span[1] - 1 if e.span[1] >= 1 else n - 1
                if not start <= end < n:
                    from ..exceptions import ModelError
                    raise ModelError(f"cable {cable.name!r}: wrap {e.name!r}: range {e.span} is outside its "
                                     f"{n} path points")
                axis, sign = _QUADRANT[e.quadrant]
                obj = objects.setdefault((rw.joint, e.frame, e.name), len(objects))
                kind = {"opensim_sphere": SPHERE, "opensim_cylinder": CYLINDER, "opensim_ellipsoid": ELLIPSOID}[e.kind]
                method = ("hybrid", "midpoint", "axial").index(e.method)
                wint.append((int(wrap_keys[len(wflt)]), kind, axis, sign, start, end, obj, method))
                flt = np.zeros(N_OFLOAT)
                flt[O_R:O_R + 9] = np.asarray(rw.placement.rotation).reshape(9)
                flt[O_P:O_P + 3] = np.asarray(rw.placement.translation).reshape(3)
                flt[O_RADIUS], flt[O_LENGTH] = rw.radius, e.length
                if e.kind == "opensim_ellipsoid":
                    flt[O_DIMS:O_DIMS + 3] = e.radii
                wflt.append(flt)
            nw = len(elems)
            rows.append((k, p0, n, s0, w0, nw, seg0 + w0, slot0 + 2 * w0))
            w0 += nw
        self.route_int = np.array(rows, dtype=np.int64).reshape(-1, N_ROUTE)
        self.wrap_int = np.array(wint, dtype=np.int64).reshape(-1, N_OINT)
        self.wrap_float = np.array(wflt, dtype=float).reshape(-1, N_OFLOAT)
        self.fun_ptr = np.array(fun_ptr, dtype=np.int64)
        self.knots = np.array(knots, dtype=float).reshape(-1, 5)
        self.wrap_len = np.zeros(len(wint))
        self.n_wraps = len(wint)
        self.arrays = OsimPaths(self.route_int, self.pt_kind, self.pt_q, self.pt_v, self.pt_fun, self.pt_float,
                                self.fun_ptr, self.knots, self.wrap_int, self.wrap_float, self.wrap_len, self.pt_dP)
        """The tables as the route kernel takes them."""

