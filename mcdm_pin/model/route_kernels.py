r"""The compiled route pass: every wrap and rotating pulley of a cable set at one instant in one call.

:class:`mcdm_pin.model.routes.RoutePaths` keeps the path arrays the cable-terms kernel reads (its module
docstring gives the layout); :func:`route_pass` rewrites them from the key bodies' world placements.
For wrap ``w`` between route points :math:`A` (on key body ``a``) and :math:`B` (on ``b``), over a
surface fixed on key body ``g`` at placement :math:`(R_w, p_w)` in that body's frame:

.. math::

    R_g = {}^0R_g R_w, \quad p_g = {}^0R_g p_w + {}^0p_g, \qquad
    A = {}^0R_a A_a + {}^0p_a \ (\text{likewise } B \text{ and the side point}),

the wrap itself is :func:`mcdm_pin.model.wrapping.wrap_in_frame` (MuJoCo 4.0's rule: the points taken
to the surface's frame, :math:`R_g^T (x - p_g)`, then the sphere or cylinder wrap with its side-point
winding or inside wrap), and an engaged wrap's tangent points go into their slots in the frame of
the surface's body, :math:`R_w t + p_w` (metres). The wrap maths is ``wrapping.py``'s own functions,
compiled inline here: one implementation (the helpers below are ``register_jitable`` too, so
the uncompiled path is Python throughout).

Then every rotating pulley (:mod:`mcdm_pin.model.pulleys`): the cable's other end :math:`B` (on key
body ``b``) is taken into the frame of the pulley's body ``k``, :math:`{}^0R_k^T(B - {}^0p_k)`; a screw
outlet moves the entry point there (:func:`~mcdm_pin.model.pulleys.screw_entry`), the exit point
(:func:`~mcdm_pin.model.pulleys.rotating_exit`) goes into the pulley's route point slot, in the frame of
the pulley's body, and the arc, times the branch's scale, into its cable's ``arc_length``.

Compiled by ``mcdm-pin compile`` with the other kernels and cached on disk (``cache=True``),
registered with :mod:`mcdm_pin.jit` like :mod:`mcdm_pin.model.kernels`; until then the same code runs
as Python (``jit.kernels("model.route_kernels").route_pass``).

Packed per-wrap and per-pulley tables (one array each, so that a call passes few arguments: numba's
dispatch costs about a microsecond per argument):

- ``wrap_int`` (W, 12) int64: key bodies of the surface, ``A``, ``B`` and the side point; has a side
  point (0/1); cylinder (0/1, else sphere); the slot of ``T_0`` (``T_1`` is the next); the segment
  ``AB`` it replaces; ``B``'s point index; the cable; whether ``A T_0`` spans two bodies; whether
  ``AB`` does.
- ``wrap_float`` (W, 23): ``A``, ``B`` and the side point in their bodies' frames; ``R_w``
  (row-major), ``p_w``; the radius; the branch's scale ``1/divisor``.
- ``pulley_int`` (Q, 5) int64: key bodies of the pulley and of ``B``; the exit point's slot; the
  cable; has a screw outlet (0/1).
- ``pulley_float`` (Q, 17): ``B`` in its body's frame; the entry point (the winch point with a screw),
  the entry direction, the screw's direction, all in the pulley body's frame; the radius; the
  branch's scale; the screw's lead, reference length and outlet position.

It returns ``(q, reason)``: the first rotating pulley without an exit point at these placements and
why (:data:`mcdm_pin.model.pulleys.REASONS`), or ``(-1, 0)``.
"""

from __future__ import annotations

import numpy as np
from ..jit import njit

from .pulleys import REASON_OK, REASON_SCREW, rotating_exit, screw_entry
from .kernel_structs import OsimPaths, Route
from .route_osim import osim_routes
from .wrapping import from_frame, register_jitable, to_frame, wrap_in_frame

# columns of wrap_int
W_KEY, A_KEY, B_KEY, S_KEY, HAS_SIDE, CYLINDER, SLOT, SEG, B_POINT, CABLE, ACTIVE_AT0, ACTIVE_AB = range(12)
N_INT = 12
# columns of wrap_float
A_LOCAL, B_LOCAL, S_LOCAL, R_W, P_W, RADIUS, SCALE = 0, 3, 6, 9, 18, 21, 22
N_FLOAT = 23
# columns of pulley_int
Q_KEY, QB_KEY, Q_SLOT, Q_CABLE, Q_SCREW = range(5)
NQ_INT = 5
# columns of pulley_float
QB_LOCAL, Q_ENTRY, Q_AXIS, Q_DIR, Q_RADIUS, Q_SCALE, Q_LEAD, Q_REF, Q_OUTLET = 0, 3, 6, 9, 12, 13, 14, 15, 16
NQ_FLOAT = 17


