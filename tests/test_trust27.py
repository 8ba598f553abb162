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
