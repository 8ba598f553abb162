r"""A task space: coordinates ``y`` of a point and an orientation of one frame of a Pinocchio model.

**Coordinates.** A :class:`TaskSpace` names a frame of the model, a point fixed in it (``point``,
metres, in the frame's axes) and the task coordinates it keeps, in order, from
``x y z a b g`` (CASPR's ``active_axes``):

* ``x``, ``y``, ``z``: the point's position :math:`p = {}^0T_f\,r` in the world (model) frame, metres;
* ``a``, ``b``, ``g``: Euler angles :math:`(\alpha, \beta, \gamma)` of the frame's rotation
  :math:`R = {}^0R_f`, radians, in one of two conventions:

  - ``zyx`` (CASPR's ``pose_euler_xyz``, fixed axes X, Y, Z): :math:`R = R_z(\gamma) R_y(\beta)
    R_x(\alpha)`, :math:`\alpha = \mathrm{atan2}(R_{32}, R_{33})`, :math:`\beta =
    \mathrm{atan2}(-R_{31}, \sqrt{R_{11}^2 + R_{21}^2})`, :math:`\gamma = \mathrm{atan2}(R_{21}, R_{11})`;
  - ``xyz`` (CASPR's ``orientation_euler_xyz``, moving axes x, y', z''): :math:`R = R_x(\alpha)
    R_y(\beta) R_z(\gamma)`, :math:`\beta = \arcsin R_{13}`, :math:`\gamma = -\mathrm{atan2}(R_{12},
    R_{11})`, :math:`\alpha = -\mathrm{atan2}(R_{23}, R_{33})`.

**Rates.** With :math:`\omega` the frame's angular velocity in world axes and :math:`E(\phi)` the
map from angle rates to it (:math:`\omega = E\dot\phi`; columns :math:`R_z R_y e_x, R_z e_y, e_z` for
``zyx`` and :math:`e_x, R_x e_y, R_x R_y e_z` for ``xyz``), the task Jacobian is

.. math:: J_y = S \begin{bmatrix} J_p \\ E^{-1} J_\omega \end{bmatrix}, \qquad \dot y = J_y \dot q,
          \qquad \ddot y = J_y \ddot q + \dot J_y \dot q

with :math:`J_p, J_\omega` Pinocchio's ``LOCAL_WORLD_ALIGNED`` Jacobian of the point (tangent space:
``nv`` columns) and :math:`S` the selection of the kept coordinates. The bias :math:`\dot J_y \dot q`
is :math:`\ddot y` at :math:`\ddot q = 0`: the point's classical acceleration for positions, and
:math:`E^{-1}(\dot\omega - \dot E\dot\phi)` for angles, with :math:`\dot\omega` at :math:`\ddot q = 0`.
:math:`E` is singular at :math:`\cos\beta = 0` (gimbal lock): angle rows are refused there.

Angle errors are wrapped into :math:`(-\pi, \pi]` (the same rotation differs by :math:`2\pi` only).

**All three angles.** When ``a``, ``b`` and ``g`` are all kept, the target orientation
:math:`R^* = R(\phi^*)` is a rotation and the inverse kinematics drives :math:`\log(R^{*T}R)` to zero
instead of the angle differences, and the rates are solved for the angular velocity
:math:`\omega^* = E(\phi^*)\dot\phi^*` and acceleration :math:`E\ddot\phi^* + \dot E\dot\phi^*` (the
same motion): no division by :math:`\cos\beta`, so a trajectory through gimbal lock is followed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..exceptions import TrajectoryError

LETTERS = "xyzabg"
CONVENTIONS = ("zyx", "xyz")
TASK_FRAME = "mcdm_task_point"  # the frame added (to a copy of the model) at the task point
GIMBAL_COS = 1e-6  # |cos beta| below which the Euler angle rates are undefined


@dataclass(frozen=True)
class TaskSpace:
    """A frame, a point in it, the task coordinates (letters of ``xyzabg``, in order) and the Euler
    convention of the angles (module docstring). Pure data: bind it with :class:`TaskKinematics`."""

    frame: str
    point: tuple[float, float, float] = (0.0, 0.0, 0.0)
    coordinates: str = "xyz"
    euler: str = "zyx"

    def __post_init__(self):
        c = self.coordinates
        if not c or any(ch not in LETTERS for ch in c) or len(set(c)) != len(c):
            raise TrajectoryError(f"task space of frame {self.frame!r}: coordinates {c!r}; expected distinct "
                                  f"letters of 'xyzabg' (x y z: position, a b g: Euler angles)")
        if self.euler not in CONVENTIONS:
            raise TrajectoryError(f"task space of frame {self.frame!r}: euler {self.euler!r}; expected one of "
                                  f"{', '.join(CONVENTIONS)}")
        p = np.asarray(self.point, dtype=float)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise TrajectoryError(f"task space of frame {self.frame!r}: point {self.point!r}; expected 3 finite "
                                  f"numbers (metres, in the frame)")

    @property
    def dim(self) -> int:
        return len(self.coordinates)

    @property
    def angle_mask(self) -> np.ndarray:
        """(dim,) True where the coordinate is an angle (wrapped in errors)."""
        return np.array([ch in "abg" for ch in self.coordinates])

    @property
    def rows(self) -> list[int]:
        """Index of each coordinate in ``(x, y, z, a, b, g)``."""
        return [LETTERS.index(ch) for ch in self.coordinates]


# ------------------------------------------------------------------------------------- Euler angles
def euler_angles(convention: str, R: np.ndarray) -> np.ndarray:
    """``(a, b, g)`` of the rotation ``R`` (module docstring)."""
    if convention == "zyx":
        return np.array([np.arctan2(R[2, 1], R[2, 2]), np.arctan2(-R[2, 0], np.hypot(R[0, 0], R[1, 0])),
                         np.arctan2(R[1, 0], R[0, 0])])
    return np.array([-np.arctan2(R[1, 2], R[2, 2]), np.arcsin(np.clip(R[0, 2], -1.0, 1.0)),
                     -np.arctan2(R[0, 1], R[0, 0])])


def _rot(axis: int, angle: float) -> np.ndarray:
    return pin.exp3(angle * np.eye(3)[axis])


def euler_rotation(convention: str, angles) -> np.ndarray:
    a, b, g = angles
    if convention == "zyx":
        return _rot(2, g) @ _rot(1, b) @ _rot(0, a)
    return _rot(0, a) @ _rot(1, b) @ _rot(2, g)


def euler_rate_map(convention: str, angles, rates=None):
    """``E`` (3, 3) with :math:`\\omega = E\\dot\\phi` (world axes), and with ``rates`` also
    :math:`\\dot E \\dot\\phi` (3,)."""
    a, b, g = angles
    ex, ey, ez = np.eye(3)
    if convention == "zyx":
        Rz, Rzy = _rot(2, g), _rot(2, g) @ _rot(1, b)
        E = np.column_stack([Rzy @ ex, Rz @ ey, ez])
        if rates is None:
            return E
        ad, bd, gd = rates
        w_zy = gd * ez + bd * E[:, 1]  # angular velocity of Rz Ry
        return E, ad * np.cross(w_zy, E[:, 0]) + bd * np.cross(gd * ez, E[:, 1])
    Rx, Rxy = _rot(0, a), _rot(0, a) @ _rot(1, b)
    E = np.column_stack([ex, Rx @ ey, Rxy @ ez])
    if rates is None:
        return E
    ad, bd, gd = rates
    w_xy = ad * ex + bd * E[:, 1]  # angular velocity of Rx Ry
    return E, bd * np.cross(ad * ex, E[:, 1]) + gd * np.cross(w_xy, E[:, 2])


def wrap(angle):
    """Angles wrapped into (-pi, pi]."""
    return np.pi - np.mod(np.pi - np.asarray(angle, dtype=float), 2 * np.pi)


# ------------------------------------------------------------------------------------- kinematics
class TaskKinematics:
    """A :class:`TaskSpace` bound to a Pinocchio model: ``y(q)``, ``J_y(q)``, the bias
    :math:`\\dot J_y \\dot q` and wrapped errors. Works on a copy of the model with one frame added at
    the point (:data:`TASK_FRAME`); the caller's model is not changed."""

    def __init__(self, model: pin.Model, space: TaskSpace):
        if not model.existFrame(space.frame):
            names = sorted({f.name for f in model.frames if f.type == pin.FrameType.BODY})
            raise TrajectoryError(f"task space: no frame {space.frame!r} in the model; expected one of "
                                  f"{', '.join(names[:30])}{', ...' if len(names) > 30 else ''}")
        self.space = space
        self.model = pin.Model(model)
        parent = self.model.getFrameId(space.frame)
        f = self.model.frames[parent]
        placement = f.placement * pin.SE3(np.eye(3), np.asarray(space.point, dtype=float))
        self.frame_id = self.model.addFrame(pin.Frame(TASK_FRAME, f.parentJoint, parent, placement,
                                                      pin.FrameType.OP_FRAME))
        self.data = self.model.createData()
        self._rows = space.rows
        self._angles = space.angle_mask
        self._pos = [i for i, ch in enumerate(space.coordinates) if ch in "xyz"]  # their places in y
        self._pos_rows = [LETTERS.index(space.coordinates[i]) for i in self._pos]  # their axes
        self.full_rotation = set("abg") <= set(space.coordinates)

    # ----------------------------------------------------------------------------- the IK residual
    def _split(self, y):
        """(positions (k,), Euler angles (3,) with NaN where not kept) of a task vector."""
        y = np.asarray(y, dtype=float)
        phi = np.full(3, np.nan)
        for i, ch in enumerate(self.space.coordinates):
            if ch in "abg":
                phi["abg".index(ch)] = y[i]
        return y[self._pos], phi

    def residual(self, data, y_target) -> np.ndarray:
        r"""The IK error at ``data`` (frame placements up to date): ``y - y*`` (angles wrapped); with all
        three angles kept, the angle rows are replaced by :math:`\log(R^{*T}R)` (frame axes, rad), which
        has no gimbal lock."""
        if not self.full_rotation:
            return self.error(self.value_from(data), y_target)
        M = data.oMf[self.frame_id]
        p, phi = self._split(y_target)
        Rt = euler_rotation(self.space.euler, phi)
        return np.concatenate([M.translation[self._pos_rows] - p, pin.log3(Rt.T @ M.rotation)])

    def residual_jacobian(self, data, y_target) -> np.ndarray:
        """Jacobian of :meth:`residual` (joint Jacobians and frame placements up to date)."""
        if not self.full_rotation:
            return self.jacobian_from(data)
        J = pin.getFrameJacobian(self.model, data, self.frame_id, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        R = data.oMf[self.frame_id].rotation
        Rt = euler_rotation(self.space.euler, self._split(y_target)[1])
        return np.vstack([J[self._pos_rows], pin.Jlog3(Rt.T @ R) @ R.T @ J[3:]])

    # ------------------------------------------------------------------------------- the rates
    def rate_targets(self, y, yd, ydd):
        r"""``(r1, r2)`` with :math:`J_r\dot q = r_1`, :math:`J_r\ddot q + b_r = r_2` (:meth:`rate_jacobian`,
        :meth:`rate_bias`): ``yd``, ``ydd``; with all three angles kept, the angle rows become the world
        angular velocity :math:`\omega = E\dot\phi` and acceleration :math:`E\ddot\phi + \dot E\dot\phi`
        at the target angles (defined at gimbal lock too)."""
        if not self.full_rotation:
            return np.asarray(yd, dtype=float), np.asarray(ydd, dtype=float)
        (p, phi), (pd, phid), (pdd, phidd) = self._split(y), self._split(yd), self._split(ydd)
        E, Ed_phid = euler_rate_map(self.space.euler, phi, phid)
        return np.concatenate([pd, E @ phid]), np.concatenate([pdd, E @ phidd + Ed_phid])

    def rate_jacobian(self, q) -> np.ndarray:
        if not self.full_rotation:
            return self.jacobian(q)
        pin.computeJointJacobians(self.model, self.data, np.asarray(q, dtype=float))
        pin.updateFramePlacements(self.model, self.data)
        J = pin.getFrameJacobian(self.model, self.data, self.frame_id, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        return np.vstack([J[self._pos_rows], J[3:]])

    def rate_bias(self, q, v) -> np.ndarray:
        if not self.full_rotation:
            return self.bias(q, v)
        q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
        pin.forwardKinematics(self.model, self.data, q, v, np.zeros(self.model.nv))
        pin.updateFramePlacements(self.model, self.data)
        acc = pin.getFrameClassicalAcceleration(self.model, self.data, self.frame_id,
                                                pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        return np.concatenate([acc.linear[self._pos_rows], acc.angular])

    # -------------------------------------------------------------- from data already computed
    # -------------------------------------------------------------- from data already computed
    def value_from(self, data) -> np.ndarray:
        """``y`` from ``data`` whose frame placements are up to date."""
        M = data.oMf[self.frame_id]
        full = np.concatenate([M.translation, euler_angles(self.space.euler, M.rotation)])
        return full[self._rows]

    def jacobian_from(self, data) -> np.ndarray:
        """``J_y`` (dim, nv) from ``data`` with joint Jacobians and frame placements up to date."""
        J = pin.getFrameJacobian(self.model, data, self.frame_id, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        out = J.copy()
        if self._angles.any():
            phi = euler_angles(self.space.euler, data.oMf[self.frame_id].rotation)
            out[3:] = np.linalg.solve(self._rate_map(phi), J[3:])
        return out[self._rows]

    def _rate_map(self, phi, rates=None):
        if abs(np.cos(phi[1])) < GIMBAL_COS:
            raise TrajectoryError(f"the Euler angles ({self.space.euler}) of frame {self.space.frame!r} are at "
                                  f"gimbal lock (b = {phi[1]:.9g} rad, |cos b| < {GIMBAL_COS:g}): their rates are "
                                  f"undefined there")
        return euler_rate_map(self.space.euler, phi, rates)

    # -------------------------------------------------------------------------- from q (and v)
    def value(self, q) -> np.ndarray:
        pin.framesForwardKinematics(self.model, self.data, np.asarray(q, dtype=float))
        return self.value_from(self.data)

    def jacobian(self, q) -> np.ndarray:
        pin.computeJointJacobians(self.model, self.data, np.asarray(q, dtype=float))
        pin.updateFramePlacements(self.model, self.data)
        return self.jacobian_from(self.data)

    def bias(self, q, v) -> np.ndarray:
        """:math:`\\dot J_y \\dot q`: ``ddot y`` at ``ddot q = 0`` (module docstring)."""
        q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
        pin.forwardKinematics(self.model, self.data, q, v, np.zeros(self.model.nv))
        pin.updateFramePlacements(self.model, self.data)
        lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        acc = pin.getFrameClassicalAcceleration(self.model, self.data, self.frame_id, lwa)
        full = np.concatenate([acc.linear, np.zeros(3)])
        if self._angles.any():
            phi = euler_angles(self.space.euler, self.data.oMf[self.frame_id].rotation)
            w = pin.getFrameVelocity(self.model, self.data, self.frame_id, lwa).angular
            E = self._rate_map(phi)
            phid = np.linalg.solve(E, w)
            _, Ed_phid = self._rate_map(phi, phid)
            full[3:] = np.linalg.solve(E, acc.angular - Ed_phid)
        return full[self._rows]

    def error(self, y, y_target) -> np.ndarray:
        """``y - y_target`` with angle differences wrapped into (-pi, pi]."""
        e = np.asarray(y, dtype=float) - np.asarray(y_target, dtype=float)
        e[self._angles] = wrap(e[self._angles])
        return e
