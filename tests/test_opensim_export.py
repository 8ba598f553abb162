"""The OpenSim export (mcdm_pin/export/opensim.py): the written file's structure, and its dynamics checked
independently against ours: OpenSim's mass matrix, inverse dynamics, cable lengths and moment arms
(Simbody's own algorithms on the written .osim) equal Pinocchio's and our cable geometry at random
states to 1e-9 relative (seen: ~1e-15, rounding)."""

from __future__ import annotations

import sys

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import HealthCheck, given, settings

from mcdm_pin.exceptions import McdmError
from mcdm_pin.export.opensim import INSTALL_HINT, MissingPackageError, euler_xyz, require_opensim

from .conftest import REPO, TWO_LINK
from .robotgen import robots

TOL = 1e-9  # relative agreement of the export's dynamics with ours (the requirement; seen ~1e-15)


@pytest.fixture(scope="module")
def osim():
    return pytest.importorskip("opensim", reason=f"OpenSim not installed (optional): {INSTALL_HINT}")


def test_missing_opensim_names_the_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "opensim", None)  # import opensim -> ImportError
    with pytest.raises(MissingPackageError, match=r"pip install 'mcdm-pin\[opensim\]'"):
        require_opensim()
    assert issubclass(MissingPackageError, McdmError) and issubclass(MissingPackageError, ImportError)


def test_euler_xyz_round_trip():
    rng = np.random.default_rng(3)
    for R in [pin.exp3(rng.normal(size=3)) for _ in range(20)] + [pin.exp3(np.array([0, np.pi / 2, 0])) @
                                                                   pin.exp3(np.array([0.3, 0, 0]))]:
        a, b, c = euler_xyz(R)
        back = pin.exp3(np.array([a, 0, 0])) @ pin.exp3(np.array([0, b, 0])) @ pin.exp3(np.array([0, 0, c]))
        assert np.abs(back - R).max() < 1e-12


def test_two_link_file_structure(osim, two_link, tmp_path):
    from mcdm_pin.export import export_opensim

    path = export_opensim(two_link, tmp_path / "arm.osim")
    model = osim.Model(str(path))
    model.initSystem()
    assert [model.getBodySet().get(i).getName() for i in range(model.getBodySet().getSize())] == ["link1", "link2"]
    for name in ("link1", "link2"):
        body = model.getBodySet().get(name)
        assert body.getMass() == 0.1
        assert body.getMassCenter().to_numpy().tolist() == [0.0, 0.0, 0.1]
        assert body.getInertia().getMoments().to_numpy().tolist() == [1.0, 1.0, 1.0]
        assert body.getInertia().getProducts().to_numpy().tolist() == [0.0, 0.0, 0.0]
    assert model.getGravity().to_numpy().tolist() == [0.0, 0.0, -9.81]
    shoulder = osim.CustomJoint.safeDownCast(model.getJointSet().get("shoulder"))
    assert shoulder is not None and shoulder.getParentFrame().findBaseFrame().getName() == "ground"
    st = shoulder.getSpatialTransform()
    for k, (coord, axis) in enumerate((("q1_x", [1, 0, 0]), ("q2_y", [0, 1, 0]), ("q3_z", [0, 0, 1]))):
        assert st.getTransformAxis(k).get_coordinates(0) == coord
        assert st.getTransformAxis(k).getAxis().to_numpy().tolist() == axis
    elbow = osim.PinJoint.safeDownCast(model.getJointSet().get("elbow"))
    assert elbow is not None and elbow.get_coordinates(0).getName() == "q4_x"
    assert elbow.getParentFrame().findBaseFrame().getName() == "link1"
    assert elbow.getChildFrame().findBaseFrame().getName() == "link2"
    # its frames turn z onto x: the PinJoint's z axis is the URDF axis
    offset = osim.PhysicalOffsetFrame.safeDownCast(elbow.getParentFrame())
    a, b, c = offset.get_orientation().to_numpy()
    R = pin.exp3(np.array([a, 0, 0])) @ pin.exp3(np.array([0, b, 0])) @ pin.exp3(np.array([0, 0, c]))
    assert np.abs(R @ [0, 0, 1] - [1, 0, 0]).max() < 1e-15
    assert offset.get_translation().to_numpy().tolist() == [0.0, 0.0, 0.2]
    fs = model.getForceSet()
    assert fs.getSize() == 8
    for k, cable in enumerate(two_link.cables):
        act = osim.PathActuator.safeDownCast(fs.get(cable.name))
        assert act.getOptimalForce() == 1000.0  # the largest f_max
        assert act.getMinControl() == cable.f_min / 1000.0 and act.getMaxControl() == cable.f_max / 1000.0
        points = act.getGeometryPath().getPathPointSet()
        assert points.getSize() == 2
        frames = [points.get(i).getParentFrame().getName() for i in range(2)]
        assert frames == ["ground", "link1" if k < 4 else "link2"]
        for i, p in enumerate(cable.route):
            loc = osim.PathPoint.safeDownCast(points.get(i)).get_location().to_numpy()
            assert np.abs(loc - np.array(p.point)).max() < 1e-15


