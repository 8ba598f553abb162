r"""Spatial-tendon paths as MuJoCo 4.0 computes them: wrapping over spheres and cylinders, side sites, pulleys.

The definitions are those of MuJoCo's ``mju_wrap`` (``engine_util_misc.c``) and ``mj_tendon``
(``engine_core_smooth.c``) as read in its 3.12 sources, written again from their description, with
the changes of MuJoCo 4.0 on top: the side-site winding rule its changelog and XML reference document
(commit a65050166), and, inferred from MuJoCo 4.0's own numbers (its changelog cites 3bc4b769a and
8694cc9ce), the inside wrap's Newton iteration on the angle ``beta`` and arc angles from ``atan2``.
Tests compare every number with MuJoCo 4.0. Lengths in metres, angles in radians; counter-clockwise
is positive about the geom's local ``z`` (cylinder) or about ``n = p0 x p1`` (sphere). No input is
modified.

**One wrap** (:func:`wrap_sphere`, :func:`wrap_cylinder`). Every point is given in the wrap geom's own
frame: centre at the origin, the cylinder's axis along local ``z`` (the cylinder is infinite: its
half-height plays no role). The path from ``p0`` to ``p1`` leaves ``p0`` in a straight line tangent to
the surface at ``t0``, follows the surface to ``t1`` and leaves tangentially to ``p1``. The problem is
solved in a plane, on a circle of radius ``r``:

- Sphere: the plane through the centre, ``p0`` and ``p1`` (2-D axes ``e1 = p0/|p0|``, ``e2 = n x e1``;
  when ``p0`` and ``p1`` are parallel, ``n`` is built from ``e1`` and the vector of ones with a zero at
  ``e1``'s largest component). The arc is a great-circle arc, ``arc = r * angle(t0, t1)``.
- Cylinder: the ``x, y`` projection; ``z`` then varies linearly with the unrolled path length
  ``L0 + a + L1`` (``L0 = |p0 - t0|``, ``L1 = |p1 - t1|`` measured in ``x, y``, ``a`` the circular arc),
  so the path on the surface is a helix and ``arc = sqrt(a^2 + (z1 - z0)^2)``.

With ``alpha_i = acos(r/|p_i|)`` (2-D norms), the tangent point ``t_i`` is ``p_i`` turned by
``alpha_i`` towards the way the path goes round, scaled to the circle.

**Side point** (MuJoCo's ``sidesite``), given in the geom frame; ``s`` is its projection onto the
plane, scaled onto the circle, and ``|side|`` (the full 3-D norm, also for a cylinder) decides:

- None: the path wraps only if the straight segment ``p0 -> p1`` meets the closed disc, and then the
  shorter way round (the solution with the shorter chord ``|t0 - t1|`` whose straight pieces do not
  cross).
- Outside (``|side| >= r``): the path is the shortest path from ``p0`` to ``p1`` homotopic to the
  polyline ``p0 -> s -> p1`` in the plane without the disc, i.e. with its winding angle
  ``w = angle(p0, s) + angle(s, p1)`` (each in ``[-pi, pi]``, counter-clockwise positive). It wraps,
  the way round of ``sign(w)``, when ``|w| > alpha_0 + alpha_1``, with the circular arc
  ``r (|w| - alpha_0 - alpha_1)``; otherwise the straight segment already passes the geom that way and
  the path is straight. So a side point can force a wrap on a segment that misses the geom, and the
  path snaps off (a jump in length) when an end point crosses the ray opposite ``s``, where ``w``
  jumps by ``2 pi``. (Before 4.0 MuJoCo used a half-plane test instead.)
- Inside (``|side| < r``): the *inside wrap*: the path is kept through the disc. When the straight
  segment meets the disc it is straight; otherwise it touches the circle at one point ``t0 = t1``
  (``arc = 0``) where both straight pieces make the same angle ``beta`` with the normal:
  ``asin(A sin beta) + asin(B sin beta) - 2 beta + G = 0`` with ``A = r/|p0|``, ``B = r/|p1|`` and
  ``G`` the angle between ``p0`` and ``p1``. MuJoCo solves it by Newton's method from ``beta = pi/2``
  and stops at a residual of 1e-6, so ``t0`` is only accurate to ~1e-7 rad; we take the same steps
  (the length is stationary in the touch point, so its error is second order).

**No wrap** (``engaged=False``, the path is the straight line ``p0 -> p1``) also when ``p0`` or ``p1``
lies inside the circle (for a cylinder: inside the infinite cylinder), within 1e-15 of the centre, or
(without side point) within ``sqrt(1e-15)`` of each other in the plane.

**A tendon** (:func:`tendon_path`) walks its elements as ``mj_tendon`` does: a site followed by a geom
and a site is one span (site -> t0, the arc, t1 -> site, or site -> site when not engaged), a site
followed by a site a straight span; a pulley starts a new branch whose length and Jacobian are
divided by its divisor. The length is MuJoCo's ``ten_length``: the sum over branches of (straight
lengths + arcs) / divisor.

**Jacobian.** Each straight segment ``a -> b`` carries ``scale = 1/divisor``; with ``u = (b - a)/|b - a|``
(world), ``ten_J = sum scale * u^T (J_b - J_a)``, where ``J_x`` is the translational Jacobian of the
point *fixed on the body of its element at this instant* (a site's body; for a tangent point, the wrap
geom's body). Arcs contribute nothing (both ends are on the same body), nor do segments between two
points on one body (``u`` is parallel to ``b - a``); MuJoCo skips those and we list them anyway.
Moving a tangent point along the surface changes the length only to second order, which is why this
is the derivative of the length (and MuJoCo's ``ten_J``): exactly for outside wraps, and to the
accuracy of the touch point (~1e-7 relative) for inside wraps.

**Smoothness.** The length is continuous where a wrap engages or disengages: the straight line then
just touches the circle, both tangent points coincide with the touch point (``arc = 0``) and the two
straight pieces add up to the straight line. ``L = dl/dq`` is continuous there too (the extra length
of a path pushed round the circle by a depth ``h`` grows like ``h^(3/2)``; ``h^2`` for the inside
wrap), but not smooth: ``dL/dq`` jumps (a kink in ``L``), e.g. a cylinder about a hinge axis has a
constant moment arm ``r`` while wrapped and a changing one while straight. With a side point outside,
the length itself jumps where an end point crosses the ray opposite the side point (see above).

**One implementation, compiled or not.** The maths are plain functions on floats and tuples marked
``register_jitable``: called from Python (:func:`wrap_sphere`, :func:`wrap_cylinder`,
:func:`tendon_path`, the route kernel's uncompiled path) they run as Python; called from the njit
route kernel (:mod:`mcdm_pin.model.route_kernels`: every wrap of a cable set in one pass) numba
compiles them inline. So this file imports numba's ``extending`` (through :mod:`mcdm_pin.jit`, which
counts it among the kernel sources whose digest stamps the compiled cache).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..exceptions import ModelError
from ..jit import extending  # register_jitable: compiled inline into the njit route kernel

register_jitable = extending.register_jitable

MINVAL = 1e-15
"""MuJoCo's ``mjMINVAL``: the smallest value it accepts in a denominator."""

