"""Issue 27's silently wrong answers, now refused or right: one configuration check for every entry
point, trajectory CSV headers matched by name, case 2 with a constant objective, an instant at a
cable anchor, and inertias no body can have."""

from __future__ import annotations

import numpy as np
import pytest

from mcdm_pin import Robot, StateError
from mcdm_pin.trajectory import Trajectory

from .conftest import REPO

BALL = REPO / "robots" / "two_link_sr_ball.yaml"


@pytest.fixture(scope="module")
def ball():
    return Robot.load(BALL)


# ------------------------------------------------------------------ 1. one configuration check
def test_every_entry_point_refuses_a_quaternion_of_norm_2(ball):
    from mcdm_pin.inverse_dynamics import InverseDynamics
    from mcdm_pin.model import terms

    q = ball.configuration([0.3, 0.1, 0.0, 0.2])
    q2 = q.copy()
    q2[:4] *= 2.0  # the shoulder's quaternion, norm 2
    ident = InverseDynamics.for_case(ball, 1)
    with pytest.raises(StateError, match="quaternion of joint 'shoulder_ball' has norm 2"):
        ident.solve(q2)
    traj = Trajectory("two", [0.0, 0.1], np.array([q, q2]), np.zeros((2, 4)), np.zeros((2, 4)))
    with pytest.raises(StateError, match=r"trajectory 'two': q\[1\]: the quaternion of joint 'shoulder_ball'"):
        ident.solve_trajectory(traj)
    data = ball.model.createData()
    for call in (lambda x: terms.cable_jacobian(ball.model, data, ball.cables, x),
                 lambda x: terms.cable_lengths(ball.model, data, ball.cables, x),
                 lambda x: terms.interaction_map(ball.model, data, ball.cables, ["shoulder_ball"], x),
                 lambda x: terms.TermsEvaluator(ball)(x)):
        with pytest.raises(StateError, match="has norm 2"):
            call(q2)
    # within the tolerance a quaternion is normalised, the same way everywhere
    q_near = q.copy()
    q_near[:4] *= 1.0 + 5e-7
    L = terms.cable_jacobian(ball.model, data, ball.cables, q)
    assert np.abs(terms.cable_jacobian(ball.model, data, ball.cables, q_near) - L).max() < 1e-14
    near = Trajectory("near", [0.0], q_near[None], np.zeros((1, 4)), np.zeros((1, 4)))
    f_traj = ident.solve_trajectory(near).f[0]
    assert np.abs(f_traj - ident.solve(q).f).max() < 1e-6


# ------------------------------------------------------------------ 2. CSV headers by name
def _quintic_csv(robot, path, order=None, rates=False):
    from mcdm_pin import load_trajectory

    tr = load_trajectory(robot, "traj2")
    names = ["t", *robot.coordinate_names]
    cols = [tr.t[:, None], tr.q]
    if rates:
        names += [f"qd:{c}" for c in robot.coordinate_names] + [f"qdd:{c}" for c in robot.coordinate_names]
        cols += [tr.qd, tr.qdd]
    data = np.hstack(cols)
    order = list(range(len(names))) if order is None else order
    np.savetxt(path, data[:, order], delimiter=",", header=",".join(names[i] for i in order), comments="")
    return tr


@pytest.mark.parametrize("rates", [False, True])
def test_csv_header_in_another_order_reads_the_same(two_link, tmp_path, rates):
    from mcdm_pin import csv_trajectory

    _quintic_csv(two_link, tmp_path / "a.csv", rates=rates)
    n = 1 + (3 if rates else 1) * two_link.nv
    order = list(np.random.default_rng(3).permutation(n))
    assert order != sorted(order)
    _quintic_csv(two_link, tmp_path / "b.csv", order=order, rates=rates)
    a, b = csv_trajectory(two_link, tmp_path / "a.csv"), csv_trajectory(two_link, tmp_path / "b.csv")
    for key in ("t", "q", "qd", "qdd"):
        assert np.array_equal(getattr(a, key), getattr(b, key)), key