def test_two_link_file_dynamics_match_pinocchio(osim, two_link, tmp_path):
    from mcdm_pin.export import OpenSimModel, export_opensim
    from mcdm_pin.export.opensim_eval import compare_with_pinocchio

    path = export_opensim(two_link, tmp_path / "arm.osim", optimal_force=250.0)
    om = OpenSimModel(two_link, path=path)  # read back from the file
    assert om.optimal_force == 250.0
    worst = compare_with_pinocchio(two_link, om, samples=10, seed=1)
    assert max(worst.values()) < TOL, worst


@settings(max_examples=4, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture,
                                 HealthCheck.large_base_example, HealthCheck.data_too_large])
@given(gen=robots(max_links=4))
def test_random_robots_match_pinocchio(osim, tmp_path_factory, gen):
    """Chains and trees of Euler triples and revolute joints on random axes (continuous ones too), origins
    turned and moved, a moved base, cables over intermediate links."""
    from mcdm_pin.export import OpenSimModel
    from mcdm_pin.export.opensim_eval import compare_with_pinocchio

    robot = gen.load(tmp_path_factory.mktemp("gen"))
    worst = compare_with_pinocchio(robot, OpenSimModel(robot), samples=3, seed=2)
    assert max(worst.values()) < TOL, worst


def _slider_universal_robot():
    """Built in code: a prismatic joint on an unaligned axis, then a universal joint (two revolute joints
    about turned axes through a massless body), then a revolute joint."""
    from mcdm_pin import Robot
    from mcdm_pin.model import physical_joints

    model = pin.Model()
    rng = np.random.default_rng(7)

    def inertia(mass):
        return pin.Inertia(mass, rng.uniform(-0.05, 0.05, 3) + [0, 0, 0.1], np.diag(rng.uniform(0.01, 0.03, 3)))

    axis = np.array([1.0, 2.0, 0.5]) / np.linalg.norm([1.0, 2.0, 0.5])
    j1 = model.addJoint(0, pin.JointModelPrismaticUnaligned(axis), pin.SE3(pin.exp3(np.array([0.1, 0.2, 0.3])),
                                                                            np.array([0.1, 0, 0.05])), "slide")
    model.appendBodyToJoint(j1, inertia(1.0), pin.SE3.Identity())
    model.addBodyFrame("cart", j1, pin.SE3.Identity(), 0)
    turn = pin.SE3(pin.exp3(np.array([0.0, 0.0, 0.4])), np.array([0.0, 0.0, 0.2]))
    j2 = model.addJoint(j1, pin.JointModelRX(), turn, "w1")
    model.addBodyFrame("w_mid", j2, pin.SE3.Identity(), 0)
    j3 = model.addJoint(j2, pin.JointModelRY(), pin.SE3.Identity(), "w2")
    model.appendBodyToJoint(j3, inertia(0.5), pin.SE3.Identity())
    model.addBodyFrame("hand", j3, pin.SE3.Identity(), 0)
    j4 = model.addJoint(j3, pin.JointModelRevoluteUnaligned(np.array([0.0, 0.6, 0.8])),
                        pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.2])), "finger_joint")
    model.appendBodyToJoint(j4, inertia(0.2), pin.SE3.Identity())
    model.addBodyFrame("finger", j4, pin.SE3.Identity(), 0)
    cables = []
    for k, (frame, pt) in enumerate([("cart", (0.1, 0, 0.1)), ("hand", (0.05, 0.05, 0.1)), ("hand", (-0.05, 0, 0.1)),
                                     ("finger", (0, 0.03, 0.1)), ("finger", (0.03, 0, 0.1)), ("cart", (-0.1, 0, 0))]):
        route = [("universe", (0.3 * np.cos(k), 0.3 * np.sin(k), 0.0))]
        if frame == "finger":
            route.append(("hand", (0.0, 0.04, 0.15)))  # over an intermediate link
        route.append((frame, pt))
        cables.append(dict(name=f"c{k}", route=route, f_min=0.0, f_max=100.0))
    joints = physical_joints(model, groups=[("wrist", "universal", ["w1", "w2"])])
    return Robot.from_model(model, cables, joints, name="slider_universal")


