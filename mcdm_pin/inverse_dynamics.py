"""State -> terms -> problem -> solver chain -> check -> result, for one instant or a whole trajectory.

Every answer is checked before it is returned: the solver chain's last stage checks the KKT conditions
(:mod:`mcdm_pin.solvers.check`), and here the equation-of-motion residual, the bounds and the cones
must hold on the *original* problem to the runner's settings (:class:`~mcdm_pin.settings.Settings`), otherwise the
instant is reported ``inaccurate`` (no point that silently breaks a constraint is returned as optimal).
An infeasible instant is diagnosed (:func:`~mcdm_pin.diagnosis.diagnose_infeasible`): the message
says whether the cable bounds or the cones cannot be met, and the f_max or cone angle that would do.
A trajectory is solved in order, or in pieces on Dask (:mod:`mcdm_pin.batch`).
"""

from __future__ import annotations

import sys
import time

import numpy as np

from . import jit
from .batch import solve_batch
from .blas import BlasLimit
from .conditioning import wrench_closure
from .diagnosis import diagnose_infeasible, soften_cones, variable_names
from .exceptions import ProblemError, StateError
from .model import charts
from .model.muscles import activation
from .model.terms import TermsEvaluator, interaction_angles
from .objectives import Smoothing, Sum
from .problem import Context, Problem, case_problem
from .qp import QPData
from .results import InstantResult, TrajectoryResult, instant_columns
from .scaling import ScaledSolver
from .settings import DEFAULT, Settings
from .solvers import ERROR, INACCURATE, INFEASIBLE, OPTIMAL, SOFTENED, Solution, get_solver
from .solvers._structs import Tensions
from .solvers.base import cone_violation_deg

