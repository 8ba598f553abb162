"""State -> terms -> problem -> solver -> result, for one instant or a whole trajectory.

Every answer is checked before it is returned: the equation-of-motion residual, the cable bounds and
the cones must hold to the stated tolerances, otherwise the instant is reported ``inaccurate`` (no
point that silently breaks a constraint is returned as optimal). An infeasible instant is diagnosed:
the message says whether the cable bounds alone, a single cone, or the cones together cannot be met.
"""

from __future__ import annotations

import sys
import time
from contextlib import contextmanager

import numpy as np

from .exceptions import ProblemError, StateError
from .objectives import Smoothing, Sum
from .problem import Context, Problem, QPData, case_problem
from .results import InstantResult, TrajectoryResult, concat_columns, instant_columns
from .scaling import ScaledSolver
from .solvers import INACCURATE, INFEASIBLE, OPTIMAL, SOFTENED, Solution, get_solver
from .solvers.base import cone_violation_deg
from .model.terms import TermsEvaluator, interaction_angles

EOM_TOL = 1e-8  # relative equation-of-motion residual
BOUND_TOL = 1e-9  # N
CONE_TOL_DEG = 1e-6  # degrees


class InverseDynamics:
    """Solve an inverse-dynamics problem on a robot, instant by instant.

    Args:
        robot: the :class:`~mcdm_pin.robot.Robot`.
        problem: a :class:`~mcdm_pin.problem.Problem` (or use :meth:`for_case`).
        solver: a back-end name (``proxqp``, ``clarabel``) or a :class:`~mcdm_pin.solvers.Solver`.
        soften: for instants where the cones cannot be met, return the forces that make the largest
            cone violation smallest (status ``softened``) instead of ``infeasible``.
        diagnose: for infeasible instants, find what conflicts and the f_max or cone angle that
            would make them feasible (:func:`diagnose_infeasible`; a few LPs and, for cones, a
            bisection of ~20 solves). Off: the message only says that the instant is infeasible.
        blas_threads: threads the BLAS library may use while solving (default 1; ``None``: leave
            it alone). The matrices of one instant are small, and waking BLAS worker threads cost
            milliseconds on a loaded machine: with them the model of a 16-link chain's case 3 took
            5.56 ms per instant instead of 0.38 ms (``benchmarks/scaling.py``, docs/speed.md). The
            limit applies only inside ``solve`` and ``solve_trajectory`` (threadpoolctl) and is
            lifted afterwards.
    """

    def __init__(self, robot, problem: Problem, solver="proxqp", soften: bool = False,
                 diagnose: bool = True, blas_threads: int | None = 1):
        self.robot = robot
        self.blas_threads = blas_threads
        self._limited = False
        self.diagnose = diagnose
        self.problem = problem
        # badly scaled robots (grams next to tonnes, mm next to m) are solved on an equilibrated
        # copy; well-scaled ones pass straight through (mcdm_pin/scaling.py)
        self.solver = ScaledSolver(get_solver(solver))
        self.soften = soften
        self.evaluate = TermsEvaluator(robot)
        from .model.kernels import warm_up

        warm_up()  # compiled kernels ready before the first (timed) instant

    @classmethod
    def for_case(cls, robot, case: int, solver="proxqp", soften: bool = False, diagnose: bool = True,
                 blas_threads: int | None = 1, **options):
        """The paper's case 1, 2 or 3 (options as :func:`~mcdm_pin.problem.case_problem`)."""
        return cls(robot, case_problem(robot, case, **options), solver=solver, soften=soften,
                   diagnose=diagnose, blas_threads=blas_threads)

    @contextmanager
    def _blas_limit(self):
        """BLAS limited to ``blas_threads`` threads inside (once, when calls nest)."""
        if self.blas_threads is None or self._limited:
            yield
            return
        self._limited = True
        try:
            with _blas_controller().limit(limits=self.blas_threads, user_api="blas"):
                yield
        finally:
            self._limited = False

    @property
    def cone_deg(self) -> np.ndarray:
        out = np.full(len(self.robot.joints), np.nan)
        for c in self.problem.cone_constraints:
            out[self.robot.joint_names.index(c.joint)] = c.angle_deg
        return out

    def solve(self, q, qd=None, qdd=None, f_prev=None) -> InstantResult:
        """Cable forces at one state."""
        with self._blas_limit():
            return self._solve(q, qd, qdd, f_prev, checked=False)

    def _solve(self, q, qd, qdd, f_prev, checked: bool) -> InstantResult:
        """:meth:`solve` inside the BLAS limit; ``checked``: the state was validated already."""
        t0 = time.perf_counter()
        if not checked:
            q = self.robot.check_configuration(q)
        terms = self.evaluate(q, qd, qdd, checked=checked)
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
            message, needed_f_max, needed_cone = diagnose_infeasible(qp, self.solver,
                                                                     self.robot.cable_names)
            if message.startswith("bounds"):
                from .conditioning import wrench_closure
                closure = wrench_closure(self.robot, terms.q, terms.L)
                if not closure.closed:
                    message = f"{message}; {closure.message}"
            if self.soften and qp.cones and not message.startswith("bounds"):
                sol, softened = soften_cones(qp, self.solver)
                if sol.status == SOFTENED:
                    message = f"cones widened by {softened:.6g} deg: {message}"
        t2 = time.perf_counter()
        eom = float("nan")
        if sol.found:
            sol, eom = _check(qp, terms, sol)
            message = sol.message or message
        f = sol.f
        if sol.found:
            wrench = terms.wrenches(f)
            objective = (sol.objective if not self.problem.has_smoothing and np.isfinite(sol.objective)
                         else self.problem.value(terms, f, context, qp))
        else:
            wrench = np.full((len(self.robot.joints), 6), np.nan)
            objective = float("nan")
        F_socket = np.einsum("jab,jb->ja", terms.R_socket, wrench[:, :3])
        angles = interaction_angles(F_socket, terms.socket_axes)
        return InstantResult(
            f=f, status=sol.status, objective=objective, eom_residual=eom,
            interaction_wrench=wrench, interaction_force_socket=F_socket,
            interaction_angle_deg=angles, iterations=sol.iterations, rounds=sol.rounds,
            time_model_s=t1 - t0, time_solve_s=t2 - t1, message=message, softened_deg=softened,
            needed_f_max=needed_f_max, needed_cone_deg=needed_cone)

    def solve_trajectory(self, traj, progress: bool | None = None, workers: int = 1) -> TrajectoryResult:
        """Solve every instant of ``traj`` in order, warm-starting each from the previous one.

        Args:
            progress: show a progress bar (after 1.5 s) on a terminal; ``None``: when stderr is a tty.
            workers: processes to use (batch mode). The trajectory is cut into ``workers``
                contiguous pieces solved in parallel, each warm-started along itself (a piece starts
                solving three instants before its first own one, to warm up). Every instant's answer is the verified optimum of the
                same problem, so the results equal the sequential run's to solver tolerance (for
                problems whose optimum is unique: the forces too). Not with smoothing, whose
                every instant depends on the previous one.
        """
        if workers is None or workers < 1:
            raise ProblemError(f"workers must be a positive integer, got {workers!r}")
        if progress is None:
            progress = sys.stderr.isatty()
        _check_trajectory(self.robot, traj)  # once, not per instant or per batch piece
        if workers > 1 and len(traj) > 1:
            if any(isinstance(t, Smoothing) for t in _terms_of(self.problem.objective)):
                raise ProblemError("batch mode (workers > 1) cannot be used with smoothing: each "
                                   "instant depends on the previous one")
            columns = self._solve_parallel(traj, min(workers, len(traj)), progress)
        else:
            columns = instant_columns(self._solve_range(traj, range(len(traj)), progress))
        return TrajectoryResult.from_columns(
            self.robot, traj, columns, self.cone_deg, robot=self.robot.name,
            problem=self.problem.describe(), solver=self.solver.name, trajectory=traj.name)

    def _solve_range(self, traj, indices, progress=False) -> list[InstantResult]:
        with self._blas_limit():
            return self._solve_range_limited(traj, indices, progress)

    def _solve_range_limited(self, traj, indices, progress=False) -> list[InstantResult]:
        self.solver.reset()
        instants: list[InstantResult] = []
        f_prev = None
        bar = None
        if progress:
            from tqdm import tqdm
            bar = tqdm(total=len(indices), delay=1.5, unit="inst", leave=False, file=sys.stderr)
        try:
            for k in indices:
                # the trajectory was checked as a whole (solve_trajectory) and BLAS is limited here
                res = self._solve(traj.q[k], traj.qd[k], traj.qdd[k], f_prev, checked=True)
                instants.append(res)
                if res.found:
                    f_prev = res.f
                if bar is not None:
                    bar.update(1)
        finally:
            if bar is not None:
                bar.close()
        return instants

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
_CONTROLLER = None


