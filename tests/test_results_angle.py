"""The results store no interaction angle for joints without a socket axis (issue 27 item 3): a
revolute joint's column is NaN in memory, in the .npz and in the CSV; spherical joints keep theirs."""

from __future__ import annotations

import numpy as np

from mcdm_pin import InverseDynamics, Robot, load_trajectory
from mcdm_pin.results import TrajectoryResult, socket_angles
from mcdm_pin.trajectory import Trajectory

from .conftest import REPO

PLANAR = REPO / "robots" / "caspr" / "Example_2R_planar_XZ" / "Example_2R_planar_XZ.yaml"


def _short(robot, name, n=5):
    traj = load_trajectory(robot, name)
    idx = np.linspace(0, len(traj.t) - 1, n).astype(int)
    return Trajectory(name, traj.t[idx], traj.q[idx], traj.qd[idx], traj.qdd[idx])


def test_revolute_joints_have_no_angle_in_the_npz(tmp_path):
    robot = Robot.load(PLANAR)
    assert [j.type for j in robot.joints] == ["revolute", "revolute"]
    run = InverseDynamics.for_case(robot, 1).solve_trajectory(_short(robot, "traj_MPC_test"), progress=False)
    assert run.found.all()
    assert np.isnan(run.interaction_angle_deg).all()
    assert np.all(np.isfinite(run.interaction_wrench))  # the forces are there; only the angle is not
    back = TrajectoryResult.load(run.save(tmp_path / "r.npz"))
    assert np.isnan(back.interaction_angle_deg).all()
    csv = (tmp_path / "r.csv")
    run.save(csv)
    header = csv.read_text().splitlines()[0].split(",")
    rows = np.genfromtxt(csv, delimiter=",", skip_header=1)
    col = header.index(f"angle_deg[{robot.joint_names[0]}]")
    assert np.isnan(rows[:, col]).all()


def test_spherical_joints_keep_their_angle(two_link):
    run = InverseDynamics.for_case(two_link, 1).solve_trajectory(_short(two_link, "traj1"), progress=False)
    types = [j.type for j in two_link.joints]
    sph = [k for k, t in enumerate(types) if t == "spherical"]
    other = [k for k, t in enumerate(types) if t != "spherical"]
    assert sph and other
    a = run.interaction_angle_deg
    assert np.isfinite(a[:, sph]).all() and np.isnan(a[:, other]).all()
    # the angle of a spherical joint is that of F (socket frame) from +z
    Fs = run.interaction_force_socket[:, sph[0]]
    ref = np.degrees(np.arccos(Fs[:, 2] / np.linalg.norm(Fs, axis=1)))
    np.testing.assert_allclose(a[:, sph[0]], ref, atol=1e-9)


def test_a_cone_keeps_the_angle():
    from types import SimpleNamespace as NS
    rob = NS(joints=[NS(type="spherical", cone_deg=None), NS(type="revolute", cone_deg=None),
                     NS(type="composite", cone_deg=19.0), NS(type="universal", cone_deg=None)])
    a = np.array([[10.0, 20.0, 30.0, 40.0]])
    out = socket_angles(a, rob, np.array([np.nan, np.nan, np.nan, 15.0]))
    assert np.isfinite(out[0, 0]) and np.isnan(out[0, 1]) and out[0, 2] == 30.0 and out[0, 3] == 40.0
