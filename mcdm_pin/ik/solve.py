r"""Task-space trajectory -> joint trajectory: positions by inverse kinematics with pink, rates by the
task Jacobian.

**Positions.** At each sample time :math:`t_k` the configuration :math:`q_k` solves
:math:`y(q_k) = y^*_k` (:mod:`.space`, angles compared modulo :math:`2\pi`) by pink's differential IK
(``pink.solve_ik``, one QP per iteration, a unit step :math:`q \leftarrow q \oplus \Delta q`) iterated
until :math:`\|y(q) - y^*\|_\infty \le` ``tol`` (1e-12 m or rad by default), or until it stops
decreasing (by half in an iteration) below 1e-2 ``check_tol`` (rounding: near gimbal lock Euler angles are
defined to about :math:`10^{-16}/|\cos\beta|` only). Each QP minimises
:math:`\tfrac12\|J_y\Delta q + e\|^2 + \tfrac12\mu\|\Delta q\|^2` (Levenberg-Marquardt
:math:`\mu = 10^{-3}\|e\|^2` plus pink's Tikhonov 1e-12) under the model's joint limits (pink's
``ConfigurationLimit``; ``limits=False`` drops them; a seed outside them is first clipped into them).
The first sample starts from ``q_seed``, every later one from the previous solution moved on by its
rates,
:math:`q_{k-1} \oplus (\dot q_{k-1} h + \tfrac12 \ddot q_{k-1} h^2)`, :math:`h = t_k - t_{k-1}`, so
the branch of solutions is followed continuously. A sample that does not converge is refused with its
time and its residual (unreachable pose, or one beyond the joint limits).

**Rates.** (With all three angles kept, :math:`\dot y^*, \ddot y^*` are first turned into the angular
velocity and acceleration: :mod:`.space`.) :math:`\dot q_k` solves :math:`J_y \dot q = \dot y^*` and
:math:`\ddot q_k` solves :math:`J_y \ddot q = \ddot y^* - \dot J_y \dot q`, both in Pinocchio's tangent
space (``nv``). Where the robot has more degrees of freedom than the task (``nv > dim``), the
**least-norm** solution is taken (``numpy.linalg.lstsq``: the smallest Euclidean norm of
:math:`\dot q`, resp. :math:`\ddot q`, no weighting between rad/s and m/s); the IK steps are
least-norm too (the Tikhonov term), so the positions move along the same least-norm direction to
first order. A sample where :math:`\dot y^*` is out of
the range of :math:`J_y` (a singular configuration) is refused with its time and residual.

**Checks.** Every sample is checked by forward kinematics on the caller's model (not the copy that
carries the task frame): :math:`\|y(q_k) - y^*_k\|_\infty \le` ``check_tol`` (1e-9), and the rate
equations' residuals likewise; :class:`TaskSolution` reports the largest of each.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..exceptions import MissingPackageError, TrajectoryError
from ..extras import optional
from .space import TaskKinematics, TaskSpace, euler_angles, euler_rotation, wrap

LM_DAMPING = 1e-3
TIKHONOV = 1e-12
STALL = 1e-2  # a residual below STALL * check_tol that stops halving is taken as converged (rounding)


def _pink():
    for module in ("pink.limits", "pink.tasks"):
        optional(module, "task-space trajectories (inverse kinematics)", "ik")
    return optional("pink", "task-space trajectories (inverse kinematics)", "ik")


_TASK_CLASS = None


def _task_class():
    """pink's :class:`~pink.tasks.Task` for the coordinates of a :class:`TaskKinematics` (made on first
    use so that importing this module does not need pink)."""
    global _TASK_CLASS
    if _TASK_CLASS is None:
        pink = _pink()

        class CoordinatesTask(pink.tasks.Task):
            """Error :math:`e = y(q) - y^*` (angles wrapped), Jacobian :math:`J_y`."""

            def __init__(self, kin: TaskKinematics):
                super().__init__(cost=None, gain=1.0, lm_damping=LM_DAMPING)
                self.kin, self.target = kin, None

            def compute_error(self, configuration):
                return self.kin.residual(configuration.data, self.target)

            def compute_jacobian(self, configuration):
                return self.kin.residual_jacobian(configuration.data, self.target)

            def __repr__(self):
                return f"CoordinatesTask({self.kin.space})"

        _TASK_CLASS = CoordinatesTask
    return _TASK_CLASS


def default_solver() -> str:
    qpsolvers = optional("qpsolvers", "inverse kinematics", "ik")

    for name in ("daqp", "proxqp"):
        if name in qpsolvers.available_solvers:
            return name
    raise MissingPackageError("inverse kinematics needs a QP solver for qpsolvers: daqp or proxsuite "
                              "(pip install daqp)")


@dataclass
class TaskSolution:
    """A joint trajectory solved from a task-space one, and its checks.

    Attributes:
        t: (N,) s; q: (N, nq) Pinocchio configurations; qd, qdd: (N, nv) tangent space.
        fk_error: max over samples of :math:`\\|y(q_k) - y^*_k\\|_\\infty` (m or rad), by forward
            kinematics on the caller's model.
        velocity_residual, acceleration_residual: max of :math:`\\|J\\dot q - \\dot y^*\\|_\\infty` and
            :math:`\\|J\\ddot q + \\dot J\\dot q - \\ddot y^*\\|_\\infty`.
        iterations: the most IK iterations any sample took.
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    fk_error: float
    velocity_residual: float
    acceleration_residual: float
    iterations: int


