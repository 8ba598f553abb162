"""Trajectories: the quintic, CASPR's one-axis spherical interpolation, and CSV files."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from mcdm_pin import TrajectoryError, csv_trajectory, load_trajectory, quintic_trajectory
from mcdm_pin.trajectory import SphericalKinematics, quintic_profile


def test_paper_trajectories_have_101_samples(two_link):
    for name in ("traj1", "traj2"):
        tr = load_trajectory(two_link, name)
        assert len(tr) == 101 and tr.t[-1] == pytest.approx(1.0)
    tr = load_trajectory(two_link, "traj2")
    assert tr.q[0] == pytest.approx([0.2, -0.2, -0.1, 0.2], abs=1e-14)
    assert tr.q[-1] == pytest.approx([-0.5, 0.5, 0.2, -0.2], abs=1e-14)
    assert np.abs(tr.qd[[0, -1]]).max() < 1e-14 and np.abs(tr.qdd[[0, -1]]).max() < 1e-12


def test_single_axis_motion_equals_per_coordinate(two_link):
    """traj1 turns about x only: CASPR's axis-angle interpolation reduces to a scalar quintic."""
    a = load_trajectory(two_link, "traj1")
    spec = two_link.sidecar.trajectories["traj1"]
    b = quintic_trajectory(two_link, spec.q_start, spec.q_end, 1.0, 0.01, spherical="per-coordinate")
    assert np.abs(a.q - b.q).max() < 1e-12
    assert np.abs(a.qd - b.qd).max() < 1e-10 and np.abs(a.qdd - b.qdd).max() < 1e-9


def test_spherical_joint_turns_about_one_fixed_axis(two_link):
    tr = load_trajectory(two_link, "traj2")
    kin = SphericalKinematics(two_link, two_link.joints[0])
    R0 = kin.rotation(tr.q[0, :3])
    phi = pin.log3(R0.T @ kin.rotation(tr.q[-1, :3]))
    s, _, _ = quintic_profile(tr.t, 1.0)
    for k in range(len(tr)):
        rel = pin.log3(R0.T @ kin.rotation(tr.q[k, :3]))
        assert np.abs(rel - s[k] * phi).max() < 1e-12
    # per-coordinate interpolation of the same end points is a different motion
    spec = two_link.sidecar.trajectories["traj2"]
    pc = quintic_trajectory(two_link, spec.q_start, spec.q_end, 1.0, 0.01, spherical="per-coordinate")
    assert np.abs(pc.q[50, :3] - tr.q[50, :3]).max() > 1e-3


def test_rates_match_finite_differences(two_link):
    spec = two_link.sidecar.trajectories["traj2"]
    dt = 1e-4
    tr = quintic_trajectory(two_link, spec.q_start, spec.q_end, 1.0, dt)
    k = np.arange(100, len(tr) - 100, 997)
    qd_fd = (tr.q[k + 1] - tr.q[k - 1]) / (2 * dt)
    qdd_fd = (tr.qd[k + 1] - tr.qd[k - 1]) / (2 * dt)
    # central differences: error ~ dt^2 |q'''| / 6 ~ 1e-8 * O(100)
    assert np.abs(qd_fd - tr.qd[k]).max() < 1e-6
    assert np.abs(qdd_fd - tr.qdd[k]).max() < 1e-5


def test_csv_trajectory_differentiates_a_quintic_spline(two_link, tmp_path):
    spec = two_link.sidecar.trajectories["traj1"]
    ref = quintic_trajectory(two_link, spec.q_start, spec.q_end, 1.0, 0.01)
    path = tmp_path / "traj.csv"
    header = "t," + ",".join(two_link.coordinate_names)
    np.savetxt(path, np.column_stack([ref.t, ref.q]), delimiter=",", header=header, comments="")
    tr = csv_trajectory(two_link, path)
    assert np.array_equal(tr.q, ref.q)
    # the quintic in t is reproduced by a quintic spline except near the not-a-knot ends
    inner = slice(5, -5)
    assert np.abs(tr.qd[inner] - ref.qd[inner]).max() < 1e-6
    assert np.abs(tr.qdd[inner] - ref.qdd[inner]).max() < 1e-4


@pytest.mark.parametrize("text, message", [
    ("t,q1_x,q2_y,q3_z,q4_x\n0,0,0,0,0\n", "at least 6"),
    ("t,a,b,c,d\n0,0,0,0,0\n", "column 2: header 'a' names no column"),
    ("0,0,0,0\n" * 7, "columns"),
    ("".join(f"{t},0,0,0,0\n" for t in [0, 1, 2, 2, 3, 4, 5]), "increase"),
    ("".join(f"{t},0,x,0,0\n" for t in range(7)), r"row 1, column 3: expected a number"),
])
def test_bad_csv(two_link, tmp_path, text, message):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(TrajectoryError, match=message) as info:
        csv_trajectory(two_link, path)
    assert str(path) in str(info.value)


def test_unknown_trajectory_lists_names(two_link):
    with pytest.raises(TrajectoryError, match="traj1"):
        load_trajectory(two_link, "nope")


def test_configuration_by_joint_name(two_link, tmp_path):
    import yaml

    from mcdm_pin import Robot

    from .conftest import TWO_LINK, TWO_LINK_URDF
    data = yaml.safe_load(TWO_LINK.read_text())
    data["urdf"] = str(TWO_LINK_URDF)
    data["trajectories"] = {"named": {"type": "quintic", "q_start": {"shoulder": [0.1, 0, 0]},
                                      "q_end": {"elbow": 0.3}, "duration": 0.5, "dt": 0.1}}
    path = tmp_path / "r.yaml"
    path.write_text(yaml.safe_dump(data))
    robot = Robot.load(path)
    tr = load_trajectory(robot, "named")
    assert tr.q[0] == pytest.approx([0.1, 0, 0, 0]) and tr.q[-1] == pytest.approx([0, 0, 0, 0.3])
    data["trajectories"]["named"]["q_end"] = {"elbow": [0.3, 0.2]}
    path.write_text(yaml.safe_dump(data))
    from mcdm_pin import SidecarError
    with pytest.raises(SidecarError, match="trajectories.named.q_end.elbow"):
        load_trajectory(Robot.load(path), "named")
