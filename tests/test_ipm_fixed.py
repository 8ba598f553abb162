"""The compiled interior-point method with variables fixed by their bounds (``lb == ub``: a muscle
whose force range has collapsed to its passive force). They are substituted out before the
iterations (mcdm_pin.solvers._fast.ipm_answer): before, a box without interior left the method no
room, and on MyoSuite's arm with the glenohumeral cone (case 3) 54 of 101 cold instants ended in a
numerical breakdown or a failed crossover and fell through to Clarabel. The answers are checked
against Clarabel's optimum and against the KKT conditions in the duals' convention
(mcdm_pin/solvers/base.py). Last, the other case the stage settles before its iterations: an
equation without a variable and a nonzero right-hand side (mcdm_pin/solvers/ipm.py, ``ipm_solve``)."""

from __future__ import annotations

import numpy as np
import pytest

from .test_solvers import OBJ_RTOL, _weak_factor_problem

pytest.importorskip("clarabel")


def _fix(qp, which):
    """``qp`` with the variables ``which`` fixed at a point inside their box (the optimum moves)."""
    lb, ub = qp.lb.copy(), qp.ub.copy()
    lb[which] = ub[which] = np.linspace(2.0, 9.0, len(which))
    return qp.replace(lb=lb, ub=ub)


def _stationarity(qp, sol) -> float:
    """``|P x + c + A^T y + z - sum_k T_k^T z_k|_inf`` relative to the gradient's size."""
    T, _ = qp.cone_rows()
    r = qp.P @ sol.x + qp.c + qp.A.T @ sol.y + sol.z
    for k in range(len(qp.cones)):
        r -= T[k].T @ sol.z_cone[k]
    return float(np.abs(r).max() / max(np.abs(qp.P @ sol.x + qp.c).max(), 1.0))


@pytest.mark.parametrize("cone", [False, True])
def test_ipm_crosses_over_with_fixed_variables(cone):
    from mcdm_pin import jit
    from mcdm_pin.solvers.chains import make_solver
    from mcdm_pin.solvers.ipm import ipm_solve

    jit.prepare(policy="wait")
    for seed in range(8):
        qp = _fix(_weak_factor_problem(seed, cone), [1, 7, 20])
        ours, ref = ipm_solve(qp), make_solver("clarabel").solve(qp)
        assert ours.status == "optimal" and ref.status == "optimal", (seed, ours.message)
        assert ours.active is not None, seed  # through the crossover: a verified active set
        np.testing.assert_array_equal(ours.x[[1, 7, 20]], qp.lb[[1, 7, 20]])
        assert qp.objective(ours.x) == pytest.approx(qp.objective(ref.x), rel=OBJ_RTOL), seed
        assert ours.objective == pytest.approx(qp.objective(ours.x), rel=1e-12)
        assert _stationarity(qp, ours) <= 1e-8, seed
        # the next instant's guess holds each fixed variable at the bound its multiplier points to
        state = ours.active.state
        for i in (1, 7, 20):
            assert state[i] == (2 if ours.z[i] > 0 else 1) or abs(ours.z[i]) <= 1e-12 * np.abs(ours.z).max()


def test_myoarm_case3_cold_instants_answer_in_the_ipm(monkeypatch, tmp_path):
    """MyoSuite's arm, case 3, ``abduction``: instants where a muscle's range collapses (every
    instant of it has one) answer in the interior-point stage, at Clarabel's optimum."""
    from mcdm_pin import InverseDynamics, Robot, jit, load_trajectory
    from mcdm_pin.problem import Context

    from .conftest import REPO

    monkeypatch.chdir(tmp_path)
    jit.prepare(policy="wait")
    robot = Robot.load(REPO / "robots" / "myosuite" / "myoarm.yaml")
    traj = load_trajectory(robot, "abduction")
    ours, ref = InverseDynamics.for_case(robot, 3), InverseDynamics.for_case(robot, 3, solver="clarabel")
    for k in (0, 30, 60, 90):
        q, qd, qdd = traj.q[k], traj.qd[k], traj.qdd[k]
        qp = ours.problem.assemble(ours.evaluate(q, qd, qdd), Context(robot))
        assert np.any(qp.lb == qp.ub), k
        ours.reset()
        a, b = ours.solve(q, qd, qdd), ref.solve(q, qd, qdd)
        assert a.status == b.status == "optimal", (k, a.message)
        assert a.stage.split(">")[0] == "ipm", (k, a.stage)
        assert a.objective == pytest.approx(b.objective, rel=OBJ_RTOL), k


def test_an_equation_without_variables_is_infeasible_at_once():
    """``0 = b_i`` with ``b_i != 0`` (a coordinate that no cable moves, under a load: BioBiped's
    torso) is its own certificate: the interior-point stage says infeasible before iterating, naming
    the rows (the method itself ran this problem to its iteration limit, 60, with one such row or
    two). A zero row with ``b_i = 0`` is only a redundant equation, and the problem solves."""
    from mcdm_pin import jit
    from mcdm_pin.qp import QPData
    from mcdm_pin.solvers.base import INFEASIBLE, OPTIMAL
    from mcdm_pin.solvers.ipm import ipm_solve

    jit.prepare(policy="wait")
    n = 4
    A = np.array([[1.0, -1.0, 0.5, 0.0], [0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0], [0.2, 0.3, -0.4, 1.0]])
    qp = QPData(np.eye(n), np.zeros(n), 0.0, A, np.array([0.3, 0.0, 0.0, 0.1]), np.zeros(n), np.full(n, 10.0))
    assert ipm_solve(qp).status == OPTIMAL  # (two zero rows with zero right-hand sides: redundant)
    for b in ([0.3, 0.0, 2.0, 0.1], [0.3, -1.0, 2.0, 0.1]):
        sol = ipm_solve(qp.replace(b=np.array(b)))
        assert sol.status == INFEASIBLE and sol.iterations == 0 and sol.stage == "ipm", sol.message
        assert ("rows 1, 2" if b[1] else "row 2") in sol.message


def test_biobiped_torso_is_certified_by_the_ipm():
    """BioBiped's torso: coordinates that no cable spans, one of them loaded (the torso's height, its
    column of ``L`` exactly zero); every instant is infeasible, said by the interior-point stage at
    once, and the diagnosis names the lost wrench closure."""
    from mcdm_pin import InverseDynamics, Robot, load_trajectory

    from .conftest import REPO

    with pytest.warns(Warning):  # (CASPR's inertias, accepted as shipped: docs/limits.md)
        robot = Robot.load(REPO / "robots" / "caspr" / "BioBiped_one_leg" / "BioBiped_one_leg.yaml")
    traj = load_trajectory(robot, "traj_test")
    ident = InverseDynamics.for_case(robot, 1)
    for k in (0, 100, 2500):
        one = ident.solve(traj.q[k], traj.qd[k], traj.qdd[k])
        assert one.status == "infeasible" and one.stage == "ipm" and one.iterations == 0, (k, one.stage, one.message)
        assert "wrench closure lost" in one.message
