"""Passive springs, variable-stiffness cables, unbounded joint motors and empty cable sets (issue 26).

References independent of the code they check: the springs' generalised force is the gradient of
their potential ``k/2 (l - l0)^2`` by central differences of lengths measured on Pinocchio's frame
placements; their share of the interaction wrench is that of a cable on the same route pulling with
the same tension (a cable's maps are checked against Newton-Euler in ``tests/test_caspr_library.py``);
unbounded motors are solved by every back-end and by Clarabel alone, and checked against the
closed-form minimiser of ``|f|^2 + |tau|^2`` on the equation of motion with the cables at a bound
held there.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

from mcdm_pin import InverseDynamics, Robot, compute_terms, load_trajectory
from mcdm_pin.caspr import import_caspr, read_bodies, read_cables
from mcdm_pin.exceptions import ModelError, SidecarError
from mcdm_pin.problem import Context
from mcdm_pin.solvers import OPTIMAL
from mcdm_pin.solvers.clarabel_ import clarabel_solve

REPO = Path(__file__).resolve().parents[1]
LINK = ('<link name="{n}"><inertial><origin xyz="0.15 0 0"/><mass value="{m}"/>'
        '<inertia ixx="0.001" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>')
SPRINGS = [("s0", "base", [0.0, 0.0, 0.5], "l1", [0.25, 0.0, 0.0], 40.0, 0.3),
           ("s1", "l1", [0.1, 0.0, -0.05], "l2", [0.2, 0.0, -0.04], 300.0, 0.25)]


def _arm(tmp_path, springs=SPRINGS, as_cables=False, tension_only=False):
    """A two-link planar arm (revolute about y, gravity -z), 4 cables, and passive springs (or the
    same routes as extra cables, ``as_cables``)."""
    urdf = "\n".join(['<link name="base"/>', LINK.format(n="l1", m=1.0), LINK.format(n="l2", m=0.6)]) + """
      <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
      <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.3 0 0"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>"""
    (tmp_path / "arm.urdf").write_text(f'<robot name="arm">\n{textwrap.dedent(urdf)}\n</robot>\n')
    routes = [("base", [0.0, 0.0, 0.3], "l1", [0.2, 0.0, 0.05]), ("base", [0.0, 0.0, -0.3], "l1", [0.2, 0.0, -0.05]),
              ("base", [0.1, 0.0, 0.4], "l2", [0.2, 0.0, 0.03]), ("base", [0.1, 0.0, -0.4], "l2", [0.2, 0.0, -0.03])]
    route = lambda a, pa, b, pb: [{"link": a, "point": pa}, {"link": b, "point": pb}]  # noqa: E731
    cables = [{"name": f"c{k}", "f_min": 1.0, "f_max": 500.0, "route": route(*r)} for k, r in enumerate(routes)]
    sc = {"version": 1, "name": "arm", "urdf": "arm.urdf", "gravity": [0.0, 0.0, -9.81],
          "joints": {j: {"type": "revolute", "urdf_joints": [j]} for j in ("j1", "j2")}, "cables": cables}
    if as_cables:
        cables += [{"name": n, "f_min": 0.0, "f_max": 1e3, "route": route(a, pa, b, pb)} for n, a, pa, b, pb, _, _ in springs]
    else:
        sc["springs"] = [{"name": n, "stiffness": k, "rest_length": l0, "route": route(a, pa, b, pb),
                          **({"tension_only": True} if tension_only else {})} for n, a, pa, b, pb, k, l0 in springs]
    name = "cables" if as_cables else "arm"
    (tmp_path / f"{name}.yaml").write_text(yaml.safe_dump(sc, sort_keys=False))
    return Robot.load(tmp_path / f"{name}.yaml")


def _spring_lengths(robot, q, springs=SPRINGS):
    """Each spring's length from Pinocchio's frame placements (no code of mcdm_pin's cables)."""
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    at = lambda frame, p: data.oMf[robot.model.getFrameId(frame)].act(np.array(p))  # noqa: E731
    return np.array([np.linalg.norm(at(b, pb) - at(a, pa)) for _, a, pa, b, pb, _, _ in springs])


