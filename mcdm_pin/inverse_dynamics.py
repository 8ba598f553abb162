"""State -> terms -> problem -> solver chain -> check -> result, for one instant or a whole trajectory.

Every answer is checked before it is returned: the solver chain's last stage checks the KKT conditions
(:mod:`mcdm_pin.solvers.check`), and here the equation-of-motion residual, the bounds and the cones
must hold on the *original* problem to the tolerances of :mod:`mcdm_pin.tolerances`, otherwise the
instant is reported ``inaccurate`` (no point that silently breaks a constraint is returned as optimal).
An infeasible instant is diagnosed (:func:`diagnose_infeasible`): the message says whether the cable
bounds or the cones cannot be met, and the f_max or cone angle that would do
(:mod:`mcdm_pin.solvers.margins`).
"""

from __future__ import annotations

import sys
import time

import numpy as np

from . import jit
from . import tolerances as tol
from .exceptions import ProblemError, StateError
from .objectives import Smoothing, Sum
from .problem import Context, Problem, QPData, case_problem
from .results import InstantResult, TrajectoryResult, concat_columns, instant_columns
from .scaling import ScaledSolver
from .solvers import ERROR, INACCURATE, INFEASIBLE, OPTIMAL, SOFTENED, Solution, get_solver
from .solvers.base import cone_violation_deg
from .model import charts
from .model.actuators import actuator_names
from .model.terms import TermsEvaluator, interaction_angles

EOM_TOL = tol.EOM_REL
BOUND_TOL = tol.BOUND_ABS
CONE_TOL_DEG = tol.CONE_DEG