def _blas_controller():
    """threadpoolctl's view of the loaded BLAS libraries (made once: it scans them, ~1.5 ms)."""
    global _CONTROLLER
    if _CONTROLLER is None:
        import scipy.linalg  # noqa: F401  (load scipy's BLAS too, so that it is limited as well)
        from threadpoolctl import ThreadpoolController

        _CONTROLLER = ThreadpoolController()
    return _CONTROLLER


def _check_trajectory(robot, traj) -> None:
    """Every state of ``traj`` is finite, with configurations of length nq and rates of length nv
    (checked once, not per instant)."""
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


def _check(qp: QPData, terms, sol: Solution) -> tuple[Solution, float]:
    """Downgrade a solution that breaks a constraint beyond tolerance to ``inaccurate``. Returns the
    solution and its relative equation-of-motion residual."""
    f = sol.f
    problems = []
    eom = terms.eom_residual(f)
    if not eom <= EOM_TOL:
        problems.append(f"equation-of-motion residual {eom:.2e} > {EOM_TOL:g}")
    broken = max(float((qp.lb - f).max(initial=0.0)), float((f - qp.ub).max(initial=0.0)))
    if not broken <= BOUND_TOL:
        problems.append(f"cable bounds broken by {broken:.2e} N")
    if qp.cones and sol.status == OPTIMAL:
        viol = cone_violation_deg(qp, f)
        if not viol.max() <= CONE_TOL_DEG:
            k = int(np.argmax(viol))
            problems.append(f"cone of {qp.cones[k].joint!r} broken by {viol[k]:.2e} deg")
    if not problems:
        return sol, eom
    return Solution(sol.f, INACCURATE, sol.objective, sol.iterations, sol.rounds, "; ".join(problems)), eom


