r"""Forward-dynamics replay: do the computed cable forces really produce the planned motion?

Starting from the first solved state of a :class:`~mcdm_pin.results.TrajectoryResult`, integrate

.. math:: \ddot q = \text{ABA}\big(q, \dot q,\; \tau = -L(q)^T f(t)\big)

(Pinocchio's articulated-body algorithm, the cables' generalised force evaluated at the *integrated*
configuration, not the planned one) and compare :math:`q` with the plan at the sample instants.

**Forcing.** ``hold='linear'`` interpolates :math:`f` linearly between the solved instants,
``hold='zoh'`` holds each instant's forces until the next one, and a callable ``forces(t) -> f``
supplies forces at any time (:func:`resolved_forces` re-solves the inverse-dynamics problem on the
planned state at the integrator's own stage times: "dense output").

**What converges, and at which order.** The integrator takes ``substeps`` equal steps per sample
interval, so every step boundary falls on a sample instant and the interpolated forcing is a
polynomial (linear, or constant) *inside* every step: the ODE being integrated is smooth on each step
and the integrator keeps its full order (RK4: 4; explicit and semi-implicit Euler: 1). Two errors
must be told apart:

* ``self`` error: :math:`\max|q_h - q_{h/2}|` at the samples (Richardson): the integrator's own
  error; it shrinks by :math:`2^p` per halving of the step.
* ``plan`` error: :math:`\max|q_h - q_{plan}|`. With interpolated forces it tends, as the step
  shrinks, to a floor that does not depend on the integrator: the difference between the plan's
  generalised force and that of piecewise-linear forces, :math:`O(\Delta^2)` in the sample spacing
  :math:`\Delta` (``zoh``: :math:`O(\Delta)`). With re-solved forces the exact solution *is* the plan
  (the forces satisfy :math:`M\ddot q + h = -L^T f` on the plan at every time), so the plan error
  itself shrinks at the integrator's order, as long as :math:`f(t)` is smooth: where the optimal
  active set changes :math:`f` has a kink, which costs RK4 its order locally (measured in
  ``docs/trust.md``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import pinocchio as pin

from .model.geometry import cable_geometry
from .exceptions import ResultsError, TrajectoryError

INTEGRATORS = ("rk4", "euler", "semi-implicit")
ORDER = {"rk4": 4, "euler": 1, "semi-implicit": 1}
HOLDS = ("linear", "zoh")


@dataclass
class ReplayReport:
    """One replay.

    Attributes:
        t: (K,) the sample instants replayed (the solved stretch of the trajectory).
        q, qd: (K, nv) integrated coordinates and rates at those instants.
        q_plan, qd_plan: (K, nv) the plan at those instants.
        error: (K,) ``max_i |q_i - q_plan_i|`` (rad or m) at each instant.
        integrator, hold: what was used; ``step``: the integration step, s; ``substeps`` per sample
            interval.
        first, last: indices (in the result) of the first and last instants replayed.
        stopped: why the replay ends before the trajectory does ('' if it does not).
        window: the replay restarts from the plan's state every ``window`` sample intervals
            (``None``: one replay over the whole stretch).
        growth_rate: the largest real part of the eigenvalues of the linearised dynamics under the
            first instant's forces, 1/s: open-loop errors grow like ``exp(growth_rate * t)``.
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    q_plan: np.ndarray
    qd_plan: np.ndarray
    integrator: str
    hold: str
    substeps: int
    step: float
    first: int
    last: int
    stopped: str = ""
    window: int | None = None
    growth_rate: float = float("nan")

    @property
    def error(self) -> np.ndarray:
        return np.abs(self.q - self.q_plan).max(axis=1)

    @property
    def max_error(self) -> float:
        return float(self.error.max())


@dataclass
class ConvergenceTable:
    """Replays with the step halved several times (:func:`convergence`)."""

    reports: list[ReplayReport]
    order: int  # the integrator's theoretical order
    self_error: np.ndarray = field(default_factory=lambda: np.zeros(0))  # max |q_h - q_{h/2}|
    observed_order: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def plan_error(self) -> np.ndarray:
        return np.array([r.max_error for r in self.reports])

    def rows(self) -> list[list[str]]:
        out = []
        for k, r in enumerate(self.reports):
            se = self.self_error[k] if k < len(self.self_error) else np.nan
            oo = self.observed_order[k] if k < len(self.observed_order) else np.nan
            po = (np.log2(r.max_error / self.reports[k + 1].max_error)
                  if k + 1 < len(self.reports) else np.nan)
            out.append([str(r.substeps), f"{r.step:.3e}", f"{r.max_error:.3e}",
                        "-" if not np.isfinite(po) else f"{po:.2f}",
                        "-" if not np.isfinite(se) else f"{se:.3e}",
                        "-" if not np.isfinite(oo) else f"{oo:.2f}"])
        return out


