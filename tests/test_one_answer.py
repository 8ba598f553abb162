"""One answer whatever the back-end: where the optimum of cases 2 and 3 is not unique (the interaction
objective is only positive semidefinite in ``f``), every back-end returns the optimum of least
``|f|^2`` (the least-norm stage, :mod:`mcdm_pin.solvers.least_norm`).

Before that stage, on the human arm's ``abduct`` (case 3) the elbow's interaction force peaked at 1297 N
with Clarabel and 76 N with the default solver, and with ``alpha: 0`` on a wrist both wrist cables were
driven to their 500 N limit. Tolerance: 1e-6 relative to the largest force, the issue's; the back-ends
stop at 1e-9 to 1e-10 relative, and the polish stage makes every answer exact on its active set.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mcdm_pin import InverseDynamics, Robot, load_trajectory

REPO = Path(__file__).resolve().parents[1]
BACKENDS = ("default", "compiled", "proxqp", "clarabel")


def _runs(robot, traj, case, **kw):
    return {name: InverseDynamics.for_case(robot, case, solver=name, **kw).solve_trajectory(traj, progress=False)
            for name in BACKENDS}


def _same_forces(runs):
    ref = runs["default"]
    assert ref.found.all(), ref.message[~ref.found]
    scale = np.abs(ref.f).max()
    for name, run in runs.items():
        assert run.found.all(), (name, run.message[~run.found])
        np.testing.assert_allclose(run.f, ref.f, rtol=0, atol=1e-6 * scale, err_msg=name)
        np.testing.assert_allclose(run.objective, ref.objective, rtol=1e-6, atol=1e-9, err_msg=name)
    return ref


def test_human_arm_abduct_case3_one_answer():
    robot = Robot.load(REPO / "robots" / "human_arm.yaml")
    assert any(j.alpha == 0.0 for j in robot.joints), "the sidecar's wrist/forearm have alpha 0"
    traj = load_trajectory(robot, "abduct").subsample(13)
    ref = _same_forces(_runs(robot, traj, 3))
    # the optimum is not unique here: the least-norm stage chose, and the results say so
    assert not ref.unique.all()
    elbow = robot.joint_names.index("elbow")
    assert ref.force_magnitude[:, elbow].max() < 200.0  # not the 1297 N of an arbitrary optimal point
    assert ref.f.max() < 0.5 * robot.f_max.max()  # no cable driven to its limit


def test_alpha_zero_joint_least_norm():
    """The 2-link arm with ``alpha = beta = 0`` on the elbow (case 2): the elbow's cables are free in the
    objective, so a whole face is optimal; every back-end returns its least-norm point, which is no
    larger than any optimal point a back-end found on its own (the first stage's answers)."""
    robot = Robot.load(REPO / "robots" / "two_link_sr.yaml")
    traj = load_trajectory(robot, "traj1").subsample(11)
    kw = dict(alpha={"elbow": 0.0}, beta={"elbow": 0.0})
    ref = _same_forces(_runs(robot, traj, 2, **kw))
    # the first stage alone (a cascade without the least-norm stage): optimal, never smaller
    from mcdm_pin.solvers.cascade import Cascade
    from mcdm_pin.solvers.clarabel_ import ClarabelStage
    from mcdm_pin.solvers.active_set import Polish
    from mcdm_pin.solvers.check import Project

    first = InverseDynamics.for_case(robot, 2, solver=Cascade([ClarabelStage(), Polish(), Project()], name="first"),
                                     **kw).solve_trajectory(traj, progress=False)
    assert first.found.all()
    np.testing.assert_allclose(first.objective, ref.objective, rtol=1e-6, atol=1e-9)
    assert np.all(np.einsum("ij,ij->i", ref.f, ref.f) <= np.einsum("ij,ij->i", first.f, first.f) * (1 + 1e-9))


@pytest.mark.parametrize("case", [1, 2, 3])
def test_reset_forgets_warm_starts(case):
    """``InverseDynamics.reset()``: an instant solved after ``reset()`` equals the same instant solved by
    a fresh object (cold), whatever was solved before."""
    robot = Robot.load(REPO / "robots" / "two_link_sr.yaml")
    traj = load_trajectory(robot, "traj1")
    ident = InverseDynamics.for_case(robot, case)
    ident.solve_trajectory(traj.subsample(20), progress=False)
    ident.reset()
    k = 37
    after = ident.solve(traj.q[k], traj.qd[k], traj.qdd[k])
    fresh = InverseDynamics.for_case(robot, case).solve(traj.q[k], traj.qd[k], traj.qdd[k])
    assert after.stage == fresh.stage and "warm" not in after.stage
    np.testing.assert_allclose(after.f, fresh.f, rtol=0, atol=1e-9 * np.abs(fresh.f).max())


def test_a_constant_objective_is_answered_by_its_least_norm_feasible_point():
    """SJTUSnake's case 2: every joint is universal, so the sidecar's weights are all zero and the
    objective is a constant; every feasible point is optimal. The first stage of every chain solves
    the least-norm feasible problem at once (before it, the warm start cycled at every instant and the
    least-norm stage solved that problem afterwards: 18 ms an instant). Every back-end gives the same
    forces, the same as the first stage followed by the least-norm stage, and no larger than case 1's
    (here the least-norm feasible point is case 1's optimum)."""
    from mcdm_pin.solvers import least_norm

    robot = Robot.load(REPO / "robots" / "caspr" / "SJTUSnake" / "SJTUSnake.yaml")
    assert all(j.alpha == 0.0 and j.beta == 0.0 for j in robot.joints)
    traj = load_trajectory(robot, "traj_test").subsample(9)
    ref = _same_forces(_runs(robot, traj, 2))
    assert all(s.startswith("flat_objective>") for s in ref.stage), set(ref.stage)
    assert not ref.unique.any()  # the least-norm point among optima, not a unique optimum
    case1 = InverseDynamics.for_case(robot, 1).solve_trajectory(traj, progress=False)
    np.testing.assert_allclose(ref.f, case1.f, rtol=0, atol=1e-9 * np.abs(case1.f).max())
    # the chain without the stage: the first stage's point, then the least-norm stage: the same forces
    ident = InverseDynamics.for_case(robot, 2)
    ident.solver.inner.stages = [s for s in ident.solver.inner.stages if not isinstance(s, least_norm.FlatObjective)]
    old = ident.solve_trajectory(traj, progress=False)
    assert old.found.all() and not any(s.startswith("flat_objective") for s in old.stage)
    np.testing.assert_allclose(old.f, ref.f, rtol=0, atol=1e-9 * np.abs(ref.f).max())