@register_jitable
def _rotation(oM, k):
    """Key body ``k``'s world rotation as a nested tuple (rows)."""
    return ((oM[k, 0, 0], oM[k, 0, 1], oM[k, 0, 2]), (oM[k, 1, 0], oM[k, 1, 1], oM[k, 1, 2]),
            (oM[k, 2, 0], oM[k, 2, 1], oM[k, 2, 2]))


@register_jitable
def _world(oM, k, f, c):
    """The point ``f[c:c+3]`` of key body ``k``'s frame in world: ``R x + p``."""
    x0, x1, x2 = f[c], f[c + 1], f[c + 2]
    return (oM[k, 0, 0] * x0 + oM[k, 0, 1] * x1 + oM[k, 0, 2] * x2 + oM[k, 0, 3],
            oM[k, 1, 0] * x0 + oM[k, 1, 1] * x1 + oM[k, 1, 2] * x2 + oM[k, 1, 3],
            oM[k, 2, 0] * x0 + oM[k, 2, 1] * x1 + oM[k, 2, 2] * x2 + oM[k, 2, 3])


@register_jitable
def _surface(oM, k, f):
    """The surface's world frame ``(R_g, p_g)`` (nested tuple, tuple) and its placement ``(R_w, p_w)``
    in key body ``k``'s frame, from the wrap's row ``f`` of ``wrap_float``."""
    Rw = ((f[R_W], f[R_W + 1], f[R_W + 2]), (f[R_W + 3], f[R_W + 4], f[R_W + 5]),
          (f[R_W + 6], f[R_W + 7], f[R_W + 8]))
    pw = (f[P_W], f[P_W + 1], f[P_W + 2])
    oR = _rotation(oM, k)
    Rg = ((oR[0][0] * Rw[0][0] + oR[0][1] * Rw[1][0] + oR[0][2] * Rw[2][0],
           oR[0][0] * Rw[0][1] + oR[0][1] * Rw[1][1] + oR[0][2] * Rw[2][1],
           oR[0][0] * Rw[0][2] + oR[0][1] * Rw[1][2] + oR[0][2] * Rw[2][2]),
          (oR[1][0] * Rw[0][0] + oR[1][1] * Rw[1][0] + oR[1][2] * Rw[2][0],
           oR[1][0] * Rw[0][1] + oR[1][1] * Rw[1][1] + oR[1][2] * Rw[2][1],
           oR[1][0] * Rw[0][2] + oR[1][1] * Rw[1][2] + oR[1][2] * Rw[2][2]),
          (oR[2][0] * Rw[0][0] + oR[2][1] * Rw[1][0] + oR[2][2] * Rw[2][0],
           oR[2][0] * Rw[0][1] + oR[2][1] * Rw[1][1] + oR[2][2] * Rw[2][1],
           oR[2][0] * Rw[0][2] + oR[2][1] * Rw[1][2] + oR[2][2] * Rw[2][2]))
    pg = _world(oM, k, f, P_W)
    return Rg, pg, Rw, pw


@register_jitable
def _vec(f, c):
    return (f[c], f[c + 1], f[c + 2])


@register_jitable
def _pulleys(oM, pulley_int, pulley_float, point_local, arc_length):
    """Every rotating pulley's exit point into its slot and its arc into ``arc_length``: ``(q,
    reason)`` of the first one without an exit point, or ``(-1, 0)``."""
    for q in range(pulley_int.shape[0]):
        qi = pulley_int[q]
        f = pulley_float[q]
        k = qi[Q_KEY]
        pk = (oM[k, 0, 3], oM[k, 1, 3], oM[k, 2, 3])
        B = to_frame(_rotation(oM, k), pk, _world(oM, qi[QB_KEY], f, QB_LOCAL))
        F = _vec(f, Q_ENTRY)
        if qi[Q_SCREW] != 0:
            ok, F = screw_entry(F, _vec(f, Q_DIR), f[Q_LEAD], f[Q_REF], f[Q_OUTLET], B)
            if not ok:
                return q, REASON_SCREW
        reason, arc, A = rotating_exit(F, _vec(f, Q_AXIS), f[Q_RADIUS], B)
        if reason != REASON_OK:
            return q, reason
        slot = qi[Q_SLOT]
        for i in range(3):
            point_local[slot, i] = A[i]
        arc_length[qi[Q_CABLE]] += f[Q_SCALE] * arc
    return -1, 0