def diagnose_infeasible(qp: QPData, solver, cable_names=None):
    """What cannot be met at an infeasible instant, and what would make it feasible.

    Returns ``(message, needed_f_max, needed_cone_deg)``:

    - bounds alone (equation of motion within ``[f_min, f_max]``, an LP decided by HiGHS): the
      message names the cables whose bounds must give (an elastic LP: the least total violation) and
      ``needed_f_max`` is the smallest common upper bound that would do (``inf``: none would, the
      cables would have to push);
    - one cone alone: named, with ``needed_cone_deg`` its smallest feasible half-angle (bisection
      to 1e-4 deg);
    - only the cones together: ``needed_cone_deg`` is the largest cone after the smallest common
      widening that makes the instant feasible.
    """
    names = list(cable_names) if cable_names is not None else [f"cable {i}" for i in range(qp.n)]
    nan = float("nan")
    if _feasible_lp(qp) is None:
        below, above = _elastic_bounds(qp)
        parts = []
        if above:
            parts.append("above f_max: " + ", ".join(names[i] for i in above))
        if below:
            parts.append("below f_min: " + ", ".join(names[i] for i in below))
        need = _smallest_common_fmax(qp)
        tail = (f"; a common f_max of {need:.6g} N would suffice" if np.isfinite(need) else
                "; no f_max suffices (some cable would have to push)")
        where = f" (the least change needs forces {'; '.join(parts)})" if parts else ""
        return ("bounds: the equation of motion cannot be met with cable forces within "
                f"[f_min, f_max]{where}{tail}", need, nan)
    alone = []
    for cone in qp.cones:
        if solver.fresh().solve(qp.with_cones([cone])).status == INFEASIBLE:
            alone.append(cone)
    if alone:
        worst = None
        texts = []
        for cone in alone:
            need = _smallest_angle(qp.with_cones([cone]), solver)
            texts.append(f"{cone.joint} ({cone.angle_deg:g} deg; feasible from {need:.4f} deg)")
            worst = need if worst is None else max(worst, need)
        return (f"cone: the stability cone of {', '.join(texts)} cannot be met within the cable "
                f"bounds", nan, float(worst))
    delta = _smallest_angle(qp, solver) - max(c.angle_deg for c in qp.cones)
    names_c = ", ".join(f"{c.joint} ({c.angle_deg:g} deg)" for c in qp.cones)
    return (f"cones: the stability cones of {names_c} cannot be met together within the cable "
            f"bounds; widening all by {delta:.4f} deg would do", nan,
            float(max(c.angle_deg for c in qp.cones) + delta))


