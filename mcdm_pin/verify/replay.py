"""The replay itself: integrate the forward dynamics under a run's cable forces (package docstring)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import pinocchio as pin

from ..exceptions import ResultsError
from ..model.geometry import cable_geometry
from .routed import RoutedL

INTEGRATORS = ("rk4", "euler", "semi-implicit")
ORDER = {"rk4": 4, "euler": 1, "semi-implicit": 1}
HOLDS = ("linear", "zoh")


@dataclass
class ReplayReport:
    """One replay.

    Attributes:
        t: (K,) the sample instants replayed (the solved stretch of the trajectory).
        q, qd: (K, nq) integrated configurations and (K, nv) velocities at those instants (NaN after
            a divergence).
        q_plan, qd_plan: (K, nq), (K, nv) the plan at those instants.
        error: (K,) ``max_i |difference(q_plan, q)_i|`` (rad or m) at each instant (``inf`` after a
            divergence).
        integrator, hold: what was used; ``step``: the integration step, s; ``substeps`` per sample
            interval.
        first, last: indices (in the result) of the first and last instants replayed.
        stopped: why the replay ends before the trajectory does ('' if it does not).
        window: the replay restarts from the plan's state every ``window`` sample intervals
            (``None``: one replay over the whole stretch).
        growth_rate: the largest real part of the eigenvalues of the linearised dynamics under the
            first instant's forces, 1/s: open-loop errors grow like ``exp(growth_rate * t)``.
        diverged_at: time, s, at which the state stopped being finite (``None``: it stayed finite).
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    q_plan: np.ndarray
    qd_plan: np.ndarray
    error: np.ndarray
    integrator: str
    hold: str
    substeps: int
    step: float
    first: int
    last: int
    stopped: str = ""
    window: int | None = None
    growth_rate: float = float("nan")
    diverged_at: float | None = None

    @property
    def max_error(self) -> float:
        return float(self.error.max())


@dataclass
class ConvergenceTable:
    """Replays with the step halved several times (:func:`convergence`).

    Attributes:
        reports: one :class:`ReplayReport` per level (step halved from one to the next).
        order: the integrator's theoretical order.
        self_error: (levels - 1,) ``max |q_h - q_h/2|`` between consecutive levels (``inf`` where a
            level diverged).
        observed_order: (levels - 2,) ``log2`` of the ratio of consecutive self errors.
        growth_rate, growth_at: the largest open-loop growth rate over a few instants of the run,
            1/s, and the time where it was found (:func:`open_loop_growth`).
    """

    reports: list[ReplayReport]
    order: int
    self_error: np.ndarray = field(default_factory=lambda: np.zeros(0))
    observed_order: np.ndarray = field(default_factory=lambda: np.zeros(0))
    growth_rate: float = float("nan")
    growth_at: float = float("nan")

    @property
    def plan_error(self) -> np.ndarray:
        return np.array([r.max_error for r in self.reports])

    @property
    def plan_order(self) -> np.ndarray:
        """(levels - 1,) ``log2`` of the ratio of consecutive plan errors."""
        e = self.plan_error
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.log2(e[:-1] / e[1:])

    def rows(self) -> list[list[str]]:
        out = []
        po = self.plan_order
        for k, r in enumerate(self.reports):
            se = self.self_error[k] if k < len(self.self_error) else np.nan
            oo = self.observed_order[k] if k < len(self.observed_order) else np.nan
            pk = po[k] if k < len(po) else np.nan
            err = (f"diverged at t = {r.diverged_at:g} s" if r.diverged_at is not None
                   else f"{r.max_error:.3e}")
            out.append([str(r.substeps), f"{r.step:.3e}", err, _num(pk, ".2f"), _num(se, ".3e"),
                        _num(oo, ".2f")])
        return out


def _num(x, fmt: str) -> str:
    return f"{x:{fmt}}" if np.isfinite(x) else "-"


