r"""Computed-torque laws: the desired acceleration from a reference and the measured state.

Both laws return the joint acceleration :math:`\ddot q_d` (Pinocchio's tangent space, ``nv``) that the
force distribution then realises: the distribution finds cable forces with
:math:`\hat M(q)\ddot q_d + \hat h(q, \dot q) = -L(q)^T f` on the *controller's* model (hats: its
masses may be wrong), so that with a perfect model the closed loop follows the error dynamics below.

**Joint space** (:class:`JointSpaceLaw`), with the configuration error taken on the manifold
(:math:`e = q_r \ominus q`, ``pin.difference(q, q_r)``: the rotation vector of a ball or free joint,
in its child frame):

.. math:: \ddot q_d = \ddot q_r + K_d (\dot q_r - \dot q) + K_p\, e + K_i \textstyle\sum_k e_k\, \Delta t .

The integral term (off by default, ``ki = 0``) removes the steady error a wrong model leaves: with
every mass ``1 + d`` times too large, the closed loop settles where
:math:`K_p e = -\tfrac{d}{1+d} M^{-1} g`, which on the neck (light vertebrae under a 1 kg skull) is
degrees at ``kp = 2500``. :func:`pid_gains` places the three poles of the error dynamics at
:math:`-\omega` (``kd = 3 w``, ``kp = 3 w^2``, ``ki = w^3``).

**Task space** (:class:`TaskSpaceLaw`) for one frame ``F`` (a platform's): with the measured and
reference placements :math:`X, X_r` (world), :math:`{}^{F}X_{r} = X^{-1} X_r`, the frame's spatial
velocity and acceleration in its own axes (``pin.LOCAL``) and the pose error
:math:`e = \log_6({}^{F}X_{r})` (m and rad, frame ``F``):

.. math:: a_d = {}^{F}X_{r}\, a_r + K_d ({}^{F}X_{r}\, \mathcal V_r - \mathcal V) + K_p\, e, \qquad
          \ddot q_d = J^{+} (a_d - \dot J \dot q) + (I - J^{+}J)\, \ddot q_{d,\mathrm{joint}},

``J`` the frame Jacobian (``LOCAL``), :math:`\dot J\dot q` the frame's spatial acceleration at
:math:`\ddot q = 0` (Pinocchio's spatial, not classical, acceleration, as :math:`a_r`), the integral
term (``ki``) on :math:`e` as above, and the
joint-space law in the null space of ``J`` (redundant robots; empty for a platform on a free joint).
Gains are in s^-2 (``kp``) and s^-1 (``kd``); critically damped: ``kd = 2 sqrt(kp)``.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..exceptions import ModelError, ProblemError


def pid_gains(omega: float) -> dict:
    """``kp``, ``kd``, ``ki`` placing the three poles of the error dynamics at ``-omega`` (rad/s)."""
    w = _gain(omega, "omega")
    return dict(kp=3.0 * w * w, kd=3.0 * w, ki=w ** 3)


class _Integral:
    """The running sum ``sum_k e_k dt`` of a law's error."""

    def __init__(self, ki: float, dt: float | None, n: int):
        self.ki = _gain(ki, "ki")
        if self.ki and not (dt is not None and np.isfinite(dt) and dt > 0):
            raise ProblemError(f"ki = {ki!r} needs the tick dt > 0 s, got dt={dt!r}")
        self.dt, self.sum = dt, np.zeros(n)

    def __call__(self, e) -> np.ndarray:
        if not self.ki:
            return 0.0
        self.sum += e * self.dt
        return self.ki * self.sum

    def reset(self) -> None:
        self.sum[:] = 0.0


def _gain(x, name: str) -> float:
    x = float(x)
    if not (np.isfinite(x) and x >= 0.0):
        raise ProblemError(f"{name}: expected a finite gain >= 0, got {x!r}")
    return x


class JointSpaceLaw:
    """Joint-space computed torque (module docstring). ``kp`` (s^-2), ``kd`` (s^-1), ``ki`` (s^-3):
    scalar gains (``kd`` default ``2 sqrt(kp)``); ``dt``: the tick (s), needed when ``ki > 0``."""

    def __init__(self, robot, kp: float = 400.0, kd: float | None = None, ki: float = 0.0,
                 dt: float | None = None):
        self.model = robot.model
        self.kp = _gain(kp, "kp")
        self.kd = _gain(2.0 * np.sqrt(self.kp) if kd is None else kd, "kd")
        self.integral = _Integral(ki, dt, robot.nv)

    def reset(self) -> None:
        """Forget the integral."""
        self.integral.reset()

    def __call__(self, q, v, q_r, v_r, a_r) -> np.ndarray:
        e = pin.difference(self.model, q, q_r)
        return a_r + self.kd * (v_r - v) + self.kp * e + self.integral(e)


class TaskSpaceLaw:
    """Task-space computed torque on frame ``frame`` (module docstring), with the joint-space law
    (same gains unless given) in the null space of the frame's Jacobian."""

    def __init__(self, robot, frame: str, kp: float = 400.0, kd: float | None = None, ki: float = 0.0,
                 dt: float | None = None, null_kp: float | None = None, null_kd: float | None = None):
        model = robot.model
        if not model.existFrame(frame):
            names = sorted({f.name for f in model.frames})
            raise ModelError(f"TaskSpaceLaw: no frame {frame!r} in robot {robot.name!r}; expected one of {names}")
        self.model, self.fid = model, model.getFrameId(frame)
        self.data, self.ref = model.createData(), model.createData()
        self.kp = _gain(kp, "kp")
        self.kd = _gain(2.0 * np.sqrt(self.kp) if kd is None else kd, "kd")
        self.null = JointSpaceLaw(robot, self.kp if null_kp is None else null_kp,
                                  null_kd if null_kd is not None else (None if null_kp is not None else self.kd))
        self.integral = _Integral(ki, dt, 6)
        self._zero = np.zeros(model.nv)

    def reset(self) -> None:
        """Forget the integral."""
        self.integral.reset()
        self.null.reset()

    def __call__(self, q, v, q_r, v_r, a_r) -> np.ndarray:
        model, fid, d, r = self.model, self.fid, self.data, self.ref
        LOCAL = pin.ReferenceFrame.LOCAL
        pin.forwardKinematics(model, r, q_r, v_r, a_r)
        X_r = pin.updateFramePlacement(model, r, fid)
        V_r = pin.getFrameVelocity(model, r, fid, LOCAL)
        A_r = pin.getFrameAcceleration(model, r, fid, LOCAL)
        pin.forwardKinematics(model, d, q, v, self._zero)
        X = pin.updateFramePlacement(model, d, fid)
        V = pin.getFrameVelocity(model, d, fid, LOCAL)
        drift = pin.getFrameAcceleration(model, d, fid, LOCAL).vector
        pin.computeJointJacobians(model, d, q)
        J = pin.getFrameJacobian(model, d, fid, LOCAL)
        cXr = X.actInv(X_r)
        e = pin.log6(cXr).vector
        a_d = cXr.act(A_r).vector + self.kd * (cXr.act(V_r).vector - V.vector) + self.kp * e + self.integral(e)
        if J.shape[1] == 6 and abs(np.linalg.det(J)) > 1e-12:
            return np.linalg.solve(J, a_d - drift)
        Jp = np.linalg.pinv(J)
        joint = self.null(q, v, q_r, v_r, a_r)
        return Jp @ (a_d - drift) + joint - Jp @ (J @ joint)
