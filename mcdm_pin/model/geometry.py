r"""Cable geometry in one vectorised pass over all segments.

For a segment from point :math:`A` (on body :math:`a`) to point :math:`B` (on body :math:`b`) with unit
vector :math:`\hat u = (x_B - x_A)/|x_B - x_A|` (world frame), the cable pulls :math:`B` with
:math:`-f\hat u` and :math:`A` with :math:`+f\hat u`. Every end point :math:`e` contributes the Plücker
vector :math:`w_e = [\hat u;\; x_e \times \hat u]` with sign :math:`s_B = +1`, :math:`s_A = -1`, so that

.. math::

    \frac{\partial \ell}{\partial q} = \sum_e s_e\, w_e^T J_{b(e)}, \qquad
    \text{wrench of the cable on body } b \text{ (world, about the origin)} = -f \sum_{e \in b} s_e w_e,

with :math:`J_b` the world Jacobian (spatial velocity at the world origin) of body :math:`b`. Segments
with both ends on one body add length but no wrench (their two terms cancel; they are skipped).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..exceptions import StateError


@dataclass
class CableGeometry:
    """Cable geometry at one configuration.

    Attributes:
        points: (P, 3) world position of every route point.
        seg_vec: (S, 3) segment vectors x_B - x_A.
        seg_len: (S,) segment lengths, m.
        lengths: (m,) cable lengths, m.
        W: (B, 6, m) per body the summed signed Plücker vectors ``sum_e s_e w_e`` of the cable
            end points on that body, per cable.
    """

    points: np.ndarray
    seg_vec: np.ndarray
    seg_len: np.ndarray
    lengths: np.ndarray
    W: np.ndarray
    w: np.ndarray | None = None


def _cross(a, b):
    """Row-wise cross product of (n, 3) arrays (faster than np.cross for small n)."""
    out = np.empty_like(a)
    out[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    out[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    out[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return out


class CableMaps:
    """Precomputed index maps of a cable set's routes for :func:`cable_geometry`.

    Args:
        cables: the :class:`~mcdm_pin.model.cables.CableSet`.
        point_body: (P,) body index of each route point (into the placements given later).
        n_bodies: number of bodies (placements).
    """

    def __init__(self, cables, point_body, n_bodies: int):
        from scipy import sparse

        self.point_body = np.asarray(point_body, dtype=int)
        act = cables.seg_active
        a, b, c = cables.seg_a[act], cables.seg_b[act], cables.seg_cable[act]
        self.act_a, self.act_b = a, b
        self.ends = np.concatenate([b, a])  # end points: B (sign +1) then A (sign -1)
        self.end_body = self.point_body[self.ends]
        self.end_cable = np.concatenate([c, c])
        self.n_bodies, self.m = n_bodies, cables.m
        self.act = act
        self.all_active = bool(np.all(act))
        self.point_index = np.arange(len(self.point_body))
        # each segment counts its share (1/divisor past a pulley) of its cable's length and tension
        scale = getattr(cables, "seg_scale", np.ones(len(cables.seg_a)))
        self.seg_to_cable = np.zeros((cables.m, len(cables.seg_a)))
        self.seg_to_cable[cables.seg_cable, np.arange(len(cables.seg_a))] = scale
        self.act_scale = scale[act]
        self.all_active = self.all_active and bool(np.all(self.act_scale == 1.0))
        n_end = len(self.ends)
        # scatter: (body, cable) <- end point
        self.scatter = sparse.csr_matrix(
            (np.ones(n_end), (self.end_body * cables.m + self.end_cable, np.arange(n_end))),
            shape=(n_bodies * cables.m, n_end))


def cable_geometry(cables, oR: np.ndarray, op: np.ndarray, maps: CableMaps | None = None) -> CableGeometry:
    """Cable geometry from body placements.

    Args:
        oR, op: (B, 3, 3) rotations and (B, 3) positions (world) of the bodies.
        maps: index maps (default: bodies are Pinocchio joints, ``oR``/``op`` indexed by joint id).

    ``W`` is (B, 6, m), indexed like ``oR``; ``w`` holds the signed Pluecker vector of every end
    point of an active segment, in the order of ``maps.ends``.
    """
    if maps is None:
        maps = CableMaps(cables, cables.point_joint, len(oR))
    pj = maps.point_body
    # every point in every body's frame in one product, then each point's own body picked out
    nb = len(oR)
    Y = cables.point_local @ oR.transpose(0, 2, 1).transpose(1, 0, 2).reshape(3, 3 * nb)
    X = Y.reshape(-1, nb, 3)[maps.point_index, pj] + op[pj]
    d = X[cables.seg_b] - X[cables.seg_a]
    seg_len = np.sqrt((d * d).sum(axis=1))
    lengths = maps.seg_to_cable @ seg_len
    if maps.all_active:
        la, da = seg_len, d
    else:
        la, da = seg_len[maps.act], d[maps.act]
    if la.size and la.min() <= 1e-12:
        s = int(np.flatnonzero(maps.act)[np.argmin(la)])
        raise StateError(f"cable {cables.cables[cables.seg_cable[s]].name!r}: a segment has zero length "
                         f"at this configuration, so its direction is undefined")
    u = da / la[:, None] if maps.all_active else da * (maps.act_scale / la)[:, None]
    n_act = len(u)
    w = np.empty((2 * n_act, 6))
    w[:n_act, :3] = u  # end points B: sign +1
    w[n_act:, :3] = -u  # end points A: sign -1
    w[:, 3:] = _cross(X[maps.ends], w[:, :3])
    W = (maps.scatter @ w).reshape(maps.n_bodies, maps.m, 6).transpose(0, 2, 1)
    return CableGeometry(points=X, seg_vec=d, seg_len=seg_len, lengths=lengths, W=W, w=w)
