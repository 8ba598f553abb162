r"""Trajectories: rest-to-rest quintics (on SO(3) and SE(3) for ball and free joints) and CSV files.

A :class:`Trajectory` holds samples of Pinocchio's configuration ``q`` (N, nq) and of its velocity and
acceleration ``qd``, ``qdd`` (N, nv: the tangent space). A *plan* (:func:`plan`) evaluates the same
motion at any time, for replays and dense forces.

**Quintic.** Start and end are given in coordinates (:mod:`mcdm_pin.model.charts`). Every coordinate
follows :math:`x(t) = x_0 + (x_1 - x_0)\, s(t/T)` with :math:`s(\tau) = 10\tau^3 - 15\tau^4 + 6\tau^5`
(zero velocity and acceleration at both ends), except rotations: a spherical joint (native ball joint,
ZYX or xyz Euler angles) and the orientation of a free joint turn about one fixed axis (CASPR's and the
source paper's interpolation): with :math:`R_0, R_1` the start and end orientations and
:math:`R_0^T R_1 = \exp([\phi]_\times)`,

.. math:: R(t) = R_0 \exp(s(t/T)[\phi]_\times), \qquad \omega = \dot s\,\phi, \qquad \dot\omega = \ddot s\,\phi

(child frame). Euler angles follow by Newton's method on SO(3) from the previous sample (to 1e-14 rad),
their rates from :math:`\omega = S(q)\dot q` and :math:`\dot\omega = S\ddot q + \dot S\dot q`. A free
joint's position follows the scalar quintic in its parent frame (translation and rotation decoupled);
its velocity is Pinocchio's :math:`(R^T\dot p, \omega)`. ``spherical: per-coordinate`` applies the scalar
quintic to each coordinate instead.

**Task.** A ``task`` trajectory (poses of a frame) is solved into joint samples by inverse kinematics:
:mod:`mcdm_pin.ik`.

**CSV.** Columns ``t`` and the nv coordinates, optionally followed by nv columns ``qd:NAME`` and nv
columns ``qdd:NAME``: Pinocchio's velocity and acceleration (tangent space), taken exactly as given.
Without them the rates are the derivatives of the interpolating quintic B-spline through the samples
(``scipy.interpolate.make_interp_spline(k=5)``, not-a-knot ends), mapped to the tangent space exactly
(:func:`mcdm_pin.model.charts.tangent`); at least 6 samples with strictly increasing times. The first
row may be a header: a row of names (no cell a number), matched by name in any order; it must name
``t`` and every coordinate (and every ``qd:``/``qdd:`` column or none), each once, and nothing else,
and every row must have as many cells as it has names. Without a header the columns are read in the
order above. Any row that does not parse is an error naming its row and column.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import pinocchio as pin

from .exceptions import SidecarError, StateError, TrajectoryError
from .limits import MAX_SAMPLES
from .ik.samples import csv_samples, pose_samples
from .ik.solve import solve_task
from .ik.space import TaskSpace
from .model import charts
from .profiles import csv_rows, is_number, quintic_profile
from .sidecar import TrajectorySpec, _names
from .vocabulary import SPHERICAL_MODES

# |det S| = |cos q2| below which a spherical joint's Euler-angle rates are refused (within 0.057 deg
# of gimbal lock the rates, and their rounding errors, are amplified more than 1000 times)
SINGULAR_DET = 1e-3


@dataclass
class Trajectory:
    """Sampled trajectory: ``t`` (N,), ``q`` (N, nq) configurations, ``qd``, ``qdd`` (N, nv)."""

    name: str
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray

    def __post_init__(self):
        try:
            self.t = np.asarray(self.t, dtype=float).reshape(-1)
            arrays = [np.asarray(getattr(self, k), dtype=float) for k in ("q", "qd", "qdd")]
        except (TypeError, ValueError) as exc:
            raise TrajectoryError(f"trajectory {self.name!r}: expected arrays of numbers ({exc})") from None
        n = len(self.t)
        for key, arr in zip(("q", "qd", "qdd"), arrays):
            if arr.ndim != 2 or arr.shape[0] != n:
                raise TrajectoryError(f"trajectory {self.name!r}: {key} has shape {arr.shape}; expected "
                                      f"{n} rows, one per time in t")
        self.q, self.qd, self.qdd = arrays

    def __len__(self) -> int:
        return len(self.t)

    def subsample(self, samples: int) -> "Trajectory":
        """Keep ``samples`` instants spread evenly over the trajectory (first and last included)."""
        if samples >= len(self.t):
            return self
        idx = np.unique(np.round(np.linspace(0, len(self.t) - 1, samples)).astype(int))
        return Trajectory(self.name, self.t[idx], self.q[idx], self.qd[idx], self.qdd[idx])


class SphericalKinematics:
    """Rotation (socket -> child) and angle-rate map of a spherical joint given by three angles: an
    xyz Euler triple of revolute joints or a native ``JointModelSphericalZYX``. Computed by Pinocchio on
    a copy of the joint's own chain (first placement set to identity)."""

    def __init__(self, robot, joint):
        m = robot.model
        sub = pin.Model()
        parent = 0
        for k, pid in enumerate(joint.pin_ids):
            placement = pin.SE3.Identity() if k == 0 else m.jointPlacements[pid]
            parent = sub.addJoint(parent, m.joints[pid], placement, m.names[pid])
        self.model, self.data, self.last = sub, sub.createData(), parent
        self.name = joint.name
        self._zero = np.zeros(3)

    def rotation(self, th) -> np.ndarray:
        """Socket -> child rotation at angles ``th`` (3,)."""
        pin.forwardKinematics(self.model, self.data, np.asarray(th, dtype=float))
        return self.data.oMi[self.last].rotation.copy()

    def S(self, th) -> np.ndarray:
        """(3, 3) map from angle rates to the child-frame angular velocity."""
        J = pin.computeJointJacobian(self.model, self.data, np.asarray(th, dtype=float), self.last)
        return J[3:].copy()

    def rates(self, th, omega, omega_dot):
        """Angle rates and accelerations for a child-frame angular velocity and acceleration."""
        S = self.S(th)
        det = float(np.linalg.det(S))
        if abs(det) < SINGULAR_DET:
            raise TrajectoryError(
                f"joint {self.name!r}: the Euler angles {np.round(th, 6).tolist()} rad are "
                f"{np.degrees(np.arcsin(min(abs(det), 1.0))):.4g} deg from +-90 deg, at the singularity "
                f"of the Euler angles (gimbal lock: |det S| = |cos q2| = {abs(det):.2e} < {SINGULAR_DET:g}); "
                f"the angle rates of this motion are undefined or amplified by 1/|det S| there. Keep "
                f"the middle angle away from +-90 deg (e.g. turn the joint's socket frame), or declare the "
                f"joint a native ball joint (parametrization: quaternion), which has no singularity")
        thd = np.linalg.solve(S, omega)
        # S thdd + dS/dt thd = omega_dot; dS/dt thd is the child's angular acceleration at thdd = 0
        pin.forwardKinematics(self.model, self.data, np.asarray(th, dtype=float), thd, self._zero)
        bias = self.data.a[self.last].angular
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
    """A sidecar configuration (list in coordinate order, or mapping joint -> values) -> coordinates (nv).
    A robot loaded from another format reads the mapping in its source's names and units (MJCF:
    MuJoCo's joint values; coupled joints left out follow their couplings)."""
    if isinstance(value, dict) and getattr(robot, "source", None) is not None:
        try:
            return robot.coordinates(robot.source.configuration(value))
        except StateError as exc:
            raise SidecarError(path, key, str(exc)) from None
    if isinstance(value, dict):
        x = np.zeros(robot.nv)
        for jname, vals in value.items():
            if jname not in robot.joint_names:
                raise SidecarError(path, f"{key}.{jname}", f"unknown joint {jname!r}; expected one of "
                                                           f"{_names(robot.joint_names)}")
            joint = robot.joint(jname)
            if len(vals) != joint.nv:
                raise SidecarError(path, f"{key}.{jname}",
                                   f"expected {joint.nv} value(s) for {joint.type} joint {jname!r}, "
                                   f"got {len(vals)}")
            x[joint.idx_v] = vals
        return x
    if len(value) != robot.nv:
        raise SidecarError(path, key, f"expected {robot.nv} values (coordinates "
                                      f"{', '.join(robot.coordinate_names)}), got {len(value)}")
    return np.array(value, dtype=float)