_INSIDE_MAXITER = 20
_INSIDE_TOL = 1e-6


@dataclass(frozen=True)
class Wrap:
    """One wrap in the geom's frame: ``engaged``; tangent points ``t0`` (nearer ``p0``), ``t1`` (3,)
    metres, ``None`` when not engaged; ``arc`` the path length on the surface from ``t0`` to ``t1``
    (metres; 0 when not engaged, and for an inside wrap, where ``t0 == t1``)."""

    engaged: bool
    t0: np.ndarray | None
    t1: np.ndarray | None
    arc: float


@dataclass(frozen=True)
class Path:
    """A spatial tendon's path at one instant, world frame.

    Attributes:
        length: MuJoCo's ``ten_length`` (metres): each branch's length divided by its divisor.
        segments: straight segments ``(a_elem, a, b_elem, b, scale)``: ``a``, ``b`` (3,) world points,
            ``a_elem``/``b_elem`` the index in ``elements`` of the element whose body carries the point
            (a site, or the wrap geom for a tangent point), ``scale = 1/divisor`` of the branch.
        arcs: ``(elem, arc, scale)`` for each engaged wrap (``elem`` the geom element).
        wrap_points: (n, 3) the rows of MuJoCo's ``wrap_xpos`` for this tendon, in its order: each
            span's first site, then its two tangent points if engaged; a branch's last site; a zero
            row per pulley.
        wrap_elems: for each row of ``wrap_points``, the index of its element (site, geom or pulley).
    """

    length: float
    segments: list
    arcs: list
    wrap_points: np.ndarray
    wrap_elems: list


