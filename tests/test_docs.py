"""The docs a newcomer follows are run: docs/first_robot.md's two URDFs and its sidecar load, ``info``
prints what the page shows, ``solve`` answers every instant; a massless subtree is refused as the page
says. And the API reference (docs/api) is what its generator makes from today's docstrings."""

from __future__ import annotations

import re
import subprocess
import sys

import numpy as np
import pytest

from mcdm_pin import InverseDynamics, Robot, load_trajectory
from mcdm_pin.cli import main

from .conftest import REPO

PAGE = REPO / "docs" / "first_robot.md"


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """The files of docs/first_robot.md, written where the page's sidecar expects them."""
    folder = tmp_path_factory.mktemp("first_robot")
    text = PAGE.read_text()
    found = re.findall(r"<!-- file: (\S+) -->\n```\w+\n(.*?)```", text, flags=re.S)
    assert [name for name, _ in found] == ["one_ball.urdf", "one_ball_native.urdf", "one_ball.yaml"]
    for name, body in found:
        (folder / name).write_text(body)
    return folder


def test_first_robot_info_prints_what_the_page_shows(files, capsys):
    assert main(["info", str(files / "one_ball.yaml")]) == 0
    out = capsys.readouterr().out.splitlines()
    shown = re.search(r"`info` ends with\n\n```\n(.*?)```", PAGE.read_text(), flags=re.S).group(1).splitlines()
    assert out[-len(shown):] == shown


def test_first_robot_solves_and_the_native_ball_joint_agrees(files):
    robot = Robot.load(files / "one_ball.yaml")
    run = InverseDynamics.for_case(robot, 3).solve_trajectory(load_trajectory(robot, "tilt"), progress=False)
    assert run.found.all() and len(run) == 51
    assert run.interaction_angle_deg[:, 0].max() < 17.0  # "within 17 deg of the socket axis"
    # the native ball joint, as the page says to declare it
    text = (files / "one_ball.yaml").read_text()
    text = text.replace("urdf: one_ball.urdf", "urdf: one_ball_native.urdf").replace(
        "urdf_joints: [ball_rx, ball_ry, ball_rz]", "urdf_joints: [ball]\n    parametrization: quaternion")
    (files / "native.yaml").write_text(text)
    ball = Robot.load(files / "native.yaml")
    assert ball.nq == 4 and ball.nv == 3 and ball.coordinate_names == ("ball.rx", "ball.ry", "ball.rz")
    run = InverseDynamics.for_case(ball, 3).solve_trajectory(load_trajectory(ball, "tilt"), progress=False)
    assert run.found.all()


def test_massless_links_need_no_inertial_but_a_massless_subtree_is_refused(files, capsys):
    import pinocchio as pin

    model = pin.buildModelFromUrdf(str(files / "one_ball.urdf"))
    assert [model.inertias[j].mass for j in (1, 2, 3)] == [0.0, 0.0, 0.5]
    data = model.createData()
    q, v, a = np.array([0.3, -0.2, 0.5]), np.array([0.1, 0.2, 0.3]), np.array([1.0, -2.0, 0.5])
    tau = pin.rnea(model, data, q, v, a)
    assert np.abs(pin.aba(model, data, q, v, tau) - a).max() < 1e-12  # measured 2.7e-15
    urdf = (files / "one_ball.urdf").read_text()
    start, end = urdf.index("<inertial>"), urdf.index("</inertial>") + len("</inertial>")
    (files / "massless.urdf").write_text(urdf[:start] + urdf[end:])
    (files / "massless.yaml").write_text((files / "one_ball.yaml").read_text().replace(
        "urdf: one_ball.urdf", "urdf: massless.urdf"))
    assert main(["info", str(files / "massless.yaml"), "--samples", "0"]) == 1
    assert "[fail] the body moved by joint" in capsys.readouterr().out


def test_api_reference_is_generated_from_todays_docstrings(tmp_path):
    """docs/api is made by docs/api/generate.py; this rebuilds it and compares, so that a changed
    docstring or signature cannot leave the reference behind (regenerate with
    ``python docs/api/generate.py``)."""
    proc = subprocess.run([sys.executable, str(REPO / "docs" / "api" / "generate.py"), "--out", str(tmp_path)],
                          cwd=REPO, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    built = {p.name: p.read_text() for p in tmp_path.glob("*.md")}
    committed = {p.name: p.read_text() for p in (REPO / "docs" / "api").glob("*.md")}
    assert sorted(built) == sorted(committed), "pages added or removed: run python docs/api/generate.py"
    stale = [name for name in built if built[name] != committed[name]]
    assert not stale, f"docs/api is stale ({', '.join(stale)}): run python docs/api/generate.py"
    # the attributes newcomers looked for in notebooks are in the reference
    results = built["mcdm_pin.results.md"]
    for name in ("found", "infeasible", "force_magnitude"):
        assert f"### `TrajectoryResult.{name}` (property)" in results, name
    for name in ("save", "load"):
        assert f"### `TrajectoryResult.{name}`" in results, name
    assert "joint_types" in results and "(N,) True at the instants with a valid answer" in results