# ----------------------------------------------------------------------------------------- plans
Plan = Callable[[float], tuple[np.ndarray, np.ndarray, np.ndarray]]


class QuinticPlan:
    """The rest-to-rest quintic from coordinates ``x0`` to ``x1`` in ``duration`` s, at any time
    (module docstring). ``spherical``: ``axis-angle`` (default) or ``per-coordinate``."""

    def __init__(self, robot, x0, x1, duration: float, spherical: str = "axis-angle"):
        if spherical not in SPHERICAL_MODES:
            raise TrajectoryError(f"spherical: expected one of {', '.join(SPHERICAL_MODES)}, got {spherical!r}")
        if not (np.isfinite(duration) and duration > 0):
            raise TrajectoryError(f"expected a finite duration > 0, got {duration!r}")
        self.robot, self.T = robot, float(duration)
        self.x0 = robot.check_vector(x0, "q_start")
        self.x1 = robot.check_vector(x1, "q_end")
        self.rotations = []  # (joint, kind, idx of its rotation in v, kinematics, R0, phi)
        if spherical == "axis-angle":
            for joint in robot.joints:
                if joint.type == "free":
                    iv = joint.idx_v[3:]
                    R0, R1 = pin.exp3(self.x0[iv]), pin.exp3(self.x1[iv])
                    self.rotations.append((joint, "free", iv, None, R0, pin.log3(R0.T @ R1)))
                elif joint.type == "spherical":
                    iv = joint.idx_v
                    if joint.parametrization == "quaternion":
                        kin, R0, R1 = None, pin.exp3(self.x0[iv]), pin.exp3(self.x1[iv])
                    else:
                        kin = SphericalKinematics(robot, joint)
                        R0, R1 = kin.rotation(self.x0[iv]), kin.rotation(self.x1[iv])
                    self.rotations.append((joint, "ball", iv, kin, R0, pin.log3(R0.T @ R1)))

    def __call__(self, t, guess=None):
        """``(q, v, a)`` at time ``t``; ``guess``: Euler angles to start Newton from (previous sample)."""
        s, ds, dds = (float(x[0]) for x in quintic_profile(np.array([float(t)]), self.T))
        dx = self.x1 - self.x0
        x, xd, xdd = self.x0 + s * dx, ds * dx, dds * dx
        rot = []
        for joint, kind, iv, kin, R0, phi in self.rotations:
            R = R0 @ pin.exp3(s * phi)
            if kind == "free" or kin is None:
                x[iv], xd[iv], xdd[iv] = pin.log3(R), 0.0, 0.0  # overwritten below in the tangent space
            else:
                th = kin.angles(R, x[iv] if guess is None else guess[iv])
                x[iv] = th
                xd[iv], xdd[iv] = kin.rates(th, ds * phi, dds * phi)
                continue
            rot.append((joint, kind, iv, R, ds * phi, dds * phi))
        q, v, a = charts.tangent(self.robot.model, x, xd, xdd, self.robot._parts)
        for joint, kind, iv, R, w, wd in rot:
            v[iv], a[iv] = w, wd
            if kind == "free":
                it = joint.idx_v[:3]
                vl = R.T @ xd[it]
                v[it], a[it] = vl, R.T @ xdd[it] - np.cross(w, vl)
        return q, v, a, x


