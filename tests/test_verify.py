"""Forward-dynamics replay (issue 7, item 1): the computed forces produce the planned motion."""

from __future__ import annotations

import numpy as np
import pytest

from mcdm_pin import InverseDynamics, ResultsError, Robot, load_trajectory
from mcdm_pin.cli import main
from mcdm_pin.trajectory import quintic_trajectory
from mcdm_pin.verify import convergence, planned_state, replay, resolved_forces

from .conftest import SHARED, TWO_LINK

RUNS = {}


def run(robot, traj_name, case, dt=None):
    key = (traj_name, case, dt)
    if key not in RUNS:
        traj = load_trajectory(robot, traj_name)
        if dt is not None:
            spec = robot.sidecar.trajectories[traj_name]
            traj = quintic_trajectory(robot, traj.q[0], traj.q[-1], spec.duration, dt, name=traj_name)
        RUNS[key] = InverseDynamics.for_case(robot, case).solve_trajectory(traj, progress=False)
    return RUNS[key]


def test_rk4_self_convergence_is_fourth_order_and_plan_error_is_the_interpolation_floor(two_link):
    res = run(two_link, "traj1", 1)
    table = convergence(two_link, res, "rk4", substeps=1, levels=4)
    # measured: observed orders 3.99, 4.00; self errors 1.9e-8, 1.2e-9, 7.4e-11
    assert np.all((table.observed_order > 3.8) & (table.observed_order < 4.2))
    assert table.self_error[-1] < 1e-10
    # the plan error does not move with the step: it is set by interpolating f (8.0e-4 rad)
    plan = table.plan_error
    assert np.ptp(plan) <= 1e-3 * plan.max() and plan.max() < 2e-3


def test_interpolation_floor_is_second_order_in_the_sample_spacing(two_link):
    errors = [replay(two_link, run(two_link, "traj1", 1, dt), "rk4", substeps=int(round(0.04 / dt))).max_error
              for dt in (0.02, 0.01)]
    # linear interpolation of f: O(dt^2); measured ratio 3.9
    assert 3.5 < errors[0] / errors[1] < 4.5


def test_resolved_forces_make_the_plan_the_exact_solution(two_link):
    """traj2, case 3: t = 0 is infeasible, so the replay starts at t = 0.01 s; with the forces re-solved
    at the stage times the plan error itself falls at fourth order (measured 3.6, 4.1)."""
    res = run(two_link, "traj2", 3)
    assert res.status[0] == "infeasible"
    plan = planned_state(two_link, two_link.sidecar.trajectories["traj2"])
    forces = resolved_forces(InverseDynamics.for_case(two_link, 3), plan)
    table = convergence(two_link, res, "rk4", substeps=1, levels=3, forces=forces)
    assert table.reports[0].first == 1 and table.reports[0].t[0] == pytest.approx(0.01)
    err = table.plan_error
    assert err[0] < 1e-7 and err[0] / err[1] > 2**3.3 and err[1] / err[2] > 2**3.3


def test_planned_state_matches_the_sampled_trajectory(two_link):
    traj = load_trajectory(two_link, "traj2")
    plan = planned_state(two_link, two_link.sidecar.trajectories["traj2"])
    for k in (0, 37, 100):
        q, qd, qdd = plan(traj.t[k])
        assert np.abs(q - traj.q[k]).max() < 1e-12
        assert np.abs(qdd - traj.qdd[k]).max() < 1e-9


def test_first_order_integrators(two_link):
    res = run(two_link, "traj1", 1)
    table = convergence(two_link, res, "euler", substeps=4, levels=3)
    assert np.all(np.abs(table.observed_order - 1.0) < 0.1)  # measured 0.98
    # semi-implicit Euler's first-order term is small on this slow motion: it looks second order at
    # coarse steps and tends to first order as the step shrinks (measured 2.00, 1.93, 1.67, 1.51, 1.34
    # from 1 substep); at least first order
    table = convergence(two_link, res, "semi-implicit", substeps=4, levels=3)
    assert np.all((table.observed_order > 0.9) & (table.observed_order < 2.1))


def test_replay_stops_before_an_unsolved_instant(two_link):
    res = run(two_link, "traj1", 1)
    broken = type(res)(**{**res.__dict__, "status": res.status.astype("<U12"), "f": res.f.copy()})
    broken.status[60] = "infeasible"
    broken.f[60] = np.nan
    rep = replay(two_link, broken)
    assert rep.last == 59 and "(t = 0.6 s) has no valid forces (infeasible)" in rep.stopped
    assert len(rep.t) == 60


def test_replay_rejects_a_result_of_another_robot(two_link, tmp_path):
    res = run(two_link, "traj1", 1)
    other = type(res)(**{**res.__dict__, "cable_names": np.array([f"x{i}" for i in range(8)])})
    with pytest.raises(ResultsError, match="wrong robot"):
        replay(two_link, other)
    with pytest.raises(ResultsError, match="integrator"):
        replay(two_link, res, integrator="leapfrog")


def test_cli_verify_prints_the_convergence_table(two_link, tmp_path, capsys):
    path = run(two_link, "traj2", 1).save(tmp_path / "run.npz")
    assert main(["verify", str(path), str(TWO_LINK), "--levels", "3"]) == 0
    out = capsys.readouterr().out
    assert "from the first solved instant t = 0.01 s" in out
    assert "max |q_h - q_h/2|" in out and "rk4 (order 4)" in out
    rows = [line.split() for line in out.splitlines() if line.strip().startswith(("1 ", "2 ", "4 "))]
    assert len(rows) == 3 and 3.8 < float(rows[0][5]) < 4.2
    assert main(["verify", str(path), str(TWO_LINK), "--levels", "2", "--resolve"]) == 0
    assert "re-solved on the plan" in capsys.readouterr().out
    assert main(["verify", str(path), str(TWO_LINK), "--substeps", "0"]) == 2


NECK = SHARED / "reference" / "caspr" / "8S_neck"


@pytest.mark.skipif(not (NECK / "8S_neck_bodies.xml").is_file(), reason="CASPR neck not available")
def test_neck_replay_in_windows(tmp_path):
    """The neck is open-loop unstable under force control (errors grow like exp(350 t)), so the replay
    restarts from the plan at every instant; RK4 then shows its order (measured 3.6, 3.8 from 4
    substeps) on the roll trajectory, case 1."""
    caspr = pytest.importorskip("mcdm_pin.caspr")
    imp = caspr.import_caspr(NECK / "8S_neck_bodies.xml", NECK / "8S_neck_cables.xml", tmp_path,
                             trajectories_xml=NECK / "8S_neck_trajectories.xml", trajectory_ids=["roll"])
    robot = Robot.load(imp.sidecar)
    res = InverseDynamics.for_case(robot, 1).solve_trajectory(load_trajectory(robot, "roll"), progress=False)
    with pytest.raises(Exception, match="exp\\(3"):
        replay(robot, res)  # diverges, and says why
    table = convergence(robot, res, "rk4", substeps=4, levels=3, window=1)
    assert table.reports[0].growth_rate > 100
    assert 3.3 < table.observed_order[0] < 4.3
