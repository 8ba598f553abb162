r"""Trajectories: rest-to-rest quintics (spherical joints about one fixed axis) and CSV files.

**Quintic.** Every coordinate not in a spherical joint follows
:math:`q(t) = q_0 + (q_1 - q_0)\, s(t/T)` with :math:`s(\tau) = 10\tau^3 - 15\tau^4 + 6\tau^5` (zero
velocity and acceleration at both ends). A spherical joint turns about one fixed axis (CASPR's and the
source paper's interpolation): with :math:`R_0, R_1` its start and end orientations (socket -> child)
and :math:`R_0^T R_1 = \exp([\phi]_\times)`,

.. math:: R(t) = R_0 \exp(s(t/T)[\phi]_\times), \qquad \omega = \dot s\,\phi, \qquad \dot\omega = \ddot s\,\phi

(child frame). The Euler angles follow by Newton's method on SO(3) from the previous sample (to 1e-14
rad), their rates from :math:`\omega = S(q)\dot q` and :math:`\dot\omega = S\ddot q + \dot S\dot q`.
``spherical: per-coordinate`` applies the scalar quintic to each Euler angle instead.

**CSV.** Columns ``t, q_1 ... q_nv`` (an optional header row of names). Velocities and accelerations
are the first and second derivatives of the interpolating quintic B-spline through the samples
(``scipy.interpolate.make_interp_spline(k=5)``, not-a-knot ends), so ``qdd`` is continuous; at least 6
samples with strictly increasing times are required.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from .exceptions import SidecarError, TrajectoryError
from .sidecar import TrajectorySpec, _names


# |det S| = |cos q2| below which a spherical joint's Euler-angle rates are refused (within 0.057 deg
# of gimbal lock the rates, and their rounding errors, are amplified more than 1000 times)
SINGULAR_DET = 1e-3


@dataclass
class Trajectory:
    """Sampled joint trajectory: ``t`` (N,), ``q``, ``qd``, ``qdd`` (N, nv)."""

    name: str
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray

    def __len__(self) -> int:
        return len(self.t)

    def subsample(self, samples: int) -> "Trajectory":
        """Keep ``samples`` instants spread evenly over the trajectory (first and last included)."""
        if samples >= len(self.t):
            return self
        idx = np.unique(np.round(np.linspace(0, len(self.t) - 1, samples)).astype(int))
        return Trajectory(self.name, self.t[idx], self.q[idx], self.qd[idx], self.qdd[idx])


def quintic_profile(t: np.ndarray, duration: float):
    """s, ds/dt, d2s/dt2 of the rest-to-rest quintic on [0, duration]."""
    tau = np.clip(t / duration, 0.0, 1.0)
    s = tau**3 * (10 - 15 * tau + 6 * tau**2)
    ds = 30 * tau**2 * (1 - tau) ** 2 / duration
    dds = 60 * tau * (1 - tau) * (1 - 2 * tau) / duration**2
    return s, ds, dds


class SphericalKinematics:
    """Rotation and Euler-rate map of one spherical joint made of three revolute URDF joints."""

    def __init__(self, robot, joint):
        m = robot.model
        data = m.createData()
        q0 = robot.pin_q(np.zeros(robot.nv))
        self.axes = []  # each URDF joint's axis in its own frame
        for j in joint.pin_ids:
            Jl = pin.computeJointJacobian(m, data, q0, j)  # LOCAL frame of joint j
            a = Jl[3:, m.joints[j].idx_v]
            self.axes.append(a / np.linalg.norm(a))
        # fixed rotations between the URDF joints (the first is part of the socket frame)
        self.P = [np.eye(3)] + [m.jointPlacements[j].rotation.copy() for j in joint.pin_ids[1:]]
        self.name = joint.name

    def rotation(self, th) -> np.ndarray:
        """Socket -> child rotation at angles ``th`` (3,)."""
        R = np.eye(3)
        for P, a, x in zip(self.P, self.axes, th):
            R = R @ P @ pin.exp3(a * x)
        return R

    def S(self, th) -> np.ndarray:
        """(3, 3) map from angle rates to the child-frame angular velocity."""
        cols = [None, None, None]
        R_k_child = np.eye(3)  # rotation from the child frame to frame k (after joint k turns)
        for k in (2, 1, 0):
            cols[k] = R_k_child.T @ self.axes[k]
            R_k_child = self.P[k] @ pin.exp3(self.axes[k] * th[k]) @ R_k_child
        return np.column_stack(cols)

    def rates(self, th, omega, omega_dot):
        """Angle rates and accelerations for a child-frame angular velocity and acceleration."""
        S = self.S(th)
        det = float(np.linalg.det(S))
        if abs(det) < SINGULAR_DET:
            raise TrajectoryError(
                f"joint {self.name!r}: the Euler angles {np.round(th, 6).tolist()} rad are "
                f"{np.degrees(np.arccos(min(abs(det), 1.0))):.4g} deg from 90 deg, at the singularity "
                f"of xyz Euler angles (gimbal lock: |det S| = |cos q2| = {abs(det):.2e} < {SINGULAR_DET:g}); "
                f"the angle rates of this motion are undefined or amplified by 1/|cos q2| there. Keep "
                f"the middle angle away from +-90 deg, e.g. turn the joint's socket frame (the first URDF "
                f"joint's origin rpy) so that the motion stays near q2 = 0")
        thd = np.linalg.solve(S, omega)
        # dS/dt thd = sum_k -(sum_{j>k} S_j thd_j) x S_k thd_k
        cols = S * thd
        bias = np.zeros(3)
        for k in range(3):
            bias -= np.cross(cols[:, k + 1:].sum(axis=1), cols[:, k])
        thdd = np.linalg.solve(S, omega_dot - bias)
        return thd, thdd

    def angles(self, R_target, th_guess) -> np.ndarray:
        """Angles with ``rotation(th) == R_target``, by Newton's method from ``th_guess``."""
        th = np.array(th_guess, dtype=float)
        for _ in range(50):
            e = pin.log3(self.rotation(th).T @ R_target)
            if np.linalg.norm(e) < 1e-14:
                return th
            th = th + np.linalg.solve(self.S(th), e)
        if np.linalg.norm(e) > 1e-10:
            raise TrajectoryError(f"joint {self.name!r}: cannot recover Euler angles from the "
                                  f"interpolated orientation (residual {np.linalg.norm(e):.2e} rad); "
                                  f"the motion passes a singularity")
        return th