# --- the maths: plain Python on floats and tuples, written so that numba compiles the same functions
# inline into the route kernel (mcdm_pin/model/route_kernels.py); a wrap that does not engage is
# ``ok = False`` with zeros in place of the points (numba types both branches alike).


@register_jitable
def _normalize2(x, y):
    """MuJoCo's ``mju_normalize`` in 2-D: a vector shorter than MINVAL becomes ``(1, 0)``."""
    n = math.sqrt(x * x + y * y)
    if n < MINVAL:
        return 1.0, 0.0
    return x / n, y / n


@register_jitable
def _normalize3(v):
    """MuJoCo's ``mju_normalize3``: the unit vector (``(1, 0, 0)`` below MINVAL) and the norm."""
    n = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    if n < MINVAL:
        return (1.0, 0.0, 0.0), n
    return (v[0] / n, v[1] / n, v[2] / n), n


@register_jitable
def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@register_jitable
def _dot3(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@register_jitable
def _segments_cross(p1, p2, p3, p4):
    """Whether the 2-D segments ``p1 -> p2`` and ``p3 -> p4`` intersect (ends included); parallel
    segments (determinant below MINVAL) do not."""
    det = (p4[1] - p3[1]) * (p2[0] - p1[0]) - (p4[0] - p3[0]) * (p2[1] - p1[1])
    if abs(det) < MINVAL:
        return False
    a = ((p4[0] - p3[0]) * (p1[1] - p3[1]) - (p4[1] - p3[1]) * (p1[0] - p3[0])) / det
    b = ((p2[0] - p1[0]) * (p1[1] - p3[1]) - (p2[1] - p1[1]) * (p1[0] - p3[0])) / det
    return 0.0 <= a <= 1.0 and 0.0 <= b <= 1.0


@register_jitable
def _arc_circle(s0, s1, second, radius):
    """Arc length from ``s0`` to ``s1`` on the circle, the way round given by the solution index
    (the angle from ``atan2``, exact also for the short arcs at wrap onset)."""
    cross = s0[1] * s1[0] - s0[0] * s1[1]
    angle = math.atan2(abs(cross), s0[0] * s1[0] + s0[1] * s1[1])
    if (cross > 0 and second) or (cross < 0 and not second):
        angle = 2.0 * math.pi - angle
    return radius * angle


@register_jitable
def _no_wrap2():
    """A 2-D wrap that does not engage: ``(False, 0.0, (0, 0), (0, 0))``."""
    return False, 0.0, (0.0, 0.0), (0.0, 0.0)


@register_jitable
def _circle_candidate(e0, e1, sgn, sqrad, r0, r1):
    """One of the two tangent solutions (``sgn`` +1 or -1) of the wrap without side point: ``(s0,
    s1, goodness)``, goodness minus the squared chord, -10000 when the straight pieces cross."""
    sqlen0 = e0[0] * e0[0] + e0[1] * e0[1]
    sqlen1 = e1[0] * e1[0] + e1[1] * e1[1]
    s0 = ((e0[0] * sqrad + sgn * e0[1] * r0) / sqlen0, (e0[1] * sqrad - sgn * e0[0] * r0) / sqlen0)
    s1 = ((e1[0] * sqrad - sgn * e1[1] * r1) / sqlen1, (e1[1] * sqrad + sgn * e1[0] * r1) / sqlen1)
    g = -((s0[0] - s1[0]) ** 2 + (s0[1] - s1[1]) ** 2)
    if _segments_cross(e0, s0, e1, s1):
        g = -10000.0
    return s0, s1, g


@register_jitable
def _wrap_circle(e0, e1, radius):
    """2-D wrap of the segment ``e0 -> e1`` round the circle of ``radius`` at the origin, without a
    side point: ``(ok, arc, t0, t1)``."""
    sqlen0 = e0[0] * e0[0] + e0[1] * e0[1]
    sqlen1 = e1[0] * e1[0] + e1[1] * e1[1]
    sqrad = radius * radius
    if sqlen0 < sqrad or sqlen1 < sqrad or radius < MINVAL:
        return _no_wrap2()
    dx, dy = e1[0] - e0[0], e1[1] - e0[1]
    dd = dx * dx + dy * dy
    if dd < MINVAL:
        return _no_wrap2()
    a = min(1.0, max(0.0, -(dx * e0[0] + dy * e0[1]) / dd))
    cx, cy = e0[0] + a * dx, e0[1] + a * dy
    if cx * cx + cy * cy > sqrad:
        return _no_wrap2()
    r0 = radius * math.sqrt(sqlen0 - sqrad)
    r1 = radius * math.sqrt(sqlen1 - sqrad)
    s0, s1, g0 = _circle_candidate(e0, e1, 1.0, sqrad, r0, r1)
    u0, u1, g1 = _circle_candidate(e0, e1, -1.0, sqrad, r0, r1)
    second = not g0 > g1
    if second:
        s0, s1 = u0, u1
    if _segments_cross(e0, s0, e1, s1):
        return _no_wrap2()
    return True, _arc_circle(s0, s1, second, radius), s0, s1


@register_jitable
def _signed_angle(a, b):
    """The angle from 2-D vector ``a`` to ``b`` in ``[-pi, pi]``, counter-clockwise positive."""
    return math.atan2(a[0] * b[1] - a[1] * b[0], a[0] * b[0] + a[1] * b[1])


@register_jitable
def _wrap_side(e0, e1, side, radius):
    """2-D wrap with a side point outside the geom (``side`` on the circle): the shortest path from
    ``e0`` to ``e1`` with the winding angle of the polyline ``e0 -> side -> e1`` about the centre.
    ``(ok, arc, t0, t1)``; not ok when the straight segment already has that winding and misses the
    circle."""
    sqlen0 = e0[0] * e0[0] + e0[1] * e0[1]
    sqlen1 = e1[0] * e1[0] + e1[1] * e1[1]
    if sqlen0 < radius * radius or sqlen1 < radius * radius or radius < MINVAL:
        return _no_wrap2()
    winding = _signed_angle(e0, side) + _signed_angle(side, e1)
    len0, len1 = math.sqrt(sqlen0), math.sqrt(sqlen1)
    a0, a1 = math.acos(radius / len0), math.acos(radius / len1)
    turn = abs(winding) - a0 - a1
    if turn <= 0:
        return _no_wrap2()
    sgn = 1.0 if winding > 0 else -1.0
    c0, s0 = math.cos(a0), sgn * math.sin(a0)
    c1, s1 = math.cos(a1), -sgn * math.sin(a1)
    k0, k1 = radius / len0, radius / len1
    t0 = (k0 * (c0 * e0[0] - s0 * e0[1]), k0 * (s0 * e0[0] + c0 * e0[1]))
    t1 = (k1 * (c1 * e1[0] - s1 * e1[1]), k1 * (s1 * e1[0] + c1 * e1[1]))
    return True, radius * turn, t0, t1


@register_jitable
def _inside_angle(A, B, G):
    """The root ``beta`` in ``[0, pi/2]`` of ``F(b) = asin(A sin b) + asin(B sin b) - 2 b + G``
    (``A, B < 1``, ``G`` the angle between the end points): the angle between each straight piece
    and the normal where the path touches the circle. ``F`` falls strictly (slope in
    ``[-2, A + B - 2]``). As MuJoCo 4.0 does, Newton's method from ``pi/2`` stops once
    ``|F| <= 1e-6``, so ``beta`` carries an error up to ~1e-7 rad (the length is stationary there)."""
    b = 0.5 * math.pi
    fb = math.asin(A) + math.asin(B) - 2.0 * b + G
    if fb >= 0.0:
        return b  # the straight segment grazes the circle
    for _ in range(_INSIDE_MAXITER):
        if abs(fb) <= _INSIDE_TOL:
            break
        sb, cb = math.sin(b), math.cos(b)
        df = A * cb / math.sqrt(1.0 - A * A * sb * sb) + B * cb / math.sqrt(1.0 - B * B * sb * sb) - 2.0
        b -= fb / df
        sb = math.sin(b)
        fb = math.asin(A * sb) + math.asin(B * sb) - 2.0 * b + G
    return b


@register_jitable
def _wrap_inside(e0, e1, radius):
    """2-D inside wrap (side point inside the geom): ``(ok, 0.0, t, t)`` with the single point where
    the shortest path from ``e0`` to ``e1`` through the closed disc touches the circle (equal angles
    to the normal); not ok when an end is inside or the straight segment already crosses the disc."""
    len0 = math.sqrt(e0[0] * e0[0] + e0[1] * e0[1])
    len1 = math.sqrt(e1[0] * e1[0] + e1[1] * e1[1])
    if len0 <= radius or len1 <= radius or radius < MINVAL:
        return _no_wrap2()
    dx, dy = e1[0] - e0[0], e1[1] - e0[1]
    dd = dx * dx + dy * dy
    if dd > MINVAL:
        a = -(dx * e0[0] + dy * e0[1]) / dd
        if 0 < a < 1 and math.hypot(e0[0] + a * dx, e0[1] + a * dy) <= radius:
            return _no_wrap2()
    A, B = radius / len0, radius / len1
    beta = _inside_angle(A, B, abs(_signed_angle(e0, e1)))
    sb = math.sin(beta)
    if e0[0] * e1[1] - e0[1] * e1[0] > 0:
        vx, vy, ang = e0[0] / len0, e0[1] / len0, beta - math.asin(A * sb)
    else:
        vx, vy, ang = e1[0] / len1, e1[1] / len1, beta - math.asin(B * sb)
    c, s = math.cos(ang), math.sin(ang)
    t = (radius * (c * vx - s * vy), radius * (s * vx + c * vy))
    return True, 0.0, t, t


@register_jitable
def _plane_axes(p0, p1):
    """The sphere's 2-D frame: ``e1`` along ``p0``, ``e2`` in the plane of ``p0``, ``p1``."""
    e1, _ = _normalize3(p0)
    normal, nrm = _normalize3(_cross(p0, p1))
    if nrm < MINVAL:
        i = 0
        if abs(e1[1]) > abs(e1[0]) and abs(e1[1]) > abs(e1[2]):
            i = 1
        if abs(e1[2]) > abs(e1[0]) and abs(e1[2]) > abs(e1[1]):
            i = 2
        other = (0.0 if i == 0 else 1.0, 0.0 if i == 1 else 1.0, 0.0 if i == 2 else 1.0)
        normal, _ = _normalize3(_cross(e1, other))
    e2, _ = _normalize3(_cross(normal, e1))
    return e1, e2


@register_jitable
def _wrap_local(cylinder, p0, p1, radius, has_side, side):
    """One wrap on tuples of floats in the geom frame (``side`` read only when ``has_side``):
    ``(ok, arc, t0, t1)``, the tangent points (3-tuples) zero when not ok."""
    zero = (0.0, 0.0, 0.0)
    if math.sqrt(_dot3(p0, p0)) < MINVAL or math.sqrt(_dot3(p1, p1)) < MINVAL:
        return False, 0.0, zero, zero
    if cylinder:
        e1, e2 = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)
    else:
        e1, e2 = _plane_axes(p0, p1)
    d0 = (_dot3(p0, e1), _dot3(p0, e2))
    d1 = (_dot3(p1, e1), _dot3(p1, e2))
    if has_side and math.sqrt(_dot3(side, side)) < radius:
        ok, arc, s0, s1 = _wrap_inside(d0, d1, radius)
    elif has_side:
        sx, sy = _normalize2(_dot3(side, e1), _dot3(side, e2))
        ok, arc, s0, s1 = _wrap_side(d0, d1, (radius * sx, radius * sy), radius)
    else:
        ok, arc, s0, s1 = _wrap_circle(d0, d1, radius)
    if not ok:
        return False, 0.0, zero, zero
    t0 = (e1[0] * s0[0] + e2[0] * s0[1], e1[1] * s0[0] + e2[1] * s0[1], e1[2] * s0[0] + e2[2] * s0[1])
    t1 = (e1[0] * s1[0] + e2[0] * s1[1], e1[1] * s1[0] + e2[1] * s1[1], e1[2] * s1[0] + e2[2] * s1[1])
    if cylinder:
        l0 = math.sqrt((p0[0] - t0[0]) ** 2 + (p0[1] - t0[1]) ** 2)
        l1 = math.sqrt((p1[0] - t1[0]) ** 2 + (p1[1] - t1[1]) ** 2)
        total = l0 + arc + l1
        t0 = (t0[0], t0[1], p0[2] + (p1[2] - p0[2]) * l0 / total)
        t1 = (t1[0], t1[1], p0[2] + (p1[2] - p0[2]) * (l0 + arc) / total)
        height = abs(t1[2] - t0[2])
        arc = math.sqrt(arc * arc + height * height)
    return True, arc, t0, t1