def quintic_trajectory(robot, q_start, q_end, duration: float, dt: float,
                       spherical: str = "axis-angle", name: str = "quintic") -> Trajectory:
    """Rest-to-rest quintic between two configurations in coordinates (nv), sampled every ``dt``
    (module docstring)."""
    if not (np.isfinite(duration) and np.isfinite(dt) and duration > 0 and dt > 0 and dt <= duration):
        raise TrajectoryError(f"expected finite 0 < dt <= duration, got dt={dt!r}, duration={duration!r}")
    if duration / dt + 1 > MAX_SAMPLES:
        raise TrajectoryError(f"expected at most {MAX_SAMPLES} samples (docs/limits.md), got duration/dt + 1 = "
                              f"{duration / dt + 1:.3g}")
    n = int(np.floor(duration / dt + 1e-9)) + 1
    plan_ = QuinticPlan(robot, q_start, q_end, duration, spherical)
    t = np.arange(n) * dt
    if not plan_.rotations and all(p.kind == charts.IDENTITY for p in robot._parts):
        s, ds, dds = quintic_profile(t, duration)  # every coordinate is a configuration entry
        dx = plan_.x1 - plan_.x0
        return Trajectory(name, t, plan_.x0 + np.outer(s, dx), np.outer(ds, dx), np.outer(dds, dx))
    Q, V, A = np.empty((n, robot.nq)), np.empty((n, robot.nv)), np.empty((n, robot.nv))
    guess = plan_.x0
    for k in range(n):
        try:
            Q[k], V[k], A[k], guess = plan_(t[k], guess)
        except TrajectoryError as exc:  # (gimbal lock: the instant where it is met)
            raise TrajectoryError(f"trajectory {name!r} at t = {t[k]:g} s (sample {k}): {exc}") from None
    if abs(t[-1] - duration) <= 1e-9 * duration and plan_.rotations:  # the last sample is the end pose
        for joint, kind, iv, kin, R0, phi in plan_.rotations:
            if kin is not None:
                th = kin.angles(kin.rotation(plan_.x1[iv]), guess[iv])
                Q[-1, joint.idx_q] = th
    return Trajectory(name, t, Q, V, A)