def test_slider_universal_built_in_code_match_pinocchio(osim):
    from mcdm_pin.export import OpenSimModel, describe
    from mcdm_pin.export.opensim_eval import compare_with_pinocchio

    robot = _slider_universal_robot()
    assert [(j.name, j.kind) for j in describe(robot).joints] == [("slide", "slider"), ("wrist", "custom"),
                                                                   ("finger_joint", "pin")]
    worst = compare_with_pinocchio(robot, OpenSimModel(robot), samples=5, seed=4)
    assert max(worst.values()) < TOL, worst


def test_native_ball_joint_is_refused_with_its_sidecar_key(osim, tmp_path):
    from mcdm_pin import Robot
    from mcdm_pin.export import export_opensim

    robot = Robot.load(REPO / "robots" / "two_link_sr_ball.yaml")
    with pytest.raises(McdmError, match=r"two_link_sr_ball\.yaml: joints\.shoulder: .*no OpenSim counterpart"):
        export_opensim(robot, tmp_path / "ball.osim")
    assert not (tmp_path / "ball.osim").exists()


def test_cli_export_and_check(osim, tmp_path, capsys):
    from mcdm_pin.cli import main

    out = tmp_path / "sub" / "arm.osim"
    assert main(["export-opensim", str(TWO_LINK), str(out), "--check", "2"]) == 2  # no folder sub/: nothing made
    assert "the folder" in capsys.readouterr().err and not out.parent.exists()
    out.parent.mkdir()
    assert main(["export-opensim", str(TWO_LINK), str(out), "--check", "2"]) == 0
    text = capsys.readouterr().out
    assert out.is_file() and "8 PathActuators" in text and "moment arms" in text
    assert main(["export-opensim", str(TWO_LINK), str(out), "--optimal-force", "0"]) == 2
    assert "--optimal-force: expected a force > 0 N" in capsys.readouterr().err


def test_names_opensim_refuses_are_rewritten(osim, tmp_path):
    """OpenSim refuses spaces, slashes and ``\\ * +`` in a component's name; the neck's cables are named
    like ``cleid-mast (right)``. They become ``_``, duplicates get ``#2``, and the model still matches
    Pinocchio's dynamics and moment arms."""
    import yaml

    from mcdm_pin import Robot
    from mcdm_pin.export import OpenSimModel, export_opensim
    from mcdm_pin.export.opensim_eval import compare_with_pinocchio

    sc = yaml.safe_load(TWO_LINK.read_text())
    sc["urdf"] = str((TWO_LINK.parent / sc["urdf"]).resolve())
    sc.pop("trajectories", None)
    sc["cables"][0]["name"] = "cleid-mast (right)"
    sc["cables"][1]["name"] = "cleid-mast/right"
    sc["cables"][2]["name"] = "a*b+c"
    (tmp_path / "arm.yaml").write_text(yaml.safe_dump(sc, sort_keys=False))
    robot = Robot.load(tmp_path / "arm.yaml")
    path = export_opensim(robot, tmp_path / "arm.osim")
    om = OpenSimModel(robot, path=path)
    names = [c.name for c in om.spec.cables]
    assert names[:3] == ["cleid-mast_(right)", "cleid-mast_right", "a_b_c"]
    worst = compare_with_pinocchio(robot, om, samples=4, seed=2)
    assert max(worst.values()) < TOL, worst