@register_jitable
def to_frame(R, p, x):
    """``R^T (x - p)``: a world point ``x`` in the frame of orientation ``R`` (3x3 nested tuple,
    columns the frame's axes) and origin ``p``."""
    dx, dy, dz = x[0] - p[0], x[1] - p[1], x[2] - p[2]
    return (R[0][0] * dx + R[1][0] * dy + R[2][0] * dz, R[0][1] * dx + R[1][1] * dy + R[2][1] * dz,
            R[0][2] * dx + R[1][2] * dy + R[2][2] * dz)


@register_jitable
def from_frame(R, p, t):
    """``R t + p``: a point ``t`` of the frame ``(R, p)`` in its parent's frame."""
    return (R[0][0] * t[0] + R[0][1] * t[1] + R[0][2] * t[2] + p[0],
            R[1][0] * t[0] + R[1][1] * t[1] + R[1][2] * t[2] + p[1],
            R[2][0] * t[0] + R[2][1] * t[1] + R[2][2] * t[2] + p[2])


@register_jitable
def wrap_in_frame(cylinder, R, p, x0, x1, radius, has_side, side):
    """The wrap of ``x0 -> x1`` over the geom of orientation ``R`` and centre ``p`` (all in one
    frame, e.g. world; ``side`` read only when ``has_side``): ``(ok, arc, t0, t1)`` with the tangent
    points in the geom's own frame."""
    s = to_frame(R, p, side) if has_side else side
    return _wrap_local(cylinder, to_frame(R, p, x0), to_frame(R, p, x1), radius, has_side, s)