class _Dynamics:
    """qdd = ABA(q, qd, -L(q)^T f) for one robot (reuses Pinocchio data)."""

    def __init__(self, robot):
        self.robot = robot
        self.model = robot.model
        self.data = robot.model.createData()

    def generalised_cable_force(self, q, f) -> np.ndarray:
        r, model, data = self.robot, self.model, self.data
        pin.computeJointJacobians(model, data, r.pin_q(q))
        nj = model.njoints
        oMi = np.array([data.oMi[j].homogeneous for j in range(nj)])
        # reshape: for a 1-DoF model Pinocchio returns the 6 x 1 Jacobian as a flat (6,) array
        J = np.array([pin.getJointJacobian(model, data, j, pin.ReferenceFrame.WORLD).reshape(6, model.nv)
                      for j in range(nj)])
        geo = cable_geometry(r, oMi[:, :3, :3], oMi[:, :3, 3])
        L = np.einsum("jkm,jkn->mn", geo.W, J)
        return -L.T @ f

    def __call__(self, q, qd, f) -> np.ndarray:
        tau = self.generalised_cable_force(q, f)
        return np.array(pin.aba(self.model, self.data, self.robot.pin_q(q), qd, tau))

    def growth_rate(self, q, qd, f, eps: float = 1e-6) -> float:
        """Largest real part of the eigenvalues of d(q, qd)/dt linearised at (q, qd) under forces f."""
        n = len(q)
        Jq, Jv = np.zeros((n, n)), np.zeros((n, n))
        for i in range(n):
            d = np.zeros(n)
            d[i] = eps
            Jq[:, i] = (self(q + d, qd, f) - self(q - d, qd, f)) / (2 * eps)
            Jv[:, i] = (self(q, qd + d, f) - self(q, qd - d, f)) / (2 * eps)
        A = np.block([[np.zeros((n, n)), np.eye(n)], [Jq, Jv]])
        return float(np.linalg.eigvals(A).real.max())


def _check_result(robot, result) -> None:
    if list(result.cable_names) != list(robot.cable_names):
        raise ResultsError(f"the results file's cables {list(result.cable_names)[:5]}... do not match "
                           f"robot {robot.name!r}'s {list(robot.cable_names)[:5]}...: wrong robot?")
    if list(result.coordinate_names) != list(robot.coordinate_names):
        raise ResultsError(f"the results file's coordinates {list(result.coordinate_names)} do not match "
                           f"robot {robot.name!r}'s {list(robot.coordinate_names)}: wrong robot?")


def solved_stretch(result) -> tuple[int, int, str]:
    """(first, last, why it stops): the first solved instant and the end of the run of solved
    instants that follows it."""
    found = np.asarray(result.found)
    if not found.any():
        raise ResultsError("no instant of the run was solved: nothing to replay")
    first = int(np.argmax(found))
    bad = np.flatnonzero(~found[first:])
    if len(bad) == 0:
        return first, len(found) - 1, ""
    last = first + int(bad[0]) - 1
    k = last + 1
    return first, last, (f"the replay stops at t = {result.t[last]:g} s: instant {k} (t = "
                         f"{result.t[k]:g} s) has no valid forces ({result.status[k]})")