@pytest.mark.parametrize("edit, message", [
    (lambda h, r: (h.replace("q2_y", "q2_z"), r), r"column 3: header 'q2_z' names no column \(did you mean"),
    (lambda h, r: (h.replace("q2_y", "q1_x"), r), "names 'q1_x' twice"),
    (lambda h, r: (",".join(h.split(",")[:5]), r), r"row 2: expected the header's 5 columns, got 13"),
    (lambda h, r: (",".join(h.split(",")[:7]), [",".join(x.split(",")[:7]) for x in r]),
     "names some rate columns but not 'qd:q3_z'"),
    (lambda h, r: (",".join(h.split(",")[:4]), [",".join(x.split(",")[:4]) for x in r]), "no column 'q4_x'"),
])
def test_csv_header_that_does_not_match_is_refused(two_link, tmp_path, edit, message):
    from mcdm_pin import TrajectoryError, csv_trajectory

    path = tmp_path / "x.csv"
    _quintic_csv(two_link, path, rates=True)
    head, *rows = path.read_text().splitlines()
    head, rows = edit(head, rows)
    path.write_text("\n".join([head, *rows]) + "\n")
    with pytest.raises(TrajectoryError, match=message) as info:
        csv_trajectory(two_link, path)
    assert str(path) in str(info.value)


# ------------------------------------------------------------------ 4. an instant at a cable anchor
def _point_through_anchor(tmp_path):
    """CASPR's Example_point_XZ (a 5 kg point in the xz plane) with anchors that hold it: cable 1's
    anchor at the origin, where every trajectory starts or passes, cables 2 and 3 above."""
    import yaml

    src = REPO / "robots" / "caspr" / "Example_point_XZ" / "Example_point_XZ.yaml"
    data = yaml.safe_load(src.read_text())
    data["urdf"] = str((src.parent / data["urdf"]).resolve())
    data["cables"][1]["route"][0]["point"] = [-1.0, 0.0, 2.0]
    data["cables"][2]["route"][0]["point"] = [1.0, 0.0, 2.0]
    path = tmp_path / "point.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def test_an_instant_at_a_cable_anchor_gets_its_own_status(tmp_path, capsys, monkeypatch):
    from mcdm_pin import TrajectoryResult
    from mcdm_pin.cli import main

    monkeypatch.chdir(tmp_path)
    robot = _point_through_anchor(tmp_path)
    npz, csv = tmp_path / "run.npz", tmp_path / "run.csv"
    # traj_bottom_to_top passes z = 0 (cable 1's anchor) at its middle sample, t = 2 s
    assert main(["solve", str(robot), "-t", "traj_bottom_to_top", "--samples", "11", "-q",
                 "--out", str(npz), "--out", str(csv)]) == 0
    out = capsys.readouterr().out
    assert "no valid answer at 1 of 11 instants" in out
    assert "t = 2.000 s  error: at t = 2 s (instant 5): cable 'cable 1': a segment has zero length" in out
    run = TrajectoryResult.load(npz)
    assert run.status.tolist() == ["optimal"] * 5 + ["error"] + ["optimal"] * 5
    assert np.isnan(run.f[5]).all() and np.isfinite(run.f[run.found]).all()
    # the others are right: the point's statics, g m = 49.05 N up, met by the forces
    assert np.abs(run.eom_residual[run.found]).max() < 1e-8
    assert csv.read_text().count("\n") == 12
    assert main(["plot", str(npz), "--out", str(tmp_path / "fig"), "--format", "png"]) == 0
    assert any((tmp_path / "fig").iterdir())
    assert main(["verify", str(robot), str(npz), "--levels", "2"]) in (0, 1)
    assert "Traceback" not in capsys.readouterr().err


