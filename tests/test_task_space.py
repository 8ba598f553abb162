"""Task-space trajectories (mcdm_pin.ik): inverse kinematics with pink, rates by the task Jacobian.

References independent of the code under test: forward kinematics by Pinocchio's frame placements with
the Euler angles from SciPy's ``Rotation.as_euler`` (``ZYX``/``XYZ`` intrinsic), and central finite
differences of that forward kinematics along the solved motion for the velocity and acceleration
relations; CASPR's quintic written out by hand for the imported BMArm trajectory.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml
from scipy.spatial.transform import Rotation

pytest.importorskip("pink")

from mcdm_pin.exceptions import MissingPackageError, TrajectoryError  # noqa: E402
from mcdm_pin.ik import TaskSpace, solve_task  # noqa: E402
from mcdm_pin.ik.samples import pose_samples  # noqa: E402

CASPR = Path(__file__).resolve().parent / "data" / "caspr"  # CASPR's BMArm XML (committed)
FRAME = "wrist2_body"
POINT = (0.1, -0.05, 0.2)


def _fk(model, space, q) -> np.ndarray:
    """y(q): the point by Pinocchio's frame placement, the angles by SciPy."""
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    M = data.oMf[model.getFrameId(space.frame)]
    p = M.act(np.asarray(space.point))
    if space.euler == "zyx":  # R = Rz(g) Ry(b) Rx(a): intrinsic ZYX gives (g, b, a)
        g, b, a = Rotation.from_matrix(M.rotation).as_euler("ZYX")
    else:  # R = Rx(a) Ry(b) Rz(g): intrinsic XYZ
        a, b, g = Rotation.from_matrix(M.rotation).as_euler("XYZ")
    full = dict(x=p[0], y=p[1], z=p[2], a=a, b=b, g=g)
    return np.array([full[c] for c in space.coordinates])


def _wrap(e, space):
    e = np.array(e, dtype=float)
    ang = space.angle_mask
    e[..., ang] = (e[..., ang] + np.pi) % (2 * np.pi) - np.pi
    return e


def _task(model, space, qa, qb, duration=1.0, dt=0.02):
    """A rest-to-rest quintic in task space between the poses of two configurations."""
    return pose_samples(((0.0, _fk(model, space, qa)), (duration, _fk(model, space, qb))), dt)


@pytest.mark.parametrize("coords, euler", [("xyz", "zyx"), ("xyzabg", "zyx"), ("zag", "xyz"), ("bx", "zyx")])
def test_fk_and_rates_against_finite_differences(coords, euler):
    """FK of the result meets the requested poses to 1e-9; J qd = yd and J qdd + Jd qd = ydd, checked
    by finite differences of the independent FK along the solved motion (redundant tasks included:
    3, 2 and 6 coordinates on a 6-DoF arm)."""
    model = pin.buildSampleModelManipulator()
    space = TaskSpace(FRAME, POINT, coords, euler)
    qa = pin.neutral(model) + np.array([0.2, -0.4, 0.6, 0.3, -0.5, 0.4])
    qb = qa + np.array([0.3, 0.2, -0.25, 0.2, 0.3, -0.2])
    t, y, yd, ydd = _task(model, space, qa, qb)
    sol = solve_task(model, space, t, y, yd, ydd, q_seed=qa, limits=False)
    assert sol.fk_error <= 1e-9 and sol.velocity_residual <= 1e-12 and sol.acceleration_residual <= 1e-11
    h = 1e-4
    for k in range(0, len(t), 7):
        q, v, a = sol.q[k], sol.qd[k], sol.qdd[k]
        assert np.max(np.abs(_wrap(_fk(model, space, q) - y[k], space))) <= 1e-9
        Y = [_fk(model, space, pin.integrate(model, q, s * h * v + 0.5 * (s * h) ** 2 * a)) for s in (-1, 0, 1)]
        vel = _wrap(Y[2] - Y[0], space) / (2 * h)
        acc = (_wrap(Y[2] - Y[1], space) - _wrap(Y[1] - Y[0], space)) / h**2
        np.testing.assert_allclose(vel, yd[k], atol=1e-6)
        np.testing.assert_allclose(acc, ydd[k], atol=2e-5 * max(1.0, np.max(np.abs(ydd[k]))))