def resolve_configuration(robot, value, key: str, path=None) -> np.ndarray:
    """A sidecar configuration (list in coordinate order, or mapping joint -> values) -> q (nv,)."""
    if isinstance(value, dict):
        q = np.zeros(robot.nv)
        for jname, vals in value.items():
            if jname not in robot.joint_names:
                raise SidecarError(path, f"{key}.{jname}", f"unknown joint {jname!r}; expected one of "
                                                           f"{_names(robot.joint_names)}")
            joint = robot.joint(jname)
            if len(vals) != joint.nv:
                raise SidecarError(path, f"{key}.{jname}",
                                   f"expected {joint.nv} value(s) for {joint.type} joint {jname!r}, "
                                   f"got {len(vals)}")
            q[joint.idx_v] = vals
        return q
    if len(value) != robot.nv:
        raise SidecarError(path, key, f"expected {robot.nv} values (coordinates "
                                      f"{', '.join(robot.coordinate_names)}), got {len(value)}")
    return np.array(value, dtype=float)


def quintic_trajectory(robot, q_start, q_end, duration: float, dt: float,
                       spherical: str = "axis-angle", name: str = "quintic") -> Trajectory:
    """Rest-to-rest quintic from ``q_start`` to ``q_end`` sampled every ``dt`` (module docstring)."""
    q0 = robot.check_vector(q_start, "q_start")
    q1 = robot.check_vector(q_end, "q_end")
    if not (duration > 0 and dt > 0 and dt <= duration):
        raise TrajectoryError(f"expected 0 < dt <= duration, got dt={dt!r}, duration={duration!r}")
    n = int(np.floor(duration / dt + 1e-9)) + 1
    t = np.arange(n) * dt
    s, ds, dds = quintic_profile(t, duration)
    dq = q1 - q0
    q = q0 + np.outer(s, dq)
    qd = np.outer(ds, dq)
    qdd = np.outer(dds, dq)
    if spherical == "axis-angle":
        for joint in robot.joints:
            if joint.type != "spherical":
                continue
            kin = SphericalKinematics(robot, joint)
            iv = joint.idx_v
            R0 = kin.rotation(q0[iv])
            phi = pin.log3(R0.T @ kin.rotation(q1[iv]))
            th = q0[iv].copy()
            for k in range(n):
                target = R0 @ pin.exp3(phi * s[k])
                th = kin.angles(target, th)
                q[k, iv] = th
                qd[k, iv], qdd[k, iv] = kin.rates(th, ds[k] * phi, dds[k] * phi)
            if abs(t[-1] - duration) <= 1e-9 * duration:  # the last sample is the end pose
                q[-1, iv] = kin.angles(kin.rotation(q1[iv]), q[-1, iv])
    elif spherical != "per-coordinate":
        raise TrajectoryError(f"spherical: expected 'axis-angle' or 'per-coordinate', got {spherical!r}")
    return Trajectory(name, t, q, qd, qdd)


