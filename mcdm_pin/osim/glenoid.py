r"""The glenohumeral stability cone of the thoracoscapular model as RMR poses it (Belli et al. 2023).

RMR reads three markers of the model (its last three: ``Glenoid_Center`` :math:`g` and
``Glenoid_Edge`` :math:`e` on the scapula, ``HumHead_Center`` :math:`h` at the humerus' origin, the
joint centre) and requires the glenohumeral reaction force *on the scapula* (``calcReactionOnParent``,
ground axes) to lie within ``maxAngle`` of :math:`g - h`, with ``maxAngle`` the angle at :math:`h`
between :math:`g` and :math:`e`:

.. math:: \rho^* = \angle(g - h,\ e - h).

Our interaction force is the parent's on the child (the scapula's on the humerus), the opposite
vector, so the same constraint is a cone of half-angle :math:`\rho^*` about :math:`h - g`, expressed
in the joint's socket (scapula-side) frame, where it is constant (all three points are fixed in the
scapula for a rotational joint). :func:`glenoid_cone` computes both from the model's markers, which
the loader keeps as frames ``/markerset/NAME``.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..exceptions import ModelError

MARKERS = ("Glenoid_Center", "HumHead_Center", "Glenoid_Edge")


def glenoid_cone(robot, q=None, joint: str = "GlenoHumeral", markers=MARKERS):
    """``(socket_axis, angle_deg)``: the unit cone axis :math:`h - g` in ``joint``'s socket frame and
    the half-angle :math:`\\rho^*` (degrees), at the configuration ``q`` (default: the source's)."""
    model = robot.model
    ids = []
    for name in markers:
        path = f"/markerset/{name}"
        if not model.existFrame(path):
            raise ModelError(f"glenoid cone: the model has no marker {name!r} (frame {path!r})")
        ids.append(model.getFrameId(path))
    q = robot.source.configuration({}) if q is None else np.asarray(q, dtype=float)
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    g, h, e = (data.oMf[i].translation.copy() for i in ids)
    j = robot.joint(joint)
    socket = data.oMi[int(j.parent_id)] * j.socket_placement
    axis = socket.rotation.T @ (h - g)
    cos = np.dot(g - h, e - h) / (np.linalg.norm(g - h) * np.linalg.norm(e - h))
    return axis / np.linalg.norm(axis), float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))