STATE = (np.array([0.4, -0.7]), np.array([0.3, -0.2]), np.array([0.5, 0.4]))


def test_springs_join_the_right_hand_side_as_the_gradient_of_their_energy(tmp_path):
    """``tau = M qdd + h + L_s^T f_s`` with ``L_s^T f_s = dV/dq``, ``V = sum k/2 (l - l0)^2``."""
    robot = _arm(tmp_path)
    q, qd, qdd = STATE
    t = compute_terms(robot, q, qd, qdd, compiled=False)
    rnea = pin.rnea(robot.model, robot.model.createData(), q, qd, qdd)
    k, l0 = np.array([s[5] for s in SPRINGS]), np.array([s[6] for s in SPRINGS])
    V = lambda x: float(np.sum(0.5 * k * (_spring_lengths(robot, x) - l0) ** 2))  # noqa: E731
    h = 1e-6
    dV = np.array([(V(q + h * e) - V(q - h * e)) / (2 * h) for e in np.eye(2)])
    assert np.allclose(t.spring_lengths, _spring_lengths(robot, q), rtol=0, atol=1e-14)
    assert np.allclose(t.spring_forces, k * (_spring_lengths(robot, q) - l0), rtol=1e-13)
    assert np.abs(t.tau - rnea - dV).max() <= 1e-7 * np.abs(dV).max()
    assert np.allclose(compute_terms(robot, q, qd, qdd, compiled=True).tau, t.tau, rtol=1e-12, atol=1e-12)


def test_springs_pull_in_the_interaction_wrenches_as_cables_of_the_same_tension(tmp_path):
    robot = _arm(tmp_path)
    twin = _arm(tmp_path, as_cables=True)  # the springs' routes as cables 4 and 5
    q, qd, qdd = STATE
    t, c = compute_terms(robot, q, qd, qdd), compute_terms(twin, q, qd, qdd)
    f_s = t.spring_forces
    assert np.allclose(t.u, c.u + c.RT[:, :, 4:] @ f_s, rtol=1e-12, atol=1e-12)
    assert np.allclose(t.RT, c.RT[:, :, :4], rtol=1e-12, atol=1e-12)
    # and an answer of case 2 (interactions) balances with the springs pulling
    r = InverseDynamics.for_case(robot, 2).solve(q, qd, qdd)
    assert r.found and t.eom_residual(r.f) <= 1e-9
    # the joints are passive: each wrench's moment about its joint's axis (y) is zero only with the
    # springs' pull in it
    assert np.abs(r.interaction_wrench[:, 4]).max() <= 1e-9 * np.abs(r.interaction_wrench).max()
    assert np.abs((c.u + c.RT[:, :, :4] @ r.f)[:, 4]).max() > 1e-3 * np.abs(r.interaction_wrench).max()


def test_a_tension_only_spring_goes_slack(tmp_path):
    slack = [(n, a, pa, b, pb, k, 5.0) for n, a, pa, b, pb, k, _ in SPRINGS]  # rest lengths beyond reach
    t = compute_terms(_arm(tmp_path, slack, tension_only=True), *STATE)
    assert np.array_equal(t.spring_forces, np.zeros(2))
    pushing = compute_terms(_arm(tmp_path, slack), *STATE).spring_forces  # CASPR's law: not clipped
    assert np.all(pushing < 0)


def test_bad_springs_are_refused_by_key(tmp_path):
    _arm(tmp_path)
    sc = yaml.safe_load((tmp_path / "arm.yaml").read_text())
    sc["springs"][1]["stiffness"] = -1.0
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(sc))
    with pytest.raises(SidecarError, match=r"springs\[1\]\.stiffness"):
        Robot.load(tmp_path / "bad.yaml")
    sc["springs"][1]["stiffness"] = 1.0
    sc["springs"][1]["route"][0]["link"] = "l2"  # both ends on one body
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(sc))
    with pytest.raises(SidecarError, match=r"springs\[1\]\.route.*spring 's1'"):
        Robot.load(tmp_path / "bad.yaml")


