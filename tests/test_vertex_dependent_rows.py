"""A vertex whose rows are dependent but for rounding (mcdm_pin/solvers/_kkt_linalg.py,
``vertex_solve_lu``): as many free cables as equations, but the free cables' columns span fewer
directions (two cables along one line). The LU of the rows then meets a pivot of rounding size
instead of zero, and its point is noise of 1e15 and more. Where the free block is diagonal, the rows'
Schur complement solves the system instead, so the optimum's own active set verifies: on the neck's
``pitch`` (case 1) instants 31-37 went on to the interior-point method because of it (docs/speed.md,
"A vertex's dependent rows"). The linear algebra's tests run compiled and uncompiled; the neck's, on
the compiled kernels the library answers with."""

from __future__ import annotations

import numpy as np
import pytest

from mcdm_pin import InverseDynamics, Robot, load_trajectory
from mcdm_pin.problem import Context
from mcdm_pin.scaling import scale_problem
from mcdm_pin.settings import DEFAULT

from .conftest import REPO

NECK = REPO / "robots" / "caspr" / "8S_neck" / "8S_neck.yaml"


@pytest.fixture
def linalg(kernel_modules):
    return kernel_modules("solvers._kkt_linalg")


def _vertex_system(seed, diagonal=True, consistent=True):
    """``[[H, R^T], [R, 0]]`` with a square ``R`` of rank ``nf - 2`` (two of its columns combinations of
    others, then every column mixed by an orthogonal matrix so that no zero shows exactly), ``H``
    diagonal or not, and ``r_c`` in ``R``'s range, or not."""
    rng = np.random.default_rng(seed)
    nf = int(rng.integers(6, 30))
    B = rng.standard_normal((nf, nf - 2))
    R = np.hstack([B, B[:, :2] @ rng.standard_normal((2, 2))]) @ np.linalg.qr(rng.standard_normal((nf, nf)))[0]
    H = np.diag(rng.uniform(0.5, 2.0, nf))
    if not diagonal:
        G = rng.standard_normal((nf, nf))
        H = H + 0.1 * G @ G.T
    K = np.zeros((2 * nf, 2 * nf))
    K[:nf, :nf], K[:nf, nf:], K[nf:, :nf] = H, R.T, R
    rc = R @ rng.standard_normal(nf) if consistent else rng.standard_normal(nf)
    return K, np.concatenate([rng.standard_normal(nf), rc]), nf


def test_a_rounding_pivot_is_told_from_a_healthy_one(linalg):
    for seed in range(50):
        K, _, nf = _vertex_system(seed)
        R = K[nf:, :nf]
        LU, _, ok = linalg.lu_factor(R)
        assert ok  # (no pivot is exactly zero: the dependence shows only as rounding)
        assert linalg._rounding_pivot(LU)
        healthy = R + np.random.default_rng(seed).standard_normal(R.shape)
        assert not linalg._rounding_pivot(linalg.lu_factor(healthy)[0])


def test_dependent_rows_with_a_diagonal_block_are_solved(linalg):
    for seed in range(50):
        K, rhs, nf = _vertex_system(seed)
        sol, _, _, from_lu = linalg.vertex_solve_lu(K, rhs, nf, True)
        assert not from_lu  # (the vertex's factors did not give it: the next ratio test must not use them)
        assert np.all(np.isfinite(sol))
        scale = np.abs(K).max() * np.abs(sol).max() + np.abs(rhs).max()
        assert np.abs(K @ sol - rhs).max() <= 1e-11 * scale
        assert np.abs(sol).max() < 1e6  # not the vertex's noise


def test_inconsistent_rows_or_a_full_block_keep_the_vertex_point(linalg):
    """Where the Schur complement does not apply (a block off the diagonal) or finds the rows
    inconsistent, the vertex's point stands, as before (its noise still names the cables to
    exchange)."""
    for seed in range(20):
        for diagonal, consistent in ((False, True), (True, False)):
            K, rhs, nf = _vertex_system(seed, diagonal, consistent)
            sol, _, _, from_lu = linalg.vertex_solve_lu(K, rhs, nf, True)
            assert from_lu or not np.all(np.isfinite(sol))


@pytest.mark.parametrize("instant", [31, 34, 37])
def test_the_necks_pitch_optimum_verifies_from_its_own_active_set(instant):
    """The compiled active-set solver, given the active set of the interior-point method's optimum
    (24 free cables for 24 equations, their columns of rank 20), verifies it in one solve, at that
    optimum."""
    from mcdm_pin import jit
    from mcdm_pin.solvers import active_set as aset
    from mcdm_pin.solvers.ipm import ipm_solve

    jit.prepare(policy="wait")
    robot = Robot.load(NECK)
    traj = load_trajectory(robot, "pitch")
    ident = InverseDynamics.for_case(robot, 1)
    qp = ident.problem.assemble(ident.evaluate(traj.q[instant], traj.qd[instant], traj.qdd[instant]),
                                Context(robot))
    qp = scale_problem(qp)[0]
    ref = ipm_solve(qp)
    state = np.where(ref.x <= qp.lb + 1e-9 * (1 + np.abs(qp.lb)), 1, 0).astype(np.int8)
    free = state == 0
    assert free.sum() == len(qp.b) and np.linalg.matrix_rank(qp.A[:, free]) < len(qp.b)
    out = aset.try_active_set(qp, aset.ActiveSet(aset._EMPTY, aset._EMPTY, state=state), 1, settings=DEFAULT)
    assert out is not None
    assert np.abs(out.x - ref.x).max() <= 1e-6 * np.abs(ref.x).max()
    assert qp.objective(out.x) <= qp.objective(ref.x) + 1e-9 * abs(qp.objective(ref.x))