class _Solver:
    """One IK problem per model and task space, reused over the samples."""

    def __init__(self, model, space, limits, solver, tol, max_iter, check_tol):
        pink = _pink()
        self.kin = TaskKinematics(model, space)
        self.task = _task_class()(self.kin)
        self.limits = [pink.limits.ConfigurationLimit(self.kin.model)] if limits else []
        if not limits:  # (the copy's) limits unbounded: pink's check of them then stays silent
            self.kin.model.lowerPositionLimit = np.full(self.kin.model.nq, -np.inf)
            self.kin.model.upperPositionLimit = np.full(self.kin.model.nq, np.inf)
        self.solver = solver or default_solver()
        self.tol, self.max_iter, self.check_tol = tol, max_iter, check_tol
        self.config = pink.Configuration(self.kin.model, self.kin.data, pin.neutral(self.kin.model))
        joints = self.limits[0].joints if self.limits else []
        self.bounded = [i for j in joints for i in range(j.idx_q, j.idx_q + j.nq)]  # seeds are clipped here
        self.solve_ik = pink.solve_ik

    def position(self, y_target, q_seed, t: float, name: str):
        """``(q, iterations)`` with ``y(q) = y_target`` to ``tol``; TrajectoryError otherwise."""
        self.task.target = np.asarray(y_target, dtype=float)
        q_seed = np.array(q_seed, dtype=float)
        lo, hi = self.kin.model.lowerPositionLimit, self.kin.model.upperPositionLimit
        q_seed[self.bounded] = np.clip(q_seed[self.bounded], lo[self.bounded], hi[self.bounded])
        self.config.update(q_seed)
        res = prev = np.inf
        for it in range(self.max_iter + 1):
            res = float(np.max(np.abs(self.task.compute_error(self.config))))
            # converged; or stalled at rounding below the check's tolerance (near gimbal lock the angles
            # of a rotation are defined only to ~1e-16 / |cos b|)
            if res <= self.tol or (res <= STALL * self.check_tol and res > 0.5 * prev):
                return self.config.q.copy(), it
            if it == self.max_iter:
                break
            prev = res
            v = self.solve_ik(self.config, [self.task], 1.0, solver=self.solver, damping=TIKHONOV,
                              limits=self.limits, safety_break=False)
            self.config.integrate_inplace(v, 1.0)
        limits = " within the joint limits" if self.limits else ""
        raise TrajectoryError(f"{name}: at t = {t:.9g} s the inverse kinematics did not converge: residual "
                              f"{res:.3g} (m or rad, largest coordinate of y(q) - y*) after {self.max_iter} "
                              f"iterations, tolerance {self.tol:g}; the pose y* = {np.round(y_target, 9).tolist()} "
                              f"({self.kin.space.coordinates}) of frame {self.kin.space.frame!r} is out of "
                              f"reach{limits}, or the iterations are stuck at a singular configuration "
                              f"(another seed may help)")

    def rates(self, q, y, yd, ydd, t: float, name: str, check_tol: float):
        yd, ydd = self.kin.rate_targets(y, yd, ydd)
        J = self.kin.rate_jacobian(q)
        qd = np.linalg.lstsq(J, yd, rcond=None)[0]
        rv = float(np.max(np.abs(J @ qd - yd), initial=0.0))
        b = self.kin.rate_bias(q, qd)
        qdd = np.linalg.lstsq(J, ydd - b, rcond=None)[0]
        ra = float(np.max(np.abs(J @ qdd + b - ydd), initial=0.0))
        for what, r, ref in (("velocity", rv, yd), ("acceleration", ra, ydd)):
            if r > check_tol * max(1.0, float(np.max(np.abs(ref), initial=0.0))):
                raise TrajectoryError(f"{name}: at t = {t:.9g} s the task {what} is out of the range of the "
                                      f"task Jacobian (a singular configuration, rank "
                                      f"{np.linalg.matrix_rank(J)} < {J.shape[0]}): residual {r:.3g}")
        return qd, qdd, rv, ra