class _Dynamics:
    r"""The forward dynamics of one robot under cable forces and actuator torques (reuses Pinocchio
    data): ``u`` is ``f`` (m, N) followed by the actuators' ``tau_act`` (n_act, N m or N), and

    .. math:: \tau = -L(q)^T f + S\,\tau_{act} + \tau_{passive}(q, v) - L_s(q)^T f_s(q)

    (``f_s``: the passive springs' known tensions ``k (l - l0)``).

    ``L`` comes from numpy, not from the cable-terms kernel that computed the forces: the replay checks
    them independently. Fixed routes: the reference cable geometry (:mod:`mcdm_pin.model.geometry`);
    routes over wraps: their path from :mod:`mcdm_pin.model.routes` (checked against MuJoCo on its
    own) and the segments' Jacobians (:mod:`mcdm_pin.verify.routed`).

    Without couplings ``a = ABA(q, v, tau)``. With couplings (:mod:`mcdm_pin.model.couplings`) the
    replay integrates all ``nv`` coordinates under the couplings' constraint forces, solved from the full
    equation of motion, not from the projected one the solver uses: each coupling
    :math:`g_c(q) = y_c - p_c(x_c) = 0` (dependent :math:`y_c`, independent :math:`x_c`; :math:`x_c`
    absent for a fixed coordinate) contributes a row of :math:`G = \partial g/\partial q`
    (:math:`+1` at :math:`y_c`, :math:`-p_c'(x_c)` at :math:`x_c`) and

    .. math:: \begin{bmatrix} M & G^T \\ G & 0 \end{bmatrix}
              \begin{bmatrix} \ddot q \\ -\lambda \end{bmatrix} =
              \begin{bmatrix} \tau - h(q, v) \\ \gamma \end{bmatrix}, \qquad
              \gamma_c = p_c''(x_c)\,\dot x_c^2,

    (``M`` from CRBA, ``h`` from RNEA at zero acceleration; the second row is :math:`\ddot g = 0`).
    :math:`\lambda_c` is the generalised force coupling ``c`` applies to its dependent coordinate
    (N m or N); it applies :math:`-p_c'\lambda_c` to the independent one, so it does no work along the
    couplings. Drift off the couplings is left to the integrator (it is of its order, and part of the
    error against the plan)."""

    def __init__(self, robot):
        from ..model.actuators import actuation_matrix

        self.robot = robot
        self.model = robot.model
        self.data = robot.model.createData()
        self.passive = getattr(robot, "passive", None)
        self.m = robot.m
        self.S = actuation_matrix(robot.nv, robot.actuators) if robot.actuators else None
        self.couplings = getattr(robot, "couplings", None)
        self._routed = RoutedL(robot) if robot.cables.configuration_dependent else None
        self._springs = None
        springs = getattr(robot, "springs", None)
        if springs is not None:  # passive springs: known tensions k (l - l0) at every state
            from ..model.terms import TermsEvaluator

            self._springs = (springs, TermsEvaluator(robot.model, springs.geometry, robot.joints, compiled=False))

    def generalised_cable_force(self, q, f) -> np.ndarray:
        if self._routed is not None:
            return -self._routed(q).T @ f
        model, data = self.model, self.data
        pin.computeJointJacobians(model, data, q)
        nj = model.njoints
        oMi = np.array([data.oMi[j].homogeneous for j in range(nj)])
        # reshape: for a 1-DoF model Pinocchio returns the 6 x 1 Jacobian as a flat (6,) array
        J = np.array([pin.getJointJacobian(model, data, j, pin.ReferenceFrame.WORLD).reshape(6, model.nv)
                      for j in range(nj)])
        geo = cable_geometry(self.robot.cables, oMi[:, :3, :3], oMi[:, :3, 3])
        L = np.einsum("jkm,jkn->mn", geo.W, J)
        return -L.T @ f

    def joint_force(self, q, v, u) -> np.ndarray:
        """``tau`` (nv) of the cables, actuators and known joint forces (class docstring)."""
        u = np.asarray(u, dtype=float)
        tau = self.generalised_cable_force(q, u[:self.m])
        if self.S is not None:
            tau = tau + self.S @ u[self.m:]
        if self.passive is not None:
            tau = tau + self.passive(q, v)
        if self._springs is not None:
            springs, ev = self._springs
            zero = np.zeros(self.model.nv)
            st = ev(q, zero, zero, checked=True)
            tau = tau - st.L.T @ springs.forces(st.lengths)
        return tau

    def constraint_rows(self, q, v) -> tuple[np.ndarray, np.ndarray]:
        """``(G, gamma)`` of the couplings at ``(q, v)`` (class docstring), one row per coupling."""
        cs = self.couplings
        G, gamma = np.zeros((len(cs.items), self.model.nv)), np.zeros(len(cs.items))
        for r, c in enumerate(cs.items):
            G[r, c.dependent] = 1.0
            if c.independent >= 0:
                _, dp, ddp = c.value(float(q[cs.q_index[c.independent]]))
                G[r, c.independent] -= dp
                xd = v[c.independent]
                gamma[r] = ddp * xd * xd
        return G, gamma

    def solve(self, q, v, u) -> tuple[np.ndarray, np.ndarray]:
        """``(a, lambda)``: the acceleration (nv) and the couplings' constraint forces (empty without
        couplings) under ``u`` at ``(q, v)``; NaN once the state is not finite (a diverging replay)."""
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
            k = 0 if self.couplings is None else len(self.couplings.items)
            return np.full(self.model.nv, np.nan), np.full(k, np.nan)
        tau = self.joint_force(q, v, u)
        if self.couplings is None:
            return np.array(pin.aba(self.model, self.data, q, v, tau)), np.zeros(0)
        M = pin.crba(self.model, self.data, q)
        M = np.triu(M) + np.triu(M, 1).T  # crba fills the upper triangle
        h = pin.rnea(self.model, self.data, q, v, np.zeros(self.model.nv))
        G, gamma = self.constraint_rows(q, v)
        n, k = len(v), len(gamma)
        K = np.block([[M, G.T], [G, np.zeros((k, k))]])
        x = np.linalg.solve(K, np.concatenate([tau - h, gamma]))
        return x[:n], -x[n:]

    def __call__(self, q, v, u) -> np.ndarray:
        return self.solve(q, v, u)[0]

    def growth_rate(self, q, v, f, eps: float = 1e-6) -> float:
        """Largest real part of the eigenvalues of d(q, v)/dt linearised at (q, v) under forces f
        (perturbations of q in the tangent space, through ``pin.integrate``)."""
        n = self.model.nv
        Jq, Jv = np.zeros((n, n)), np.zeros((n, n))
        for i in range(n):
            d = np.zeros(n)
            d[i] = eps
            qp, qm = (pin.integrate(self.model, q, s * d) for s in (1.0, -1.0))
            Jq[:, i] = (self(qp, v, f) - self(qm, v, f)) / (2 * eps)
            Jv[:, i] = (self(q, v + d, f) - self(q, v - d, f)) / (2 * eps)
        A = np.block([[np.zeros((n, n)), np.eye(n)], [Jq, Jv]])
        return float(np.linalg.eigvals(A).real.max())