def test_positions_follow_their_rates_on_a_square_task():
    """6 coordinates on 6 DoF: the IK positions and the rates are one motion (fourth-order central
    differences of q over the samples against qd, to O(dt^4))."""
    model = pin.buildSampleModelManipulator()
    space = TaskSpace(FRAME, POINT, "xyzabg", "zyx")
    qa = pin.neutral(model) + np.array([0.2, -0.4, 0.6, 0.3, -0.5, 0.4])
    t, y, yd, ydd = _task(model, space, qa, qa + 0.3, dt=0.002)
    sol = solve_task(model, space, t, y, yd, ydd, q_seed=qa, limits=False)
    dt = t[1] - t[0]
    d = [[pin.difference(model, sol.q[k], sol.q[k + j]) for j in (-2, -1, 1, 2)] for k in range(2, len(t) - 2)]
    fd = np.array([(m2 - 8 * m1 + 8 * p1 - p2) / (12 * dt) for m2, m1, p1, p2 in d])
    np.testing.assert_allclose(fd, sol.qd[2:-2], atol=1e-7)


def test_full_orientation_passes_gimbal_lock():
    """All three angles kept: the orientation is compared as a rotation, so a motion to b = 1.5708 rad
    (just past pi/2, as CASPR's SpiderBot_UR3 'orientation' asks; the Euler rates are undefined at pi/2)
    is solved, here on a free-flying body (nq = 7, nv = 6); FK meets it to 1e-9."""
    model = pin.Model()
    root = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root")
    model.appendBodyToJoint(root, pin.Inertia.FromSphere(1.0, 0.1), pin.SE3.Identity())
    model.addBodyFrame("body", root, pin.SE3.Identity(), 0)
    space = TaskSpace("body", POINT, "xyzabg", "zyx")
    y0 = np.array([0.1, 0.2, 0.3, 0.3, 0.2, -0.1])
    y1 = np.array([0.2, 0.1, 0.4, 0.0, 1.5708, 0.5])
    t, y, yd, ydd = pose_samples(((0.0, y0), (1.0, y1)), 0.02)
    sol = solve_task(model, space, t, y, yd, ydd)
    assert sol.fk_error <= 1e-9 and sol.velocity_residual <= 1e-12
    data = model.createData()
    for k in (0, len(t) // 2, len(t) - 1):  # the orientation against the angles, by SciPy
        pin.framesForwardKinematics(model, data, sol.q[k])
        want = Rotation.from_euler("ZYX", y[k][[5, 4, 3]]).as_matrix()
        assert np.linalg.norm(pin.log3(want.T @ data.oMf[model.getFrameId("body")].rotation)) <= 1e-9


def test_unreachable_pose_is_refused_with_time_and_residual():
    model = pin.buildSampleModelManipulator()
    space = TaskSpace(FRAME, POINT, "xyz")
    qa = pin.neutral(model) + 0.3
    y0 = _fk(model, space, qa)
    t, y, yd, ydd = pose_samples(((0.0, y0), (1.0, y0 + [5.0, 0.0, 0.0])), 0.05)  # 5 m away: out of reach
    with pytest.raises(TrajectoryError, match=r"trajectory 'far': at t = 0\.\d+ s the inverse kinematics did "
                                              r"not converge: residual [0-9.e+-]+ .* out of reach"):
        solve_task(model, space, t, y, yd, ydd, q_seed=qa, name="trajectory 'far'", limits=False)


def test_missing_pink_names_the_extra(monkeypatch):
    model = pin.buildSampleModelManipulator()
    monkeypatch.setitem(sys.modules, "pink", None)
    with pytest.raises(MissingPackageError, match=r"pip install 'mcdm-pin\[ik\]'"):
        solve_task(model, TaskSpace(FRAME), [0.0], [[0, 0, 0]], [[0, 0, 0]], [[0, 0, 0]])


# ------------------------------------------------------------------------------------------ CASPR
def _bmarm(tmp_path, *ids):
    from mcdm_pin.cli import main

    L = CASPR / "BMArm"
    args = ["import-caspr", str(L / "BMArm_bodies.xml"), str(L / "BMArm_cables.xml"), "--trajectories",
            str(L / "BMArm_trajectories.xml"), "--out", str(tmp_path / "out")]
    for i in ids:
        args += ["--trajectory", i]
    return main(args)


def test_caspr_operational_trajectory_end_to_end(tmp_path, capsys):
    """BMArm's op_space_control_traj_1 (set ee_pose: the point 0.243 m along y of link 2, xyz) through
    import-caspr (its operational-spaces file found beside the bodies file): FK of the written joint
    trajectory against CASPR's quintic written out by hand, then case 1 solved along it."""
    from mcdm_pin.inverse_dynamics import InverseDynamics
    from mcdm_pin.robot import Robot
    from mcdm_pin.trajectory import load_trajectory

    tid = "operational:op_space_control_traj_1"
    assert _bmarm(tmp_path, tid) == 0
    assert "forward kinematics misses the poses by" in capsys.readouterr().out
    robot = Robot.load(tmp_path / "out" / "BMArm.yaml")
    traj = load_trajectory(robot, tid)
    assert len(traj.t) == 201 and traj.t[-1] == pytest.approx(1.0)
    y0, y1 = np.array([0, 0.5851, 0.0066]), np.array([0.08, 0.57, 0.08])
    tau = traj.t / 1.0
    s = tau**3 * (10 - 15 * tau + 6 * tau**2)
    space = TaskSpace("Lower_Arm", (0.0, 0.2430, 0.0), "xyz")
    fk = np.array([_fk(robot.model, space, q) for q in traj.q])
    assert np.max(np.abs(fk - (y0 + np.outer(s, y1 - y0)))) <= 1e-9
    run = InverseDynamics.for_case(robot, 1).solve_trajectory(traj.subsample(21), progress=False)
    assert set(run.status) == {"optimal"} and np.max(run.eom_residual) <= 1e-9


def test_caspr_unreachable_trajectory_is_refused_alone(tmp_path, capsys):
    """BMArm's simple_motion asks for (0.2, 0.3, 0.3) m, out of the arm's reach within its joint limits:
    refused alone, with its time and residual; the other trajectory asked for is imported."""
    from mcdm_pin.caspr import import_caspr

    L = CASPR / "BMArm"
    res = import_caspr(L / "BMArm_bodies.xml", L / "BMArm_cables.xml", tmp_path / "out",
                       trajectories_xml=L / "BMArm_trajectories.xml",
                       trajectory_ids=["operational:op_space_control_traj_1", "traj_test"])
    assert set(res.trajectories) == {"operational:op_space_control_traj_1", "traj_test"}
    from mcdm_pin.robot import Robot
    from mcdm_pin.trajectory import load_trajectory

    robot = Robot.load(res.sidecar)
    tid = "operational:op_space_control_traj_1"
    exact, written = res.exact_trajectory(robot, tid), load_trajectory(robot, tid)
    for key in ("t", "q", "qd", "qdd"):  # the CSV holds the solution to the last bit
        np.testing.assert_array_equal(getattr(exact, key), getattr(written, key))
    assert res.samples(tid).q.shape == (201, 3)
    from mcdm_pin.exceptions import CasprError

    with pytest.raises(CasprError, match=r"simple_motion.*at t = 0 s the inverse kinematics did not converge: "
                                         r"residual 0\.04\d+ .*out of reach within the joint limits"):
        import_caspr(L / "BMArm_bodies.xml", L / "BMArm_cables.xml", tmp_path / "out2",
                     trajectories_xml=L / "BMArm_trajectories.xml", trajectory_ids=["operational:simple_motion"])


# ---------------------------------------------------------------------------------------- sidecar
def test_sidecar_task_trajectory_poses_and_csv(tmp_path):
    """A sidecar declares a task trajectory on any robot (here the imported BMArm): by poses and by a
    CSV of poses (columns in any order); FK of the result meets the poses to 1e-9."""
    from mcdm_pin.robot import Robot
    from mcdm_pin.trajectory import load_trajectory

    _bmarm(tmp_path, "traj_test")
    sc = tmp_path / "out" / "BMArm.yaml"
    data = yaml.safe_load(sc.read_text())
    poses = [{"t": 0.0, "y": [0.0, 0.5851, 0.0066]}, {"t": 0.5, "y": [0.05, 0.575, 0.05]},
             {"t": 1.0, "y": [0.0, 0.56, 0.08]}]
    t = np.linspace(0, 1, 11)
    rows = ["t,z,x,y"] + [f"{a},{0.0066 + 0.05 * a * a},{0.08 * a * a},{0.5851 - 0.01 * a}" for a in t]
    (tmp_path / "out" / "poses.csv").write_text("\n".join(rows) + "\n")
    common = {"type": "task", "frame": "Lower_Arm", "point": [0, 0.243, 0]}
    data["trajectories"] = {"reach": dict(common, poses=poses, dt=0.05, q_seed=[0.18, 0, 0, -0.45]),
                            "file": dict(common, file="poses.csv")}
    sc.write_text(yaml.safe_dump(data))
    robot = Robot.load(sc)
    space = TaskSpace("Lower_Arm", (0.0, 0.243, 0.0), "xyz")
    reach = load_trajectory(robot, "reach")
    ts, y, _, _ = pose_samples([(p["t"], p["y"]) for p in poses], 0.05)
    np.testing.assert_allclose(reach.t, ts)
    assert max(np.max(np.abs(_fk(robot.model, space, q) - yk)) for q, yk in zip(reach.q, y)) <= 1e-9
    f = load_trajectory(robot, "file")
    want = np.column_stack([0.08 * t * t, 0.5851 - 0.01 * t, 0.0066 + 0.05 * t * t])
    assert max(np.max(np.abs(_fk(robot.model, space, q) - w)) for q, w in zip(f.q, want)) <= 1e-9
    data["trajectories"] = {"bad": dict(common, poses=poses)}
    sc.write_text(yaml.safe_dump(data))
    from mcdm_pin.exceptions import SidecarError

    with pytest.raises(SidecarError, match=r"trajectories\.bad\.dt: missing"):
        Robot.load(sc)


def test_documented_task_trajectory_solves(tmp_path):
    """The ``reach`` trajectory of docs/sidecar.md's complete example solves on its two-link arm."""
    from mcdm_pin import load_trajectory
    from mcdm_pin.robot import Robot

    from .conftest import REPO, TWO_LINK_URDF

    text = (REPO / "docs" / "sidecar.md").read_text()
    data = yaml.safe_load(text.split("```yaml\n", 1)[1].split("```", 1)[0])
    data["urdf"] = str(TWO_LINK_URDF)
    (tmp_path / "robot.yaml").write_text(yaml.safe_dump(data))
    robot = Robot.load(tmp_path / "robot.yaml")
    spec = robot.sidecar.trajectories["reach"]
    tr = load_trajectory(robot, "reach")
    space = TaskSpace(spec.frame, spec.point, spec.coordinates)
    assert len(tr.t) == 101
    np.testing.assert_allclose(_fk(robot.model, space, tr.q[-1]), spec.poses[-1][1], atol=1e-9)


def test_caspr_operational_spaces_file_types_and_refusals(tmp_path):
    """A synthetic model (the SR arm of tests/caspr_xml.py): the operational-spaces file found beside the
    bodies file; quintic and linear operational trajectories solved (FK against the splines written out
    by hand), a cubic one refused as CASPR does not implement it, an unreadable file found beside the
    bodies refuses the operational trajectories alone, and the same file given explicitly is an error."""
    from mcdm_pin.caspr import import_caspr
    from mcdm_pin.exceptions import CasprError
    from mcdm_pin.robot import Robot
    from mcdm_pin.trajectory import load_trajectory

    from . import caspr_xml as X

    b, c, t = X.sr_arm(tmp_path)
    X.bodies(b, [dict(type="S_EULER_XYZ", mass=0.1, ixx=1, iyy=1, izz=1),  # the elbow starts bent: q_initial
                 dict(type="R_X", mass=0.1, ixx=1, iyy=1, izz=1, q=[0.3])])  # off the stretched singularity
    robot = Robot.load(import_caspr(b, c, tmp_path / "probe").sidecar)
    space = TaskSpace("L2", (0.0, 0.0, 0.1), "zx")
    ya, yb = (_fk(robot.model, space, robot.configuration(x)) for x in ([0.1, 0.2, 0, 0.3], [0.2, -0.1, 0, 0.5]))
    (tmp_path / "sr_operational_spaces.xml").write_text(
        '<operational_spaces default_operational_set="tip"><operational_set id="tip"><position marker_id="1" '
        'name="tip"><link>2</link><offset>0 0 0.1</offset><axes active_axes="zx"/></position></operational_set>'
        '</operational_spaces>')

    def pts(rates):
        r = "<y_dot>0 0</y_dot><y_ddot>0 0</y_ddot>" if rates else ""
        return (f"<points><point><y>{X._nums(ya)}</y>{r}</point><point time=\"1\"><y>{X._nums(yb)}</y>{r}</point>"
                f"</points>")

    ops = [f'<{tag} id="{tid}" time_definition="absolute" time_step="0.05">{pts(tag.startswith("quintic"))}</{tag}>'
           for tag, tid in (("quintic_spline_trajectory", "reach"), ("linear_spline_trajectory", "line"),
                            ("cubic_spline_trajectory", "cub"))]
    traj = X.trajectories(tmp_path / "sr_trajectories.xml", [X.trajectory("quintic_spline_trajectory", "j", [
        X.point([0] * 4, [0] * 4, [0] * 4), X.point([0.1] * 4, [0] * 4, [0] * 4, time=1)])], ops)
    res = import_caspr(b, c, tmp_path / "out", trajectories_xml=traj)
    assert set(res.trajectories) == {"j", "operational:reach", "operational:line"}
    assert "implements quintic_spline_trajectory and linear_spline_trajectory only" in res.refused["operational:cub"]
    robot = Robot.load(res.sidecar)
    quintic = lambda s: s**3 * (10 - 15 * s + 6 * s**2)  # noqa: E731
    for tid, profile in (("operational:reach", quintic), ("operational:line", lambda s: s)):
        tr = load_trajectory(robot, tid)
        want = ya + np.outer(profile(tr.t), yb - ya)
        assert np.max(np.abs(np.array([_fk(robot.model, space, q) for q in tr.q]) - want)) <= 1e-9
    (tmp_path / "sr_operational_spaces.xml").write_text("<operational_spaces><operational_set id='x'>")
    res = import_caspr(b, c, tmp_path / "out2", trajectories_xml=traj)
    assert set(res.trajectories) == {"j"} and "cannot be read" in res.refused["operational:reach"]
    with pytest.raises(CasprError, match="sr_operational_spaces.xml"):
        import_caspr(b, c, tmp_path / "out3", trajectories_xml=traj,
                     operational_spaces_xml=tmp_path / "sr_operational_spaces.xml")