@njit(cache=True, nogil=True)
def route_pass(oM, wrap_int, wrap_float, pulley_int, pulley_float, point_local, seg_b, seg_active, seg_scale,
               arc_length, engaged, n_segments):
    """Rewrite the path arrays for the placements ``oM`` (K, 4, 4) (module docstring), in place:
    ``point_local`` (P + 2W, 3) the tangent slots (zeros when not engaged) and the rotating pulleys'
    exit points, ``seg_b`` and ``seg_active`` of each wrap's segment (``T_0`` and ``A T_0`` when
    engaged, else ``B`` and ``AB``), ``seg_scale`` of the slot segments ``T_1 B`` (index
    ``n_segments + w``: the branch's scale when engaged, else 0), ``arc_length`` (m,) each cable's
    arcs times their scales and ``engaged`` (W,). Returns ``(q, reason)`` (module docstring)."""
    arc_length[:] = 0.0
    for w in range(wrap_int.shape[0]):
        wi = wrap_int[w]
        f = wrap_float[w]
        Rg, pg, Rw, pw = _surface(oM, wi[W_KEY], f)
        pa = _world(oM, wi[A_KEY], f, A_LOCAL)
        pb = _world(oM, wi[B_KEY], f, B_LOCAL)
        has_side = wi[HAS_SIDE] != 0
        ps = _world(oM, wi[S_KEY], f, S_LOCAL) if has_side else (0.0, 0.0, 0.0)
        ok, arc, t0, t1 = wrap_in_frame(wi[CYLINDER] != 0, Rg, pg, pa, pb, f[RADIUS], has_side, ps)
        engaged[w] = ok
        slot, seg = wi[SLOT], wi[SEG]
        if ok:  # tangent points from the surface's frame to the frame of the body carrying it
            t0 = from_frame(Rw, pw, t0)
            t1 = from_frame(Rw, pw, t1)
        for i in range(3):
            point_local[slot, i] = t0[i]
            point_local[slot + 1, i] = t1[i]
        if ok:
            seg_b[seg] = slot
            seg_active[seg] = wi[ACTIVE_AT0] != 0
            seg_scale[n_segments + w] = f[SCALE]
            arc_length[wi[CABLE]] += f[SCALE] * arc
        else:
            seg_b[seg] = wi[B_POINT]
            seg_active[seg] = wi[ACTIVE_AB] != 0
            seg_scale[n_segments + w] = 0.0
    return _pulleys(oM, pulley_int, pulley_float, point_local, arc_length)


@njit(cache=True, nogil=True, error_model="numpy")
def osim_route_pass(oM, q, paths, route, arc_length, L_extra, lever):
    """The routes that follow OpenSim's rules, after :func:`route_pass` at the same instant:
    :func:`mcdm_pin.model.route_osim.osim_routes` (its tables ``paths``: ``route_osim.OsimTables``).

    numba's ``error_model="numpy"``: a division carries no zero test (C's division, as in OpenSim),
    so the ellipsoid fan's sweeps (:func:`~mcdm_pin.model.wrapping_osim_ellipsoid._fan_newton`)
    compile to vector instructions; their quotients are chosen by tests of their own, so they
    answer as their Python runs do. A zero divisor elsewhere (a degenerate route) gives inf or NaN,
    which the terms report as not finite; the Python run raises ``ZeroDivisionError`` there, which
    :class:`~mcdm_pin.model.routes.RoutePaths` turns into a :class:`~mcdm_pin.exceptions.StateError`."""
    paths, route = OsimPaths(*paths), Route(*route)  # (plain tuples at the boundary: solvers._structs)
    osim_routes(oM, q, paths, route, arc_length, L_extra, lever)


@njit(cache=True, nogil=True)
def osim_levers(lever, seg_a, seg_b, seg_cable, seg_active, seg_scale, point_key, X, oM, Jt, sub_v, sub_phys,
                child_key, L, RT):
    """:func:`mcdm_pin.model.routes.add_levers` (its docstring) in one pass over the segments, in
    place on ``L`` (m, nv) and ``RT`` (Jn, 6, m); ``Jt`` (nv, 6) the world Jacobian's transpose."""
    for s in range(seg_a.shape[0]):
        if not (seg_scale[s] > 0 and seg_active[s]):
            continue
        a, b = seg_a[s], seg_b[s]
        if not (_moved(lever, a) or _moved(lever, b)):
            continue
        d0, d1, d2 = X[b, 0] - X[a, 0], X[b, 1] - X[a, 1], X[b, 2] - X[a, 2]
        c = seg_scale[s] / np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        u = (d0 * c, d1 * c, d2 * c)
        for e, sign in ((b, 1.0), (a, -1.0)):
            if _moved(lever, e):
                _lever_moment(lever, e, sign, u, point_key[e], seg_cable[s], oM, Jt, sub_v, sub_phys, child_key,
                              L, RT)


