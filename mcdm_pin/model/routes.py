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
"""

from __future__ import annotations

import numpy as np

from .wrapping import wrap_cylinder, wrap_sphere

_WRAP_FUNCTIONS = {"sphere": wrap_sphere, "cylinder": wrap_cylinder}


class RoutePaths:
    """The per-instant path arrays of a cable set with wraps.

    Args:
        cables: the :class:`~mcdm_pin.model.cables.CableSet`.
        key_of_joint: (njoints,) the position of each Pinocchio joint among the placements the
            evaluator reads (-1: not read).

    Call with the world placements ``oM`` (K, 4, 4) of those joints; returns ``(point_local,
    point_key, seg_a, seg_b, seg_cable, seg_active, seg_scale, arc_length)``, the last (m,) the arc
    lengths (branch-scaled) to add to each cable's length. The arrays are owned by this object and
    rewritten at every call.
    """

    def __init__(self, cables, key_of_joint: np.ndarray):
        wraps = cables.wraps
        self.cables = cables
        n_p, n_s, n_w = len(cables.point_local), len(cables.seg_a), len(wraps)
        key = np.asarray(key_of_joint)
        self.n_points, self.n_segments = n_p, n_s
        base_key = key[cables.point_joint]
        wkey = np.array([key[w.joint] for w in wraps], dtype=np.int64)
        self.point_key = np.concatenate([base_key, np.repeat(wkey, 2)]).astype(np.int64)
        self._base_local = np.concatenate([cables.point_local, np.zeros((2 * n_w, 3))])
        self.point_local = self._base_local.copy()
        slot_t0 = n_p + 2 * np.arange(n_w)
        self._slot_t0, self._slot_t1 = slot_t0, slot_t0 + 1
        self._seg = np.array([w.seg for w in wraps], dtype=np.int64)
        self._wrap_b = np.array([w.b for w in wraps], dtype=np.int64)
        self.seg_a = np.concatenate([cables.seg_a, slot_t0 + 1]).astype(np.int64)
        self._base_b = np.concatenate([cables.seg_b, self._wrap_b]).astype(np.int64)
        self.seg_b = self._base_b.copy()
        self.seg_cable = np.concatenate([cables.seg_cable, [w.cable for w in wraps]]).astype(np.int64)
        self._base_active = np.concatenate([cables.seg_active, base_key[self._wrap_b] != wkey])
        self._active_a_t0 = base_key[np.array([w.a for w in wraps], dtype=np.int64)] != wkey
        self.seg_active = self._base_active.copy()
        self._base_scale = np.concatenate([cables.seg_scale, np.zeros(n_w)])
        self.seg_scale = self._base_scale.copy()
        self._scale = np.array([w.scale for w in wraps])
        self.arc_length = np.zeros(cables.m)
        self.engaged = np.zeros(n_w, dtype=bool)
        # what each wrap needs at every instant, stacked for one vectorised pass
        self._a_key, self._b_key = base_key[[w.a for w in wraps]], base_key[[w.b for w in wraps]]
        self._a_local = cables.point_local[[w.a for w in wraps]]
        self._b_local = cables.point_local[[w.b for w in wraps]]
        self._w_key = wkey
        self._w_R = np.array([w.placement.rotation for w in wraps]).reshape(n_w, 3, 3)
        self._w_p = np.array([w.placement.translation for w in wraps]).reshape(n_w, 3)
        self._has_side = np.array([w.side_joint >= 0 for w in wraps], dtype=bool)
        self._side_key = np.array([key[w.side_joint] if w.side_joint >= 0 else 0 for w in wraps], dtype=np.int64)
        self._side_local = np.array([w.side_local for w in wraps]).reshape(n_w, 3)
        self._fn = [_WRAP_FUNCTIONS[w.kind] for w in wraps]
        self._radius = [w.radius for w in wraps]

    def __call__(self, oM: np.ndarray):
        oR, op = oM[:, :3, :3], oM[:, :3, 3]
        # the wrap's end points and side point in the surface's frame
        Rg = oR[self._w_key] @ self._w_R  # (W, 3, 3) surface -> world
        pg = np.einsum("wij,wj->wi", oR[self._w_key], self._w_p) + op[self._w_key]
        pa = np.einsum("wij,wj->wi", oR[self._a_key], self._a_local) + op[self._a_key]
        pb = np.einsum("wij,wj->wi", oR[self._b_key], self._b_local) + op[self._b_key]
        ps = np.einsum("wij,wj->wi", oR[self._side_key], self._side_local) + op[self._side_key]
        ga = np.einsum("wji,wj->wi", Rg, pa - pg)
        gb = np.einsum("wji,wj->wi", Rg, pb - pg)
        gs = np.einsum("wji,wj->wi", Rg, ps - pg)
        self.point_local[:] = self._base_local
        self.seg_b[:] = self._base_b
        self.seg_active[:] = self._base_active
        self.seg_scale[:] = self._base_scale
        self.arc_length[:] = 0.0
        n_s = self.n_segments
        for w, fn in enumerate(self._fn):
            side = gs[w] if self._has_side[w] else None
            res = fn(ga[w], gb[w], self._radius[w], side)
            self.engaged[w] = res.engaged
            if not res.engaged:
                continue
            t0, t1 = self._slot_t0[w], self._slot_t1[w]
            # tangent points from the surface's frame to the frame of the joint carrying it
            self.point_local[t0] = self._w_R[w] @ res.t0 + self._w_p[w]
            self.point_local[t1] = self._w_R[w] @ res.t1 + self._w_p[w]
            s = self._seg[w]
            self.seg_b[s] = t0
            self.seg_active[s] = self._active_a_t0[w]
            self.seg_scale[n_s + w] = self._scale[w]
            self.arc_length[self.cables.wraps[w].cable] += self._scale[w] * res.arc
        return (self.point_local, self.point_key, self.seg_a, self.seg_b, self.seg_cable, self.seg_active,
                self.seg_scale, self.arc_length)
