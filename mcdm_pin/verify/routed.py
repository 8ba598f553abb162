r"""The replay's own ``L`` for wrapped routes: numpy on the path of :class:`~mcdm_pin.model.routes.RoutePaths`,
independent of the cable-terms kernel that computed the forces.

At one configuration the route pass gives every straight segment :math:`a \to b` of the path (route
points, and the tangent points of engaged wraps treated as points fixed on the wrap's body at this
instant), its branch scale :math:`s` (``1/divisor``; 0 for a wrap slot that does not engage) and
whether its ends lie on different bodies. With :math:`u = (X_b - X_a)/|X_b - X_a|` (world) and the
translational Jacobian of a point :math:`X` fixed on joint :math:`k`'s body,
:math:`J_X = J^{lin}_k - [X]_\times J^{ang}_k` (Pinocchio's ``WORLD`` joint Jacobian: the motion at the
world origin),

.. math:: L_{c,:} = \sum_{\text{segments of } c} s\, u^T (J_{X_b} - J_{X_a}) \qquad (m \times n_v),

the derivative of the cable lengths with respect to the velocity (arcs add length but nothing here:
:mod:`mcdm_pin.model.routes`).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..exceptions import StateError
from ..model.routes import RoutePaths


class RoutedL:
    """``L(q)`` (m, nv) of a robot whose cables wrap (module docstring); reuses its Pinocchio data."""

    def __init__(self, robot):
        self.robot = robot
        self.model = robot.model
        self.data = robot.model.createData()
        self.paths = RoutePaths(robot.cables, np.arange(robot.model.njoints))

    def __call__(self, q) -> np.ndarray:
        model, data, P = self.model, self.data, self.paths
        pin.computeJointJacobians(model, data, q)
        nj, nv = model.njoints, model.nv
        oM = np.array([data.oMi[j].homogeneous for j in range(nj)])
        J = np.array([pin.getJointJacobian(model, data, j, pin.ReferenceFrame.WORLD).reshape(6, nv)
                      for j in range(nj)])
        P(oM)
        key = P.point_key
        X = np.einsum("pij,pj->pi", oM[key, :3, :3], P.point_local) + oM[key, :3, 3]
        use = P.seg_active & (P.seg_scale > 0)
        a, b = P.seg_a[use], P.seg_b[use]
        d = X[b] - X[a]
        length = np.linalg.norm(d, axis=1)
        if length.size and length.min() <= 1e-12:
            s = int(np.flatnonzero(use)[np.argmin(length)])
            raise StateError(f"cable {self.robot.cables.names[P.seg_cable[s]]!r}: a segment has zero length "
                             f"at this configuration, so its direction is undefined")
        u = d * (P.seg_scale[use] / length)[:, None]

        def jac(points, keys):  # (S, 3, nv) translational Jacobians of points fixed on bodies
            lin, ang = J[keys, :3], J[keys, 3:]
            return lin - np.cross(points[:, :, None], ang, axis=1)

        rows = np.einsum("si,sin->sn", u, jac(X[b], key[b]) - jac(X[a], key[a]))
        L = np.zeros((self.robot.m, nv))
        np.add.at(L, P.seg_cable[use], rows)
        return L
