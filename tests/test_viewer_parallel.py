"""The viewer on parallel cable robots and long chains (issue 27 item 3): a platform drawn as the hull
of its attachment points, no arrow for a free joint's round-off, the camera framing the anchors, the
neck's arrows thinned, and the workspace cloud's cable scale from the store. Scene-level checks, no
render (the screenshots in docs/pictures.md are looked at by hand)."""

from __future__ import annotations

import numpy as np
import pytest

from mcdm_pin import InverseDynamics, Robot, load_trajectory
from mcdm_pin.viewer import build_scene
from mcdm_pin.viewer.animation import FORCE_FLOOR, arrow_share, drawn_forces
from mcdm_pin.viewer.camera import FILL, FOV_DEG, camera_basis
from mcdm_pin.viewer.visuals import platform_hull

from .conftest import REPO

COGIRO = REPO / "robots" / "caspr" / "CoGiRo" / "CoGiRo.yaml"


@pytest.fixture(scope="module")
def cogiro():
    robot = Robot.load(COGIRO)
    traj = load_trajectory(robot, "general_1")
    idx = np.arange(0, len(traj.t), 40)
    from mcdm_pin.trajectory import Trajectory
    short = Trajectory("general_1", traj.t[idx], traj.q[idx], traj.qd[idx], traj.qdd[idx])
    result = InverseDynamics.for_case(robot, 1).solve_trajectory(short, progress=False)
    return robot, result, build_scene(robot, result)


def _objects(scene):
    return {c["path"]: c for c in scene.commands if c["type"] == "set_object"}


def test_platform_is_the_hull_of_its_attachment_points(cogiro):
    robot, _, scene = cogiro
    objects = _objects(scene)
    path = "/meshcat/mcdm/bodies/CoGiRo_free/platform"
    assert path in objects, sorted(p for p in objects if "bodies" in p)
    from scipy.spatial import ConvexHull
    on = robot.cables.point_local[robot.cables.point_joint == robot.model.getJointId("CoGiRo_free")]
    v, faces = platform_hull(on)
    # every attachment point is a vertex of the hull, and the hull's volume is that of the points'
    assert len(on) == 8 and all(np.min(np.linalg.norm(v - p, axis=1)) < 1e-12 for p in on)
    vol = np.einsum("ij,ij->i", v[faces[:, 0]], np.cross(v[faces[:, 1]], v[faces[:, 2]])).sum() / 6
    assert vol == pytest.approx(ConvexHull(on).volume, rel=1e-9) and vol > 0  # outward faces
    # no 1.6 cm sphere stands for the platform
    assert "/meshcat/mcdm/bodies/CoGiRo_free/joint" not in objects


def test_flat_platform_gets_a_thickness_and_a_line_none():
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    v, faces = platform_hull(square)
    assert np.ptp(v[:, 2]) == pytest.approx(0.04 * np.sqrt(2))
    assert platform_hull(np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]], float)) is None


def test_free_joint_round_off_is_not_an_arrow(cogiro):
    robot, result, scene = cogiro
    F = np.linalg.norm(np.asarray(result.interaction_wrench)[:, 0, :3], axis=1)
    assert 0 < F.max() < 1e-9  # what the solver reports on the free joint: round-off
    assert not any("/forces/" in p or "/labels/" in p for p in _objects(scene))
    assert scene.arrow_scale == 0.0
    assert not drawn_forces(robot, result.interaction_wrench, result.f).any()


def test_small_forces_below_the_floor_are_not_drawn(two_link):
    wrench = np.zeros((3, len(two_link.joints), 6))
    wrench[:, 0, 0] = [10.0, 5e-6, 0.0]
    wrench[:, 1, 2] = 1e-8
    shown = drawn_forces(two_link, wrench, np.full((3, two_link.m), 1.0))
    assert shown[:, 0].tolist() == [True, False, False] and not shown[:, 1].any()
    assert FORCE_FLOOR * 10.0 < 5e-6 * 10


def test_camera_frames_the_anchors_over_the_trajectory(cogiro):
    robot, _, scene = cogiro
    anchors = robot.cables.point_local[robot.cables.point_joint == 0] @ scene.up.T - scene.center
    u, right, up = camera_basis(scene.camera)
    depth = np.linalg.norm(scene.camera) - anchors @ u
    x, y = anchors @ right / depth, anchors @ up / depth
    tv = np.tan(np.radians(FOV_DEG) / 2)
    share_h, share_w = np.ptp(y) / (2 * tv), np.ptp(x) / (2 * tv * 1.25)
    assert max(share_h, share_w) > 0.6 and min(share_h, share_w) > 0.3  # c30bf0a: 0.72 x 0.14
    assert np.all(np.abs(y) <= tv * FILL + 1e-9) and np.all(np.abs(x) <= 1.25 * tv * FILL + 1e-9)


def test_many_arrows_are_thinner_and_shorter():
    assert arrow_share(1) == arrow_share(2) == 1.0
    assert arrow_share(8) == pytest.approx(0.5)


def test_workspace_cloud_cables_on_the_stores_scale():
    from mcdm_pin.workspace.cloud import cable_scale
    assert cable_scale(np.array([[1e-3, 1e-3], [420.0, np.nan]])) == 500.0
    assert cable_scale(np.full((2, 2), np.nan)) == 1.0
