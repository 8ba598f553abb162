"""Hybrid robots (HCDM): actuated joints whose torques join the cable forces as unknowns.

References independent of the problem assembly: Pinocchio's RNEA for ``M qdd + h``, the closed-form
minimiser of ``|f|^2 + w |tau|^2`` on the equation of motion alone (where no bound is active, checked),
and Clarabel, called here directly on a problem written out from those terms, where bounds bind.
"""

from __future__ import annotations

import textwrap

import clarabel
import numpy as np
import pinocchio as pin
import pytest
import yaml
from scipy import sparse

from mcdm_pin import InverseDynamics, Robot
from mcdm_pin.model.terms import cable_jacobian
from mcdm_pin.results import TrajectoryResult
from mcdm_pin.trajectory import Trajectory

LINK = ('<link name="{n}"><inertial><origin xyz="0.15 0 0"/><mass value="{m}"/>'
        '<inertia ixx="0.001" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>')


def _arm(tmp_path, actuated):
    """A three-link planar arm (revolute joints about y, gravity along -z), 5 cables, the middle joint
    actuated as given."""
    urdf = "\n".join(['<link name="base"/>'] + [LINK.format(n=n, m=m) for n, m in
                                                 (("l1", 1.0), ("l2", 0.7), ("l3", 0.4))]) + """
      <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
      <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.3 0 0"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
      <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0.3 0 0"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>"""
    (tmp_path / "arm.urdf").write_text(f'<robot name="arm">\n{textwrap.dedent(urdf)}\n</robot>\n')
    routes = [("base", [0.0, 0.0, 0.3], "l1", [0.2, 0.0, 0.05]), ("base", [0.0, 0.0, -0.3], "l1", [0.2, 0.0, -0.05]),
              ("l1", [0.1, 0.0, 0.08], "l2", [0.15, 0.0, 0.05]), ("base", [0.1, 0.0, 0.4], "l3", [0.2, 0.0, 0.03]),
              ("base", [0.1, 0.0, -0.4], "l3", [0.2, 0.0, -0.03])]
    cables = [{"name": f"c{k}", "f_min": 1.0, "f_max": 500.0,
               "route": [{"link": a, "point": pa}, {"link": b, "point": pb}]} for k, (a, pa, b, pb) in enumerate(routes)]
    joints = {"j1": {"type": "revolute", "urdf_joints": ["j1"]},
              "j2": {"type": "revolute", "urdf_joints": ["j2"], **({"actuated": actuated} if actuated else {})},
              "j3": {"type": "revolute", "urdf_joints": ["j3"]}}
    sidecar = {"version": 1, "name": "arm", "urdf": "arm.urdf", "gravity": [0.0, 0.0, -9.81], "joints": joints,
               "cables": cables}
    (tmp_path / "arm.yaml").write_text(yaml.safe_dump(sidecar, sort_keys=False))
    return Robot.load(tmp_path / "arm.yaml")


STATE = (np.array([0.3, -0.5, 0.4]), np.array([0.2, -0.1, 0.3]), np.array([0.5, 0.2, -0.4]))


def _terms(robot, q, qd, qdd):
    """``M qdd + h`` from Pinocchio's RNEA, and ``L`` (m, nv)."""
    data = robot.model.createData()
    tau = pin.rnea(robot.model, data, q, qd, qdd)
    L = cable_jacobian(robot.model, robot.model.createData(), robot.cables, q)
    return tau, L


def test_actuator_joins_the_cables_closed_form(tmp_path):
    """Case 1 against its KKT system written out here: ``min x^T W x`` with ``x = [f; tau]``,
    ``W = diag(1, ..., w)``, ``A x = b`` (``A = [L^T, -S]``, ``b = -(M qdd + h)`` from RNEA) and the
    cables that our answer holds at ``f_min`` fixed there; the reference is optimal when the
    multipliers of those bounds have the right sign (checked), and ours equals it to 1e-9."""
    w = 0.5
    robot = _arm(tmp_path, {"min": -50.0, "max": 50.0, "weight": w})
    assert robot.n_act == 1
    q, qd, qdd = STATE
    res = InverseDynamics.for_case(robot, 1).solve(q, qd, qdd)
    assert res.status == "optimal"
    tau, L = _terms(robot, q, qd, qdd)
    S = np.eye(3)[:, [1]]
    A = np.hstack([L.T, -S])
    m, n = robot.m, robot.m + 1
    at_min = np.flatnonzero(res.f <= robot.f_min + 1e-9)
    assert 0 < len(at_min) < m and abs(res.tau_act[0]) < 50.0 and np.all(res.f < robot.f_max)
    E = np.eye(n)[at_min]
    K = np.block([[np.diag(np.r_[np.ones(m), w]), A.T, E.T],
                  [A, np.zeros((3, 3)), np.zeros((3, len(at_min)))],
                  [E, np.zeros((len(at_min), 3 + len(at_min)))]])
    sol = np.linalg.solve(K, np.r_[np.zeros(n), -tau, robot.f_min[at_min]])
    x, mult = sol[:n], sol[n + 3:]
    # W x + A^T y + E^T mu = 0 with mu <= 0 at a lower bound: the bound pushes x up (KKT)
    assert np.all(mult < 0) and np.all(x[:m] >= robot.f_min - 1e-12)
    np.testing.assert_allclose(np.r_[res.f, res.tau_act], x, rtol=1e-9, atol=1e-9 * np.abs(x).max())
    np.testing.assert_allclose(L.T @ res.f - S[:, 0] * res.tau_act[0], -tau, atol=1e-9 * np.abs(tau).max())
    assert res.objective == pytest.approx(res.f @ res.f + w * res.tau_act[0] ** 2, rel=1e-12)
    # the motor carries part of the load: the cables alone need larger forces
    bare = InverseDynamics.for_case(_arm(tmp_path, None), 1).solve(q, qd, qdd)
    assert bare.status == "optimal" and abs(res.tau_act[0]) > 1e-2
    assert res.f @ res.f < bare.f @ bare.f - 1e-6