def _check_result(robot, result) -> None:
    where = f" ({robot.sidecar.path})" if getattr(robot, "sidecar", None) is not None else ""
    for what, key, cut in (("cables", "cable_names", 5), ("coordinates", "coordinate_names", None)):
        got = [str(s) for s in getattr(result, key)]  # plain text, not numpy's np.str_('...')
        want = [str(s) for s in getattr(robot, key)]
        if got != want:
            more = "..." if cut is not None and max(len(got), len(want)) > cut else ""
            raise ResultsError(f"the results file's {what} {got[:cut]}{more} do not match those of robot "
                               f"{robot.name}{where}: {want[:cut]}{more}; wrong robot?")


def _configurations(robot, result) -> np.ndarray:
    """(N, nq) the run's configurations (older files hold coordinates only)."""
    conf = np.asarray(result.configuration, float)
    if conf.ndim == 2 and conf.shape[1] == robot.nq:
        return conf
    return np.array([robot.configuration(x) for x in np.asarray(result.q, float)]).reshape(-1, robot.nq)


def _inputs(robot, result) -> np.ndarray:
    """(N, m + n_act) the run's cable forces followed by its actuator torques (hybrid robots, reserves)."""
    F = np.asarray(result.f, float)
    n_act = sum(len(a.idx_v) for a in robot.actuators)
    if n_act == 0:
        return F
    tau = np.asarray(result.tau_act, float).reshape(len(F), -1)
    if tau.shape[1] != n_act:
        raise ResultsError(f"the results file has {tau.shape[1]} actuator torque column(s); robot {robot.name} "
                           f"has {n_act} actuator components")
    return np.hstack([F, tau])


def _checked_inputs(robot, u, tt) -> np.ndarray:
    u = np.asarray(u, float).reshape(-1)
    n = robot.m + sum(len(a.idx_v) for a in robot.actuators)
    if len(u) != n:
        raise ResultsError(f"forces(t = {tt:g}) returned {len(u)} values; expected the {robot.m} cable "
                           f"forces followed by the {n - robot.m} actuator torques")
    return u


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