class InverseDynamics:
    """Solve an inverse-dynamics problem on a robot, instant by instant.

    Args:
        robot: the :class:`~mcdm_pin.robot.Robot`.
        problem: a :class:`~mcdm_pin.problem.Problem` (or use :meth:`for_case`).
        solver: a back-end name (``default``, ``compiled``, ``proxqp``, ``clarabel``; see
            :mod:`mcdm_pin.solvers.chains`) or a :class:`~mcdm_pin.solvers.Solver`.
        soften: for instants where the cones cannot be met, return the forces with every cone at
            least at the smallest common half-angle that makes the instant feasible (status
            ``softened``) instead of ``infeasible``.
        diagnose: for infeasible instants, find what conflicts and the f_max or cone angle that
            would make them feasible (:func:`diagnose_infeasible`: an LP and a few cone programs).
            Off: the message only says that the instant is infeasible.
        settings: the tolerances, pivot limits and time budget (:class:`~mcdm_pin.settings.Settings`),
            passed to the solver chain built from a name, to the answer check and to the diagnosis. A
            solve that has not answered within ``settings.budget_s`` is reported with status
            ``budget``; while the kernels run uncompiled the budget is multiplied by
            :data:`mcdm_pin.jit.UNCOMPILED_SLOWDOWN`. A :class:`~mcdm_pin.solvers.Solver` given
            keeps the settings it was built with.
        blas_threads: threads the BLAS library may use while solving (default 1; ``None``: leave
            it alone). The matrices of one instant are small, and waking BLAS worker threads cost
            milliseconds on a loaded machine: with them the model of a 16-link chain's case 3 took
            5.56 ms per instant instead of 0.38 ms (``benchmarks/scaling.py``, docs/speed.md). The
            limit applies only inside ``solve`` and ``solve_trajectory`` (threadpoolctl) and is
            lifted afterwards.
    """

    def __init__(self, robot, problem: Problem, solver="default", soften: bool = False,
                 diagnose: bool = True, blas_threads: int | None = 1, settings: Settings = DEFAULT):
        self.robot = robot
        self.blas_threads = blas_threads
        self._blas = BlasLimit()
        self.solver_spec, self.settings = solver, settings  # as given (batch mode rebuilds from them)
        self.diagnose = diagnose
        self.problem = problem
        # the kernels run compiled when `mcdm-pin compile` has cached them, else as the same Python
        # functions (mcdm_pin/jit.py): one path, one answer. Uncompiled they take longer, and the
        # time budget grows by the same factor, so that an instant answers alike on both
        budget_s = settings.budget_s
        if not jit.prepare() and budget_s is not None:
            budget_s = budget_s * jit.UNCOMPILED_SLOWDOWN
        # every back-end solves a copy scaled to magnitudes of order one (mcdm_pin/scaling.py);
        # well-scaled problems pass straight through
        chain = get_solver(solver, settings.replace(budget_s=budget_s)) if isinstance(solver, str) else solver
        self.solver = ScaledSolver(chain)
        self.soften = soften
        self.evaluate = TermsEvaluator(robot)

    @classmethod
    def for_case(cls, robot, case: int, solver="default", soften: bool = False, diagnose: bool = True,
                 blas_threads: int | None = 1, settings: Settings = DEFAULT, **options):
        """The paper's case 1, 2 or 3 (options as :func:`~mcdm_pin.problem.case_problem`)."""
        return cls(robot, case_problem(robot, case, **options), solver=solver, soften=soften,
                   diagnose=diagnose, blas_threads=blas_threads, settings=settings)

    def reset(self) -> None:
        """Forget every warm start (the next instant is solved cold, as if it were the first)."""
        self.solver.reset()

    def blas_limit(self) -> BlasLimit:
        """A context in which BLAS runs ``blas_threads`` threads (once, when entries nest): :meth:`solve`
        enters it at every call; a caller solving many instants one by one (a workspace's chunk of
        poses) enters it once around them all."""
        self._blas.threads = self.blas_threads
        return self._blas

    @property
    def cone_deg(self) -> np.ndarray:
        out = np.full(len(self.robot.joints), np.nan)
        for c in self.problem.cone_constraints:
            out[self.robot.joint_names.index(c.joint)] = c.angle_deg
        return out

    def solve(self, q, qd=None, qdd=None, f_prev=None) -> InstantResult:
        """Cable forces at one state."""
        with self.blas_limit():
            return self._solve(q, qd, qdd, f_prev, checked=False)

    def _solve(self, q, qd, qdd, f_prev, checked: bool) -> InstantResult:
        """:meth:`solve` inside the BLAS limit; ``checked``: the state was validated already."""
        t0 = time.perf_counter()
        if not checked:  # (q once: the configuration's check is the evaluator's and more)
            q = self.robot.check_configuration(q)
            qd, qdd = self.evaluate.check_motion(qd, qdd)
            if self.robot.couplings is not None:  # coupled coordinates follow their couplings
                self.robot.couplings.check(q, qd, qdd)
        terms = self.evaluate(q, qd, qdd, checked=True)
        if not terms.finite and not (np.all(np.isfinite(terms.tau)) and np.all(np.isfinite(terms.L))):
            raise StateError("the dynamics overflow at this state (non-finite M qdd + h or L): check "
                             "the model's masses, lengths and the state's magnitude")
        context = Context(self.robot, f_prev)
        qp = self.problem.assemble(terms, context)
        t1 = time.perf_counter()
        sol = self.solver.solve(qp)
        message = sol.message
        softened = 0.0
        needed_f_max = needed_cone = float("nan")
        if sol.status == INFEASIBLE and self.diagnose:
            message, needed_f_max, needed_cone = diagnose_infeasible(qp, variable_names(self.robot), self.settings)
            if message.startswith("bounds"):
                closure = wrench_closure(self.robot, terms.q, terms.L)
                if not closure.closed:
                    message = f"{message}; {closure.message}"
            elif message.startswith("solver"):
                sol = sol.but(status=INACCURATE)
            if self.soften and qp.cones and message.startswith("cone"):
                sol, softened = soften_cones(qp, self.solver, needed_cone, self.settings)
                if sol.status == SOFTENED:
                    message = f"cones widened by {softened:.6g} deg: {message}"
        t2 = time.perf_counter()
        eom = float("nan")
        m = self.robot.m
        act = self.problem.actuation
        outputs = None
        if sol.found:
            # the answer checked on the original problem (and, compiled, the outputs in the same pass)
            sol, eom, outputs = _check(qp, terms, sol, m, self.settings, act, with_outputs=True,
                                       cables=self.robot.cables)
            message = sol.message or message
        f, tau_act = sol.x[:m], sol.x[m:]
        if sol.found:
            objective = (sol.objective if not self.problem.has_smoothing and np.isfinite(sol.objective)
                         else self.problem.value(terms, sol.x, context, qp))
        else:
            objective = float("nan")
        if outputs is None or not sol.found:
            forces = f if sol.found else None
            outputs = _outputs(terms, forces, len(self.robot.joints), tau_act) + (
                _activations(terms, forces, self.robot.cables, self.settings.bound_abs),)
        wrench, F_socket, angles, activations = outputs
        return InstantResult(
            f=f, status=sol.status, objective=objective, eom_residual=eom,
            interaction_wrench=wrench, interaction_force_socket=F_socket,
            interaction_angle_deg=angles, iterations=sol.iterations, rounds=sol.rounds,
            time_model_s=t1 - t0, time_solve_s=t2 - t1, message=message, softened_deg=softened,
            needed_f_max=needed_f_max, needed_cone_deg=needed_cone, unique=bool(sol.unique and sol.found),
            stage=sol.stage, tau_act=tau_act, activation=activations)

    def solve_trajectory(self, traj, progress: bool | None = None, workers: int = 1,
                         scheduler: str = "local") -> TrajectoryResult:
        """Solve every instant of ``traj`` in order, warm-starting each from the previous one. An
        instant at which the model is undefined (a cable segment of zero length) gets status
        ``error`` and the reason with its time in ``message``; the others are solved.

        Args:
            progress: show a progress bar (after 1.5 s) on a terminal; ``None``: when stderr is a tty.
            workers: pieces to solve in parallel (batch mode, :mod:`mcdm_pin.batch`). The trajectory
                is cut into ``workers`` contiguous pieces solved on Dask, each warm-started along
                itself; the results equal the sequential run's to solver tolerance. Not with
                smoothing, whose every instant depends on the previous one.
            scheduler: batch mode's Dask scheduler (:mod:`mcdm_pin.runtime`): ``local`` (default: a
                local cluster of ``workers`` processes), ``tcp://HOST:PORT`` or ``inline``.
        """
        if workers is None or workers < 1:
            raise ProblemError(f"workers must be a positive integer, got {workers!r}")
        if progress is None:
            progress = sys.stderr.isatty()
        traj = _check_trajectory(self.robot, traj)  # once, not per instant or per batch piece
        if workers > 1 and len(traj) > 1:
            if any(isinstance(t, Smoothing) for t in _terms_of(self.problem.objective)):
                raise ProblemError("batch mode (workers > 1) cannot be used with smoothing: each "
                                   "instant depends on the previous one")
            columns = solve_batch(self, traj, min(workers, len(traj)), scheduler)
        else:
            columns = instant_columns(self._solve_range(traj, range(len(traj)), progress))
        return TrajectoryResult.from_columns(
            self.robot, traj, columns, self.cone_deg, robot=self.robot.name,
            problem=self.problem.describe(), solver=self.solver.name, trajectory=traj.name,
            problem_json=self.problem.to_json())

    def _solve_range(self, traj, indices, progress=False) -> list[InstantResult]:
        with self.blas_limit():
            return self._solve_range_limited(traj, indices, progress)

    def _solve_range_limited(self, traj, indices, progress=False) -> list[InstantResult]:
        self.reset()
        instants: list[InstantResult] = []
        f_prev = None
        bar = None
        if progress:
            from tqdm import tqdm  # (imported only when a bar is shown: its import is slow)
            bar = tqdm(total=len(indices), delay=1.5, unit="inst", leave=False, file=sys.stderr)
        try:
            for k in indices:
                # the trajectory was checked as a whole (solve_trajectory) and BLAS is limited here
                try:
                    res = self._solve(traj.q[k], traj.qd[k], traj.qdd[k], f_prev, checked=True)
                except StateError as exc:  # the model is undefined at this instant alone
                    res = self._undefined(f"at t = {float(traj.t[k]):g} s (instant {k}): {exc}")
                instants.append(res)
                if res.found:
                    f_prev = res.f
                if bar is not None:
                    bar.update(1)
        finally:
            if bar is not None:
                bar.close()
        return instants

    def _undefined(self, message: str) -> InstantResult:
        """The result of an instant of a trajectory at which the model is undefined (a cable
        segment of zero length: the cable passes through its anchor; dynamics that overflow): status
        ``error``, the reason in ``message``, no forces (NaN rows); the other instants are solved."""
        nan = float("nan")
        J = len(self.robot.joints)
        return InstantResult(
            f=np.full(self.robot.m, nan), status=ERROR, objective=nan, eom_residual=nan,
            interaction_wrench=np.full((J, 6), nan), interaction_force_socket=np.full((J, 3), nan),
            interaction_angle_deg=np.full(J, nan), iterations=0, rounds=0, time_model_s=0.0,
            time_solve_s=0.0, message=message, tau_act=np.full(self.problem.n_variables - self.robot.m, nan))


