"""Native Pinocchio joints and joint groups through the sidecar: a free-flying platform (a cable-driven
parallel robot), planar joints (native and grouped), universal and translation groups, actuated joints,
trajectories on SE(3) and CSV files with exact rates.

References: Pinocchio's ``pin.difference`` (finite differences in the tangent space) for trajectory rates;
the equation of motion for the free joint's wrench (zero whenever it holds)."""

from __future__ import annotations

import textwrap

import numpy as np
import pinocchio as pin
import pytest
import yaml

from mcdm_pin import InverseDynamics, Robot, load_trajectory
from mcdm_pin.exceptions import SidecarError

INERTIAL = '<inertial><origin xyz="0 0 0.05"/><mass value="{m}"/><inertia ixx="{i}" iyy="{i}" izz="{i}" ixy="0" ixz="0" iyz="0"/></inertial>'


def _write(tmp_path, name, urdf_body, sidecar):
    (tmp_path / f"{name}.urdf").write_text(f'<robot name="{name}">\n{textwrap.dedent(urdf_body)}\n</robot>\n')
    sidecar = {"version": 1, "name": name, "urdf": f"{name}.urdf", **sidecar}
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(sidecar, sort_keys=False))
    return path


def platform_robot(tmp_path):
    """An 8-cable spatial parallel robot: a 2 kg box platform on a floating joint inside a 2 m frame."""
    urdf = f"""
      <link name="base"/>
      <link name="platform">{INERTIAL.format(m=2.0, i=0.05)}</link>
      <joint name="platform_joint" type="floating"><parent link="base"/><child link="platform"/>
        <origin xyz="0 0 1"/></joint>"""
    corners = [(sx, sy, sz) for sz in (-1, 1) for sy in (-1, 1) for sx in (-1, 1)]
    # base corner k pulls platform corner PERM[k]: a crossing pattern with wrench closure at the centre
    # (found by an LP over the 8! patterns: a positive null vector of the structure matrix of rank 6)
    perm = (1, 6, 5, 2, 4, 0, 3, 7)
    cables = []
    for k, (sx, sy, sz) in enumerate(corners):
        px, py, pz = corners[perm[k]]
        cables.append({"name": f"c{k}", "f_min": 1.0, "f_max": 500.0, "route": [
            {"link": "base", "point": [1.0 * sx, 1.0 * sy, 1.0 + 1.0 * sz]},
            {"link": "platform", "point": [0.1 * px, 0.1 * py, 0.05 + 0.05 * pz]}]})
    sidecar = {"joints": {"platform": {"type": "free", "urdf_joints": ["platform_joint"]}}, "cables": cables,
               "trajectories": {"move": {"type": "quintic", "q_start": [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                                         "q_end": [0.1, -0.05, 0.08, 0.1, -0.08, 0.12], "duration": 1.0,
                                         "dt": 0.02}}}
    return Robot.load(_write(tmp_path, "platform", urdf, sidecar))


def test_free_platform_trajectory_and_solution(tmp_path):
    robot = platform_robot(tmp_path)
    assert robot.nq == 7 and robot.nv == 6 and robot.joints[0].type == "free"
    assert robot.coordinate_names == tuple(f"platform_joint.{s}" for s in ("x", "y", "z", "rx", "ry", "rz"))
    tr = load_trajectory(robot, "move")
    model = robot.model
    # rates against finite differences of the sampled configurations (tangent space)
    dt = tr.t[1] - tr.t[0]
    for k in range(2, len(tr) - 2, 5):
        v_fd = pin.difference(model, tr.q[k - 1], tr.q[k + 1]) / (2 * dt)
        # O(dt^2) = 4e-4 of the rates' second derivative (~ 20 /s^3 here)
        np.testing.assert_allclose(tr.qd[k], v_fd, atol=2e-2)
        a_fd = (tr.qd[k + 1] - tr.qd[k - 1]) / (2 * dt)
        np.testing.assert_allclose(tr.qdd[k], a_fd, atol=2e-1)
    # ends: the given poses, at rest
    np.testing.assert_allclose(robot.coordinates(tr.q[-1]), [0.1, -0.05, 0.08, 0.1, -0.08, 0.12], atol=1e-12)
    assert np.abs(tr.qd[[0, -1]]).max() < 1e-12 and np.abs(tr.qdd[[0, -1]]).max() < 1e-9
    # the orientation turns about one fixed axis: log(R0^T R(t)) is parallel to the end's
    axis = np.array([0.1, -0.08, 0.12]) / np.linalg.norm([0.1, -0.08, 0.12])
    for k in range(1, len(tr)):
        rv = robot.coordinates(tr.q[k])[3:]
        np.testing.assert_allclose(np.cross(rv, axis), 0.0, atol=1e-12)
    run = InverseDynamics.for_case(robot, 1).solve_trajectory(tr, progress=False)
    assert run.found.all(), run.message[~run.found]
    # a free joint transmits nothing: its wrench vanishes where the equation of motion holds
    scale = np.abs(run.f).max()
    assert np.abs(run.interaction_wrench).max() < 1e-8 * scale
    assert run.q.shape == (len(tr), 6) and run.configuration.shape == (len(tr), 7)


def test_csv_with_rate_columns_is_taken_exactly(tmp_path):
    robot = platform_robot(tmp_path)
    tr = load_trajectory(robot, "move")
    names = robot.coordinate_names
    header = ["t", *names, *(f"qd:{n}" for n in names), *(f"qdd:{n}" for n in names)]
    rows = [[t, *robot.coordinates(q), *v, *a] for t, q, v, a in zip(tr.t, tr.q, tr.qd, tr.qdd)]
    path = tmp_path / "move.csv"
    path.write_text(",".join(header) + "\n" + "\n".join(",".join(repr(float(x)) for x in r) for r in rows) + "\n")
    from mcdm_pin.trajectory import csv_trajectory

    back = csv_trajectory(robot, path)
    np.testing.assert_array_equal(back.qd, tr.qd)
    np.testing.assert_array_equal(back.qdd, tr.qdd)
    for q0, q1 in zip(back.q, tr.q):  # the same rotation (a quaternion and its negative are one)
        np.testing.assert_allclose(pin.difference(robot.model, q0, q1), 0.0, atol=1e-14)
    bad = path.read_text().replace("qdd:platform_joint.x", "acc_x", 1)
    path.write_text(bad)
    with pytest.raises(Exception, match=r"row 1, column 14: header 'acc_x'.*'qdd:platform_joint.x'"):
        csv_trajectory(robot, path)


def test_native_planar_joint_and_its_axis(tmp_path):
    link = f'<link name="cart">{INERTIAL.format(m=1.0, i=0.01)}</link>'
    cables = [{"name": f"c{k}", "f_min": 0.0, "f_max": 100.0, "route": [
        {"link": "base", "point": p}, {"link": "cart", "point": [0.0, 0.0, 0.0]}]}
        for k, p in enumerate([[1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0.1]])]
    for axis, ok in (("0 0 1", True), ("0 1 0", False)):
        urdf = f"""<link name="base"/>{link}
          <joint name="xy" type="planar"><parent link="base"/><child link="cart"/><axis xyz="{axis}"/></joint>"""
        path = _write(tmp_path, f"cart{ok}", urdf,
                      {"joints": {"cart": {"type": "planar", "urdf_joints": ["xy"]}}, "cables": cables,
                       "gravity": [0.0, 0.0, 0.0]})
        if ok:
            robot = Robot.load(path)
            assert robot.joints[0].type == "planar" and robot.nq == 4 and robot.nv == 3
            assert robot.coordinate_names == ("xy.x", "xy.y", "xy.theta")
        else:
            with pytest.raises(SidecarError, match=r"joints.cart.urdf_joints\[0\].*axis must be 0 0 1"):
                Robot.load(path)


def test_groups_universal_translation_planar_and_actuators(tmp_path):
    massless = '<link name="{}"/>'
    urdf = f"""<link name="base"/>
      {massless.format("m1")}{massless.format("m2")}{massless.format("m3")}{massless.format("m4")}
      <link name="slider">{INERTIAL.format(m=1.0, i=0.01)}</link>
      <link name="arm">{INERTIAL.format(m=0.5, i=0.01)}</link>
      <link name="hand">{INERTIAL.format(m=0.2, i=0.005)}</link>
      <joint name="sx" type="prismatic"><parent link="base"/><child link="m1"/><axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
      <joint name="sz" type="prismatic"><parent link="m1"/><child link="slider"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
      <joint name="ux" type="revolute"><parent link="slider"/><child link="m2"/><origin xyz="0 0 0.1"/><axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
      <joint name="uz" type="revolute"><parent link="m2"/><child link="arm"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
      <joint name="px" type="prismatic"><parent link="arm"/><child link="m3"/><origin xyz="0 0 0.3"/><axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
      <joint name="pz" type="prismatic"><parent link="m3"/><child link="m4"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
      <joint name="ry" type="revolute"><parent link="m4"/><child link="hand"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
    """
    rng = np.random.default_rng(3)
    cables = [{"name": f"c{k}", "f_min": 0.0, "f_max": 1000.0, "route": [
        {"link": "base", "point": rng.uniform(-1, 1, 3).round(3).tolist()},
        {"link": ["slider", "arm", "hand"][k % 3], "point": rng.uniform(-0.1, 0.1, 3).round(3).tolist()}]}
        for k in range(14)]
    joints = {"slide": {"type": "translation", "urdf_joints": ["sx", "sz"]},
              "wrist": {"type": "universal", "urdf_joints": ["ux", "uz"], "actuated": {"min": [-5, -5], "max": [5, 5], "weight": 2.0}},
              "hand": {"type": "planar", "urdf_joints": ["px", "pz", "ry"]}}
    robot = Robot.load(_write(tmp_path, "groups", urdf, {"joints": joints, "cables": cables}))
    assert [(j.name, j.type, j.nv) for j in robot.joints] == [("slide", "translation", 2), ("wrist", "universal", 2),
                                                              ("hand", "planar", 3)]
    assert robot.n_act == 2 and robot.actuators[0].weight == 2.0
    np.testing.assert_array_equal(robot.actuation[:, 0], np.eye(7)[2])
    joints["wrist"]["actuated"] = {"min": [-5], "max": [5]}
    with pytest.raises(SidecarError, match=r"joints.wrist.actuated.min: expected 2 bound"):
        Robot.load(_write(tmp_path, "groups2", urdf, {"joints": joints, "cables": cables}))
    joints["wrist"] = {"type": "universal", "urdf_joints": ["ux", "px"]}
    joints["hand"] = {"type": "planar", "urdf_joints": ["uz", "pz", "ry"]}
    with pytest.raises(SidecarError, match="joints.wrist.urdf_joints"):
        Robot.load(_write(tmp_path, "groups3", urdf, {"joints": joints, "cables": cables}))


def test_ball_joint_needs_a_floating_urdf_joint(tmp_path):
    urdf = f"""<link name="base"/><link name="a">{INERTIAL.format(m=1.0, i=0.01)}</link>
      <joint name="j" type="revolute"><parent link="base"/><child link="a"/><axis xyz="1 0 0"/>
      <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>"""
    cables = [{"name": "c", "f_min": 0.0, "f_max": 1.0, "route": [{"link": "base", "point": [0, 0, 1]},
                                                                   {"link": "a", "point": [0, 0, 0.1]}]}]
    path = _write(tmp_path, "wrong", urdf, {"joints": {"ball": {"type": "spherical", "urdf_joints": ["j"]}},
                                            "cables": cables})
    with pytest.raises(SidecarError, match=r"joints.ball.urdf_joints: a spherical joint needs 3 revolute URDF "
                                           r"joints \(xyz Euler angles\) or 1 URDF 'floating' joint"):
        Robot.load(path)
