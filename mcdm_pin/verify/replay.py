"""The replay itself: integrate the forward dynamics under a run's cable forces (package docstring)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import pinocchio as pin

from ..exceptions import ResultsError
from ..model.geometry import cable_geometry

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
    """``a = ABA(q, v, -L(q)^T f + tau_passive(q, v) - L_s^T f_s(q))`` for one robot (``f_s``: the
    passive springs' known tensions) (reuses Pinocchio data). ``L``
    comes from the numpy reference of the cable geometry (:mod:`mcdm_pin.model.geometry`), not from the
    compiled kernels that computed the forces: the replay checks them independently. Routes over wraps
    take their path from :mod:`mcdm_pin.model.routes` (checked against MuJoCo on its own). A robot
    with coupled coordinates is refused: its replay needs the couplings' constraint forces."""

    def __init__(self, robot):
        from ..exceptions import ModelError

        if getattr(robot, "couplings", None) is not None:
            raise ModelError(f"robot {robot.name!r} couples coordinates ({len(robot.couplings)} couplings): "
                             f"verify does not replay coupled coordinates (their constraint forces are "
                             f"not integrated)")
        self.robot = robot
        self.model = robot.model
        self.data = robot.model.createData()
        self.passive = getattr(robot, "passive", None)
        self._routed = self._springs = None
        springs = getattr(robot, "springs", None)
        if springs is not None:  # passive springs: known tensions k (l - l0) at every state
            from ..model.terms import TermsEvaluator

            self._springs = (springs, TermsEvaluator(robot.model, springs.geometry, robot.joints, compiled=False))
        if robot.cables.configuration_dependent:
            from ..model.terms import TermsEvaluator

            self._routed = TermsEvaluator(robot, compiled=False)

    def generalised_cable_force(self, q, f) -> np.ndarray:
        if self._routed is not None:
            zero = np.zeros(self.model.nv)
            return -self._routed(q, zero, zero, checked=True).L_full.T @ f
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

    def __call__(self, q, v, f) -> np.ndarray:
        tau = self.generalised_cable_force(q, f)
        if self.passive is not None:
            tau = tau + self.passive(q, v)
        if self._springs is not None:
            springs, ev = self._springs
            zero = np.zeros(self.model.nv)
            st = ev(q, zero, zero, checked=True)
            tau = tau - st.L.T @ springs.forces(st.lengths)
        return np.array(pin.aba(self.model, self.data, q, v, tau))

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
           window: int | None = None) -> ReplayReport:
    """Integrate the forward dynamics under the result's cable forces (package docstring).

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
        instant without valid forces. When the state stops being finite the report says when
        (``diverged_at``) and its error is ``inf`` from there on.
    """
    _check_options(integrator, hold, substeps, window)
    _check_result(robot, result)
    first, last, stopped = solved_stretch(result)
    if last <= first:
        raise ResultsError(f"only one solved instant (t = {result.t[first]:g} s) before an unsolved one: "
                           f"nothing to integrate. {stopped}")
    t, F = np.asarray(result.t, float), np.asarray(result.f, float)
    Q, V = _configurations(robot, result), np.asarray(result.qd, float)
    dyn = _Dynamics(robot)
    model = robot.model

    def force_at(tt, k):
        """Forces at time tt inside sample interval [t_k, t_{k+1}]."""
        if forces is not None:
            return np.asarray(forces(tt), float)
        if hold == "zoh":
            return F[k]
        s = (tt - t[k]) / (t[k + 1] - t[k])
        return (1.0 - s) * F[k] + s * F[k + 1]

    q, v = Q[first].copy(), V[first].copy()
    growth = dyn.growth_rate(q, v, force_at(t[first], first))
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
    Q, V, F = _configurations(robot, result), np.asarray(result.qd, float), np.asarray(result.f, float)
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
    reports = [replay(robot, result, integrator, substeps * 2**k, hold, forces, window)
               for k in range(levels)]
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