def _check_trajectory(robot, traj):
    """Every state of ``traj`` is finite, with configurations of length nq and rates of length nv,
    and every configuration passes :func:`~mcdm_pin.model.charts.check_configuration` (unit
    quaternions) and follows the robot's couplings, as :meth:`InverseDynamics.solve` checks one
    (checked once, not per instant).
    Returns ``traj``, or a copy whose quaternions are normalised."""
    for name, n in (("q", robot.nq), ("qd", robot.nv), ("qdd", robot.nv)):
        x = getattr(traj, name)
        if not (isinstance(x, np.ndarray) and x.dtype == np.float64 and x.ndim == 2
                and x.shape[1] == n and x.shape[0] == len(traj)):
            for k in range(len(traj)):  # the per-state check names what is wrong
                robot.check_vector(x[k], f"{name}[{k}]", n)
            raise StateError(f"trajectory {traj.name!r}: {name} must be an array of shape "
                             f"({len(traj)}, {n})")
        if not np.all(np.isfinite(x)):
            k = int(np.flatnonzero(~np.all(np.isfinite(x), axis=1))[0])
            robot.check_vector(x[k], f"{name}[{k}]", n)
    q = charts.check_configurations(robot.model, traj.q, f"trajectory {traj.name!r}: q", robot._parts)
    couplings = getattr(robot, "couplings", None)
    if couplings is not None:  # coupled coordinates follow their couplings at every instant
        for k in range(len(traj)):
            try:
                couplings.check(q[k], traj.qd[k], traj.qdd[k])
            except StateError as exc:
                raise StateError(f"trajectory {traj.name!r}, instant {k} (t = {traj.t[k]:g} s): {exc}") from None
    if q is traj.q:
        return traj
    return type(traj)(traj.name, traj.t, q, traj.qd, traj.qdd)