def _point(x, what: str) -> tuple[float, float, float]:
    a = np.asarray(x, dtype=float)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ModelError(f"{what}: expected 3 finite coordinates (metres), got {x!r}")
    return float(a[0]), float(a[1]), float(a[2])


def _radius(radius, what: str) -> float:
    r = float(radius)
    if not (math.isfinite(r) and r > 0):
        raise ModelError(f"{what}: expected a finite positive radius (metres), got {radius!r}")
    return r


def _wrap(cylinder: bool, p0, p1, radius, side) -> Wrap:
    kind = "wrap_cylinder" if cylinder else "wrap_sphere"
    r = _radius(radius, kind)
    s = (0.0, 0.0, 0.0) if side is None else _point(side, f"{kind} side")
    ok, arc, t0, t1 = _wrap_local(cylinder, _point(p0, f"{kind} p0"), _point(p1, f"{kind} p1"), r,
                                  side is not None, s)
    if not ok:
        return Wrap(False, None, None, 0.0)
    return Wrap(True, np.array(t0), np.array(t1), float(arc))


def wrap_sphere(p0, p1, radius: float, side=None) -> Wrap:
    """MuJoCo's wrap of the path ``p0 -> p1`` over a sphere of ``radius`` (metres) at the origin;
    ``p0``, ``p1`` and the optional side point ``side`` are (3,) in the sphere's frame. See the module
    docstring for when it engages and what the side point does."""
    return _wrap(False, p0, p1, radius, side)


