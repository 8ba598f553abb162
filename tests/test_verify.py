"""Forward-dynamics replay (issue 7, item 1): the computed forces produce the planned motion; the
verdict (issue 15): converged, diverged (with a window that works) or not converged."""

from __future__ import annotations

import numpy as np
import pytest

from mcdm_pin import InverseDynamics, ResultsError, Robot, load_trajectory
from mcdm_pin.cli import main
from mcdm_pin.trajectory import quintic_trajectory
from mcdm_pin.verify import convergence, judge, planned_state, replay, resolved_forces

from .conftest import REPO, TWO_LINK, TWO_LINK_URDF

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


def test_cli_verify_prints_the_convergence_table_and_the_verdict(two_link, tmp_path, capsys):
    path = run(two_link, "traj2", 1).save(tmp_path / "run.npz")
    assert main(["verify", str(TWO_LINK), str(path), "--levels", "3"]) == 0
    out = capsys.readouterr().out
    assert "from the first solved instant t = 0.01 s" in out
    assert "max |q_h - q_h/2|" in out and "rk4 (order 4)" in out
    rows = [line.split() for line in out.splitlines() if line.strip().startswith(("1 ", "2 ", "4 "))]
    assert len(rows) == 3 and 3.8 < float(rows[0][5]) < 4.2
    assert "verdict: converged" in out and "floor set by interpolating f" in out
    assert main(["verify", str(TWO_LINK), str(path), "--levels", "2", "--resolve"]) == 0
    assert "re-solved on the plan" in capsys.readouterr().out
    assert main(["verify", str(TWO_LINK), str(path), "--substeps", "0"]) == 2


def test_verify_takes_its_files_in_either_order_and_names_what_each_is(two_link, tmp_path, capsys):
    """Every other command takes ROBOT first; verify accepts both orders (told apart by content), and
    a URDF, two sidecars or two results files get one line naming each file, never a codec error."""
    path = run(two_link, "traj2", 1).save(tmp_path / "run.npz")
    assert main(["verify", str(path), str(TWO_LINK), "--levels", "3"]) == 0  # the old order still works
    capsys.readouterr()
    cases = [([str(TWO_LINK_URDF), str(path)], "is a URDF; mcdm-pin reads a robot from its cable sidecar"),
             ([str(TWO_LINK), str(TWO_LINK)], "got " + str(TWO_LINK) + " (a cable sidecar (YAML))"),
             ([str(path), str(path)], "(a results file (.npz, from mcdm-pin solve --out))")]
    for files, message in cases:
        assert main(["verify", *files]) == 2
        err = capsys.readouterr().err
        assert message in err and "codec" not in err and len(err.strip().splitlines()) == 1
    # the URDF message points at the sidecar that names it
    assert main(["verify", str(TWO_LINK_URDF), str(path)]) == 2
    assert "robots/two_link_sr.yaml" in capsys.readouterr().err


@pytest.fixture(scope="module")
def weak_arm(tmp_path_factory):
    """The 2-link arm with realistic (small) link inertias, 4e-4 kg m^2 instead of 1 kg m^2: standing
    upright on weak cables (f_min 1 mN) it is open-loop unstable under force control (growth rate
    ~16 1/s): errors grow 1e7-fold over the 1 s of traj1."""
    folder = tmp_path_factory.mktemp("weak")
    urdf = TWO_LINK_URDF.read_text().replace('ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"',
                                             'ixx="4e-4" ixy="0" ixz="0" iyy="4e-4" iyz="0" izz="1e-5"')
    (folder / "weak.urdf").write_text(urdf)
    (folder / "weak.yaml").write_text(TWO_LINK.read_text().replace("../urdf/two_link_sr.urdf", "weak.urdf")
                                      .replace("name: two_link_sr", "name: weak_arm"))
    robot = Robot.load(folder / "weak.yaml")
    res = InverseDynamics.for_case(robot, 1).solve_trajectory(load_trajectory(robot, "traj1"),
                                                               progress=False)
    assert res.found.all()
    return robot, res, res.save(folder / "weak.npz")