def _terms_of(objective):
    return objective.terms if isinstance(objective, Sum) else [objective]


def _u_of(terms, tau_act):
    """``terms.u`` plus the closed loops' share of the actuator torques (``terms.RT_act``)."""
    RT_act = getattr(terms, "RT_act", None)
    if RT_act is None or tau_act is None or len(tau_act) == 0:
        return terms.u
    return terms.u + RT_act @ np.asarray(tau_act, dtype=float)


def _outputs(terms, f, n_joints: int, tau_act=None):
    """Interaction wrenches (child frame), socket-frame forces and their angles at forces ``f``
    (``None``: no answer, NaN wrenches) and actuator torques ``tau_act``."""
    if f is not None and jit.ready():  # one compiled pass, the same formulas
        c_ = np.ascontiguousarray
        return jit.kernels("solvers._fast").instant_outputs(c_(_u_of(terms, tau_act), dtype=float), c_(terms.RT, dtype=float),
                               c_(terms.R_socket, dtype=float), c_(terms.socket_axes, dtype=float),
                               c_(f, dtype=float))
    if f is None:
        wrench = np.full((n_joints, 6), np.nan)
    else:
        wrench = terms.wrenches(f if tau_act is None else np.concatenate([f, tau_act]))
    F_socket = np.einsum("jab,jb->ja", terms.R_socket, wrench[:, :3])
    return wrench, F_socket, interaction_angles(F_socket, terms.socket_axes)


def _activations(terms, f, cables, bound_abs: float) -> np.ndarray:
    """The muscles' activations at tensions ``f`` ((m,), NaN on other cables and where ``f`` is
    ``None``; ``bound_abs``: :func:`~mcdm_pin.model.muscles.activation`'s); (0,) for a robot without
    muscles."""
    if terms.muscles is None:
        return np.zeros(0)
    k = cables.muscle_index
    if f is not None and cables.all_muscles:  # no gather, no scatter
        return activation(terms.muscles, f, bound_abs)
    out = np.full(cables.m, np.nan)
    if f is not None:
        out[k] = activation(terms.muscles, f[k], bound_abs)
    return out