def wrap_cylinder(p0, p1, radius: float, side=None) -> Wrap:
    """MuJoCo's wrap of the path ``p0 -> p1`` over an infinite cylinder of ``radius`` (metres) whose
    axis is the local ``z`` axis; points in the cylinder's frame. The path on the surface is a helix
    and ``arc`` its length."""
    return _wrap(True, p0, p1, radius, side)


_ARITY = {"site": 2, "geom": 6, "pulley": 2}


def _kind(element, k: int) -> str:
    """The tag of ``elements[k]``, its arity checked."""
    tag = element[0] if isinstance(element, (tuple, list)) and element else None
    if tag not in _ARITY or len(element) != _ARITY[tag]:
        raise ModelError(f"tendon element {k}: expected ('site', x), ('geom', kind, R, p, radius, side) "
                         f"or ('pulley', divisor), got {element!r}")
    return tag


def _check_order(kinds: list[str]) -> None:
    """MuJoCo's rules: a tendon starts and ends at a site; a geom or a pulley sits between two sites."""
    n = len(kinds)
    if n < 2 or kinds[0] != "site" or kinds[-1] != "site":
        raise ModelError(f"tendon elements: expected at least two, the first and last a site, got {kinds}")
    for k in range(1, n - 1):
        if kinds[k] != "site" and (kinds[k - 1] != "site" or kinds[k + 1] != "site"):
            raise ModelError(f"tendon element {k} ({kinds[k]}): expected a site on either side, got "
                             f"{kinds[k - 1]} and {kinds[k + 1]}")