def test_unstable_arm_is_called_diverged_and_the_window_that_works_is_found(weak_arm, capsys):
    """Before issue 15, verify printed the same ~8 rad error at every step size with a footer blaming
    interpolation (and exit 0). The integrator converges (order ~4), but the open-loop growth amplifies
    the interpolation error past the motion's range: the verdict is 'diverged', and the window search
    finds --window 6 (1 / (growth rate x dt) = 1 / (16.5 x 0.01)), where the replay follows the plan to
    2.6e-5 rad (measured)."""
    robot, res, path = weak_arm
    table = convergence(robot, res, "rk4", levels=3)
    assert 14 < table.growth_rate < 19  # measured 16.5 1/s (at t = 0.25 s)
    assert np.all(table.plan_error > 5.0)  # measured 8.07 rad at every step
    assert abs(table.observed_order[-1] - 4) < 0.3  # the integrator is not the cause
    verdict = judge(robot, res, table, "rk4")
    assert verdict.status == "diverged" and not verdict.converged
    assert verdict.window == 6 and verdict.window_error < 1e-4
    windowed = convergence(robot, res, "rk4", levels=3, window=verdict.window)
    assert windowed.plan_error.max() < 1e-4
    assert judge(robot, res, windowed, "rk4", window=verdict.window).status == "converged"
    # the command line: exit 1 and the suggestion; then exit 0 with it
    assert main(["verify", str(robot.sidecar.path), str(path), "--levels", "3"]) == 1
    out = capsys.readouterr().out
    assert "verdict: diverged" in out and "open-loop unstable" in out and "--window 6" in out
    assert "floor set by interpolating" not in out
    assert main(["verify", str(robot.sidecar.path), str(path), "--levels", "3", "--window", "6"]) == 0
    assert "verdict: converged" in capsys.readouterr().out


def test_quaternion_ball_joint_replay_keeps_rk4_order():
    """The native ball joint (quaternion) is integrated on SO(3) (Runge-Kutta-Munthe-Kaas): on a motion
    about a general axis the self error still falls at order 4 (measured 4.04, 4.02), and on traj1
    the ball-joint arm replays exactly like the Euler-triple arm (plan error 8.029e-4 rad both)."""
    ball = Robot.load(REPO / "robots" / "two_link_sr_ball.yaml")
    traj = quintic_trajectory(ball, [0.2, -0.2, -0.1, 0.2], [-0.5, 0.5, 0.2, -0.2], 1.0, 0.02, name="t2")
    res = InverseDynamics.for_case(ball, 1).solve_trajectory(traj, progress=False)
    table = convergence(ball, res, "rk4", levels=4)
    assert np.all(np.abs(table.observed_order - 4) < 0.2)
    assert judge(ball, res, table).status == "converged"


NECK = REPO / "robots" / "caspr" / "8S_neck" / "8S_neck.yaml"  # converted from CASPR, committed


def test_neck_replay_in_windows(tmp_path):
    """The neck is open-loop unstable under force control (errors grow like exp(350 t)), so the replay
    restarts from the plan at every instant; RK4 then shows its order (measured 3.6, 3.8 from 4
    substeps) on the roll trajectory, case 1."""
    robot = Robot.load(NECK)
    res = InverseDynamics.for_case(robot, 1).solve_trajectory(load_trajectory(robot, "roll"), progress=False)
    whole = replay(robot, res)  # diverges (the state stops being finite), and says when
    assert whole.diverged_at is not None and whole.max_error == np.inf and whole.growth_rate > 100
    table = convergence(robot, res, "rk4", substeps=4, levels=3, window=1)
    assert table.reports[0].growth_rate > 100
    assert 3.3 < table.observed_order[0] < 4.3


def test_problem_of_a_run_is_rebuilt_from_its_problem_json(two_link):
    """``--resolve`` re-solves the problem the run solved: from ``problem_json`` any problem rebuilds
    (smoothing included, which the problem string could not give), and files without it (older runs)
    still rebuild the paper's cases from the problem string."""
    from mcdm_pin import InverseDynamics, load_trajectory
    from mcdm_pin.verify import problem_from_run

    traj = load_trajectory(two_link, "traj1").subsample(5)
    ident = InverseDynamics.for_case(two_link, 3, smoothing=0.1)
    run = ident.solve_trajectory(traj, progress=False)
    assert problem_from_run(two_link, run).spec() == ident.problem.spec()
    plain = InverseDynamics.for_case(two_link, 3).solve_trajectory(traj, progress=False)
    plain.problem_json = ""
    assert problem_from_run(two_link, plain).spec() == InverseDynamics.for_case(two_link, 3).problem.spec()
    run.problem_json = ""
    with pytest.raises(ResultsError, match="smoothing"):
        problem_from_run(two_link, run)