def replay(robot, result, integrator: str = "rk4", substeps: int = 1, hold: str = "linear",
           forces: Callable[[float], np.ndarray] | None = None,
           window: int | None = None) -> ReplayReport:
    """Integrate the forward dynamics under the result's cable forces (module docstring).

    Args:
        robot: the :class:`~mcdm_pin.robot.Robot` the result was computed for.
        result: a :class:`~mcdm_pin.results.TrajectoryResult` (``q``, ``qd``, ``f`` at instants ``t``).
        integrator: ``rk4`` (classical Runge-Kutta, order 4), ``euler`` (explicit, order 1) or
            ``semi-implicit`` (symplectic Euler: velocity first, then position with the new velocity;
            order 1).
        substeps: integration steps per sample interval (the step is ``(t[k+1] - t[k]) / substeps``).
        hold: ``linear`` (forces interpolated linearly between instants) or ``zoh`` (held).
        forces: optional callable ``t -> f`` used instead of the samples (e.g. :func:`resolved_forces`).
        window: restart from the plan's state every ``window`` sample intervals. Under force control
            a cable robot can be open-loop unstable (the 8-vertebra neck: errors grow like
            ``exp(350 t)``), so a replay over the whole run measures rounding amplified by
            ``exp(growth_rate * T)``; windows keep the amplification bounded.

    Returns:
        a :class:`ReplayReport`; it starts at the first solved instant and ends before the next
        instant without valid forces.
    """
    if integrator not in INTEGRATORS:
        raise ResultsError(f"integrator: expected one of {', '.join(INTEGRATORS)}, got {integrator!r}")
    if hold not in HOLDS:
        raise ResultsError(f"hold: expected one of {', '.join(HOLDS)}, got {hold!r}")
    if not (isinstance(substeps, (int, np.integer)) and substeps >= 1):
        raise ResultsError(f"substeps: expected a positive integer, got {substeps!r}")
    if window is not None and not (isinstance(window, (int, np.integer)) and window >= 1):
        raise ResultsError(f"window: expected a positive integer or None, got {window!r}")
    _check_result(robot, result)
    first, last, stopped = solved_stretch(result)
    if last <= first:
        raise ResultsError(f"only one solved instant (t = {result.t[first]:g} s) before an unsolved one: "
                           f"nothing to integrate. {stopped}")
    t, F = np.asarray(result.t, float), np.asarray(result.f, float)
    dyn = _Dynamics(robot)

    def force_at(tt, k):
        """Forces at time tt inside sample interval [t_k, t_{k+1}]."""
        if forces is not None:
            return np.asarray(forces(tt), float)
        if hold == "zoh":
            return F[k]
        s = (tt - t[k]) / (t[k + 1] - t[k])
        return (1.0 - s) * F[k] + s * F[k + 1]

    def acc(q, qd, tt, k):
        return dyn(q, qd, force_at(tt, k))

    q, qd = np.array(result.q[first], float), np.array(result.qd[first], float)
    growth = dyn.growth_rate(q, qd, force_at(t[first], first))
    qs, qds = [q.copy()], [qd.copy()]
    steps = []
    for k in range(first, last):
        if window is not None and (k - first) % window == 0:
            q, qd = np.array(result.q[k], float), np.array(result.qd[k], float)
        h = (t[k + 1] - t[k]) / substeps
        steps.append(h)
        for s in range(substeps):
            t0 = t[k] + s * h
            if integrator == "rk4":
                a1 = acc(q, qd, t0, k)
                q2, v2 = q + 0.5 * h * qd, qd + 0.5 * h * a1
                a2 = acc(q2, v2, t0 + 0.5 * h, k)
                q3, v3 = q + 0.5 * h * v2, qd + 0.5 * h * a2
                a3 = acc(q3, v3, t0 + 0.5 * h, k)
                q4, v4 = q + h * v3, qd + h * a3
                a4 = acc(q4, v4, t0 + h, k)
                q = q + h / 6.0 * (qd + 2 * v2 + 2 * v3 + v4)
                qd = qd + h / 6.0 * (a1 + 2 * a2 + 2 * a3 + a4)
            elif integrator == "euler":
                a1 = acc(q, qd, t0, k)
                q, qd = q + h * qd, qd + h * a1
            else:  # semi-implicit Euler
                qd = qd + h * acc(q, qd, t0, k)
                q = q + h * qd
            if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd))):
                raise TrajectoryError(
                    f"the replay diverged at t = {t0 + h:g} s (step {h:g} s, {integrator}); the "
                    f"dynamics under these forces grow errors like exp({growth:.3g} t) (linearised at "
                    f"t = {t[first]:g} s): " + ("take a smaller step" if growth * (t[last] - t[first])
                                                 < 30 else "restart from the plan every few instants "
                                                           "(window / --window)"))
        qs.append(q.copy())
        qds.append(qd.copy())
    sl = slice(first, last + 1)
    return ReplayReport(t=t[sl].copy(), q=np.array(qs), qd=np.array(qds), q_plan=np.array(result.q[sl], float),
                        qd_plan=np.array(result.qd[sl], float), integrator=integrator,
                        hold="callable" if forces is not None else hold, substeps=int(substeps),
                        step=float(np.max(steps)), first=first, last=last, stopped=stopped,
                        window=window, growth_rate=growth)


def convergence(robot, result, integrator: str = "rk4", substeps: int = 1, levels: int = 5,
                hold: str = "linear", forces=None, window: int | None = None) -> ConvergenceTable:
    """Replays with ``substeps, 2 substeps, ..., 2^(levels-1) substeps`` per sample interval, the
    Richardson self-error ``max |q_h - q_{h/2}|`` and the observed order ``log2`` of its ratio."""
    if levels < 2:
        raise ResultsError(f"levels: expected at least 2, got {levels!r}")
    reports = [replay(robot, result, integrator, substeps * 2**k, hold, forces, window)
               for k in range(levels)]
    self_err = np.array([np.abs(a.q - b.q).max() for a, b in zip(reports, reports[1:])])
    with np.errstate(divide="ignore", invalid="ignore"):
        obs = np.log2(self_err[:-1] / self_err[1:])
    return ConvergenceTable(reports, ORDER[integrator], self_err, obs)


