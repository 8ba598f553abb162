r"""Configuration-dependent routes: the path of every wrapped cable at one instant, as the arrays the
cable-terms kernel reads.

A wrap sits between route points :math:`A` and :math:`B` of one cable. When the straight segment
:math:`AB` would pass through the surface (MuJoCo's rule, :mod:`mcdm_pin.model.wrapping`), the cable runs
:math:`A \to T_0`, over the surface from :math:`T_0` to :math:`T_1`, then :math:`T_1 \to B`, with the
tangent points :math:`T_0, T_1` on the surface. Treating :math:`T_0, T_1` as points fixed on the
surface's body *at this instant* gives the exact ``L`` and wrenches: moving a tangent point along the
surface changes the length only to second order (the path is shortest), so the straight-segment
formulas of :mod:`mcdm_pin.model.geometry` apply to :math:`A T_0` and :math:`T_1 B` unchanged, and the
arc adds length but no wrench of its own (its pull on the surface is the two segments' pull at
:math:`T_0` and :math:`T_1`). So a muscle that presses on a bone loads that bone.

``L`` is continuous where a wrap engages (the tangent points meet the straight segment there) but not
smooth: its derivative jumps. Warm starts do not rely on smoothness: a warm active set is re-checked
and falls back to a cold solve when it fails.

Layout (fixed for a cable set, so the kernel's arrays keep their sizes): the set's route points, then
two tangent-point slots per wrap; the set's segments, then one slot per wrap (``T_1 -> B``). At each
instant a wrap that engages turns its segment :math:`AB` into :math:`A T_0` and fills its slot; one that
does not keeps :math:`AB` and leaves its slot at scale 0 (no length, no wrench).

A rotating pulley (:mod:`mcdm_pin.model.pulleys`) needs no extra slot: its route point, on the
pulley's body, holds its exit point at each instant, and its arc joins ``arc_length``.

At each instant one call of :func:`mcdm_pin.model.route_kernels.route_pass` (compiled, or the same
function as Python before ``mcdm-pin compile``: :mod:`mcdm_pin.jit`) does every wrap and rewrites
these arrays in place.
"""

from __future__ import annotations

import importlib

import numpy as np

from ..exceptions import StateError
from .kernel_structs import Route