def _vec3(x, what: str) -> tuple[float, float, float]:
    """A 3-vector as three floats (cheaper than numpy for the few operations per point)."""
    if isinstance(x, np.ndarray) and x.shape == (3,) and x.dtype == np.float64:
        return tuple(x.tolist())
    try:
        a, b, c = x
        return float(a), float(b), float(c)
    except (TypeError, ValueError):
        raise ModelError(f"{what}: expected 3 coordinates (metres), got {x!r}") from None


def _wrap_world(element, k: int, x0, x1):
    """The wrap of ``x0 -> x1`` (world, tuples) over geom element ``k``: ``(arc, t0, t1)`` with world
    tuples, or None."""
    _, kind, rot, pos, radius, side = element
    if kind not in ("sphere", "cylinder"):
        raise ModelError(f"tendon element {k} (geom): expected kind 'sphere' or 'cylinder', got {kind!r}")
    rot = np.asarray(rot, dtype=float)
    if rot.shape != (3, 3):
        raise ModelError(f"tendon element {k} (geom): expected R of shape (3, 3), got {rot.shape}")
    R = tuple(tuple(row) for row in rot.tolist())
    p = _vec3(pos, f"tendon element {k} (geom) p")
    r = _radius(radius, f"tendon element {k} (geom) radius")
    s = (0.0, 0.0, 0.0) if side is None else _vec3(side, f"tendon element {k} (geom) side")
    ok, arc, t0, t1 = wrap_in_frame(kind == "cylinder", R, p, x0, x1, r, side is not None, s)
    if not ok:
        return None
    return arc, from_frame(R, p, t0), from_frame(R, p, t1)