# ------------------------------------------------------------------------------- unbounded motors
def _fastkit():
    return Robot.load(REPO / "robots" / "caspr" / "FASTKIT_Planar" / "FASTKIT_Planar.yaml")


def test_unbounded_motors_every_back_end_agrees():
    """FASTKIT_Planar's four motors, unbounded as in CASPR: the default chain, the compiled method,
    ProxQP, Clarabel (through the chain) and Clarabel alone agree along ``line_test``, and the answer
    is the least-norm solution of the equation of motion with the cables at a bound held there."""
    robot = _fastkit()
    assert all(np.all(np.isinf(a.tau_min)) and np.all(np.isinf(a.tau_max)) for a in robot.actuators)
    traj = load_trajectory(robot, "line_test").subsample(6)
    runs = {s: InverseDynamics.for_case(robot, 1, solver=s).solve_trajectory(traj, progress=False)
            for s in ("default", "compiled", "proxqp", "clarabel")}
    ref = runs["clarabel"]
    assert np.all(ref.status == OPTIMAL)
    x_ref = np.hstack([ref.f, ref.tau_act])
    S = robot.actuation
    evaluate = InverseDynamics.for_case(robot, 1)
    closed = 0
    for k in range(len(traj)):
        terms = evaluate.evaluate(traj.q[k], traj.qd[k], traj.qdd[k])
        raw = clarabel_solve(evaluate.problem.assemble(terms, Context(robot, None)))
        assert raw.status == OPTIMAL
        scale = max(np.abs(raw.x).max(), 1.0)
        for name, run in runs.items():
            x = np.hstack([run.f[k], run.tau_act[k]])
            assert run.status[k] == OPTIMAL, name
            assert np.abs(x - raw.x).max() <= 1e-6 * scale, (name, k, np.abs(x - raw.x).max())
        # min |x|^2 s.t. [L^T, -S] x = -tau with the cables Clarabel puts at a bound held there: the
        # free unknowns (the other cables, every motor) are the least-norm solution of the rest
        m = robot.m
        at = np.flatnonzero((raw.x[:m] <= robot.f_min + 1e-6 * scale) | (raw.x[:m] >= robot.f_max - 1e-6 * scale))
        free = np.setdiff1d(np.arange(len(raw.x)), at)
        B = np.hstack([terms.L.T, -S])
        x_closed = np.zeros(len(raw.x))
        x_closed[at] = np.where(raw.x[at] <= robot.f_min[at] + 1e-6 * scale, robot.f_min[at], robot.f_max[at])
        x_closed[free] = np.linalg.pinv(B[:, free]) @ (-terms.tau - B[:, at] @ x_closed[at])
        assert np.abs(x_closed - x_ref[k]).max() <= 1e-6 * scale, (k, x_closed, x_ref[k])
        closed += 1
    assert closed == len(traj) and np.abs(ref.tau_act).max() > 1.0


def test_actuated_sidecar_bounds(tmp_path):
    """``actuated:`` takes ``-.inf``/``.inf`` or no bounds at all (unbounded, weight > 0 required)."""
    _arm(tmp_path)
    sc = yaml.safe_load((tmp_path / "arm.yaml").read_text())
    sc["joints"]["j2"]["actuated"] = {"weight": 2.0}
    (tmp_path / "a.yaml").write_text(yaml.safe_dump(sc))
    robot = Robot.load(tmp_path / "a.yaml")
    assert robot.actuators[0].tau_min[0] == -np.inf and robot.actuators[0].tau_max[0] == np.inf
    def load(actuated, name):
        sc["joints"]["j2"]["actuated"] = actuated
        (tmp_path / name).write_text(yaml.safe_dump(sc))
        return Robot.load(tmp_path / name)

    assert load({"min": -np.inf, "max": 5.0}, "b.yaml").actuators[0].tau_max[0] == 5.0
    for bad, key in (({"weight": 0.0}, r"actuated\.weight"), ({"min": np.inf, "max": 5.0}, r"actuated\.min\[0\]"),
                     ({"min": -np.inf, "max": np.inf, "weight": 0.0}, r"actuated\.weight")):
        with pytest.raises(SidecarError, match=key):
            load(bad, "c.yaml")
    from mcdm_pin.model.actuators import Actuator

    with pytest.raises(ModelError, match="weight > 0"):
        Actuator("j", np.array([0]), np.array([-np.inf]), np.array([np.inf]), 0.0)