class RoutePaths:
    """The per-instant path arrays of a cable set with wraps.

    Args:
        cables: the :class:`~mcdm_pin.model.cables.CableSet`.
        key_of_joint: (njoints,) the position of each Pinocchio joint among the placements the
            evaluator reads (-1: not read).

    Call with the world placements ``oM`` (K, 4, 4) of those joints; returns ``(route, arc_length)``:
    the routes at this instant (a :class:`~mcdm_pin.model.kernel_structs.Route`) and, (m,), the arc
    lengths (branch-scaled) to add to each cable's length. The arrays are owned by this object and
    rewritten at every call; ``engaged`` (W,) says which wraps engaged. Routes that follow OpenSim's
    rules (:mod:`mcdm_pin.model.route_osim`) need the configuration ``q`` too, and then ``L_extra``
    (m, nv) holds their moving points' own terms, to add to ``L``.
    """

    def __init__(self, cables, key_of_joint: np.ndarray):
        from .. import jit

        # imported here: the kernels import numba, which ``import mcdm_pin`` does not
        rk = importlib.import_module("mcdm_pin.model.route_kernels")
        self._pass = jit.kernels("model.route_kernels").route_pass  # compiled or not (mcdm_pin/jit.py)
        wraps = cables.wraps
        self.cables = cables
        n_p, n_s, n_w = len(cables.point_local), len(cables.seg_a), len(wraps)
        key = np.asarray(key_of_joint)
        self.n_points, self.n_segments = n_p, n_s
        base_key = key[cables.point_joint]
        wkey = np.array([key[w.joint] for w in wraps], dtype=np.int64)
        self.point_key = np.concatenate([base_key, np.repeat(wkey, 2)]).astype(np.int64)
        self.point_local = np.concatenate([cables.point_local, np.zeros((2 * n_w, 3))])
        slot_t0 = n_p + 2 * np.arange(n_w)
        self.seg_a = np.concatenate([cables.seg_a, slot_t0 + 1]).astype(np.int64)
        wrap_b = np.array([w.b for w in wraps], dtype=np.int64)
        self.seg_b = np.concatenate([cables.seg_b, wrap_b]).astype(np.int64)
        self.seg_cable = np.concatenate([cables.seg_cable, [w.cable for w in wraps]]).astype(np.int64)
        self.seg_active = np.concatenate([cables.seg_active, base_key[wrap_b] != wkey]).astype(np.bool_)
        self.seg_scale = np.concatenate([cables.seg_scale, np.zeros(n_w)])
        self.arc_length = np.zeros(cables.m)
        self.engaged = np.zeros(n_w, dtype=np.bool_)
        self._wrap_int, self._wrap_float = _tables(rk, cables, key, base_key, wkey, slot_t0)
        self._pulley_int, self._pulley_float = _pulley_tables(rk, cables, key)
        self._osim = self._osim_layout(cables, key) if cables.osim_cables else None
        self.route = Route(self.point_local, self.point_key, self.seg_a, self.seg_b, self.seg_cable, self.seg_active,
                           self.seg_scale)  # (the arrays the passes rewrite in place)

    def _osim_layout(self, cables, key):
        """Two tangent slots and one segment slot per OpenSim wrap after the MuJoCo wraps' slots, and
        the tables of :func:`mcdm_pin.model.route_osim.osim_routes` (OpenSim's path rules)."""
        from .. import jit
        from .route_osim import OsimTables

        okey = np.array([key[w.joint] for w in cables.osim_wraps], dtype=np.int64)
        n_o, slot0, seg0 = len(okey), len(self.point_local), len(self.seg_a)
        self.point_key = np.concatenate([self.point_key, np.repeat(okey, 2)]).astype(np.int64)
        self.point_local = np.concatenate([self.point_local, np.zeros((2 * n_o, 3))])
        self.seg_a = np.concatenate([self.seg_a, np.zeros(n_o, dtype=np.int64)])
        self.seg_b = np.concatenate([self.seg_b, np.ones(n_o, dtype=np.int64)])
        self.seg_cable = np.concatenate([self.seg_cable, [w.cable for w in cables.osim_wraps]]).astype(np.int64)
        self.seg_active = np.concatenate([self.seg_active, np.zeros(n_o, dtype=np.bool_)])
        self.seg_scale = np.concatenate([self.seg_scale, np.zeros(n_o)])
        self.L_extra = np.zeros((cables.m, cables.model_signature[1]))
        self.lever = np.zeros((len(self.point_local) + 2 * n_o, 3))
        self._osim_pass = jit.kernels("model.route_kernels").osim_route_pass
        return OsimTables(cables, okey, len(self.point_local), slot0, seg0)

    def __call__(self, oM: np.ndarray, q: np.ndarray | None = None):
        bad, reason = self._pass(oM, self._wrap_int, self._wrap_float, self._pulley_int, self._pulley_float,
                                 self.point_local, self.seg_b, self.seg_active, self.seg_scale, self.arc_length,
                                 self.engaged, self.n_segments)
        if bad >= 0:
            from .pulleys import REASONS

            rp = self.cables.rotating[bad]
            name = f" {rp.name!r}" if rp.name else ""
            raise StateError(f"cable {self.cables.names[rp.cable]!r}: rotating pulley{name}: {REASONS[int(reason)]} "
                             f"at this configuration")
        if self._osim is not None:  # OpenSim's routes read the configuration too
            try:
                self._osim_pass(oM, q, tuple(self._osim.arrays), tuple(self.route), self.arc_length, self.L_extra,
                                self.lever)  # (plain tuples at the kernel's boundary: solvers._structs)
            except ZeroDivisionError:  # (uncompiled; compiled, the pass divides as C does and the terms
                # report the inf or NaN as not finite)
                raise StateError("an OpenSim path divides by zero at this configuration (a degenerate wrap: "
                                 "its lengths and moment arms are undefined here)") from None
        return self.route, self.arc_length


