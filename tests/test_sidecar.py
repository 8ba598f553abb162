"""Bad sidecar input gets a clear error: the package's own type, naming file, key path and what was
expected. One test per case (issue 2, item 6)."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
import yaml

from mcdm_pin import Robot, SidecarError, StateError, compute_terms, load_sidecar
from mcdm_pin.exceptions import McdmError, ModelError

from .conftest import TWO_LINK, TWO_LINK_URDF

BASE = yaml.safe_load(TWO_LINK.read_text())
BASE["urdf"] = str(TWO_LINK_URDF)


def write(tmp_path, data, name="robot.yaml"):
    path = tmp_path / name
    path.write_text(data if isinstance(data, str) else yaml.safe_dump(data, sort_keys=False))
    return path


def load_error(tmp_path, data, exc=SidecarError):
    path = write(tmp_path, data)
    with pytest.raises(exc) as info:
        Robot.load(path)
    assert isinstance(info.value, McdmError)
    if exc is SidecarError:
        assert str(path) in str(info.value)
    return info.value


def mutate(fn):
    data = copy.deepcopy(BASE)
    fn(data)
    return data


def test_valid_sidecar_loads(tmp_path):
    sc = load_sidecar(write(tmp_path, BASE))
    assert sc.version == 1 and len(sc.cables) == 8 and sc.joints[0].cone_deg == 30.0
    assert sc.gravity == (0.0, 0.0, -9.81)


def test_missing_file(tmp_path):
    with pytest.raises(SidecarError, match="file not found"):
        load_sidecar(tmp_path / "nope.yaml")


def test_malformed_yaml(tmp_path):
    err = load_error(tmp_path, "version: 1\njoints: [a, b\n")
    assert "malformed YAML" in str(err) and "line" in str(err)


def test_unknown_top_level_key(tmp_path):
    err = load_error(tmp_path, mutate(lambda d: d.update(cabels=[])))
    assert err.key == "cabels" and "unknown key" in str(err) and "'cables'" in str(err)


def test_unknown_nested_key(tmp_path):
    err = load_error(tmp_path, mutate(lambda d: d["cables"][3]["route"][1].update(pt=[0, 0, 0])))
    assert err.key == "cables[3].route[1].pt"


def test_unsupported_version(tmp_path):
    err = load_error(tmp_path, mutate(lambda d: d.update(version=7)))
    assert err.key == "version" and "[1]" in str(err)


def test_missing_urdf(tmp_path):
    err = load_error(tmp_path, mutate(lambda d: d.update(urdf="missing.urdf")))
    assert err.key == "urdf" and "not found" in str(err)


def test_unresolvable_package_uri(tmp_path):
    err = load_error(tmp_path, mutate(lambda d: d.update(urdf="package://no_such_pkg/robot.urdf")))
    assert err.key == "urdf" and "no_such_pkg" in str(err)


def test_unknown_link_lists_valid_links(tmp_path):
    err = load_error(tmp_path, mutate(lambda d: d["cables"][3]["route"][1].update(link="lnik1")))
    assert err.key == "cables[3].route[1].link"
    assert "'lnik1'" in str(err) and "'link1'" in str(err) and "'base'" in str(err)


def test_unknown_urdf_joint_lists_valid_joints(tmp_path):
    err = load_error(tmp_path, mutate(lambda d: d["joints"]["elbow"].update(urdf_joints=["q9"])))
    assert err.key == "joints.elbow.urdf_joints[0]" and "'q4_x'" in str(err)


def test_route_with_one_point(tmp_path):
    err = load_error(tmp_path, mutate(lambda d: d["cables"][0].update(route=d["cables"][0]["route"][:1])))
    assert err.key == "cables[0].route" and "at least two" in str(err)


def test_negative_f_min(tmp_path):
    err = load_error(tmp_path, mutate(lambda d: d["cables"][2].update(f_min=-1.0)))
    assert err.key == "cables[2].f_min" and ">= 0" in str(err)


def test_f_max_not_above_f_min(tmp_path):
    err = load_error(tmp_path, mutate(lambda d: d["cables"][2].update(f_min=5.0, f_max=5.0)))
    assert err.key == "cables[2].f_max" and "f_max > f_min" in str(err)


@pytest.mark.parametrize("bad", [".nan", ".inf", "-.inf"])
def test_non_finite_number(tmp_path, bad):
    text = yaml.safe_dump(BASE, sort_keys=False).replace("f_max: 1000.0", f"f_max: {bad}", 1)
    err = load_error(tmp_path, text)
    assert err.key == "cables[0].f_max" and "finite" in str(err)


def test_wrong_type(tmp_path):
    err = load_error(tmp_path, mutate(lambda d: d["cables"][1]["route"][0].update(point=[0, "x", 0])))
    assert err.key == "cables[1].route[0].point[1]" and "number" in str(err)


def test_duplicate_cable_name(tmp_path):
    err = load_error(tmp_path, mutate(lambda d: d["cables"][4].update(name="cable1")))
    assert err.key == "cables[4].name" and "cables[0]" in str(err)


def test_cable_spanning_no_two_bodies(tmp_path):
    def same_body(d):
        d["cables"][0]["route"] = [{"link": "link1", "point": [0, 0, 0]},
                                   {"link": "link1", "point": [0, 0, 0.1]}]
    err = load_error(tmp_path, mutate(same_body))
    assert err.key == "cables[0].route" and "no segment spanning two different bodies" in str(err)


def test_cable_on_massless_intermediate_link(tmp_path):
    err = load_error(tmp_path, mutate(lambda d: d["cables"][0]["route"][1].update(link="link1_rx")))
    assert err.key == "cables[0].route[1].link" and "massless" in str(err)


def test_movable_joint_not_assigned(tmp_path):
    err = load_error(tmp_path, mutate(lambda d: d["joints"].pop("elbow")))
    assert err.key == "joints" and "'q4_x'" in str(err)


def test_locked_unknown_joint(tmp_path):
    err = load_error(tmp_path, mutate(lambda d: d.update(locked_joints={"nope": 0.0})))
    assert err.key == "locked_joints.nope"


def test_cone_on_revolute_joint(tmp_path):
    err = load_error(tmp_path, mutate(lambda d: d["joints"]["elbow"].update(cone_deg=20)))
    assert err.key == "joints.elbow.cone_deg" and "spherical" in str(err)


def test_socket_axis_not_unit(tmp_path):
    err = load_error(tmp_path, mutate(lambda d: d["joints"]["shoulder"].update(socket_axis=[0, 0, 2])))
    assert err.key == "joints.shoulder.socket_axis" and "unit" in str(err)


def test_spherical_needs_three(tmp_path):
    err = load_error(tmp_path, mutate(lambda d: d["joints"]["shoulder"].update(urdf_joints=["q1_x"])))
    assert err.key == "joints.shoulder.urdf_joints" and "3" in str(err)


# --- spherical groups that are not three orthogonal revolutes in series joined by massless links
URDF_TEMPLATE = """<?xml version="1.0"?>
<robot name="s">
  <link name="base"/>
  <link name="a">{a_inertial}</link>
  <link name="b"/>
  <link name="c"><inertial><origin xyz="0 0 0.1"/><mass value="1"/>
    <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
  <joint name="jx" type="revolute"><parent link="base"/><child link="a"/>
    <axis xyz="1 0 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="jy" type="revolute"><parent link="a"/><child link="b"/><origin xyz="{by}"/>
    <axis xyz="{y_axis}"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="jz" type="revolute"><parent link="b"/><child link="c"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>