def test_gimbal_lock_names_the_file_the_trajectory_and_the_instant(tmp_path):
    import yaml

    from mcdm_pin import TrajectoryError, load_trajectory

    from .conftest import TWO_LINK, TWO_LINK_URDF

    data = yaml.safe_load(TWO_LINK.read_text())
    data["urdf"] = str(TWO_LINK_URDF)
    data["trajectories"]["traj1"]["q_end"] = [0.3, float(np.pi / 2), 0.2, 0.0]
    path = tmp_path / "lock.yaml"
    path.write_text(yaml.safe_dump(data))
    robot = Robot.load(path)
    with pytest.raises(TrajectoryError) as info:
        load_trajectory(robot, "traj1")
    text = str(info.value)
    assert text.startswith(f"{path}: trajectories.traj1: trajectory 'traj1' at t = 0.96 s (sample 96): ")
    assert "are 0.0542 deg from +-90 deg" in text and "gimbal lock" in text


# ------------------------------------------------------------------ 3. a constant objective
@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("solver", ["default", "proxqp", "clarabel"])
def test_case_2_with_every_weight_zero_is_the_least_norm_answer(solver, compiled, monkeypatch):
    """CASPR's ACROBOT (a free-floating platform, alpha = beta = 0): case 2's objective is zero on
    the feasible set, so every feasible force is optimal and the least-norm one is case 1's answer."""
    import warnings

    from mcdm_pin import jit
    from mcdm_pin.inverse_dynamics import InverseDynamics

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = Robot.load(REPO / "robots" / "caspr" / "ACROBOT" / "ACROBOT.yaml")
    x = np.array([0.4, 0.4, 0.5, 0.1, -0.05, 0.2])
    ref = InverseDynamics.for_case(robot, 1, solver="clarabel").solve(x)
    assert ref.status == "optimal"
    if not compiled:
        jit.prepare()
        monkeypatch.setattr(jit, "_READY", False)
    res = InverseDynamics.for_case(robot, 2, solver=solver).solve(x)
    assert res.status == "optimal", res.message
    assert res.objective == pytest.approx(0.0, abs=1e-12)
    assert np.abs(res.f - ref.f).max() < 1e-6 * np.abs(ref.f).max()


def test_case_2_planar_all_ones_is_optimal():
    """A planar robot whose cables lie in its plane: the interaction wrench is fixed by the motion,
    so the objective (weights 1) is constant on the feasible set and its gradient is rounding."""
    import warnings

    from mcdm_pin import load_trajectory
    from mcdm_pin.inverse_dynamics import InverseDynamics

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = Robot.load(REPO / "robots" / "caspr" / "Example_planar_XY" / "Example_planar_XY.yaml")
    traj = load_trajectory(robot, "example_quintic").subsample(11)
    ones = {j.name: 1.0 for j in robot.joints}
    for solver in ("default", "proxqp"):
        run = InverseDynamics.for_case(robot, 2, solver=solver, alpha=ones, beta=ones).solve_trajectory(traj)
        assert run.found.all(), (solver, run.status, run.message)
        ref = InverseDynamics.for_case(robot, 1, solver="clarabel").solve_trajectory(traj)
        assert np.abs(run.f - ref.f).max() < 1e-6 * np.abs(ref.f).max()


# ------------------------------------------------------------------ 5. inertias no body can have
def _two_link_with_inertia(tmp_path, izz: str, provenance: bool = False):
    """The paper's arm with link 1's inertia replaced by (0.01, 0.01, izz) kg m^2 about its COM."""
    import re

    import yaml

    from .conftest import TWO_LINK, TWO_LINK_URDF

    text = TWO_LINK_URDF.read_text()
    start = text.index('<link name="link1"')
    body = text[start:text.index("</link>", start)]
    new = re.sub(r"<inertia [^>]*/>", f'<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="{izz}"/>', body)
    text = text[:start] + new + text[start + len(body):]
    if provenance:
        from mcdm_pin.urdf import CASPR_PROVENANCE
        text = text.replace("<robot", f"<!--\n  {CASPR_PROVENANCE}some_bodies.xml.\n-->\n<robot", 1)
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(text)
    data = yaml.safe_load(TWO_LINK.read_text())
    data["urdf"] = str(urdf)
    path = tmp_path / "arm.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_a_hand_written_urdf_with_an_impossible_inertia_is_refused(tmp_path):
    from mcdm_pin.exceptions import ModelError

    with pytest.raises(ModelError) as info:
        Robot.load(_two_link_with_inertia(tmp_path, "0.0201"))
    text = str(info.value)
    assert "arm.urdf" in text and "'link1' [0.01, 0.01, 0.0201]" in text and "A + B >= C" in text
    Robot.load(_two_link_with_inertia(tmp_path, "0.02"))  # a flat plate: A + B = C exactly


