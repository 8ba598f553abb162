"""RMR's shoulder problem (mcdm_pin.osim.rmr) on committed data (RMR's ABD01 IK and its answers in the
excerpt): the sidecar's cone is the model's glenoid markers' (as RMR computes it), a few frames at RMR's
states with and without the cone reach Clarabel's objective, hold our constraints and land near RMR's
activations, xsol's 51st column is RMR's serratus mean, and RMR's residual in our equation is the one
OpenSim predicts from RMR's own acceleration error."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mcdm_pin.inverse_dynamics import InverseDynamics
from mcdm_pin.osim.glenoid import glenoid_cone
from mcdm_pin.osim.rmr import (GH, N_MUSCLES, excerpt_answers, rmr_objective, rmr_problem, rmr_robot,
                               rmr_states)

REPO = Path(__file__).resolve().parents[1]
EXCERPT = REPO / "robots" / "opensim" / "motions" / "abd01"
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
    Q, V, A = rmr_states(robot, "abd01", ROWS)  # RMR's own states: its filtered IK
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


def test_xsol_51st_column_is_the_serratus_anterior_mean():
    """RMR's Results/RMR analysis/average_serratus_anterior.m appended it after solving: 33 activations,
    17 controls, then the mean of the three serratus anterior activations (columns 5-7)."""
    for cone in (False, True):
        _, X = excerpt_answers(EXCERPT, cone)
        assert X.shape[1] == 51
        assert np.abs(X[:, 50] - X[:, 4:7].mean(axis=1)).max() < 1e-9  # the CSV's 10 digits


def test_rmr_answer_in_our_equation_is_its_opensim_residual(robot):
    """At RMR's own states (its filtered IK) and force model (no fibre damping), our muscle forces at
    RMR's answer equal OpenSim's, and RMR's residual in our equation of motion is the one OpenSim's
    forward dynamics predicts from RMR's acceleration error (fmincon's tolerance), -(N K)^T E^T M r."""
    import importlib.util

    from mcdm_pin.osim import speeds
    from mcdm_pin.osim.rmr import IK_FOLDER, _unknowns, rmr_kinematics, rmr_states
    from mcdm_pin.problem import Context

    spec = importlib.util.spec_from_file_location("rmr_opensim", REPO / "tools" / "rmr_opensim.py")
    rmr_opensim = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(rmr_opensim)
    q_t, u_t, a_t = rmr_kinematics(IK_FOLDER / "ABD01.mot")
    names = list(q_t.labels)
    unit = np.array([1.0 if n.startswith("ground_thorax_t") else np.pi / 180.0 for n in names])
    ref = rmr_opensim.OpenSimRMR(robot.source.maps.source, names)
    maps = robot.source.maps
    cv = [int(maps.coordinate_v[maps.coordinates.index(n)]) for n in names]
    rows, X = excerpt_answers(EXCERPT, False)
    ident = InverseDynamics(robot, rmr_problem(robot, False))
    for k, q, v, a in zip(ROWS, *rmr_states(robot, "abd01", ROWS)):
        x = X[list(rows).index(k), :50]
        ref.frame(q_t.data[k] * unit, u_t.data[k] * unit)
        r = ref.accelerations(x) - a_t.data[k] * unit
        terms = ident.evaluate(q, v, a)
        qp = ident.problem.assemble(terms, Context(robot))
        y = _unknowns(robot, terms.muscles, x)
        f_ours, f_osim = y[robot.cables.muscle_index], ref.muscle_forces(x)
        assert np.abs(f_ours - f_osim).max() < 1e-6 * np.abs(f_osim).max()
        n = terms.tau.shape[0]
        tau = np.zeros(robot.model.nv)
        tau[cv] = ref.times_mass(r)
        predicted = -terms.basis.T @ speeds.forces_to_pin(maps.angular, q, tau)
        ours = qp.A[:n] @ y - qp.b[:n]
        assert np.abs(ours - predicted).max() < 0.01 * max(np.abs(predicted).max(), 0.1)  # measured 2e-3 N m


@pytest.mark.parametrize("cone", [False, True], ids=["without_GH", "with_GH"])
def test_rmr_closed_onto_our_problem_is_never_below_our_optimum(robot, cone):
    """RMR's exact problem as a cone program (rmr_socp: RMR's weights, our constraints) has our optimum,
    and RMR's answer closed onto it (close_answer) is feasible and never below it."""
    from mcdm_pin.osim.rmr import close_answer, rmr_exact_objective, rmr_in_our_problem, rmr_socp
    from mcdm_pin.problem import Context

    rows, X = excerpt_answers(EXCERPT, cone)
    ident = InverseDynamics(robot, rmr_problem(robot, cone))
    for k, q, v, a in zip(ROWS, *rmr_states(robot, "abd01", ROWS)):
        res = ident.solve(q, v, a)
        terms = ident.evaluate(q, v, a)
        qp = ident.problem.assemble(terms, Context(robot))
        x = X[list(rows).index(k)]
        optimum = rmr_exact_objective(rmr_socp(robot, terms, qp))
        assert abs(res.objective - optimum) <= 1e-6 * optimum
        check = rmr_in_our_problem(ident, terms, qp, x)
        assert check["closed_eom_rel"] < 1e-8 and check["closed_bounds"] < 1e-8 and check["closed_cone_deg"] < 1e-6
        assert rmr_exact_objective(close_answer(robot, terms, qp, x)) >= res.objective * (1 - 1e-7)
        assert check["closed_change"] < 0.02  # measured 0.001-0.003 at these frames


def test_the_warm_active_set_answers_rmrs_problem_along_the_motion(robot):
    """RMR's problem with the cone along 40 frames of the committed abduction: every frame optimal
    and answered by the warm active set after the first (the interior-point method there), at
    Clarabel's objective. Eight of RMR's reserves weigh 0: the objective does not see them, their
    Tikhonov term's residual stood above the check of stationarity at every frame, and the chain
    answered by the interior-point method (2 ms) or, on 17 of 217 frames, by Clarabel after a
    numerical breakdown, until the active-set solve refined its point
    (:func:`mcdm_pin.solvers._kkt_eq._refine`)."""
    from mcdm_pin.osim.motion import read_table
    from mcdm_pin.osim.rmr import RATE, frame_rows, frame_states
    from mcdm_pin.trajectory import Trajectory

    files = tuple(EXCERPT / f"Kinematics_{k}.sto" for k in ("q", "u", "dudt"))
    t = read_table(files[0]).time
    rows = frame_rows(files)
    rows = rows[np.isin(np.round(rows / RATE, 9), np.round(t, 9))][:40]
    q, v, a = frame_states(robot, files, rows)
    traj = Trajectory(name="abd01", t=rows / RATE, q=q, qd=v, qdd=a)
    problem = rmr_problem(robot, True)
    res = InverseDynamics(robot, problem).solve_trajectory(traj, progress=False)
    assert np.all(res.status == "optimal")
    assert res.stage[0] == "ipm" and np.all(res.stage[1:] == "warm_active_set"), res.stage
    ref = InverseDynamics(robot, problem, solver="clarabel")
    for k in (1, 20, 39):
        cla = ref.solve(q[k], v[k], a[k])
        assert abs(res.objective[k] - cla.objective) <= 1e-6 * abs(cla.objective)