def csv_trajectory(robot, path, name: str | None = None) -> Trajectory:
    """Read ``t, q...`` columns from a CSV file and differentiate a quintic spline through them."""
    from scipy.interpolate import make_interp_spline

    path = Path(path)
    try:
        with path.open(newline="", encoding="utf-8") as fh:
            rows = [row for row in csv.reader(fh) if row and any(c.strip() for c in row)]
    except FileNotFoundError:
        raise TrajectoryError(f"{path}: file not found") from None
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise TrajectoryError(f"{path}: cannot read the CSV ({exc})") from None
    if rows and not _is_numeric_row(rows[0]):
        rows = rows[1:]  # header
    values = []
    for i, row in enumerate(rows):
        if len(row) != robot.nv + 1:
            raise TrajectoryError(f"{path}: row {i + 1}: expected {robot.nv + 1} columns (t, "
                                  f"{', '.join(robot.coordinate_names)}), got {len(row)}")
        try:
            values.append([float(c) for c in row])
        except ValueError:
            raise TrajectoryError(f"{path}: row {i + 1}: expected numbers, got {row}") from None
    data = np.array(values, dtype=float).reshape(-1, robot.nv + 1)
    if len(data) < 6:
        raise TrajectoryError(f"{path}: expected at least 6 samples for a quintic spline, got {len(data)}")
    if not np.all(np.isfinite(data)):
        raise TrajectoryError(f"{path}: expected finite numbers only")
    t = data[:, 0]
    if np.any(np.diff(t) <= 0):
        k = int(np.flatnonzero(np.diff(t) <= 0)[0])
        raise TrajectoryError(f"{path}: times must increase strictly; row {k + 2} has t={t[k + 1]!r} "
                              f"after t={t[k]!r}")
    spline = make_interp_spline(t, data[:, 1:], k=5)
    return Trajectory(name or path.stem, t, data[:, 1:].copy(), spline(t, 1), spline(t, 2))


def _is_numeric_row(row) -> bool:
    try:
        [float(c) for c in row]
        return True
    except ValueError:
        return False


def trajectory_from_spec(robot, spec: TrajectorySpec) -> Trajectory:
    path = robot.sidecar.path
    if spec.type == "csv":
        return csv_trajectory(robot, spec.file, name=spec.name)
    q0 = resolve_configuration(robot, spec.q_start, f"{spec.key}.q_start", path)
    q1 = resolve_configuration(robot, spec.q_end, f"{spec.key}.q_end", path)
    return quintic_trajectory(robot, q0, q1, spec.duration, spec.dt, spec.spherical, name=spec.name)


def load_trajectory(robot, name: str) -> Trajectory:
    """The sidecar's trajectory ``name``."""
    specs = robot.sidecar.trajectories
    if name not in specs:
        raise TrajectoryError(f"{robot.sidecar.path}: no trajectory {name!r}; expected one of "
                              f"{_names(specs) if specs else '(none defined)'}")
    return trajectory_from_spec(robot, specs[name])