def fk_coordinates(model: pin.Model, space: TaskSpace, q) -> np.ndarray:
    """``y(q)`` by forward kinematics on ``model`` itself (the check of :func:`solve_task`)."""
    data = model.createData()
    pin.framesForwardKinematics(model, data, np.asarray(q, dtype=float))
    M = data.oMf[model.getFrameId(space.frame)]
    p = M.rotation @ np.asarray(space.point, dtype=float) + M.translation
    return np.concatenate([p, euler_angles(space.euler, M.rotation)])[space.rows]


def fk_error(model: pin.Model, space: TaskSpace, q, y_target) -> float:
    r""":math:`\|y(q) - y^*\|_\infty` by forward kinematics on ``model`` (angles wrapped); with all three
    angles kept, the orientation's part is the angle of :math:`R^{*T}R(q)` (rad)."""
    y_target = np.asarray(y_target, dtype=float)
    y = fk_coordinates(model, space, q)
    e = y - y_target
    ang = space.angle_mask
    e[ang] = wrap(e[ang])
    if set("abg") <= set(space.coordinates):
        data = model.createData()
        pin.framesForwardKinematics(model, data, np.asarray(q, dtype=float))
        R = data.oMf[model.getFrameId(space.frame)].rotation
        phi = [y_target[space.coordinates.index(c)] for c in "abg"]
        e[ang] = 0.0
        e = np.append(e, np.linalg.norm(pin.log3(euler_rotation(space.euler, phi).T @ R)))
    return float(np.max(np.abs(e)))


def solve_task(model: pin.Model, space: TaskSpace, t, y, yd, ydd, q_seed=None, *, name: str = "trajectory",
               limits: bool = True, solver: str | None = None, tol: float = 1e-12, max_iter: int = 100,
               check_tol: float = 1e-9) -> TaskSolution:
    """The joint trajectory of the task-space samples ``y, yd, ydd`` (N, dim) at times ``t`` (N,)
    (module docstring). ``q_seed``: the configuration (nq) the first IK starts from (default: the
    model's neutral configuration). Raises :class:`~mcdm_pin.exceptions.TrajectoryError` naming
    ``name``, the sample time and the residual when a sample cannot be solved."""
    t = np.asarray(t, dtype=float).reshape(-1)
    y, yd, ydd = (np.asarray(a, dtype=float).reshape(len(t), space.dim) for a in (y, yd, ydd))
    if len(t) == 0 or np.any(np.diff(t) <= 0) or not np.all(np.isfinite(np.hstack([y, yd, ydd]))):
        raise TrajectoryError(f"{name}: expected at least one sample, strictly increasing times and finite "
                              f"task coordinates and rates")
    s = _Solver(model, space, limits, solver, tol, max_iter, check_tol)
    q = pin.neutral(model) if q_seed is None else np.asarray(q_seed, dtype=float)
    if q.shape != (model.nq,):
        raise TrajectoryError(f"{name}: q_seed has shape {q.shape}; expected ({model.nq},)")
    N = len(t)
    Q, V, A = np.empty((N, model.nq)), np.empty((N, model.nv)), np.empty((N, model.nv))
    worst_v = worst_a = 0.0
    iters = 0
    for k in range(N):
        if k > 0:
            h = t[k] - t[k - 1]
            q = pin.integrate(model, Q[k - 1], V[k - 1] * h + 0.5 * A[k - 1] * h * h)
        Q[k], n = s.position(y[k], q, t[k], name)
        iters = max(iters, n)
        V[k], A[k], rv, ra = s.rates(Q[k], y[k], yd[k], ydd[k], t[k], name, check_tol)
        worst_v, worst_a = max(worst_v, rv), max(worst_a, ra)
    fk = max(fk_error(model, space, Q[k], y[k]) for k in range(N))
    if fk > check_tol:
        raise TrajectoryError(f"{name}: forward kinematics of the solution misses the task by {fk:.3g} "
                              f"(tolerance {check_tol:g})")
    return TaskSolution(t, Q, V, A, fk, worst_v, worst_a, iters)
