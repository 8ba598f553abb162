"""The warm active set's second guess (mcdm_pin/solvers/_dual_guess.py): Newton's method on the dual of
a QP with a diagonal, positive definite objective and no cones, from the last answer's multipliers.

On random separable QPs the guess is the optimum's active set (the active-set solver verifies it in
one KKT solve and its point is Clarabel's optimum), compiled and uncompiled alike; an infeasible
problem and dependent equations end without an error; and on the neck's ``roll`` (case 1) the warm
starts that used to fail and go on to the interior-point method are answered by the warm stage with
the forces the interior-point method gave."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mcdm_pin import jit
from mcdm_pin.exceptions import SolverError
from mcdm_pin.qp import QPData
from mcdm_pin.settings import DEFAULT
from mcdm_pin.solvers import make_solver
from mcdm_pin.solvers.active_set import ActiveSet, try_active_set

_NONE = np.zeros(0, dtype=int)


def _problems(count=40, seed=3):
    """Feasible separable QPs: ``d`` spread over up to six decades, some infinite bounds, ``b`` the
    image of a point inside the box."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        n = int(rng.integers(6, 41))
        m = int(rng.integers(1, max(2, n // 3)))
        d = 10.0 ** rng.uniform(-3, 3, n) if rng.random() < 0.3 else rng.uniform(0.5, 3.0, n)
        c = rng.normal(size=n)
        A = rng.normal(size=(m, n))
        lb = rng.uniform(-2.0, 0.5, n)
        ub = lb + rng.uniform(0.2, 3.0, n)
        lb[rng.random(n) < 0.1] = -np.inf
        ub[rng.random(n) < 0.1] = np.inf
        inside = np.clip(rng.normal(size=n), np.where(np.isfinite(lb), lb, -5.0), np.where(np.isfinite(ub), ub, 5.0))
        b = A @ inside
        out.append((d, c, A, b, lb, ub))
    return out


def _qp(d, c, A, b, lb, ub) -> QPData:
    n = len(d)
    return QPData(np.diag(d), c, 0.0, A, b, lb, ub, P_diag=d, P_factor=np.zeros((0, n)))


@pytest.fixture
def kernel(kernel_modules):
    return kernel_modules("solvers._dual_guess").dual_guess


def test_the_dual_guess_is_the_optimums_active_set(kernel):
    s = DEFAULT
    rng = np.random.default_rng(5)
    stopped = total = 0
    for d, c, A, b, lb, ub in _problems():
        qp = _qp(d, c, A, b, lb, ub)
        ref = make_solver("clarabel").solve(qp)
        assert ref.status == "optimal"
        # from no information, and from the optimum's multipliers disturbed as a neighbour's are
        for y0 in (np.zeros(len(b)), ref.y * (1.0 + 0.2 * rng.normal(size=len(b)))):
            state, steps, converged = kernel(d, c, A, b, lb, ub, y0, 60, s.warm_dual_regularisation, s.warm_dual_tol)
            stopped += bool(converged)
            total += 1
            assert 0 <= steps <= 60
            out = try_active_set(qp, ActiveSet(_NONE, _NONE, state=state), 1, settings=s)
            assert out is not None, "the guess is not the optimum's active set"
            scale = max(1.0, np.abs(ref.x).max())
            assert np.abs(out.x - ref.x).max() <= 1e-6 * scale
    # the stopping test (the equations met at x(y)) holds within the steps on every one of them
    assert stopped == total


def test_the_compiled_and_uncompiled_guesses_agree(monkeypatch):
    pytest.importorskip("numba")
    jit.prepare(policy="wait")
    compiled = jit.kernels("solvers._dual_guess").dual_guess
    monkeypatch.setattr(jit, "_COMPILED", False)
    plain = jit.kernels("solvers._dual_guess").dual_guess
    s = DEFAULT
    for d, c, A, b, lb, ub in _problems(count=15, seed=8):
        y0 = np.zeros(len(b))
        a = compiled(d, c, A, b, lb, ub, y0, 60, s.warm_dual_regularisation, s.warm_dual_tol)
        p = plain(d, c, A, b, lb, ub, y0, 60, s.warm_dual_regularisation, s.warm_dual_tol)
        np.testing.assert_array_equal(a[0], p[0])
        assert (a[1], a[2]) == (p[1], p[2])


def test_an_infeasible_problem_and_dependent_equations_end_without_an_error(kernel):
    s = DEFAULT
    n = 8
    d, c = np.ones(n), np.zeros(n)
    lb, ub = np.zeros(n), np.ones(n)
    A = np.ones((1, n))
    # sum x = 20 with 0 <= x <= 1: infeasible, the dual is unbounded
    state, steps, converged = kernel(d, c, A, np.array([20.0]), lb, ub, np.zeros(1), 30,
                                     s.warm_dual_regularisation, s.warm_dual_tol)
    assert not converged and steps == 30 and state.shape == (n,)
    # the same equation twice (dependent rows), feasible: the guess is still the optimum's
    A2 = np.vstack([A, A])
    b2 = np.array([3.0, 3.0])
    state, _, converged = kernel(d, c, A2, b2, lb, ub, np.zeros(2), 30, s.warm_dual_regularisation, s.warm_dual_tol)
    assert converged
    np.testing.assert_array_equal(state, np.zeros(n, dtype=np.int8))  # x = 3/8 each: all free


def test_the_steps_setting_switches_the_guess_off_and_is_checked():
    assert DEFAULT.replace(warm_dual_steps=0).warm_dual_steps == 0
    for bad in (-1, 1.5, True):
        with pytest.raises(SolverError, match="warm_dual_steps"):
            DEFAULT.replace(warm_dual_steps=bad)
    with pytest.raises(SolverError, match="warm_dual_regularisation"):
        DEFAULT.replace(warm_dual_regularisation=0.0)


def test_the_necks_failed_warm_starts_are_answered_by_the_warm_stage():
    from mcdm_pin import InverseDynamics, Robot, load_trajectory

    robot = Robot.load(Path(__file__).resolve().parents[1] / "robots/caspr/8S_neck/8S_neck.yaml")
    traj = load_trajectory(robot, "roll")
    runs = {}
    for steps in (0, DEFAULT.warm_dual_steps):
        ident = InverseDynamics.for_case(robot, 1, settings=DEFAULT.replace(warm_dual_steps=steps))
        runs[steps] = ident.solve_trajectory(traj, progress=False)
    off, on = runs[0], runs[DEFAULT.warm_dual_steps]
    moved = np.flatnonzero((off.stage == "ipm") & (on.stage == "warm_active_set"))
    assert len(moved) >= 3  # (48, 51 and 52: the pivot limit twice, a singular system once)
    assert list(np.flatnonzero(on.stage != "warm_active_set")) == [0]  # only the first instant is cold
    assert (on.status == "optimal").all() and (off.status == "optimal").all()
    np.testing.assert_allclose(on.f, off.f, rtol=0, atol=1e-12 * np.abs(off.f).max())


def _dual(d, c, A, b, lb, ub, y):
    """The dual function ``g(y)`` of the module docstring, in numpy."""
    s = A.T @ y + c
    x = np.clip(-s / d, lb, ub)
    return float(np.sum((0.5 * d * x + s) * x) - b @ y)


def _breakpoints_before(d, c, A, lb, ub, y, step, t):
    """How many of the ray's breakpoints (where a variable meets a bound) lie in ``(0, t)``."""
    s, q = A.T @ y + c, A.T @ step
    out = 0
    for j in np.flatnonzero(q):
        a = -q[j] / d[j]
        for bound in (lb[j], ub[j]):
            tj = (bound + s[j] / d[j]) / a
            out += bool(0.0 < tj < t)
    return out


def test_the_exact_step_is_the_duals_maximiser_along_the_ray(kernel_modules):
    """``_exact_step`` moves ``y`` to the maximiser of the concave dual along the Newton direction:
    no point of a fine grid along the ray, nor a point a hair either side, is higher. The last
    problems, wide and started far from their optimum, pass more breakpoints before the step than the
    step finds by a scan (16), so that the rest are sorted."""
    mod = kernel_modules("solvers._dual_guess")
    rng = np.random.default_rng(11)
    wide = [(np.ones(n), np.zeros(n), rng.normal(size=(3, n)), np.zeros(3), np.zeros(n), np.full(n, 1.0))
            for n in (120, 200)]
    passed = []
    for i, (d, c, A, b, lb, ub) in enumerate(_problems(count=12, seed=13) + wide):
        m, n = A.shape
        far = 30.0 if i >= 12 else 1.0
        y = far * rng.normal(size=m)
        step = rng.normal(size=m)
        x = np.empty(n)
        mod._primal(np.ascontiguousarray(A.T), c, d, lb, ub, y, x)
        grad = A @ x - b
        if grad @ step < 0:
            step = -step
        y1, x1 = y.copy(), np.empty(n)
        work = (np.empty(n), np.empty(n), np.empty(2 * n), np.empty(2 * n))
        mod._exact_step(np.ascontiguousarray(A), c, d, lb, ub, y1, x1, step, grad, work)
        t = float((y1 - y) @ step / (step @ step))
        np.testing.assert_allclose(y1, y + t * step, rtol=0, atol=1e-12 * (1 + np.abs(y).max()))
        best = _dual(d, c, A, b, lb, ub, y1)
        scale = 1e-10 * max(1.0, abs(best))
        for u in np.concatenate([np.linspace(0.0, 3.0 * max(t, 1.0), 601), [t * (1 - 1e-6), t * (1 + 1e-6)]]):
            assert _dual(d, c, A, b, lb, ub, y + u * step) <= best + scale
        want = np.clip(-(A.T @ y1 + c) / d, lb, ub)
        np.testing.assert_allclose(x1, want, rtol=0, atol=1e-12 * (1 + np.abs(x1).max()))
        passed.append(_breakpoints_before(d, c, A, lb, ub, y, step, t))
    assert max(passed[12:]) > 16, passed


def test_the_newton_matrix_kept_up_to_date_equals_the_one_summed_again(kernel_modules):
    """``_newton_matrix`` updates its sum over the free variables by the ones that entered or left
    (or sums again where more changed than stayed free): along a sequence of free sets it equals the
    matrix summed from scratch, to rounding."""
    mod = kernel_modules("solvers._dual_guess")
    rng = np.random.default_rng(17)
    m, n = 7, 30
    A = rng.normal(size=(m, n))
    d = rng.uniform(0.5, 2.0, n)
    AT = np.ascontiguousarray(A.T)
    Bt, S, floor = mod._metric(AT, d)
    M, kept, inside = np.empty((m, m)), np.zeros((m, m)), np.zeros(n, dtype=np.bool_)
    reg = DEFAULT.warm_dual_regularisation
    state = np.ones(n, dtype=np.int8)
    for k in range(25):
        flips = rng.choice(n, size=int(rng.integers(1, 4 if k % 5 else n)), replace=False)
        state[flips] = np.where(state[flips] == 0, 1, 0)
        mod._newton_matrix(M, kept, inside, S, Bt, state, reg, floor)
        F = state == 0
        want = (A[:, F] / d[F]) @ A[:, F].T + reg * (A / d) @ A.T + floor * np.eye(m)
        low = np.tril_indices(m)
        np.testing.assert_allclose(M[low], want[low], rtol=0, atol=1e-12 * np.abs(want).max())
        np.testing.assert_array_equal(inside, F)


def test_a_cold_instant_of_case_1_is_answered_by_the_dual_guess_with_the_interior_point_methods_forces():
    """The default chain's cold instants of case 1 (after ``reset``) go to :class:`DualActiveSet`
    (the active set read off the dual's optimum from zero multipliers): on the neck's three motions
    every cold instant, with the forces of the interior-point method (``cold_dual_steps=0``) to
    rounding (the degenerate instants too, verified within the whole pivot limit); warm instants stay
    with the warm stage, and cases 2 and 3 (not separable, or with cones) never reach the dual
    guess."""
    from mcdm_pin import InverseDynamics, Robot, load_trajectory

    robot = Robot.load(Path(__file__).resolve().parents[1] / "robots/caspr/8S_neck/8S_neck.yaml")
    answered = total = 0
    for name in ("roll", "pitch", "yaw"):
        traj = load_trajectory(robot, name)
        on = InverseDynamics.for_case(robot, 1)
        off = InverseDynamics.for_case(robot, 1, settings=DEFAULT.replace(cold_dual_steps=0))
        # (with 6 and 36: the degenerate instants of ``pitch``, whose guess needs seven KKT solves)
        for k in sorted(set(range(0, len(traj), 10)) | {6, 36}):
            on.reset()
            off.reset()
            a = on.solve(traj.q[k], traj.qd[k], traj.qdd[k])
            b = off.solve(traj.q[k], traj.qd[k], traj.qdd[k])
            assert a.status == b.status == "optimal"
            assert "dual_active_set" not in b.stage
            answered += a.stage.startswith("dual_active_set")
            total += 1
            np.testing.assert_allclose(a.f, b.f, rtol=0, atol=1e-10 * np.abs(b.f).max())
        warm = on.solve_trajectory(traj, progress=False)
        assert not any(str(s).startswith("dual_active_set") for s in warm.stage[1:])
    assert answered == total
    traj = load_trajectory(robot, "roll")
    base = dict(alpha={j: 0.125 for j in robot.joint_names}, beta={j: 0.0 for j in robot.joint_names})
    for case, kw in ((2, base), (3, dict(base, cones={j: 15.0 for j in robot.joint_names}))):
        ident = InverseDynamics.for_case(robot, case, **kw)
        r = ident.solve(traj.q[0], traj.qd[0], traj.qdd[0])
        assert r.status == "optimal" and not r.stage.startswith("dual_active_set")


def test_the_cold_steps_setting_switches_the_cold_guess_off_and_is_checked():
    assert DEFAULT.replace(cold_dual_steps=0).cold_dual_steps == 0
    for bad in (-1, 2.5, True):
        with pytest.raises(SolverError, match="cold_dual_steps"):
            DEFAULT.replace(cold_dual_steps=bad)


def test_the_arms_activations_cold_with_a_muscle_fixed_by_its_bounds(tmp_path, monkeypatch):
    """MyoSuite's arm, case 1 (activations): one muscle's force range is a single value along the
    abduction (its bounds one value, its weight zero), so the objective is not positive definite;
    the cold stage takes it all the same (that variable is at its bound whatever the multipliers),
    with the interior-point method's forces, and the warm stage's test stays the cheap one."""
    pytest.importorskip("mujoco")
    from mcdm_pin import InverseDynamics, Robot, load_trajectory
    from mcdm_pin.problem import Context
    from mcdm_pin.solvers.active_set import _separable

    from .conftest import REPO

    monkeypatch.chdir(tmp_path)  # (MuJoCo writes its log where it runs)
    robot = Robot.load(REPO / "robots" / "myosuite" / "myoarm.yaml")
    traj = load_trajectory(robot, "abduction")
    on = InverseDynamics.for_case(robot, 1)
    off = InverseDynamics.for_case(robot, 1, settings=DEFAULT.replace(cold_dual_steps=0))
    for k in (0, 50, 100):
        qp = on.problem.assemble(on.evaluate(traj.q[k], traj.qd[k], traj.qdd[k]), Context(robot))
        assert not _separable(qp) and _separable(qp, fixed_ok=True)
        on.reset()
        off.reset()
        a = on.solve(traj.q[k], traj.qd[k], traj.qdd[k])
        b = off.solve(traj.q[k], traj.qd[k], traj.qdd[k])
        assert a.status == b.status == "optimal"
        assert a.stage.startswith("dual_active_set") and b.stage.startswith("ipm"), (a.stage, b.stage)
        np.testing.assert_allclose(a.f, b.f, rtol=0, atol=1e-10 * np.abs(b.f).max())
