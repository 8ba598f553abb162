"""The reference must be right too (issue: solver core, item 6), and a stalled solve ends (item 3).

Scaling every mass by ``k`` and every force bound by ``k`` scales the equation of motion by ``k`` and
leaves the problem otherwise the same: the optimal forces are ``k`` times the original ones, exactly.
Before the problem was scaled for every back-end, Clarabel called "infeasible" 98-101 of 101 instants
of the 2-link arm with links of 1e6 kg, and answered "optimal" 2.6e5x worse than the optimum with
links of 1e-6 kg. A cone of 89.99 deg that never binds must leave case 2's answer unchanged (Clarabel
called 69 of 101 such instants infeasible).
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml

from mcdm_pin import InverseDynamics, Robot, Settings, load_trajectory

REPO = Path(__file__).resolve().parents[1]
BACKENDS = ("default", "proxqp", "clarabel")


def _scaled_arm(tmp_path: Path, k: float, bounds: bool = True) -> Robot:
    """The 2-link arm with every mass and inertia times ``k`` and (``bounds``) every f_min, f_max times ``k``."""
    urdf = (REPO / "urdf" / "two_link_sr.urdf").read_text()
    urdf = re.sub(r'<mass value="([^"]+)"', lambda m: f'<mass value="{float(m.group(1)) * k!r}"', urdf)
    urdf = re.sub(r'(i[xyz]{2})="([^"]+)"', lambda m: f'{m.group(1)}="{float(m.group(2)) * k!r}"', urdf)
    (tmp_path / "arm.urdf").write_text(urdf)
    sc = yaml.safe_load((REPO / "robots" / "two_link_sr.yaml").read_text())
    sc["urdf"] = "arm.urdf"
    sc.pop("trajectories", None)
    shutil.copy(REPO / "robots" / "two_link_sr.yaml", tmp_path / "orig.yaml")
    if bounds:
        for c in sc["cables"]:
            c["f_min"], c["f_max"] = c["f_min"] * k, c["f_max"] * k
    (tmp_path / "arm.yaml").write_text(yaml.safe_dump(sc, sort_keys=False))
    return Robot.load(tmp_path / "arm.yaml")


@pytest.fixture(scope="module")
def arm():
    return Robot.load(REPO / "robots" / "two_link_sr.yaml")


@pytest.fixture(scope="module")
def traj(arm):
    return load_trajectory(arm, "traj1").subsample(21)


@pytest.mark.parametrize("k", [1e6, 1e-6])
@pytest.mark.parametrize("case", [1, 2, 3])
def test_heavy_and_light_robots_scale_exactly(tmp_path, arm, traj, k, case):
    base = InverseDynamics.for_case(arm, case).solve_trajectory(traj, progress=False)
    assert base.found.all()
    scaled = _scaled_arm(tmp_path, k)
    for name in BACKENDS:
        run = InverseDynamics.for_case(scaled, case, solver=name).solve_trajectory(traj, progress=False)
        assert run.found.all(), (name, k, run.message[~run.found])
        # 1e-6 of the largest force: the tolerance between back-ends
        np.testing.assert_allclose(run.f / k, base.f, rtol=0, atol=1e-6 * np.abs(base.f).max(), err_msg=name)


def test_a_cone_that_never_binds_changes_nothing(arm, traj):
    case2 = InverseDynamics.for_case(arm, 2).solve_trajectory(traj, progress=False)
    assert case2.found.all() and case2.interaction_angle_deg[:, 0].max() < 89.0
    for name in BACKENDS:
        run = InverseDynamics.for_case(arm, 3, cones={"shoulder": 89.99}, solver=name).solve_trajectory(
            traj, progress=False)
        assert run.found.all(), (name, run.message[~run.found])
        np.testing.assert_allclose(run.f, case2.f, rtol=0, atol=1e-6 * np.abs(case2.f).max(), err_msg=name)


def test_heavy_robot_without_force_answers_infeasible_and_the_cli_says_why(tmp_path, capsys):
    """Links of 1e6 kg on cables of at most 1000 N: every instant is infeasible by the bounds. Case 1
    has no cones: the diagnosis must not look for one (it crashed with ``max() arg is an empty
    sequence``); the command line reports the instants without an answer and why (exit 0: an
    infeasible instant is an answer, not an error)."""
    from mcdm_pin.cli import main

    robot = _scaled_arm(tmp_path, 1e6, bounds=False)
    q = np.array([0.3, -0.2, 0.1, 0.5])
    res = InverseDynamics.for_case(robot, 1).solve(q, np.zeros(4), np.zeros(4))
    assert res.status == "infeasible" and res.needed_f_max > 1000.0 and np.isnan(res.needed_cone_deg)
    assert "bounds" in res.message
    sc = yaml.safe_load((tmp_path / "arm.yaml").read_text())
    sc["trajectories"] = {"hold": {"type": "quintic", "duration": 1.0, "dt": 0.5,
                                   "q_start": {"shoulder": [0.3, -0.2, 0.1], "elbow": 0.5},
                                   "q_end": {"shoulder": [0.3, -0.2, 0.1], "elbow": 0.5}}}
    (tmp_path / "arm.yaml").write_text(yaml.safe_dump(sc, sort_keys=False))
    code = main(["solve", str(tmp_path / "arm.yaml"), "--trajectory", "hold", "--case", "1", "--samples", "3", "-q"])
    out = capsys.readouterr()
    assert code == 0 and "Traceback" not in out.err, out.err
    assert "infeasible" in out.out and "f_max" in out.out, out.out


def test_budget_turns_a_stall_into_a_status(arm):
    """The instant where ProxQP once ran 6.9 M iterations (traj2, t = 0.32, a 4.95374 deg cone): with
    the default budget it answers; with a budget of zero the solve stops before its first stage and
    says so (status ``budget``) instead of waiting."""
    tr = load_trajectory(arm, "traj2")
    k = int(np.argmin(np.abs(tr.t - 0.32)))
    ident = InverseDynamics.for_case(arm, 3, cones={"shoulder": 4.95374})
    res = ident.solve(tr.q[k], tr.qd[k], tr.qdd[k])
    assert res.status in ("optimal", "infeasible"), res.message
    stalled = InverseDynamics.for_case(arm, 3, cones={"shoulder": 4.95374}, settings=Settings(budget_s=0.0),
                                       diagnose=False)
    out = stalled.solve(tr.q[k], tr.qd[k], tr.qdd[k])
    assert out.status == "budget" and "budget" in out.message and np.isnan(out.f).all()