ARM = REPO / "robots" / "myosuite" / "myoarm.yaml"  # 63 muscles over wraps, 11 couplings, 22 reserves


@pytest.fixture(scope="module")
def arm_run(tmp_path_factory):
    """Minimum activations on 7 instants (0.8 .. 0.92 s) of the arm's abduction, saved."""
    pytest.importorskip("mujoco")
    from mcdm_pin.objectives import MinActivations
    from mcdm_pin.problem import Problem
    from mcdm_pin.trajectory import Trajectory

    robot = Robot.load(ARM)
    full = load_trajectory(robot, "abduction")
    part = slice(40, 47)
    traj = Trajectory("abduction", full.t[part], full.q[part], full.qd[part], full.qdd[part])
    res = InverseDynamics(robot, Problem(robot, MinActivations(), [])).solve_trajectory(traj, progress=False)
    assert res.found.all()
    return robot, res, res.save(tmp_path_factory.mktemp("arm") / "arm.npz")


def test_coupled_arm_dynamics_with_constraint_forces_reproduce_the_plan(arm_run):
    """The replay's dynamics are computed independently of the solve: the full equation of motion with
    the couplings' constraint forces (KKT), and L in numpy from the route's path. At every planned
    state the run's forces and reserve torques give the planned acceleration (measured 2e-12 rad/s^2;
    without the constraint forces ~3e3 rad/s^2 off), and the numpy L equals the kernel's (4e-16)."""
    from mcdm_pin.model.terms import TermsEvaluator
    from mcdm_pin.verify.replay import _Dynamics, _inputs
    from mcdm_pin.verify.routed import RoutedL

    robot, res, _ = arm_run
    dyn, U = _Dynamics(robot), _inputs(robot, res)
    assert len(robot.couplings) == 11 and U.shape == (len(res.t), robot.m + 22)
    ev, zero = TermsEvaluator(robot, compiled=False), np.zeros(robot.nv)
    routed = RoutedL(robot)
    for k in range(len(res.t)):
        q, v = res.configuration[k], res.qd[k]
        a, lam = dyn.solve(q, v, U[k])
        assert np.abs(a - res.qdd[k]).max() < 1e-9
        assert lam.shape == (11,) and 1.0 < np.abs(lam).max() < 1e3  # N m, measured 16 .. 35
        G, gamma = dyn.constraint_rows(q, v)
        assert np.abs(G @ res.qdd[k] - gamma).max() < 1e-9  # the plan keeps the couplings
        L = ev(q, zero, zero, checked=True).L_full
        assert np.abs(routed(q) - L).max() < 1e-12 * np.abs(L).max()
    free = np.asarray(__import__("pinocchio").aba(robot.model, dyn.data, q, v, dyn.joint_force(q, v, U[-1])))
    assert np.abs(free - res.qdd[-1]).max() > 10.0


def test_cli_verify_passes_the_coupled_arm_and_fails_it_tampered(arm_run, tmp_path, capsys):
    """RK4 from 4 substeps (the finger dampers make modes of -500 1/s: 5 ms is inside RK4's stability
    region): self error at order 4.7, 4.3 to 1e-10, plan error 2.5e-5 rad, the floor of interpolating
    f linearly (measured). One muscle's force 20 % too high puts the replay 3e-2 rad off the plan."""
    from mcdm_pin.results import TrajectoryResult

    robot, res, path = arm_run
    assert main(["verify", str(ARM), str(path), "--substeps", "4", "--levels", "4"]) == 0
    out = capsys.readouterr().out
    assert "verdict: converged" in out and "11 couplings' constraint forces" in out
    bad = TrajectoryResult.load(path)
    j = int(np.argmax(bad.f[0]))
    bad.f[:, j] *= 1.2
    assert main(["verify", str(ARM), str(bad.save(tmp_path / "tampered.npz")), "--substeps", "4",
                 "--levels", "2"]) == 1
    out = capsys.readouterr().out
    assert "verdict: diverged" in out
    err = float(out.split("strays up to ")[1].split()[0])
    assert err > 2e-2  # rad; the untampered run's replay stays within 2.5e-5 of the plan