# -------------------------------------------------------------------------------------------- CSV
def _header_columns(path: Path, header: list[str], robot) -> list[int]:
    """The file column of each canonical column (``t``, the coordinates, then ``qd:``/``qdd:`` when
    the header names them), matched by name; :class:`TrajectoryError` naming the column otherwise."""
    import difflib

    coords = list(robot.coordinate_names)
    rates = [f"{k}:{c}" for k in ("qd", "qdd") for c in coords]
    known = ["t", *coords, *rates]
    for sep in (";", "\t"):
        if len(header) == 1 and sep in header[0]:
            raise TrajectoryError(f"{path}: row 1: one cell {header[0][:80]!r}, whose columns are separated by "
                                  f"{sep!r}; expected commas (t,{','.join(coords)})")
    for k, name in enumerate(header):
        if name not in known:
            near = difflib.get_close_matches(name, known, n=1)
            absent = [n for n in (known if len(header) > 1 + len(coords) else known[:1 + len(coords)])
                      if n not in header]
            hint = (f" (did you mean {near[0]!r}?)" if near else
                    f" (the header does not name {', '.join(map(repr, absent[:3]))})" if absent else "")
            raise TrajectoryError(f"{path}: row 1, column {k + 1}: header {name!r} names no column{hint}; "
                                  f"expected t, the coordinates {', '.join(coords)} and optionally qd:NAME "
                                  f"and qdd:NAME for each (in any order)")
        if header.index(name) != k:
            raise TrajectoryError(f"{path}: row 1: the header names {name!r} twice (columns "
                                  f"{header.index(name) + 1} and {k + 1})")
    missing = [n for n in ("t", *coords) if n not in header]
    if missing:
        raise TrajectoryError(f"{path}: row 1: the header has no column {', '.join(map(repr, missing))}; "
                              f"expected t and every coordinate ({', '.join(coords)})")
    given = [n for n in rates if n in header]
    if given and len(given) != len(rates):
        absent = [n for n in rates if n not in header]
        raise TrajectoryError(f"{path}: row 1: the header names some rate columns but not "
                              f"{', '.join(map(repr, absent[:6]))}{', ...' if len(absent) > 6 else ''}; "
                              f"rates are given for every coordinate (qd: and qdd:) or for none")
    return [header.index(n) for n in known if n in header]


