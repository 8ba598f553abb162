"""MJCF robots solved end to end: MyoSuite's elbow along its flexion and the arm along its abduction,
minimum activations without and with the glenohumeral cone, every instant optimal and each objective
equal to Clarabel's (the committed models: no MyoSuite needed)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mujoco")

from mcdm_pin import InverseDynamics  # noqa: E402
from mcdm_pin.constraints import InteractionCone  # noqa: E402
from mcdm_pin.model.terms import TermsEvaluator  # noqa: E402
from mcdm_pin.objectives import MinActivations  # noqa: E402
from mcdm_pin.problem import Problem, case_problem  # noqa: E402
from mcdm_pin.robot import Robot  # noqa: E402
from mcdm_pin.trajectory import load_trajectory  # noqa: E402

ROBOTS = Path(__file__).resolve().parents[1] / "robots" / "myosuite"


def _both(robot, problem, traj):
    ours = InverseDynamics(robot, problem).solve_trajectory(traj, progress=False)
    ref = InverseDynamics(robot, problem, solver="clarabel").solve_trajectory(traj, progress=False)
    return ours, ref


def _same_answer(ours, ref):
    assert ours.found.all() and ref.found.all(), (ours.status, ours.message)
    rel = np.abs(ours.objective - ref.objective) / np.maximum(1.0, np.abs(ref.objective))
    assert rel.max() < 1e-6, rel.max()
    assert np.all(np.isfinite(ours.activation[:, np.isfinite(ours.activation).any(axis=0)]))


def test_elbow_flexion_case_1_is_minimum_activation_through_wrap_switches():
    """The flexion engages and releases wraps (where ``L`` has a kink): warm starts carry through."""
    robot = Robot.load(ROBOTS / "myoelbow.yaml")
    traj = load_trajectory(robot, "flexion")
    ev = TermsEvaluator(robot)
    engaged = []
    for q in traj.q:
        ev(q)
        engaged.append(ev._routes.engaged.copy())
    engaged = np.array(engaged)
    assert (np.diff(engaged.astype(int), axis=0) != 0).any(axis=1).sum() >= 2
    problem = case_problem(robot, 1)
    assert "MinActivations" in problem.describe()
    ours, ref = _both(robot, problem, traj)
    _same_answer(ours, ref)
    a = ours.activation
    assert a.shape == (len(traj), robot.m) and np.all((a > -1e-9) & (a < 1 + 1e-9))


@pytest.mark.parametrize("cone", [False, True])
def test_arm_abduction_with_and_without_the_glenohumeral_cone(cone):
    robot = Robot.load(ROBOTS / "myoarm.yaml")
    assert robot.couplings is not None and robot.couplings.n == 27
    traj = load_trajectory(robot, "abduction").subsample(6)
    problem = Problem(robot, MinActivations(), [InteractionCone("scapphant_r")] if cone else [])
    ours, ref = _both(robot, problem, traj)
    _same_answer(ours, ref)
    j = robot.joint_names.index("scapphant_r")
    angle = ours.interaction_angle_deg[:, j]
    if cone:
        assert np.all(angle <= robot.joint("scapphant_r").cone_deg + 1e-6)
    else:
        assert angle.max() > robot.joint("scapphant_r").cone_deg  # the cone binds along this motion


def test_a_state_that_breaks_a_coupling_is_refused_by_solve():
    """One instant, as a trajectory's are: the coupled coordinates must follow their couplings."""
    from mcdm_pin.exceptions import StateError

    robot = Robot.load(ROBOTS / "myoarm.yaml")
    q = robot.configuration({"shoulder_elv_r": 0.8})
    ident = InverseDynamics.for_case(robot, 1)
    assert ident.solve(q).found
    bad = q.copy()
    bad[robot.couplings.q_index[robot.couplings.dependent[0]]] += 0.1
    with pytest.raises(StateError, match="coupling"):
        ident.solve(bad)


@pytest.mark.parametrize("name", ["myoelbow", "myoelbow_2dof"])
def test_the_bundled_elbows_motions_are_answered_at_every_instant(name):
    """The motions shipped with the elbows are within their muscles' reach: every instant answered in
    case 1, at Clarabel's optimum (the 2-DoF elbow's flexion moves its shoulder too: with the shoulder
    held at 0 the muscles cannot hold the arm past about 1.67 rad of flexion, and that is infeasible)."""
    robot = Robot.load(ROBOTS / f"{name}.yaml")
    for t in robot.sidecar.trajectories:
        traj = load_trajectory(robot, t)
        ours, ref = _both(robot, case_problem(robot, 1), traj)
        _same_answer(ours, ref)


def test_the_chains_meet_a_held_cones_surface_alike():
    """Along the arm's whole abduction with the glenohumeral cone held at every instant, the default
    chain's forces and Clarabel's agree to 1e-11 of the largest: the warm start's Newton steps put the
    force on the cone's surface to ``Settings.active_set_settle`` (1e-12 of it), not just within the
    check's ``active_set_surface`` (1e-10), where they differed by 1.4e-10 (1.1e-7 N)."""
    robot = Robot.load(ROBOTS / "myoarm.yaml")
    traj = load_trajectory(robot, "abduction")
    problem = Problem(robot, MinActivations(), [InteractionCone("scapphant_r")])
    ours, ref = _both(robot, problem, traj)
    _same_answer(ours, ref)
    j = robot.joint_names.index("scapphant_r")
    cone = robot.joint("scapphant_r").cone_deg
    assert np.all(np.abs(ours.interaction_angle_deg[:, j] - cone) < 1e-9)  # held at every instant
    assert np.abs(ours.f - ref.f).max() <= 1e-11 * np.abs(ref.f).max()