"""


def spherical_case(tmp_path, order=("jx", "jy", "jz"), a_inertial="", by="0 0 0", y_axis="0 1 0"):
    urdf = tmp_path / "s.urdf"
    urdf.write_text(URDF_TEMPLATE.format(a_inertial=a_inertial, by=by, y_axis=y_axis))
    data = {"version": 1, "urdf": "s.urdf",
            "joints": {"ball": {"type": "spherical", "urdf_joints": list(order)}},
            "cables": [{"name": f"c{i}", "f_min": 0.0, "f_max": 10.0,
                        "route": [{"link": "base", "point": [math.cos(i), math.sin(i), 0.0]},
                                  {"link": "c", "point": [0.0, 0.0, 0.1]}]} for i in range(4)]}
    return data


def test_spherical_valid_group_loads(tmp_path):
    Robot.load(write(tmp_path, spherical_case(tmp_path)))


def test_spherical_not_orthogonal(tmp_path):
    err = load_error(tmp_path, spherical_case(tmp_path, y_axis="0.6 0.8 0"))
    assert err.key == "joints.ball.urdf_joints" and "orthogonal" in str(err)


def test_spherical_not_in_series(tmp_path):
    err = load_error(tmp_path, spherical_case(tmp_path, order=("jx", "jz", "jy")))
    assert "in series" in str(err)


def test_spherical_not_meeting_at_one_point(tmp_path):
    err = load_error(tmp_path, spherical_case(tmp_path, by="0 0 0.05"))
    assert "one point" in str(err)


def test_spherical_massive_intermediate_link(tmp_path):
    inertial = ('<inertial><mass value="0.5"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" '
                'izz="1"/></inertial>')
    err = load_error(tmp_path, spherical_case(tmp_path, a_inertial=inertial))
    assert "massless" in str(err) and "'jx'" in str(err)


def test_spherical_revolute_group_of_prismatic(tmp_path):
    data = mutate(lambda d: d["joints"]["elbow"].update(type="prismatic"))
    err = load_error(tmp_path, data)
    assert err.key == "joints.elbow.urdf_joints[0]" and "prismatic" in str(err)


def test_broken_urdf_is_model_error(tmp_path):
    (tmp_path / "bad.urdf").write_text("<robot name='x'><link name='a'/><joint name='j'/></robot>")
    data = copy.deepcopy(BASE)
    data["urdf"] = "bad.urdf"
    err = load_error(tmp_path, data, exc=ModelError)
    assert "bad.urdf" in str(err)


@pytest.mark.parametrize("arg, value, message", [
    ("q", np.zeros(3), "length 4"),
    ("q", [0.0, np.nan, 0.0, 0.0], "finite"),
    ("qd", [0.0, 0.0, np.inf, 0.0], "finite"),
    ("qdd", np.zeros(5), "length 4"),
    ("q", "abc", "expected"),
])
def test_bad_state_is_state_error(two_link, arg, value, message):
    kwargs = {"q": np.zeros(4), "qd": np.zeros(4), "qdd": np.zeros(4)}
    kwargs[arg] = value
    with pytest.raises(StateError, match=message) as info:
        compute_terms(two_link, **kwargs)
    assert arg in str(info.value)


def test_documented_example_loads(tmp_path):
    """The complete example in docs/sidecar.md is valid (keeps the docs in sync with the code)."""
    from .conftest import REPO
    text = (REPO / "docs" / "sidecar.md").read_text()
    block = text.split("```yaml\n", 1)[1].split("```", 1)[0]
    data = yaml.safe_load(block)
    data["urdf"] = str(TWO_LINK_URDF)
    robot = Robot.load(write(tmp_path, data))
    assert robot.m == 2 and robot.joint_names == ("shoulder", "elbow")
    from mcdm_pin import load_trajectory
    tr = load_trajectory(robot, "traj1")
    assert tr.q[-1] == pytest.approx([-math.pi / 6, 0, 0, math.pi / 10], abs=1e-14)
