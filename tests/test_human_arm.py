"""robots/human_arm.yaml: muscle-like cables on the left arm of example-robot-data's `human` model."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mcdm_pin.exceptions import SidecarError
from mcdm_pin.robot import Robot, resolve_package_uri

from .fd import lengths_jacobian

SIDECAR = Path(__file__).resolve().parents[1] / "robots" / "human_arm.yaml"
HUMAN_URDF = "package://example-robot-data/robots/human_description/robots/human.urdf"

try:
    resolve_package_uri(HUMAN_URDF)
except SidecarError:  # pragma: no cover - depends on the environment
    pytest.skip("example-robot-data (the human model) is not installed", allow_module_level=True)


@pytest.fixture(scope="module")
def robot() -> Robot:
    return Robot.load(SIDECAR)


def test_structure(robot):
    sc = robot.sidecar
    assert sc.urdf == HUMAN_URDF
    # the human URDF is y-up: gravity along -y
    np.testing.assert_allclose(sc.gravity, [0.0, -9.81, 0.0])
    # 36 revolute joints in the URDF; the left shoulder (3), elbow flexion and pronation stay
    assert len(sc.locked_joints) == 31
    assert robot.nv == 5
    assert robot.model.njoints == 6  # universe + 5
    assert [j.name for j in robot.joints] == ["shoulder", "elbow", "forearm"]
    assert [j.type for j in robot.joints] == ["spherical", "revolute", "revolute"]
    shoulder = robot.joint("shoulder")
    assert shoulder.urdf_joints == ("left_shoulder_Z", "left_shoulder_X", "left_shoulder_Y")
    assert shoulder.cone_deg == 30.0
    np.testing.assert_allclose(shoulder.socket_axis, [0.0, 0.0, -1.0])


def test_cables(robot):
    assert robot.m >= 10
    assert np.all(robot.f_min > 0) and np.all(robot.f_max > robot.f_min)
    # cables routed over two moving links: points on three different bodies (the fixed trunk, the
    # upper arm and the forearm), so they span both the shoulder and the elbow
    spans = {}
    for cable in robot.cables:
        bodies = {robot.link_placement(link)[0] for link in cable.links}
        spans[cable.name] = bodies
    two_link = sorted(n for n, b in spans.items() if len(b - {0}) >= 2 and 0 in b)
    assert len(two_link) >= 2, two_link
    assert {"biceps_long", "triceps_long"} <= set(two_link)
    # every degree of freedom is crossed by at least one cable pulling each way at q = 0
    from mcdm_pin.model.terms import compute_terms

    L = compute_terms(robot, np.zeros(robot.nv)).L
    assert np.linalg.matrix_rank(L) == robot.nv
    assert np.all((L > 1e-4).any(axis=0)) and np.all((L < -1e-4).any(axis=0))


def test_L_matches_finite_differences(robot):
    from mcdm_pin.model.terms import TermsEvaluator

    rng = np.random.default_rng(7)
    evaluate = TermsEvaluator(robot)
    q = rng.uniform(-0.6, 0.6, robot.nv)
    q[robot.joint("elbow").idx_v] = rng.uniform(0.2, 1.8)
    L = evaluate(q).L.copy()
    fd = lengths_jacobian(lambda x: evaluate(x).lengths, q)
    rel = np.abs(L - fd).max() / np.abs(L).max()
    assert rel <= 1e-7, rel


@pytest.mark.parametrize("name", ["reach_forward", "abduct"])
def test_trajectory_case1_solves(robot, name):
    from mcdm_pin.inverse_dynamics import InverseDynamics
    from mcdm_pin.trajectory import load_trajectory

    traj = load_trajectory(robot, name)
    assert len(traj) == 151
    res = InverseDynamics.for_case(robot, 1).solve_trajectory(traj, progress=False)
    assert np.all(res.status == "optimal"), res.message[res.status != "optimal"]
    assert np.max(res.eom_residual) <= 1e-8
    assert np.all(res.f >= robot.f_min - 1e-9) and np.all(res.f <= robot.f_max + 1e-9)


def test_cli_info(capsys):
    from mcdm_pin.cli import main

    assert main(["info", str(SIDECAR)]) == 0
    out = capsys.readouterr().out
    assert "5 DoF" in out and "[fail]" not in out and "[warn]" not in out
    assert "cables span all 5 DoF" in out
    assert "holds the zero pose against gravity" in out