def read_csv(robot, path) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None]:
    """``(t, coordinates, qd, qdd)`` of a trajectory CSV (``qd``, ``qdd`` ``None`` when absent). A
    header's columns are matched by name (any order); without a header, columns are ``t``, the
    coordinates (and the rates) in order."""
    path = Path(path)
    rows = csv_rows(path)
    nv = robot.nv
    first, order = 0, None
    if rows and not any(is_number(c) for c in rows[0]):
        order = _header_columns(path, [c.strip() for c in rows[0]], robot)
        first = 1
    width = len(order) if order is not None else len(rows[first]) if len(rows) > first else 0
    if width not in (1 + nv, 1 + 3 * nv):
        raise TrajectoryError(f"{path}: row {first + 1}: expected {1 + nv} columns (t, "
                              f"{', '.join(robot.coordinate_names)}) or {1 + 3 * nv} (with qd:/qdd: columns), "
                              f"got {width}")
    values = []
    for i in range(first, len(rows)):
        row = rows[i]
        if len(row) != width:
            what = f"the header's {width}" if order is not None else f"{width}"
            raise TrajectoryError(f"{path}: row {i + 1}: expected {what} columns, got {len(row)}")
        try:
            values.append([float(c) for c in row])
        except ValueError:
            col = next(j for j, c in enumerate(row) if not is_number(c))
            raise TrajectoryError(f"{path}: row {i + 1}, column {col + 1}: expected a number, got "
                                  f"{row[col]!r}") from None
    data = np.array(values, dtype=float).reshape(-1, width)
    if not np.all(np.isfinite(data)):
        i, j = np.argwhere(~np.isfinite(data))[0]
        raise TrajectoryError(f"{path}: row {i + first + 1}, column {j + 1}: expected a finite number")
    if order is not None:
        data = data[:, order]  # canonical order: t, coordinates, qd:, qdd:
    t = data[:, 0]
    if len(t) and np.any(np.diff(t) <= 0):
        k = int(np.flatnonzero(np.diff(t) <= 0)[0])
        raise TrajectoryError(f"{path}: times must increase strictly; row {k + first + 2} has "
                              f"t={t[k + 1]!r} after t={t[k]!r}")
    if width == 1 + nv:
        return t, data[:, 1:], None, None
    return t, data[:, 1:1 + nv], data[:, 1 + nv:1 + 2 * nv], data[:, 1 + 2 * nv:]


def csv_trajectory(robot, path, name: str | None = None) -> Trajectory:
    """Read a trajectory CSV (module docstring)."""
    path = Path(path)
    t, x, qd, qdd = read_csv(robot, path)
    name = name or path.stem
    if qd is not None:
        if len(t) < 1:
            raise TrajectoryError(f"{path}: no samples")
        Q = np.array([robot.configuration(xi) for xi in x]).reshape(len(t), robot.nq)
        return Trajectory(name, t, Q, qd, qdd)
    if len(t) < 6:
        raise TrajectoryError(f"{path}: expected at least 6 samples for a quintic spline, got {len(t)}")
    return _spline_trajectory(robot, name, t, x)


def _spline_trajectory(robot, name, t, x) -> Trajectory:
    from scipy.interpolate import make_interp_spline

    spline = make_interp_spline(t, x, k=5)
    xd, xdd = spline(t, 1), spline(t, 2)
    Q, V, A = np.empty((len(t), robot.nq)), np.empty_like(xd), np.empty_like(xdd)
    for k in range(len(t)):
        Q[k], V[k], A[k] = charts.tangent(robot.model, x[k], xd[k], xdd[k], robot._parts)
    return Trajectory(name, t, Q, V, A)


# ---------------------------------------------------------------------------------------- sidecar
def task_trajectory(robot, spec):
    """The joint :class:`~mcdm_pin.trajectory.Trajectory` of a sidecar ``task`` trajectory ``spec``
    (:func:`mcdm_pin.ik.solve_task` on the robot's model; first seed ``spec.q_start`` or the robot's
    reference pose); errors name the sidecar and the trajectory's key."""
    where = robot.sidecar.path if robot.sidecar is not None else robot.name
    if getattr(robot, "couplings", None) is not None:
        raise TrajectoryError(f"{where}: {spec.key}: task trajectories on a robot with joint couplings are not "
                              f"supported (the inverse kinematics would move coupled coordinates freely)")
    try:
        space = TaskSpace(frame=spec.frame, point=tuple(spec.point), coordinates=spec.coordinates, euler=spec.euler)
        if spec.file is not None:
            t, y, yd, ydd = csv_samples(spec.file, spec.coordinates)
        else:
            t, y, yd, ydd = pose_samples(spec.poses, spec.dt)
        path = robot.sidecar.path if robot.sidecar is not None else None
        x0 = (resolve_configuration(robot, spec.q_start, f"{spec.key}.q_seed", path)
              if spec.q_start is not None else robot.reference_coordinates())
        sol = solve_task(robot.model, space, t, y, yd, ydd, robot.configuration(x0), name=f"trajectory {spec.name!r}")
    except TrajectoryError as exc:
        raise TrajectoryError(f"{where}: {spec.key}: {exc}") from None
    return Trajectory(spec.name, sol.t, sol.q, sol.qd, sol.qdd)


