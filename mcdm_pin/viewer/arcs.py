r"""The drawn path of wrapped routes: the straight pieces, and each engaged wrap's path on its surface
as a polyline whose length equals the wrapped length to a stated tolerance.

At every instant the route pass (:class:`~mcdm_pin.model.routes.RoutePaths`) gives the straight
segments (route points, and the tangent points :math:`T_0, T_1` of engaged wraps); between
:math:`T_0` and :math:`T_1` the cable lies on the surface (:mod:`mcdm_pin.model.wrapping`), in the
surface's own frame (centre at the origin, a cylinder's axis along local :math:`z`):

- **sphere**: the great-circle arc in the plane of the centre, :math:`A` and :math:`B` (the wrap's two
  route points), i.e. of the centre and both tangent points: with the plane's axes :math:`e_1, e_2`,
  :math:`P(\varphi) = r(\cos\varphi\, e_1 + \sin\varphi\, e_2)`;
- **cylinder**: MuJoCo's helix: the circular arc of the :math:`x, y` projection, with :math:`z` linear in
  the angle from :math:`T_0`'s to :math:`T_1`'s, so the path has length
  :math:`\sqrt{(r\theta)^2 + (z_1 - z_0)^2}`.

:math:`\varphi` runs from :math:`T_0`'s angle through :math:`\theta = ` (planar arc) / :math:`r`, the way
round that ends on :math:`T_1` (a side point can make it the longer way). The wrap's arc comes from
the same function the route pass calls (:func:`~mcdm_pin.model.wrapping.wrap_in_frame`).

**Sampling rule.** A wrap is drawn as :math:`K` pieces of equal angle :math:`\theta/K`, their vertices
on the surface; :math:`K` is fixed over the instants (the scene animates a fixed set of pieces). A
chord of angle :math:`\delta` on radius :math:`r` falls short of its arc by
:math:`r(\delta - 2\sin(\delta/2)) \le r\delta^3/24`, and a helix piece by no more than its circular
projection's chord, so the :math:`K` pieces fall short by at most :math:`r\theta^3/(24K^2)`. With
:math:`\theta_w` the wrap's largest angle over the instants, :math:`L_c` its cable's shortest route length
and :math:`n_c` the number of its cable's wraps,

.. math:: K_w = \Big\lceil \theta_w \sqrt{r\,\theta_w\, n_c / (24\, \mathrm{tol}\, L_c)} \Big\rceil

makes every drawn cable at most ``tol`` (relative) shorter than its route (:data:`ARC_TOL`: 1e-6).
A wrap kind without a surface path here is drawn as its chord (one piece).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from ..model.routes import RoutePaths
from ..model.wrapping import _plane_axes, wrap_in_frame

ARC_TOL = 1e-6
"""Relative tolerance of a drawn cable's length against its route's (sampling rule above)."""

SURFACES = ("sphere", "cylinder")


class SurfacePath(NamedTuple):
    """An engaged wrap's path at one instant: ``M`` (4, 4) the surface frame in the world; ``e1``,
    ``e2`` (3,) the plane of the circle in that frame; ``phi0`` T0's angle in it, ``turn`` the signed
    angle to T1, rad; ``z0``, ``rise`` the helix's height at T0 and its rise to T1 (cylinder; 0 for a
    sphere), m; ``t0``, ``t1`` (3,) the tangent points in the surface frame; ``length`` the path's, m."""

    M: np.ndarray
    e1: np.ndarray
    e2: np.ndarray
    radius: float
    phi0: float
    turn: float
    z0: float
    rise: float
    t0: np.ndarray
    t1: np.ndarray
    length: float


