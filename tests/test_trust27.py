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