def trajectory_from_spec(robot, spec: TrajectorySpec) -> Trajectory:
    """The sidecar's trajectory ``spec``, sampled; an error in a quintic names the sidecar file and
    the trajectory's key (a CSV's names its file)."""
    if spec.type == "csv":
        return follow_couplings(robot, csv_trajectory(robot, spec.file, name=spec.name))
    if spec.type == "task":  # inverse kinematics (mcdm_pin.ik)
        return follow_couplings(robot, task_trajectory(robot, spec))
    x0, x1 = _ends(robot, spec)
    try:
        traj = quintic_trajectory(robot, x0, x1, spec.duration, spec.dt, spec.spherical, name=spec.name)
    except TrajectoryError as exc:
        where = robot.sidecar.path if robot.sidecar is not None else robot.name
        raise TrajectoryError(f"{where}: {spec.key}: {exc}") from None
    return follow_couplings(robot, traj)


def follow_couplings(robot, traj: Trajectory) -> Trajectory:
    """``traj`` with every coupled coordinate computed from the independent ones at every sample
    (:mod:`mcdm_pin.model.couplings`: positions, then velocities and accelerations by the chain rule);
    unchanged for a robot without couplings."""
    couplings = getattr(robot, "couplings", None)
    if couplings is None:
        return traj
    rows = [couplings.fill(q, v, a) for q, v, a in zip(traj.q, traj.qd, traj.qdd)]
    return Trajectory(traj.name, traj.t, np.array([r[0] for r in rows]), np.array([r[1] for r in rows]),
                      np.array([r[2] for r in rows]))


def _ends(robot, spec: TrajectorySpec):
    path = robot.sidecar.path if robot.sidecar is not None else None
    return (resolve_configuration(robot, spec.q_start, f"{spec.key}.q_start", path),
            resolve_configuration(robot, spec.q_end, f"{spec.key}.q_end", path))


def plan(robot, spec: TrajectorySpec) -> Plan:
    """The motion of a sidecar trajectory at any time: ``t -> (q, v, a)``. Quintics are evaluated
    exactly; CSV trajectories through the quintic spline of their samples (coordinates and, when the
    file has them, the given rates at the samples); task trajectories through the quintic spline of
    their solved samples' coordinates."""
    if spec.type == "task":
        from scipy.interpolate import make_interp_spline

        traj = trajectory_from_spec(robot, spec)
        spline = make_interp_spline(traj.t, np.array([robot.coordinates(q) for q in traj.q]), k=5)

        def state(tt):
            return _coupled(robot, *charts.tangent(robot.model, spline(tt), spline(tt, 1), spline(tt, 2),
                                                   robot._parts))

        return state
    if spec.type == "csv":
        from scipy.interpolate import make_interp_spline

        t, x, qd, _ = read_csv(robot, spec.file)
        spline = make_interp_spline(t, x, k=5)

        def state(tt):
            return _coupled(robot, *charts.tangent(robot.model, spline(tt), spline(tt, 1), spline(tt, 2),
                                                   robot._parts))

        return state
    x0, x1 = _ends(robot, spec)
    quintic = QuinticPlan(robot, x0, x1, spec.duration, spec.spherical)
    samples = quintic_trajectory(robot, x0, x1, spec.duration, spec.dt, spec.spherical) if quintic.rotations else None

    def state(tt):
        guess = None
        if samples is not None:  # Newton starts from the nearest sample (the same branch of angles)
            k = int(np.clip(np.rint(tt / spec.dt), 0, len(samples) - 1))
            guess = robot.coordinates(samples.q[k])
        q, v, a, _ = quintic(tt, guess)
        return _coupled(robot, q, v, a)

    return state


def _coupled(robot, q, v, a):
    couplings = getattr(robot, "couplings", None)
    return (q, v, a) if couplings is None else couplings.fill(q, v, a)


def load_trajectory(robot, name: str) -> Trajectory:
    """The sidecar's trajectory ``name``."""
    specs = robot.sidecar.trajectories if robot.sidecar is not None else {}
    if name not in specs:
        where = robot.sidecar.path if robot.sidecar is not None else robot.name
        raise TrajectoryError(f"{where}: no trajectory {name!r}; expected one of "
                              f"{_names(specs) if specs else '(none defined)'}")
    return trajectory_from_spec(robot, specs[name])