class InverseDynamics:
    """Solve an inverse-dynamics problem on a robot, instant by instant.

    Args:
        robot: the :class:`~mcdm_pin.robot.Robot`.
        problem: a :class:`~mcdm_pin.problem.Problem` (or use :meth:`for_case`).
        solver: a back-end name (``default``, ``compiled``, ``proxqp``, ``clarabel``; see
            :mod:`mcdm_pin.solvers.cascade`) or a :class:`~mcdm_pin.solvers.Solver`.
        soften: for instants where the cones cannot be met, return the forces with every cone at
            least at the smallest common half-angle that makes the instant feasible (status
            ``softened``) instead of ``infeasible``.
        diagnose: for infeasible instants, find what conflicts and the f_max or cone angle that
            would make them feasible (:func:`diagnose_infeasible`: an LP and a few cone programs).
            Off: the message only says that the instant is infeasible.
        budget_s: per-instant time budget of the solver chain, seconds (``None``: none): a solve
            that has not answered by then is reported with status ``budget``. While the kernels run
            uncompiled it is multiplied by :data:`mcdm_pin.jit.UNCOMPILED_SLOWDOWN`.
        blas_threads: threads the BLAS library may use while solving (default 1; ``None``: leave
            it alone). The matrices of one instant are small, and waking BLAS worker threads cost
            milliseconds on a loaded machine: with them the model of a 16-link chain's case 3 took
            5.56 ms per instant instead of 0.38 ms (``benchmarks/scaling.py``, docs/speed.md). The
            limit applies only inside ``solve`` and ``solve_trajectory`` (threadpoolctl) and is
            lifted afterwards.
    """

    def __init__(self, robot, problem: Problem, solver="default", soften: bool = False,
                 diagnose: bool = True, blas_threads: int | None = 1, budget_s: float | None = tol.BUDGET_S):
        self.robot = robot
        self.blas_threads = blas_threads
        self._blas = _BlasLimit()
        self.diagnose = diagnose
        self.problem = problem
        # the kernels run compiled when `mcdm-pin compile` has cached them, else as the same Python
        # functions (mcdm_pin/jit.py): one path, one answer. Uncompiled they take longer, and the
        # time budget grows by the same factor, so that an instant answers alike on both
        if not jit.prepare() and budget_s is not None:
            budget_s = budget_s * jit.UNCOMPILED_SLOWDOWN
        # every back-end solves a copy scaled to magnitudes of order one (mcdm_pin/scaling.py);
        # well-scaled problems pass straight through
        self.solver = ScaledSolver(get_solver(solver, budget_s=budget_s) if isinstance(solver, str) else solver)
        self.soften = soften
        self.evaluate = TermsEvaluator(robot)

    @classmethod
    def for_case(cls, robot, case: int, solver="default", soften: bool = False, diagnose: bool = True,
                 blas_threads: int | None = 1, budget_s: float | None = tol.BUDGET_S, **options):
        """The paper's case 1, 2 or 3 (options as :func:`~mcdm_pin.problem.case_problem`)."""
        return cls(robot, case_problem(robot, case, **options), solver=solver, soften=soften,
                   diagnose=diagnose, blas_threads=blas_threads, budget_s=budget_s)

    def reset(self) -> None:
        """Forget every warm start (the next instant is solved cold, as if it were the first)."""
        self.solver.reset()

    def blas_limit(self) -> "_BlasLimit":
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
            message, needed_f_max, needed_cone = diagnose_infeasible(qp, _variable_names(self.robot))
            if message.startswith("bounds"):
                from .conditioning import wrench_closure
                closure = wrench_closure(self.robot, terms.q, terms.L)
                if not closure.closed:
                    message = f"{message}; {closure.message}"
            elif message.startswith("solver"):
                sol = sol.but(status=INACCURATE)
            if self.soften and qp.cones and message.startswith("cone"):
                sol, softened = soften_cones(qp, self.solver, needed_cone)
                if sol.status == SOFTENED:
                    message = f"cones widened by {softened:.6g} deg: {message}"
        t2 = time.perf_counter()
        eom = float("nan")
        m = self.robot.m
        act = self.problem.actuation
        outputs = None
        if sol.found:
            # the answer checked on the original problem (and, compiled, the outputs in the same pass)
            sol, eom, outputs = _check(qp, terms, sol, m, act, with_outputs=True)
            message = sol.message or message
        f, tau_act = sol.x[:m], sol.x[m:]
        if sol.found:
            objective = (sol.objective if not self.problem.has_smoothing and np.isfinite(sol.objective)
                         else self.problem.value(terms, sol.x, context, qp))
        else:
            objective = float("nan")
        if outputs is None or not sol.found:
            outputs = _outputs(terms, f if sol.found else None, len(self.robot.joints), tau_act)
        wrench, F_socket, angles = outputs
        return InstantResult(
            f=f, status=sol.status, objective=objective, eom_residual=eom,
            interaction_wrench=wrench, interaction_force_socket=F_socket,
            interaction_angle_deg=angles, iterations=sol.iterations, rounds=sol.rounds,
            time_model_s=t1 - t0, time_solve_s=t2 - t1, message=message, softened_deg=softened,
            needed_f_max=needed_f_max, needed_cone_deg=needed_cone, unique=bool(sol.unique and sol.found),
            stage=sol.stage, tau_act=tau_act, activation=_activations(terms, f if sol.found else None, self.robot.cables))

    def solve_trajectory(self, traj, progress: bool | None = None, workers: int = 1) -> TrajectoryResult:
        """Solve every instant of ``traj`` in order, warm-starting each from the previous one. An
        instant at which the model is undefined (a cable segment of zero length) gets status
        ``error`` and the reason with its time in ``message``; the others are solved.

        Args:
            progress: show a progress bar (after 1.5 s) on a terminal; ``None``: when stderr is a tty.
            workers: processes to use (batch mode). The trajectory is cut into ``workers``
                contiguous pieces solved in parallel, each warm-started along itself (a piece starts
                solving three instants before its first own one, to warm up). Every instant's answer
                is the verified optimum of the same problem, and the least-norm one where the optimum
                is not unique, so the results equal the sequential run's to solver tolerance. Not with
                smoothing, whose every instant depends on the previous one.
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
            columns = self._solve_parallel(traj, min(workers, len(traj)), progress)
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
            from tqdm import tqdm
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

    def _solve_parallel(self, traj, workers: int, progress: bool) -> dict:
        import multiprocessing as mp

        global _BATCH
        bounds = np.linspace(0, len(traj), workers + 1).round().astype(int)
        pieces = [(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:]) if b > a]
        _BATCH = (self, traj)
        try:
            # fork: the workers inherit the robot, the problem and the trajectory without pickling
            with mp.get_context("fork").Pool(len(pieces)) as pool:
                chunks = pool.map(_solve_piece, pieces)
        finally:
            _BATCH = None
        return concat_columns(chunks)


_BATCH = None


class _BlasLimit:
    """:meth:`InverseDynamics.blas_limit`'s context: each BLAS library's own setter, its count
    restored on the way out (also after an exception; entries nest). A class, not a generator: it
    is entered at every :meth:`~InverseDynamics.solve` (threadpoolctl's ``limit()``, which asks every
    library for its whole description, ~15 us; a generator around the setters ~6 us; this, with the
    libraries' own functions (:func:`_blas_setters`), ~2 us)."""

    __slots__ = ("threads", "depth", "changed")

    def __init__(self):
        self.threads = None
        self.depth = 0
        self.changed = []

    def __enter__(self):
        if self.depth == 0 and self.threads is not None:
            try:
                for get, set_ in _blas_setters():
                    old = get()
                    if old != self.threads:
                        set_(self.threads)
                        self.changed.append((set_, old))
            except BaseException:
                self._restore()
                raise
        self.depth += 1
        return self

    def __exit__(self, *exc) -> bool:
        self.depth -= 1
        if self.depth == 0:
            self._restore()
        return False

    def _restore(self) -> None:
        changed = self.changed
        while changed:
            set_, old = changed.pop()
            set_(old)


_CONTROLLER = None


def _blas_setters():
    """``(get, set)`` of each loaded BLAS library's thread count (listed once): OpenBLAS's own C
    functions where threadpoolctl names them (``openblas_get_num_threads``, ``..._set_...`` with the
    library's symbol affixes, its pthreads build: one process-wide count), else threadpoolctl's
    methods. The C functions skip threadpoolctl's check of which Python thread controls OpenBLAS;
    the limit is set and restored within one call, so two threads solving at once with the same
    ``blas_threads`` only run each other's BLAS calls at the limit meanwhile and leave the count as
    they found it (with different limits at once, the last to leave restores what it found, which
    may be the other's limit: as before, threadpoolctl's own setters did not order them either). In
    a solve's time: ~0.2 us a call instead of ~1-3 us (an eighth of the instant's Python, measured
    on the neck's cold instants: the limit cost 18 us of 0.52 ms)."""
    global _BLAS_SETTERS
    if _BLAS_SETTERS is None:
        out = []
        for lib in _blas_controller().select(user_api="blas").lib_controllers:
            get = set_ = None
            symbol = getattr(lib, "_get_symbol", None)
            if getattr(lib, "internal_api", "") == "openblas" and getattr(lib, "threading_layer", "") == "pthreads" \
                    and symbol is not None:
                get, set_ = symbol("openblas_get_num_threads"), symbol("openblas_set_num_threads")
            out.append((get, set_) if get is not None and set_ is not None else (lib.get_num_threads,
                                                                                 lib.set_num_threads))
        _BLAS_SETTERS = tuple(out)
    return _BLAS_SETTERS


_BLAS_SETTERS = None


def _blas_controller():
    """threadpoolctl's view of the loaded BLAS libraries (made once: it scans them, ~1.5 ms)."""
    global _CONTROLLER
    if _CONTROLLER is None:
        import scipy.linalg  # noqa: F401  (load scipy's BLAS too, so that it is limited as well)
        from threadpoolctl import ThreadpoolController

        _CONTROLLER = ThreadpoolController()
    return _CONTROLLER


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


_OVERLAP = 3  # instants a batch piece solves before its own first one, to warm its solver up


def _solve_piece(piece):
    ident, traj = _BATCH
    start, stop = piece
    # a piece starts a few instants early (answers discarded) so that its first own instant is
    # warm-started like in the sequential run, not solved cold by a different path
    lead = min(_OVERLAP, start)
    instants = ident._solve_range(traj, range(start - lead, stop))[lead:]
    # stacked arrays travel back to the parent far faster than a list of per-instant objects
    return instant_columns(instants)


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


def _activations(terms, f, cables) -> np.ndarray:
    """The muscles' activations at tensions ``f`` ((m,), NaN on other cables and where ``f`` is
    ``None``); (0,) for a robot without muscles."""
    if terms.muscles is None:
        return np.zeros(0)
    out = np.full(cables.m, np.nan)
    if f is not None:
        from .model.muscles import activation

        out[cables.muscle_index] = activation(terms.muscles, f[cables.muscle_index])
    return out


def _check(qp: QPData, terms, sol: Solution, m: int, actuation=None, with_outputs: bool = False):
    """Downgrade a solution that breaks a constraint beyond tolerance to ``inaccurate``. Returns the
    solution and its relative equation-of-motion residual (``m`` cables; ``actuation``: the problem's
    actuated joints, whose torques follow the cable forces in ``sol.x``); ``with_outputs``: and the
    :func:`_outputs` at its forces when they came in the same compiled pass (else ``None``)."""
    f = sol.x
    problems = []
    extra = None if actuation is None else -actuation.rows(terms) @ f[m:]
    outputs = None
    if jit.ready():  # one compiled pass, the same formulas
        fast = jit.kernels("solvers._fast")
        _, _, _, lb, ub, G, g, axis = qp.kernel_arrays()[:8]
        c_ = np.ascontiguousarray
        args = (c_(terms.L, dtype=float), c_(terms.tau, dtype=float),
                _NO_1 if extra is None else c_(extra, dtype=float), c_(f, dtype=float), lb, ub, G, g, axis,
                c_(qp.cone_consts()[1], dtype=float))
        if with_outputs:
            eom, broken, worst, k, *outputs = fast.answer_check_outputs(
                *args, c_(_u_of(terms, f[m:]), dtype=float), c_(terms.RT, dtype=float), c_(terms.R_socket, dtype=float),
                c_(terms.socket_axes, dtype=float))
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
    if not eom <= tol.EOM_REL:
        problems.append(f"equation-of-motion residual {eom:.2e} > {tol.EOM_REL:g}")
    if not broken <= tol.BOUND_ABS:
        problems.append(f"cable (or actuator) bounds broken by {broken:.2e}")
    if qp.cones and sol.status == OPTIMAL and not worst <= tol.CONE_DEG:
        problems.append(f"cone of {qp.cones[k].joint!r} broken by {worst:.2e} deg")
    if problems:
        sol = sol.but(status=INACCURATE, message="; ".join(problems))
    return (sol, eom, outputs) if with_outputs else (sol, eom)


_NO_1 = np.zeros(0)


def diagnose_infeasible(qp: QPData, cable_names=None):
    """What cannot be met at an infeasible instant, and what would make it feasible.

    Returns ``(message, needed_f_max, needed_cone_deg)``:

    - bounds alone (equation of motion within the bounds, an LP decided by HiGHS): the message names
      the cables whose bounds must give (an elastic LP: the least total violation) and
      ``needed_f_max`` is the smallest common upper bound that would do
      (:func:`~mcdm_pin.solvers.margins.needed_f_max`; ``inf``: none would, the cables would have to
      push);
    - the cones: ``needed_cone_deg`` is the smallest common half-angle of all cones that makes the
      instant feasible (:func:`~mcdm_pin.solvers.margins.needed_cone_deg`, a few cone programs), and
      the message names the cones that bind there;
    - neither (the bounds' LP is feasible and there is no cone): the solver's infeasibility was
      false; the message starts with ``solver`` and the caller reports the instant ``inaccurate``.
    """
    from .solvers.margins import needed_cone_deg, needed_f_max

    names = list(cable_names) if cable_names is not None else [f"cable {i}" for i in range(qp.n)]
    nan = float("nan")
    if _feasible_lp(qp) is None:
        below, above = _elastic_bounds(qp)
        parts = []
        if above:
            parts.append("above f_max: " + ", ".join(names[i] for i in above))
        if below:
            parts.append("below f_min: " + ", ".join(names[i] for i in below))
        need = needed_f_max(qp.without_cones())
        tail = (f"; a common f_max of {need:.6g} N would suffice" if np.isfinite(need) else
                "; no f_max suffices (some cable would have to push)")
        where = f" (the least change needs forces {'; '.join(parts)})" if parts else ""
        return ("bounds: the equation of motion cannot be met with cable forces within "
                f"[f_min, f_max]{where}{tail}", need, nan)
    if not qp.cones:
        return ("solver: reported infeasible, but the equation of motion can be met within the bounds "
                "(a numerical failure of the solver)", nan, nan)
    need = needed_cone_deg(qp)
    if len(qp.cones) == 1:
        cone = qp.cones[0]
        where = (f"feasible from {need:.4f} deg" if need < 90.0 else
                 "only a half-space would do: the force must lie in the socket's plane" if need == 90.0 else
                 "no cone will do: the force must point out of the socket")
        return (f"cone: the stability cone of {cone.joint} ({cone.angle_deg:g} deg; {where}) cannot be met "
                f"within the cable bounds", nan, float(need))
    names_c = ", ".join(f"{c.joint} ({c.angle_deg:g} deg)" for c in qp.cones)
    if not need < 90.0:
        return (f"cones: the stability cones of {names_c} cannot be met together within the cable bounds; "
                f"{'only half-spaces would do' if need == 90.0 else 'no common cone will do: a force must point out of its socket'}",
                nan, float(need))
    binding = _binding_cones(qp, need)
    return (f"cones: the stability cones of {names_c} cannot be met together within the cable bounds; "
            f"a common half-angle of {need:.4f} deg would do (binding there: {', '.join(binding)})",
            nan, float(need))


def _binding_cones(qp: QPData, angle_deg: float) -> list[str]:
    """The cones at their limit when every cone is at ``angle_deg`` (solved by Clarabel)."""
    if not np.isfinite(angle_deg) or angle_deg >= 90.0:
        return [c.joint for c in qp.cones]
    from .solvers.clarabel_ import clarabel_solve

    wide = qp.with_cones([c.with_angle(max(c.angle_deg, angle_deg) + 1e-6) for c in qp.cones])
    sol = clarabel_solve(wide)
    if sol.status != OPTIMAL:
        return [c.joint for c in qp.cones]
    return [c.joint for c in wide.cones if c.angle_of(sol.x) >= angle_deg - 1e-3]


def _feasible_lp(qp: QPData):
    from scipy.optimize import linprog

    res = linprog(np.zeros(qp.n), A_eq=qp.A if len(qp.b) else None, b_eq=qp.b if len(qp.b) else None,
                  bounds=list(zip(qp.lb, qp.ub)), method="highs")
    return res.x if res.status == 0 else None


def _elastic_bounds(qp: QPData, rel: float = 1e-9):
    """Cables whose bounds must give, by the least total violation (relative to each bound)."""
    from scipy.optimize import linprog

    n = qp.n
    w_lo = 1.0 / (1.0 + np.abs(qp.lb))
    w_hi = 1.0 / (1.0 + np.abs(qp.ub))
    c = np.concatenate([np.zeros(n), w_lo, w_hi])
    eye = np.eye(n)
    A_ub = np.block([[-eye, -eye, np.zeros((n, n))], [eye, np.zeros((n, n)), -eye]])
    b_ub = np.concatenate([-qp.lb, qp.ub])
    A_eq = np.hstack([qp.A, np.zeros((len(qp.b), 2 * n))])
    res = linprog(c, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=qp.b,
                  bounds=[(None, None)] * n + [(0, None)] * (2 * n), method="highs")
    if res.status != 0:
        return [], []
    s_lo, s_hi = res.x[n:2 * n], res.x[2 * n:]
    return (np.flatnonzero(s_lo > rel * (1.0 + np.abs(qp.lb))).tolist(),
            np.flatnonzero(s_hi > rel * (1.0 + np.abs(qp.ub))).tolist())


def soften_cones(qp: QPData, solver, needed: float | None = None) -> tuple[Solution, float]:
    """Every cone at least at the smallest common half-angle that makes the instant feasible
    (``needed``: that angle when known), solved there. Returns the solution (status ``softened``)
    and the largest widening, degrees."""
    from .solvers.margins import needed_cone_deg

    need = needed_cone_deg(qp) if needed is None or not np.isfinite(needed) else needed
    if not np.isfinite(need) or need >= 90.0:
        return Solution(np.full(qp.n, np.nan), INFEASIBLE, float("nan"),
                        message="no force presses the balls into their sockets at all"), 0.0
    # a hair above the limit: at exactly the limit the feasible set is a single point
    angle = min(need + 1e-7, 89.999999)
    cones = [c.with_angle(max(c.angle_deg, angle)) for c in qp.cones]
    sol = solver.fresh().solve(qp.with_cones(cones))
    widening = max(c.angle_deg - c0.angle_deg for c, c0 in zip(cones, qp.cones))
    if sol.status != OPTIMAL:
        return sol, widening
    return sol.but(status=SOFTENED), widening


def _variable_names(robot) -> list[str]:
    """The unknowns' names: the cables, then the actuator components (hybrid robots)."""
    return list(robot.cable_names) + actuator_names(robot)