def _check(qp: QPData, terms, sol: Solution, m: int, settings: Settings, actuation=None,
           with_outputs: bool = False, cables=None):
    """Downgrade a solution that breaks a constraint beyond ``settings``' tolerances (``eom_rel``,
    ``bound_abs``, ``cone_deg``) to ``inaccurate``. Returns the
    solution and its relative equation-of-motion residual (``m`` cables; ``actuation``: the problem's
    actuated joints, whose torques follow the cable forces in ``sol.x``); ``with_outputs``: and the
    :func:`_outputs` at its forces with the :func:`_activations` (of ``cables``' muscles) when they
    came in the same compiled pass (else ``None``)."""
    f = sol.x
    problems = []
    extra = None if actuation is None else -(actuation.rows(terms) @ f[m:])  # (the product negated: exact)
    outputs = None
    if jit.ready():  # one compiled pass, the same formulas
        fast = jit.kernels("solvers._fast")
        _, _, _, lb, ub, G, g, axis = qp.kernel_arrays()[:8]
        c_ = np.ascontiguousarray
        args = (c_(terms.L, dtype=float), c_(terms.tau, dtype=float),
                _NO_1 if extra is None else c_(extra, dtype=float), c_(f, dtype=float), lb, ub, G, g, axis,
                c_(qp.cone_consts()[1], dtype=float))
        tensions = _tensions(terms, cables, settings.bound_abs) if with_outputs else None
        if tensions is not None:
            eom, broken, worst, k, *outputs = fast.answer_check_outputs(
                *args, c_(_u_of(terms, f[m:]), dtype=float), c_(terms.RT, dtype=float), c_(terms.R_socket, dtype=float),
                c_(terms.socket_axes, dtype=float), tuple(tensions))  # (a plain tuple: solvers._structs)
        else:
            eom, broken, worst, k = fast.answer_check(*args)
    else:
        eom = terms.eom_residual(f[:m], extra)
        broken = max(float((qp.lb - f).max(initial=0.0)), float((f - qp.ub).max(initial=0.0)))
        worst, k = 0.0, -1
        if qp.cones:
            viol = cone_violation_deg(qp, f)
            k = int(np.argmax(viol))
            worst = viol[k]
    if not eom <= settings.eom_rel:
        problems.append(f"equation-of-motion residual {eom:.2e} > {settings.eom_rel:g}")
    if not broken <= settings.bound_abs:
        problems.append(f"cable (or actuator) bounds broken by {broken:.2e}")
    if qp.cones and sol.status == OPTIMAL and not worst <= settings.cone_deg:
        problems.append(f"cone of {qp.cones[k].joint!r} broken by {worst:.2e} deg")
    if problems:
        sol = sol.but(status=INACCURATE, message="; ".join(problems))
    return (sol, eom, outputs) if with_outputs else (sol, eom)


def _tensions(terms, cables, bound_abs: float) -> Tensions | None:
    """The muscles' state as the compiled answer check takes it to give their activations
    (:class:`~mcdm_pin.solvers._structs.Tensions`; no muscles: an empty index), or ``None`` where
    the state's arrays do not match the muscles (:func:`_activations` then says what is wrong)."""
    state = terms.muscles
    if state is None:
        return Tensions(_NO_INDEX, _NO_1, _NO_1, _NO_1, float(bound_abs))
    if cables is None:
        return None
    c_ = np.ascontiguousarray
    k = cables.muscle_index
    passive, gain, a_min = c_(state.passive, dtype=float), c_(state.gain, dtype=float), c_(state.a_min, dtype=float)
    if not passive.shape == gain.shape == a_min.shape == k.shape:
        return None
    # (writable C arrays: a read-only one, as a broadcast a_min is, is a type of its own to numba)
    passive, gain, a_min = (a if a.flags.writeable else a.copy() for a in (passive, gain, a_min))
    return Tensions(c_(k, dtype=np.int64), passive, gain, a_min, float(bound_abs))


_NO_1 = np.zeros(0)
_NO_INDEX = np.zeros(0, dtype=np.int64)


__all__ = ["InverseDynamics", "diagnose_infeasible", "soften_cones"]