def _dist(a, b) -> float:
    return math.sqrt((b[0] - a[0]) ** 2 + (b[1] - a[1]) ** 2 + (b[2] - a[2]) ** 2)


def tendon_path(elements: Sequence) -> Path:
    """Walk one spatial tendon as MuJoCo's ``mj_tendon`` does, at one instant (world frame).

    Args:
        elements: the tendon's path in order; each one of ``("site", x)`` with ``x`` (3,) metres,
            ``("geom", kind, R, p, radius, side)`` with ``kind`` ``"sphere"`` or ``"cylinder"``, ``R``
            (3, 3) the geom's orientation (columns: its axes in world), ``p`` (3,) its centre, ``radius``
            metres and ``side`` the (3,) side point or None, or ``("pulley", divisor)``.

    Returns:
        the :class:`Path`: length, straight segments with the element carrying each end, arcs, and
        the rows of MuJoCo's ``wrap_xpos``. Segment end points are rows of ``wrap_points`` (views).
    """
    kinds = [_kind(e, k) for k, e in enumerate(elements)]
    _check_order(kinds)
    n = len(kinds)
    pieces, arcs, rows, row_elems = [], [], [], []  # pieces: (a_elem, a_row, b_elem, b_row, scale)
    length, divisor, j = 0.0, 1.0, 0
    while j < n - 1:
        if kinds[j] == "pulley" or kinds[j + 1] == "pulley":
            if kinds[j] == "pulley":
                divisor = float(elements[j][1])
                if not (math.isfinite(divisor) and divisor > 0):
                    raise ModelError(f"tendon element {j} (pulley): expected a finite positive divisor, "
                                     f"got {elements[j][1]!r}")
                rows.append((0.0, 0.0, 0.0))
                row_elems.append(j)
            j += 1
            continue
        scale = 1.0 / divisor
        g = j + 1 if kinds[j + 1] == "geom" else -1
        end = j + 2 if g >= 0 else j + 1
        x0 = _vec3(elements[j][1], f"tendon element {j} (site)")
        x1 = _vec3(elements[end][1], f"tendon element {end} (site)")
        wrapped = _wrap_world(elements[g], g, x0, x1) if g >= 0 else None
        i0 = len(rows)
        rows.append(x0)
        row_elems.append(j)
        if wrapped is None:
            pieces.append((j, i0, end, i0 + 1, scale))
            length += _dist(x0, x1) / divisor
        else:
            arc, t0, t1 = wrapped
            pieces += [(j, i0, g, i0 + 1, scale), (g, i0 + 2, end, i0 + 3, scale)]
            arcs.append((g, arc, scale))
            rows += [t0, t1]
            row_elems += [g, g]
            length += (_dist(x0, t0) + arc + _dist(t1, x1)) / divisor
        j = end
        if j == n - 1 or kinds[j + 1] == "pulley":
            rows.append(x1)
            row_elems.append(j)
    points = np.array(rows)
    segments = [(a, points[ia], b, points[ib], sc) for a, ia, b, ib, sc in pieces]
    return Path(length, segments, arcs, points, row_elems)
