"""RMR's shoulder problem (mcdm_pin.osim.rmr) on the committed ABD01 excerpt: the sidecar's cone is
the model's glenoid markers' (as RMR computes it), the excerpt reproduces the full motion where the
reference data are present, and a few frames with and without the cone reach Clarabel's objective,
hold our constraints, and land near RMR's activations."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mcdm_pin.inverse_dynamics import InverseDynamics
from mcdm_pin.osim.glenoid import glenoid_cone
from mcdm_pin.osim.rmr import (GH, N_MUSCLES, excerpt_answers, frame_states, rmr_objective, rmr_problem,
                               rmr_robot)

REPO = Path(__file__).resolve().parents[1]
EXCERPT = REPO / "robots" / "opensim" / "motions" / "abd01"
FILES = tuple(EXCERPT / f"Kinematics_{k}.sto" for k in ("q", "u", "dudt"))
ROWS = (100, 450, 700)  # frames k (k / 100 s): arm low, rising, high


@pytest.fixture(scope="module")
def robot():
    return rmr_robot("abd01")


def test_the_sidecar_cone_is_rmrs_glenoid_cone(robot):
    axis, angle = glenoid_cone(robot)
    gh = robot.joint(GH)
    assert np.allclose(gh.socket_axis, axis, atol=1e-6)
    assert abs(gh.cone_deg - angle) < 1e-5
    assert angle == pytest.approx(19.0338, abs=1e-4)


def test_rmr_weights_and_bounds(robot):
    weights = {a.label: a.weight * float(a.tau_max[0] / 1e4) ** 2 for a in robot.actuators}
    assert sum(w == 0 for w in weights.values()) == 8 and sum(w == 10 for w in weights.values()) == 9
    assert np.all([m.a_min == 0.0 for m in robot.cables.muscles.muscles])


@pytest.mark.parametrize("cone", [False, True], ids=["without_GH", "with_GH"])
def test_frames_match_clarabel_and_land_near_rmr(robot, cone):
    rows, X = excerpt_answers(EXCERPT, cone)
    Q, V, A = frame_states(robot, FILES, ROWS)
    problem = rmr_problem(robot, cone)
    ours, ref = InverseDynamics(robot, problem), InverseDynamics(robot, problem, solver="clarabel")
    j = robot.joint_names.index(GH)
    for k, q, v, a in zip(ROWS, Q, V, A):
        res, cla = ours.solve(q, v, a), ref.solve(q, v, a)
        assert res.status == "optimal" and cla.status == "optimal", (res.message, cla.message)
        assert abs(res.objective - cla.objective) <= 1e-6 * abs(cla.objective)
        assert res.eom_residual < 1e-8
        if cone:
            assert res.interaction_angle_deg[j] <= robot.joint(GH).cone_deg + 1e-6
        x = X[list(rows).index(k)]
        act = res.activation[robot.cables.muscle_index]
        assert np.sqrt(np.mean((act - x[:N_MUSCLES]) ** 2)) < 0.02  # measured 0.001-0.009 (docs/opensim.md)
        assert abs(res.objective - rmr_objective(robot, x)) < 0.1 * rmr_objective(robot, x)