def _check_options(integrator, hold, substeps, window) -> None:
    if integrator not in INTEGRATORS:
        raise ResultsError(f"integrator: expected one of {', '.join(INTEGRATORS)}, got {integrator!r}")
    if hold not in HOLDS:
        raise ResultsError(f"hold: expected one of {', '.join(HOLDS)}, got {hold!r}")
    if not (isinstance(substeps, (int, np.integer)) and substeps >= 1):
        raise ResultsError(f"substeps: expected a positive integer, got {substeps!r}")
    if window is not None and not (isinstance(window, (int, np.integer)) and window >= 1):
        raise ResultsError(f"window: expected a positive integer or None, got {window!r}")


def _stepper(model, integrator: str, acc):
    """One step ``(q, v, t0, h) -> (q, v)`` of the integrator. Positions move through
    ``pin.integrate``; on robots with quaternion joints RK4 is Runge-Kutta-Munthe-Kaas (stage
    velocities mapped back to the step's tangent space by ``dIntegrate``), which keeps order 4."""
    euclidean = model.nq == model.nv

    def tangent(q, omega, v):
        if euclidean:
            return v
        J = pin.dIntegrate(model, q, omega, pin.ArgumentPosition.ARG1)
        return np.linalg.solve(J, v)

    def rk4(q, v, t0, h):
        a1 = acc(q, v, t0)
        k1 = v
        w2 = 0.5 * h * k1
        v2 = v + 0.5 * h * a1
        a2 = acc(pin.integrate(model, q, w2), v2, t0 + 0.5 * h)
        k2 = tangent(q, w2, v2)
        w3 = 0.5 * h * k2
        v3 = v + 0.5 * h * a2
        a3 = acc(pin.integrate(model, q, w3), v3, t0 + 0.5 * h)
        k3 = tangent(q, w3, v3)
        w4 = h * k3
        v4 = v + h * a3
        a4 = acc(pin.integrate(model, q, w4), v4, t0 + h)
        k4 = tangent(q, w4, v4)
        return (pin.integrate(model, q, h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)),
                v + h / 6.0 * (a1 + 2 * a2 + 2 * a3 + a4))

    def euler(q, v, t0, h):
        return pin.integrate(model, q, h * v), v + h * acc(q, v, t0)

    def semi_implicit(q, v, t0, h):  # velocity first, then position with the new velocity
        v = v + h * acc(q, v, t0)
        return pin.integrate(model, q, h * v), v

    return {"rk4": rk4, "euler": euler, "semi-implicit": semi_implicit}[integrator]