def _feasible_lp(qp: QPData):
    from scipy.optimize import linprog

    res = linprog(np.zeros(qp.n), A_eq=qp.A if len(qp.b) else None, b_eq=qp.b if len(qp.b) else None,
                  bounds=list(zip(qp.lb, qp.ub)), method="highs")
    return res.x if res.status == 0 else None


def _elastic_bounds(qp: QPData, tol: float = 1e-9):
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
    return (np.flatnonzero(s_lo > tol * (1.0 + np.abs(qp.lb))).tolist(),
            np.flatnonzero(s_hi > tol * (1.0 + np.abs(qp.ub))).tolist())


def _smallest_common_fmax(qp: QPData) -> float:
    """min t such that A f = b, f_min <= f <= t (inf when even an unbounded f_max fails)."""
    from scipy.optimize import linprog

    n = qp.n
    c = np.zeros(n + 1)
    c[-1] = 1.0
    A_ub = np.hstack([np.eye(n), -np.ones((n, 1))])
    res = linprog(c, A_ub=A_ub, b_ub=np.zeros(n), A_eq=np.hstack([qp.A, np.zeros((len(qp.b), 1))]),
                  b_eq=qp.b, bounds=[(lo, None) for lo in qp.lb] + [(float(qp.lb.max()), None)],
                  method="highs")
    return float(res.x[-1]) if res.status == 0 else float("inf")


def _smallest_angle(qp: QPData, solver, tol_deg: float = 1e-4) -> float:
    """The smallest half-angle, common widening of every cone of ``qp``, that is feasible
    (returned as the largest widened cone's angle); inf when none below 90 deg is."""
    from .constraints import ConeData

    top = max(c.angle_deg for c in qp.cones)

    def ok(delta):
        cones = [ConeData(c.joint, c.G, c.g, c.axis, min(c.angle_deg + delta, 89.999999), c.basis)
                 for c in qp.cones]
        return solver.fresh().solve(qp.with_cones(cones)).status == OPTIMAL

    lo, hi = 0.0, 90.0 - min(c.angle_deg for c in qp.cones)
    if not ok(hi):
        return float("inf")
    while hi - lo > tol_deg:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if ok(mid) else (mid, hi)
    return top + hi


def soften_cones(qp: QPData, solver, tol_deg: float = 1e-4) -> tuple[Solution, float]:
    """Widen every cone by the smallest common angle that makes the instant feasible (bisection to
    ``tol_deg``) and solve there. Returns the solution (status ``softened``) and the widening."""
    from .constraints import ConeData

    def widened(delta):
        return qp.with_cones([ConeData(c.joint, c.G, c.g, c.axis, min(c.angle_deg + delta, 89.999999),
                                       c.basis) for c in qp.cones])

    lo, hi = 0.0, 90.0 - min(c.angle_deg for c in qp.cones)
    if solver.fresh().solve(widened(hi)).status != OPTIMAL:
        sol = solver.fresh().solve(qp)
        return Solution(sol.f, INFEASIBLE, sol.objective, sol.iterations, sol.rounds,
                        "no force presses the balls into their sockets at all"), 0.0
    while hi - lo > tol_deg:
        mid = 0.5 * (lo + hi)
        if solver.fresh().solve(widened(mid)).status == OPTIMAL:
            hi = mid
        else:
            lo = mid
    sol = solver.fresh().solve(widened(hi))
    if sol.status != OPTIMAL:
        return sol, hi
    return Solution(sol.f, SOFTENED, sol.objective, sol.iterations, sol.rounds), hi