# ------------------------------------------------------------------------------- dense forces
def planned_state(robot, spec) -> Callable[[float], tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """The plan of a sidecar trajectory at any time: ``t -> (q, qd, qdd)``.

    Quintic trajectories are evaluated exactly (spherical joints about one fixed axis, as
    :func:`~mcdm_pin.trajectory.quintic_trajectory`); CSV trajectories through the same quintic spline
    that gives their rates.
    """
    from .trajectory import (SphericalKinematics, csv_trajectory, quintic_profile,
                             quintic_trajectory, resolve_configuration)

    if spec.type == "csv":
        from scipy.interpolate import make_interp_spline

        tr = csv_trajectory(robot, spec.file, name=spec.name)
        spline = make_interp_spline(tr.t, tr.q, k=5)
        return lambda tt: (spline(tt), spline(tt, 1), spline(tt, 2))
    path = robot.sidecar.path
    q0 = resolve_configuration(robot, spec.q_start, f"{spec.key}.q_start", path)
    q1 = resolve_configuration(robot, spec.q_end, f"{spec.key}.q_end", path)
    T = spec.duration
    sph = []
    if spec.spherical == "axis-angle":
        for joint in robot.joints:
            if joint.type == "spherical":
                kin = SphericalKinematics(robot, joint)
                R0 = kin.rotation(q0[joint.idx_v])
                sph.append((joint.idx_v, kin, R0, pin.log3(R0.T @ kin.rotation(q1[joint.idx_v]))))
    # Newton starts from the nearest sample of the sampled trajectory (the same branch of angles)
    samples = quintic_trajectory(robot, q0, q1, T, spec.dt, spec.spherical, name=spec.name) if sph else None

    def state(tt):
        s, ds, dds = (float(x[0]) for x in quintic_profile(np.array([float(tt)]), T))
        q, qd, qdd = q0 + s * (q1 - q0), ds * (q1 - q0), dds * (q1 - q0)
        for iv, kin, R0, phi in sph:
            k = int(np.clip(np.rint(tt / spec.dt), 0, len(samples) - 1))
            th = kin.angles(R0 @ pin.exp3(phi * s), samples.q[k, iv])
            q[iv] = th
            qd[iv], qdd[iv] = kin.rates(th, ds * phi, dds * phi)
        return q, qd, qdd

    return state


def resolved_forces(ident, plan) -> Callable[[float], np.ndarray]:
    """``t -> f``: the inverse-dynamics problem re-solved on the planned state at time ``t``
    (``ident``: an :class:`~mcdm_pin.inverse_dynamics.InverseDynamics`; ``plan``: :func:`planned_state`).
    Raises :class:`TrajectoryError` at a time where it has no valid answer."""
    cache: dict[float, np.ndarray] = {}

    def forces(tt):
        key = float(tt)
        if key not in cache:
            res = ident.solve(*plan(key))
            if not res.found:
                raise TrajectoryError(f"re-solving the forces at t = {key:g} s: {res.status} "
                                      f"({res.message})")
            cache[key] = res.f
        return cache[key]

    return forces


def problem_from_run(robot, result):
    """Rebuild the paper-case problem of a run written by ``mcdm-pin solve`` (its ``problem`` string
    ``case N: minimise ... subject to ...`` and its ``cone_deg``), for :func:`resolved_forces`.

    Raises :class:`ResultsError` for problems it cannot rebuild exactly (smoothing, cable weights,
    problems built in code)."""
    import ast
    import re

    from .problem import case_problem

    text = str(result.problem)
    m = re.match(r"^(?:case [123]: )?minimise (.*) subject to (.*)$", text)
    if not m or "Smoothing" in text or "MinCableForceSum" in text:
        raise ResultsError(f"cannot rebuild the problem of this run from {text!r}: only the paper's "
                           f"cases without smoothing can be re-solved")
    objective = m.group(1)
    case = 1 if objective.startswith("MinCableForces") else 3 if "InteractionCone" in m.group(2) else 2
    alpha = beta = None
    if case == 1:
        if objective != "MinCableForces()":
            raise ResultsError(f"cannot rebuild objective {objective!r} (case 1 with cable weights)")
    else:
        mi = re.match(r"^MinInteractions\(alpha=(.*), beta=(.*)\)$", objective)
        if not mi:
            raise ResultsError(f"cannot rebuild objective {objective!r}")
        alpha, beta = (None if g == "sidecar" else ast.literal_eval(g) for g in mi.groups())
    cones = frame = None
    if case == 3:
        cones = {str(j): float(c) for j, c in zip(result.joint_names, result.cone_deg) if np.isfinite(c)}
        fm = re.search(r"frame='(socket|child)'", text)
        frame = fm.group(1) if fm else "socket"
    return case_problem(robot, case, alpha=alpha, beta=beta, cones=cones, frame=frame or "socket")