def _tables(rk, cables, key, base_key, wkey, slot_t0):
    """The route pass's packed per-wrap tables ``(wrap_int, wrap_float)`` (columns: route_kernels)."""
    wraps = cables.wraps
    n_w = len(wraps)
    wi = np.zeros((n_w, rk.N_INT), dtype=np.int64)
    wf = np.zeros((n_w, rk.N_FLOAT))
    for w, wr in enumerate(wraps):
        wi[w, rk.W_KEY] = wkey[w]
        wi[w, rk.A_KEY], wi[w, rk.B_KEY] = base_key[wr.a], base_key[wr.b]
        wi[w, rk.S_KEY] = key[wr.side_joint] if wr.side_joint >= 0 else 0
        wi[w, rk.HAS_SIDE] = wr.side_joint >= 0
        wi[w, rk.CYLINDER] = {"cylinder": 1, "sphere": 0}[wr.kind]
        wi[w, rk.SLOT], wi[w, rk.SEG], wi[w, rk.CABLE] = slot_t0[w], wr.seg, wr.cable
        wi[w, rk.B_POINT] = cables.seg_b[wr.seg]  # B, the end of AB
        wi[w, rk.ACTIVE_AT0] = base_key[wr.a] != wkey[w]
        wi[w, rk.ACTIVE_AB] = bool(cables.seg_active[wr.seg])
        wf[w, rk.A_LOCAL:rk.A_LOCAL + 3] = cables.point_local[wr.a]
        wf[w, rk.B_LOCAL:rk.B_LOCAL + 3] = cables.point_local[wr.b]
        wf[w, rk.S_LOCAL:rk.S_LOCAL + 3] = np.asarray(wr.side_local, dtype=float).reshape(3)
        wf[w, rk.R_W:rk.R_W + 9] = np.asarray(wr.placement.rotation).reshape(9)
        wf[w, rk.P_W:rk.P_W + 3] = np.asarray(wr.placement.translation).reshape(3)
        wf[w, rk.RADIUS], wf[w, rk.SCALE] = wr.radius, wr.scale
    return wi, wf


def _pulley_tables(rk, cables, key):
    """The route pass's packed per-pulley tables ``(pulley_int, pulley_float)`` (columns: route_kernels)."""
    n_q = len(cables.rotating)
    qi = np.zeros((n_q, rk.NQ_INT), dtype=np.int64)
    qf = np.zeros((n_q, rk.NQ_FLOAT))
    for q, rp in enumerate(cables.rotating):
        qi[q, rk.Q_KEY], qi[q, rk.QB_KEY] = key[rp.joint], key[cables.point_joint[rp.b]]
        qi[q, rk.Q_SLOT], qi[q, rk.Q_CABLE], qi[q, rk.Q_SCREW] = rp.point, rp.cable, rp.screw is not None
        qf[q, rk.QB_LOCAL:rk.QB_LOCAL + 3] = cables.point_local[rp.b]
        qf[q, rk.Q_ENTRY:rk.Q_ENTRY + 3] = rp.entry
        qf[q, rk.Q_AXIS:rk.Q_AXIS + 3] = rp.axis
        qf[q, rk.Q_DIR:rk.Q_DIR + 3] = rp.screw_direction
        qf[q, rk.Q_RADIUS], qf[q, rk.Q_SCALE] = rp.radius, rp.scale
        if rp.screw is not None:
            qf[q, rk.Q_LEAD], qf[q, rk.Q_REF], qf[q, rk.Q_OUTLET] = rp.screw
    return qi, qf


def add_levers(routes, L, RT, J, X, oM, sub_v, sub_phys, child_key) -> None:
    r"""OpenSim's forces act where a wrap last put its tangent points while their directions (and the
    lengths) use the points' cached positions (:mod:`mcdm_pin.model.route_osim`). For each straight
    segment end :math:`e` (sign :math:`s_e`, +1 at the segment's end) with a lever :math:`d_e`
    (world) the end's Plücker vector gains :math:`[0;\ m_e]`, :math:`m_e = s_e\, d_e \times \hat u`
    (world, about the origin): ``L`` (m, nv) gains :math:`\omega_v \cdot m_e` in the columns ``v``
    that move the end's body (``sub_v`` (nv, K); :math:`\omega_v` the angular rows ``J[3:]`` of the
    world Jacobian), and ``RT`` (Jn, 6, m) the moment :math:`R_c^T m_e` for every physical joint whose
    subtree holds that body (``sub_phys`` (Jn, K); :math:`R_c` the child frame's rotation, key
    ``child_key``). ``X`` (P, 3): the points the kernel used. One pass over the segments:
    :func:`mcdm_pin.model.route_kernels.osim_levers` (compiled or not: mcdm_pin/jit.py)."""
    from .. import jit

    jit.kernels("model.route_kernels").osim_levers(
        routes.lever, routes.seg_a, routes.seg_b, routes.seg_cable, routes.seg_active, routes.seg_scale,
        routes.point_key, X, oM, np.ascontiguousarray(J.T), sub_v, sub_phys, child_key, L, RT)