@register_jitable
def _moved(lever, p):
    return abs(lever[p, 0]) + abs(lever[p, 1]) + abs(lever[p, 2]) > 0


@register_jitable
def _lever_moment(lever, e, sign, u, k, cable, oM, Jt, sub_v, sub_phys, child_key, L, RT):
    """End ``e``'s moment ``m = sign (R_k lever_e) x u`` (world) into ``L[cable]`` and ``RT[:, 3:6, cable]``."""
    d = [0.0, 0.0, 0.0]
    for i in range(3):
        d[i] = oM[k, i, 0] * lever[e, 0] + oM[k, i, 1] * lever[e, 1] + oM[k, i, 2] * lever[e, 2]
    m = (sign * (d[1] * u[2] - d[2] * u[1]), sign * (d[2] * u[0] - d[0] * u[2]), sign * (d[0] * u[1] - d[1] * u[0]))
    for v in range(Jt.shape[0]):
        if sub_v[v, k] != 0:
            L[cable, v] += m[0] * Jt[v, 3] + m[1] * Jt[v, 4] + m[2] * Jt[v, 5]
    for j in range(sub_phys.shape[0]):
        if sub_phys[j, k] != 0:
            ck = child_key[j]
            for i in range(3):
                RT[j, 3 + i, cable] += oM[ck, 0, i] * m[0] + oM[ck, 1, i] * m[1] + oM[ck, 2, i] * m[2]


def warm_calls():
    """This module's kernel with example arguments of the types :class:`~mcdm_pin.model.routes.RoutePaths`
    passes (registered with :mod:`mcdm_pin.jit`)."""
    i64 = np.int64
    oM = np.tile(np.eye(4), (1, 1, 1))
    wi = np.zeros((1, N_INT), dtype=i64)
    wi[0, SLOT], wi[0, B_POINT] = 2, 1
    wf = np.zeros((1, N_FLOAT))
    wf[0, R_W:R_W + 9] = np.eye(3).ravel()
    wf[0, A_LOCAL], wf[0, B_LOCAL + 1], wf[0, RADIUS], wf[0, SCALE] = 1.0, 1.0, 0.1, 1.0
    from . import route_osim as ro

    route = np.array([[0, 0, 2, 0, 0, 0, 1, 2]], dtype=i64)  # one OpenSim route of two fixed points
    paths = OsimPaths(route, np.zeros(2, dtype=i64), np.zeros(2, dtype=i64), np.zeros(2, dtype=i64),
                      np.zeros((2, 3), dtype=i64), np.zeros((2, ro.N_PFLOAT)), np.zeros(1, dtype=i64),
                      np.zeros((0, 5)), np.zeros((0, ro.N_OINT), dtype=i64), np.zeros((0, ro.N_OFLOAT)), np.zeros(0),
                      np.zeros((2, 3)))
    points = Route(np.array([[0.0, 0, 0], [1, 0, 0]]), np.zeros(2, dtype=i64), np.array([0], dtype=i64),
                   np.array([1], dtype=i64), np.array([0], dtype=i64), np.array([False]), np.ones(1))
    osim_args = (oM, np.zeros(1), tuple(paths), tuple(points), np.zeros(1), np.zeros((1, 1)), np.zeros((2, 3)))
    qi = np.zeros((1, NQ_INT), dtype=i64)
    qi[0, Q_SCREW] = 1
    qf = np.zeros((1, NQ_FLOAT))
    qf[0, QB_LOCAL], qf[0, Q_AXIS + 2], qf[0, Q_DIR + 1] = 1.0, 1.0, 1.0
    qf[0, Q_RADIUS], qf[0, Q_SCALE], qf[0, Q_LEAD], qf[0, Q_REF] = 0.05, 1.0, 0.005, 1.0
    i1 = np.array([1], dtype=i64)
    lever_args = (np.zeros((2, 3)), np.array([0], dtype=i64), i1, np.array([0], dtype=i64), np.array([True]),
                  np.ones(1), np.zeros(2, dtype=i64), np.array([[0.0, 0, 0], [1, 0, 0]]), oM, np.zeros((1, 6)),
                  np.ones((1, 1)), np.ones((1, 1)), np.zeros(1, dtype=i64), np.zeros((1, 1)), np.zeros((1, 6, 1)))
    return [(route_pass, (oM, wi, wf, qi, qf, np.zeros((4, 3)), i1, np.array([False]),
                          np.zeros(2), np.zeros(1), np.zeros(1, dtype=np.bool_), 1)),
            (osim_route_pass, osim_args), (osim_levers, lever_args)]


def _register() -> None:
    from .. import jit

    jit.register("mcdm_pin.model.route_kernels", warm_calls)


_register()