# ------------------------------------------------------------------------------------ CASPR import
CASPR = REPO / "tests" / "data" / "caspr"  # CASPR's XML of the models these tests import (committed)


def _files(model):
    return [CASPR / model / f"{model}_{k}.xml" for k in ("bodies", "cables")]


def test_caspr_cable_models(tmp_path):
    """Passive springs become ``springs:``; VSD and linear-spring cables are cables with their bounds;
    an empty default set gives way to the first set with cables, said in the notes."""
    b, c = _files("Passive_springs_planar")
    res = import_caspr(b, c, tmp_path / "p")
    robot = Robot.load(res.sidecar)
    assert robot.m == 4 and robot.springs.names == ("spring 1", "spring 2", "spring 3", "spring 4")
    assert np.all(robot.springs.stiffness == 5.0) and np.all(robot.springs.rest_length == 1.0)
    b, c = _files("2_DoF_VSD")
    cset = read_cables(c, read_bodies(b))
    assert cset.id == "basic" and {x.kind for x in cset.cables} == {"cable_vsd_torsion_spring"}
    assert [(x.f_min, x.f_max) for x in cset.cables] == [(3.0, 80.0)] * 4
    b, c = _files("PlanarSnakeArm")
    res = import_caspr(b, c, tmp_path / "s")
    assert res.cable_set == "PlaceHOlder" and any("'Empty' has no cable" in n for n in res.notes)
    b, c = _files("SpiderBot_X52")
    robot = Robot.load(import_caspr(b, c, tmp_path / "x").sidecar)
    assert robot.n_act == 4 and all(np.isinf(a.tau_max).all() for a in robot.actuators)


def test_replay_with_springs_reproduces_the_acceleration(tmp_path):
    """``mcdm-pin verify``'s forward dynamics counts the springs: ABA under the solved cable forces and
    the springs' tensions gives back the planned acceleration."""
    from mcdm_pin.verify.replay import _Dynamics

    robot = _arm(tmp_path)
    q, qd, qdd = STATE
    r = InverseDynamics.for_case(robot, 1).solve(q, qd, qdd)
    assert r.found
    assert np.allclose(_Dynamics(robot)(q, qd, r.f), qdd, rtol=0, atol=1e-8)


def test_a_trajectory_with_springs_solves_as_its_instants(tmp_path):
    """The trajectory path (warm starts, one evaluator) gives each instant's own answer, springs in."""
    from mcdm_pin.trajectory import Trajectory

    robot = _arm(tmp_path)
    t = np.linspace(0.0, 1.0, 5)
    Q = np.stack([0.4 + 0.3 * t, -0.7 + 0.2 * t**2], axis=1)
    V = np.stack([0.3 + 0 * t, 0.4 * t], axis=1)
    A = np.stack([0 * t, 0.4 + 0 * t], axis=1)
    solver = InverseDynamics.for_case(robot, 2)
    run = solver.solve_trajectory(Trajectory("ramp", t, Q, V, A), progress=False)
    for k in range(len(t)):
        r = solver.solve(Q[k], V[k], A[k])
        assert run.status[k] == r.status == OPTIMAL
        assert np.allclose(run.f[k], r.f, rtol=1e-9, atol=1e-9)
        assert np.allclose(run.interaction_wrench[k], r.interaction_wrench, rtol=1e-9, atol=1e-9)
