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
    # where the free set changes at every step near a vertex the stopping test may not be met
    # within the steps (the guess above was right all the same)
    assert stopped >= 0.9 * total


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