def test_a_caspr_conversion_keeps_its_inertias_loudly(tmp_path):
    from mcdm_pin.exceptions import InertiaWarning

    with pytest.warns(InertiaWarning, match=r"'link1' \[0.01, 0.01, 0.0201\].*accepted as CASPR ships them"):
        Robot.load(_two_link_with_inertia(tmp_path, "0.0201", provenance=True))


def test_a_pin_model_with_an_impossible_inertia_is_refused():
    import pinocchio as pin

    from mcdm_pin.exceptions import ModelError

    model = pin.Model()
    j = model.addJoint(0, pin.JointModelRX(), pin.SE3.Identity(), "hinge")
    model.appendBodyToJoint(j, pin.Inertia(1.0, np.array([0.0, 0.0, 0.1]), np.diag([0.01, 0.01, 0.03])),
                            pin.SE3.Identity())
    model.addBodyFrame("arm", j, pin.SE3.Identity(), 0)
    cables = [dict(name="c", route=[("universe", (0.1, 0.0, 0.0)), ("arm", (0.0, 0.0, 0.1))], f_min=0.0, f_max=10.0)]
    with pytest.raises(ModelError, match=r"pin.Model: .* the body of joint 'hinge' \[0.01, 0.01, 0.03\]"):
        Robot.from_model(model, cables)
    model.inertias[j] = pin.Inertia(1.0, np.array([0.0, 0.0, 0.1]), np.diag([0.01, 0.02, 0.03]))
    Robot.from_model(model, cables)


def test_shipped_caspr_models_with_impossible_inertias_load_with_a_warning(capsys):
    from mcdm_pin.cli import main
    from mcdm_pin.exceptions import InertiaWarning

    path = REPO / "robots" / "caspr" / "RoboyUpperBody" / "RoboyUpperBody.yaml"
    with pytest.warns(InertiaWarning, match=r"19 link\(s\) have principal moments"):
        Robot.load(path)
    with pytest.warns(InertiaWarning):
        assert main(["info", str(REPO / "robots" / "caspr" / "BioBiped_one_leg" / "BioBiped_one_leg.yaml"),
                     "--samples", "0"]) == 0
    out = capsys.readouterr().out
    assert "[warn] inertias as CASPR ships them: 3 link(s)" in out and "'Thigh' [0.01815, 0.01815, 0.1]" in out


def test_caspr_import_warns_naming_the_element(tmp_path):
    from mcdm_pin.caspr import import_caspr
    from mcdm_pin.exceptions import InertiaWarning

    from . import caspr_xml as X

    b = X.bodies(tmp_path / "b.xml", [dict(type="R_X", ixx=0.01, iyy=0.01, izz=0.03)])
    c = X.cables(tmp_path / "c.xml", {"s": X.star(1, 6)})
    with pytest.warns(InertiaWarning) as record:
        res = import_caspr(b, c, tmp_path / "out")
    texts = [str(w.message) for w in record]
    assert len(texts) == 1 and "link_rigid[num='1', name='L1']/physical/inertia" in texts[0] and str(b) in texts[0]
    with pytest.warns(InertiaWarning, match="accepted as CASPR ships them"):
        Robot.load(res.sidecar)