def _clarabel_reference(robot, q, qd, qdd, lo, hi, w):
    """``min |f|^2 + w tau^2`` s.t. the equation of motion and all bounds, by Clarabel directly."""
    tau, L = _terms(robot, q, qd, qdd)
    m = robot.m
    n = m + 1
    A = np.hstack([L.T, -np.eye(3)[:, [1]]])
    lb = np.r_[robot.f_min, lo]
    ub = np.r_[robot.f_max, hi]
    P = sparse.csc_matrix(np.diag(np.r_[np.ones(m), w]))
    G = sparse.csc_matrix(np.vstack([A, np.eye(n), -np.eye(n)]))
    h = np.r_[-tau, ub, -lb]
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = 1e-12
    sol = clarabel.DefaultSolver(P, np.zeros(n), G, h, [clarabel.ZeroConeT(3), clarabel.NonnegativeConeT(2 * n)],
                                 settings).solve()
    assert str(sol.status) == "Solved"
    return np.array(sol.x)


@pytest.mark.parametrize("case", [1, 2])
def test_actuator_bounds_bind(tmp_path, case):
    """A weak motor (|tau| <= 0.3 N m) is driven to its bound; the cables carry the rest. Case 1 against
    Clarabel on the problem written out here (1e-6 relative: Clarabel's accuracy); case 2 (interaction
    objective plus the actuator's weight) solves with the bound held and the equation of motion met."""
    robot = _arm(tmp_path, {"min": -0.3, "max": 0.3, "weight": 0.01})
    q, qd, qdd = STATE
    res = InverseDynamics.for_case(robot, case).solve(q, qd, qdd)
    assert res.status == "optimal"
    assert abs(abs(res.tau_act[0]) - 0.3) < 1e-9
    tau, L = _terms(robot, q, qd, qdd)
    np.testing.assert_allclose(L.T @ res.f - np.eye(3)[1] * res.tau_act[0], -tau, atol=1e-8 * np.abs(tau).max())
    assert res.eom_residual < 1e-9
    if case == 1:
        ref = _clarabel_reference(robot, q, qd, qdd, -0.3, 0.3, 0.01)
        np.testing.assert_allclose(np.r_[res.f, res.tau_act], ref, rtol=1e-6, atol=1e-6 * np.abs(ref).max())
    for solver in ("proxqp", "clarabel"):
        other = InverseDynamics.for_case(robot, case, solver=solver).solve(q, qd, qdd)
        np.testing.assert_allclose(np.r_[other.f, other.tau_act], np.r_[res.f, res.tau_act], rtol=1e-6,
                                   atol=1e-6 * np.abs(res.f).max())


def test_actuator_results_files(tmp_path):
    """``tau_act`` and ``actuator_names`` in the trajectory results, the .npz and the .csv."""
    robot = _arm(tmp_path, {"min": -50.0, "max": 50.0, "weight": 0.5})
    q, qd, qdd = STATE
    traj = Trajectory("three", np.array([0.0, 0.1, 0.2]), np.array([q, q * 1.1, q * 1.2]), np.array([qd] * 3),
                      np.array([qdd] * 3))
    run = InverseDynamics.for_case(robot, 1).solve_trajectory(traj)
    assert run.tau_act.shape == (3, 1) and list(run.actuator_names) == ["j2"]
    assert np.all(np.isfinite(run.tau_act)) and run.found.all()
    back = TrajectoryResult.load(run.save(tmp_path / "run.npz"))
    np.testing.assert_array_equal(back.tau_act, run.tau_act)
    assert list(back.actuator_names) == ["j2"]
    header = (run.save(tmp_path / "run.csv")).read_text().splitlines()[0].split(",")
    assert "tau_act[j2]" in header
    # a robot without actuators: an empty column
    plain = InverseDynamics.for_case(_arm(tmp_path, None), 1).solve_trajectory(traj)
    assert plain.tau_act.shape == (3, 0) and len(plain.actuator_names) == 0