def replay(robot, result, integrator: str = "rk4", substeps: int = 1, hold: str = "linear",
           forces: Callable[[float], np.ndarray] | None = None,
           window: int | None = None, growth_rate: float | None = None) -> ReplayReport:
    """Integrate the forward dynamics under the result's cable forces (package docstring).

    Args:
        robot: the :class:`~mcdm_pin.robot.Robot` the result was computed for.
        result: a :class:`~mcdm_pin.results.TrajectoryResult` (``q``, ``qd``, ``f`` at instants ``t``).
        integrator: ``rk4`` (classical Runge-Kutta, order 4), ``euler`` (explicit, order 1) or
            ``semi-implicit`` (symplectic Euler: velocity first, then position with the new velocity;
            order 1).
        substeps: integration steps per sample interval (the step is ``(t[k+1] - t[k]) / substeps``).
        hold: ``linear`` (forces interpolated linearly between instants) or ``zoh`` (held).
        forces: optional callable ``t -> f`` used instead of the samples (e.g. :func:`resolved_forces`);
            on robots with actuators it returns ``f`` followed by ``tau_act``.
        window: restart from the plan's state every ``window`` sample intervals. Under force control
            a cable robot can be open-loop unstable (the 8-vertebra neck: errors grow like
            ``exp(350 t)``), so a replay over the whole run measures rounding amplified by
            ``exp(growth_rate * T)``; windows keep the amplification bounded.
        growth_rate: the open-loop growth rate at the first solved instant, when already known (a
            replay of the same run at another step): not computed again.

    Returns:
        a :class:`ReplayReport`; it starts at the first solved instant and ends before the next
        instant without valid forces. When the state stops being finite the report says when
        (``diverged_at``) and its error is ``inf`` from there on.
    """
    _check_options(integrator, hold, substeps, window)
    _check_result(robot, result)
    first, last, stopped = solved_stretch(result)
    if last <= first:
        raise ResultsError(f"only one solved instant (t = {result.t[first]:g} s) before an unsolved one: "
                           f"nothing to integrate. {stopped}")
    t, F = np.asarray(result.t, float), _inputs(robot, result)
    Q, V = _configurations(robot, result), np.asarray(result.qd, float)
    dyn = _Dynamics(robot)
    model = robot.model

    def force_at(tt, k):
        """Forces (and actuator torques) at time tt inside sample interval [t_k, t_{k+1}]."""
        if forces is not None:
            return _checked_inputs(robot, forces(tt), tt)
        if hold == "zoh":
            return F[k]
        s = (tt - t[k]) / (t[k + 1] - t[k])
        return (1.0 - s) * F[k] + s * F[k + 1]

    q, v = Q[first].copy(), V[first].copy()
    growth = dyn.growth_rate(q, v, force_at(t[first], first)) if growth_rate is None else float(growth_rate)
    qs, vs = [q.copy()], [v.copy()]
    steps = []
    diverged_at = None
    for k in range(first, last):
        if window is not None and (k - first) % window == 0:
            q, v = Q[k].copy(), V[k].copy()
        h = (t[k + 1] - t[k]) / substeps
        steps.append(h)
        step = _stepper(model, integrator, lambda qq, vv, tt, k=k: dyn(qq, vv, force_at(tt, k)))
        with np.errstate(over="ignore", invalid="ignore"):
            for s in range(substeps):
                q, v = step(q, v, t[k] + s * h, h)
                if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
                    diverged_at = float(t[k] + (s + 1) * h)
                    break
        if diverged_at is not None:
            break
        qs.append(q.copy())
        vs.append(v.copy())
    sl = slice(first, last + 1)
    K = last - first + 1
    q_out, v_out = np.full((K, robot.nq), np.nan), np.full((K, robot.nv), np.nan)
    q_out[:len(qs)], v_out[:len(vs)] = qs, vs
    error = np.full(K, np.inf)
    for i in range(len(qs)):
        error[i] = np.abs(pin.difference(model, Q[first + i], q_out[i])).max()
    return ReplayReport(t=t[sl].copy(), q=q_out, qd=v_out, q_plan=Q[sl].copy(), qd_plan=V[sl].copy(),
                        error=error, integrator=integrator,
                        hold="callable" if forces is not None else hold, substeps=int(substeps),
                        step=float(np.max(steps)), first=first, last=last, stopped=stopped,
                        window=window, growth_rate=growth, diverged_at=diverged_at)


def open_loop_growth(robot, result, instants: int = 5, hold: str = "linear") -> tuple[float, float]:
    """(rate 1/s, time s): the largest open-loop growth rate of the dynamics under the run's forces,
    linearised at ``instants`` solved instants spread over the replayed stretch (the first among
    them), and where it was found."""
    first, last, _ = solved_stretch(result)
    Q, V, F = _configurations(robot, result), np.asarray(result.qd, float), _inputs(robot, result)
    dyn = _Dynamics(robot)
    best = (-np.inf, float(result.t[first]))
    for k in np.unique(np.linspace(first, last, max(1, instants)).round().astype(int)):
        rate = dyn.growth_rate(Q[k], V[k], F[k])
        if rate > best[0]:
            best = (rate, float(result.t[k]))
    return best


def convergence(robot, result, integrator: str = "rk4", substeps: int = 1, levels: int = 5,
                hold: str = "linear", forces=None, window: int | None = None) -> ConvergenceTable:
    """Replays with ``substeps, 2 substeps, ..., 2^(levels-1) substeps`` per sample interval, the
    Richardson self-error ``max |q_h - q_h/2|`` and the observed order ``log2`` of its ratio."""
    if levels < 2:
        raise ResultsError(f"levels: expected at least 2, got {levels!r}")
    reports = [replay(robot, result, integrator, substeps, hold, forces, window)]
    reports += [replay(robot, result, integrator, substeps * 2**k, hold, forces, window,
                       growth_rate=reports[0].growth_rate) for k in range(1, levels)]
    model = robot.model

    def self_error(a, b):
        if a.diverged_at is not None or b.diverged_at is not None:
            return np.inf
        return max(np.abs(pin.difference(model, x, y)).max() for x, y in zip(a.q, b.q))

    self_err = np.array([self_error(a, b) for a, b in zip(reports, reports[1:])])
    with np.errstate(divide="ignore", invalid="ignore"):
        obs = np.log2(self_err[:-1] / self_err[1:])
    rate, at = open_loop_growth(robot, result)
    return ConvergenceTable(reports, ORDER[integrator], self_err, obs, rate, at)