def route_polylines(robot, conf, tol: float | None = None):
    """The drawn segments of a robot with wrapped routes at configurations ``conf`` (N, nq); ``tol``:
    the relative tolerance of the sampling rule (default :data:`ARC_TOL`).

    Returns ``(segments, seg_cable, seg_scale)``: (N, S, 2, 3) the ends of every drawn segment (world,
    m; a segment not on the path at an instant has both ends at one point), (S,) its cable, and (N, S)
    its branch scale (``1/divisor``; 0 where it is not on the path), so that each cable's
    ``sum(seg_scale * |b - a|)`` is its route's length to ``tol`` relative (module docstring)."""
    tol = ARC_TOL if tol is None else float(tol)
    model, data = robot.model, robot.model.createData()
    cables = robot.cables
    wraps = cables.wraps
    paths = RoutePaths(cables, np.arange(model.njoints))
    n_s, N, W = len(paths.seg_a), len(conf), len(wraps)
    straight, scale = np.empty((N, n_s, 2, 3)), np.zeros((N, n_s))
    chords = np.empty((N, W, 2, 3))  # T0, T1 (world); both B when not engaged
    arcs: list[list[SurfacePath | None]] = [[None] * W for _ in range(N)]
    length = np.zeros((N, cables.m))
    engaged = np.zeros((N, W), dtype=bool)
    for k, q in enumerate(conf):
        pin.forwardKinematics(model, data, robot.check_configuration(q))
        oM = np.array([data.oMi[j].homogeneous for j in range(model.njoints)])
        paths(oM)
        key = paths.point_key
        X = np.einsum("pij,pj->pi", oM[key, :3, :3], paths.point_local) + oM[key, :3, 3]
        on = paths.seg_scale > 0
        a = X[paths.seg_a]
        straight[k, :, 0], straight[k, :, 1] = a, np.where(on[:, None], X[paths.seg_b], a)
        scale[k] = np.where(on, paths.seg_scale, 0.0)
        np.add.at(length[k], paths.seg_cable, scale[k] * np.linalg.norm(straight[k, :, 1] - a, axis=1))
        for w, wr in enumerate(wraps):
            slot = paths.n_points + 2 * w
            engaged[k, w] = paths.engaged[w]
            chords[k, w] = X[slot:slot + 2] if engaged[k, w] else X[wr.b]
            if not engaged[k, w]:
                continue
            arc = _surface_path(wr, oM, X[wr.a], X[wr.b]) if wr.kind in SURFACES else None
            arcs[k][w] = arc
            chord = float(np.linalg.norm(chords[k, w, 1] - chords[k, w, 0]))
            length[k, wr.cable] += wr.scale * (chord if arc is None else arc.length)
    pieces = _pieces(wraps, arcs, length.min(axis=0, initial=np.inf), tol)
    segments = np.concatenate([straight, np.empty((N, int(pieces.sum()), 2, 3))], axis=1)
    seg_scale = np.concatenate([scale, np.zeros((N, int(pieces.sum())))], axis=1)
    start = n_s
    for w, wr in enumerate(wraps):
        K = int(pieces[w])
        for k in range(N):
            if arcs[k][w] is not None:
                P = _sample(arcs[k][w], K)
            else:  # a chord (not engaged: both ends at B)
                P = chords[k, w, 0] + np.linspace(0.0, 1.0, K + 1)[:, None] * (chords[k, w, 1] - chords[k, w, 0])
            segments[k, start:start + K, 0], segments[k, start:start + K, 1] = P[:-1], P[1:]
            seg_scale[k, start:start + K] = wr.scale if engaged[k, w] else 0.0
        start += K
    seg_cable = np.concatenate([paths.seg_cable, np.repeat([w.cable for w in wraps], pieces)]).astype(int)
    return segments, seg_cable, seg_scale


def _surface_path(wr, oM, xa, xb) -> SurfacePath | None:
    """The path on the surface of a sphere or cylinder wrap from route point ``xa`` to ``xb`` (world),
    as the route pass finds it (module docstring); ``None`` when it does not engage."""
    M = oM[wr.joint] @ wr.placement.homogeneous
    R, p = M[:3, :3], M[:3, 3]
    has_side = wr.side_joint >= 0
    side = oM[wr.side_joint, :3, :3] @ wr.side_local + oM[wr.side_joint, :3, 3] if has_side else np.zeros(3)
    cylinder = wr.kind == "cylinder"
    ok, arc, t0, t1 = wrap_in_frame(cylinder, _tup(R), _tup(p), _tup(xa), _tup(xb), float(wr.radius),
                                    has_side, _tup(side))
    if not ok:
        return None
    t0, t1, r = np.array(t0), np.array(t1), float(wr.radius)
    if cylinder:
        e1, e2, z0, rise = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]), t0[2], t1[2] - t0[2]
        planar = math.sqrt(max(arc * arc - rise * rise, 0.0))
    else:
        e1, e2 = (np.array(e) for e in _plane_axes(_tup(R.T @ (xa - p)), _tup(R.T @ (xb - p))))
        z0 = rise = 0.0
        planar = arc
    angle = planar / r
    phi0, phi1 = math.atan2(t0 @ e2, t0 @ e1), math.atan2(t1 @ e2, t1 @ e1)
    # the way round that ends on T1: turning by +angle or by -angle from T0's angle
    miss = [abs(math.remainder(phi0 + s * angle - phi1, 2.0 * math.pi)) for s in (1.0, -1.0)]
    turn = angle if miss[0] <= miss[1] else -angle
    return SurfacePath(M, e1, e2, r, phi0, turn, z0, rise, t0, t1, float(arc))


def _tup(x):
    """A nested tuple of floats (what the route maths take: :mod:`mcdm_pin.model.wrapping`)."""
    x = np.asarray(x, dtype=float)
    return tuple(_tup(row) for row in x) if x.ndim > 1 else tuple(float(v) for v in x)


def _sample(path: SurfacePath, K: int) -> np.ndarray:
    """(K + 1, 3) world vertices of a wrap's path on its surface, from T0 to T1 (exactly), at equal
    angles."""
    s = np.linspace(0.0, 1.0, K + 1)
    phi = path.phi0 + path.turn * s
    local = path.radius * (np.cos(phi)[:, None] * path.e1 + np.sin(phi)[:, None] * path.e2)
    local[:, 2] += path.z0 + path.rise * s  # the helix's height (0 on a sphere)
    local[0], local[-1] = path.t0, path.t1
    return local @ path.M[:3, :3].T + path.M[:3, 3]


def _pieces(wraps, arcs, cable_length, tol: float) -> np.ndarray:
    """(W,) pieces per wrap by the sampling rule (module docstring); 1 for a wrap that never engages or
    is drawn as a chord."""
    per_cable = np.bincount([w.cable for w in wraps], minlength=len(cable_length))
    out = np.ones(len(wraps), dtype=int)
    for w, wr in enumerate(wraps):
        th = max((abs(a[w].turn) for a in arcs if a[w] is not None), default=0.0)
        if th > 0:
            need = wr.radius * th * per_cable[wr.cable] / (24.0 * tol * cable_length[wr.cable])
            out[w] = max(1, math.ceil(th * math.sqrt(need)))
    return out
