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

from .exceptions import StateError


@dataclass
class CableGeometry:
    """Cable geometry at one configuration.

    Attributes:
        points: (P, 3) world position of every route point.
        seg_vec: (S, 3) segment vectors x_B - x_A.
        seg_len: (S,) segment lengths, m.
        lengths: (m,) cable lengths, m.
        W: (nj, 6, m) per Pinocchio joint (body) the summed signed Plücker vectors
            ``sum_e s_e w_e`` of the cable end points on that body, per cable.
    """

    points: np.ndarray
    seg_vec: np.ndarray
    seg_len: np.ndarray
    lengths: np.ndarray
    W: np.ndarray


def cable_geometry(robot, oR: np.ndarray, op: np.ndarray) -> CableGeometry:
    """Cable geometry from the joint placements (``oR``: (nj, 3, 3), ``op``: (nj, 3) world)."""
    pj = robot.point_joint
    X = np.einsum("pij,pj->pi", oR[pj], robot.point_local) + op[pj]
    d = X[robot.seg_b] - X[robot.seg_a]
    seg_len = np.linalg.norm(d, axis=1)
    lengths = np.bincount(robot.seg_cable, weights=seg_len, minlength=robot.m)
    act = robot.seg_active
    if np.any(seg_len[act] <= 1e-12):
        s = int(np.flatnonzero(act & (seg_len <= 1e-12))[0])
        raise StateError(f"cable {robot.cables[robot.seg_cable[s]].name!r}: a segment has zero length "
                         f"at this configuration, so its direction is undefined")
    a, b, c = robot.seg_a[act], robot.seg_b[act], robot.seg_cable[act]
    u = d[act] / seg_len[act, None]
    # end points: B with sign +1, A with sign -1
    ends = np.concatenate([b, a])
    sign = np.concatenate([np.ones(len(b)), -np.ones(len(a))])[:, None]
    uu = np.concatenate([u, u])
    w = sign * np.hstack([uu, np.cross(X[ends], uu)])  # (2S, 6)
    nj, m = robot.model.njoints, robot.m
    flat = np.zeros((nj * m, 6))
    np.add.at(flat, pj[ends] * m + np.concatenate([c, c]), w)
    W = flat.reshape(nj, m, 6).transpose(0, 2, 1)
    return CableGeometry(points=X, seg_vec=d, seg_len=seg_len, lengths=lengths, W=W)
