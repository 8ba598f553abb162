"""The thoracoscapular model's acromioclavicular loop in the solve path (mcdm_pin.model.terms): with
straight test cables (and reserve actuators) on the TSM skeleton, the reduced equation of motion and
the recovered loop force close the full equation, and the interaction wrenches equal RNEA's
``data.f`` with the cable forces and the loop force applied as external forces (an independent
assembly of the same physics)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from mcdm_pin.model.actuators import Actuator, actuation_matrix
from mcdm_pin.model.cables import Cable, CableSet
from mcdm_pin.model.joints import physical_joints
from mcdm_pin.model.terms import TermsEvaluator
from mcdm_pin.osim.load import osim_skeleton
from mcdm_pin.problem import Problem
from mcdm_pin.constraints import InteractionCone
from mcdm_pin.objectives import MinCableForces
from mcdm_pin.robot import Robot

TSM = Path(__file__).resolve().parents[1] / "robots" / "opensim" / "TSM_subject_noWeight.osim"

# straight cables: (name, (body, point), (body, point)), points in the body frames (m)
ROUTES = [
    ("thorax_clavicle", ("thorax", (0.02, 0.0, 0.03)), ("clavicle", (-0.01, 0.01, 0.08))),
    ("thorax_clavicle2", ("thorax", (0.0, 0.05, 0.02)), ("clavicle", (0.0, -0.01, 0.12))),
    ("thorax_scapula", ("thorax", (-0.08, 0.0, 0.05)), ("scapula", (-0.06, -0.03, -0.05))),
    ("thorax_scapula2", ("thorax", (-0.05, -0.1, 0.06)), ("scapula", (-0.09, -0.09, -0.09))),
    ("thorax_scapula3", ("thorax", (-0.04, 0.05, 0.02)), ("scapula", (-0.05, 0.0, -0.1))),
    ("clavicle_scapula", ("clavicle", (0.0, 0.02, 0.1)), ("scapula", (-0.03, 0.0, -0.02))),
    ("clavicle_humerus", ("clavicle", (0.01, 0.0, 0.1)), ("humerus", (0.01, -0.05, 0.0))),
    ("scapula_humerus", ("scapula", (-0.03, 0.0, -0.03)), ("humerus", (0.0, -0.02, 0.01))),
    ("scapula_humerus2", ("scapula", (-0.05, -0.04, -0.05)), ("humerus", (-0.01, -0.1, 0.01))),
    ("scapula_humerus3", ("scapula", (-0.01, 0.01, 0.0)), ("humerus", (0.02, -0.08, -0.01))),
    ("thorax_humerus", ("thorax", (0.05, -0.05, 0.05)), ("humerus", (0.0, -0.1, 0.02))),
    ("thorax_humerus2", ("thorax", (-0.1, -0.05, 0.06)), ("humerus", (-0.01, -0.06, -0.01))),
    ("humerus_ulna", ("humerus", (0.0, -0.2, 0.01)), ("ulna", (0.01, -0.05, 0.0))),
    ("humerus_ulna2", ("humerus", (0.01, -0.25, -0.01)), ("ulna", (-0.02, -0.02, 0.01))),
    ("humerus_radius", ("humerus", (0.0, -0.25, 0.02)), ("radius", (0.01, -0.1, 0.01))),
    ("ulna_radius", ("ulna", (0.0, -0.1, 0.0)), ("radius", (0.02, -0.15, 0.0))),
]
REACTION_ATOL = 1e-9  # N and N m; the wrenches are of order 10-100


THORAX = tuple(f"ground_thorax_{c}" for c in ("rot_x", "rot_y", "rot_z", "tx", "ty", "tz"))


def _robot(actuated=()):
    """The TSM skeleton with the straight test cables, and reserve actuators on the thorax's six
    coordinates (the model's own CoordinateActuators hold the free-floating thorax) and on
    ``actuated`` (OpenSim coordinate names)."""
    actuated = THORAX + tuple(actuated)
    om, couplings, src, _ = osim_skeleton(TSM)
    cables = CableSet(om.model, [Cable(n, route=(a, b), f_min=0.0, f_max=1e4) for n, a, b in ROUTES])
    joints = physical_joints(om.model)
    bound = lambda c: 1e4 if c in THORAX else 100.0  # noqa: E731
    acts = tuple(Actuator.on_coordinate(joints, int(om.coordinate_v[om.coordinates.index(c)]), -bound(c), bound(c),
                                        label=c) for c in actuated)
    return Robot(om.model, cables, joints, acts, "tsm_test", couplings=couplings,
                 coordinate_names=om.velocity_names, source=src)


def _state(robot, rng):
    """A state on the loop: q projected, v and a in the allowed directions with ``G a + gamma = 0``."""
    loops = robot.source.loops
    q = loops.project(robot.source.configuration({}) + rng.uniform(-0.15, 0.15, robot.model.nq))
    B = loops.basis(q)
    v = B @ rng.normal(size=B.shape[1])
    G = loops.jacobian(q)
    a = B @ rng.normal(size=B.shape[1]) - np.linalg.pinv(G) @ loops.bias(q, v)
    return q, v, a


def _external(robot, q, f, lam):
    """``fext`` of the cable forces ``f`` (point forces at the route points) and the loop force."""
    model, data = robot.model, robot.model.createData()
    pin.framesForwardKinematics(model, data, q)
    fext = robot.source.loops.external_forces(q, lam)
    for cable, t in zip(robot.cables, f):
        (fa, pa), (fb, pb) = [(model.getFrameId(p.frame), np.array(p.point)) for p in cable.route_points]
        xa, xb = data.oMf[fa].act(pa), data.oMf[fb].act(pb)
        e = (xb - xa) / np.linalg.norm(xb - xa)
        for fid, p, force in ((fa, pa, t * e), (fb, pb, -t * e)):
            frame = model.frames[fid]
            j = int(frame.parentJoint)
            local = data.oMi[j].rotation.T @ force
            point = frame.placement.act(p)
            fext[j] += pin.Force(local, np.cross(point, local))
    return fext


def _solve_eom(t, n_act):
    """A solution ``x = [f; tau_act]`` of the reduced equation of motion (least norm)."""
    A = np.hstack([t.L.T, -t.actuation])
    x = np.linalg.lstsq(A, -t.tau, rcond=None)[0]
    assert np.abs(A @ x + t.tau).max() < 1e-9 * max(1.0, np.abs(t.tau).max())
    return x


@pytest.mark.parametrize("actuated", [(), ("clav_prot", "scapula_upward_rot", "elbow_flexion")],
                         ids=["cables", "cables+actuators"])
def test_loop_terms_close_the_full_equation_and_equal_rnea_wrenches(actuated):
    robot = _robot(actuated)
    ev = TermsEvaluator(robot, compiled=False)
    model, data = robot.model, robot.model.createData()
    loops = robot.source.loops
    S = actuation_matrix(model.nv, robot.actuators)
    rng = np.random.default_rng(3)
    worst_eq = worst_w = 0.0
    for _ in range(5):
        q, v, a = _state(robot, rng)
        t = ev(q, v, a)
        assert t.L.shape == (robot.m, model.nv - 3) and t.tau.shape == (model.nv - 3,)
        x = _solve_eom(t, robot.n_act)
        f, tau_act = x[:robot.m], x[robot.m:]
        lam0, Lam, Lam_act = t.loop_force
        lam = lam0 + Lam @ f + (0 if Lam_act is None else Lam_act @ tau_act)
        tau0 = pin.rnea(model, data, q, v, a)
        full = tau0 + t.L_full.T @ f - S @ tau_act - loops.jacobian(q).T @ lam
        worst_eq = max(worst_eq, np.abs(full).max() / np.abs(tau0).max())
        # RNEA with cables and loop as external forces: the joints' wrenches; its torques are the actuators'
        tau_ext = pin.rnea(model, data, q, v, a, _external(robot, q, f, lam))
        assert np.allclose(tau_ext, S @ tau_act, rtol=0, atol=1e-8)
        reference = np.array([data.f[j.child_id].vector for j in robot.joints])
        worst_w = max(worst_w, np.abs(t.wrenches(x) - reference).max())
    assert worst_eq < 1e-10
    assert worst_w < REACTION_ATOL


def test_the_compiled_kernel_path_gives_the_same_loop_terms():
    """The same terms either way; and the uncompiled terms hand the compiled loop kernel the types
    the compile types, so no specialisation is added at runtime (a strided ``RT`` would add one)."""
    pytest.importorskip("numba")
    from mcdm_pin import jit
    from mcdm_pin.osim import loop_kernels

    jit.prepare(policy="wait")
    robot = _robot(("clav_elev",))
    rng = np.random.default_rng(4)
    q, v, a = _state(robot, rng)
    before = set(map(str, loop_kernels.loop_terms.signatures))
    slow, fast = TermsEvaluator(robot, compiled=False)(q, v, a), TermsEvaluator(robot, compiled=True)(q, v, a)
    for name in ("tau", "L", "u", "RT", "actuation", "RT_act"):
        assert np.allclose(getattr(slow, name), getattr(fast, name), rtol=0, atol=1e-10), name
    assert set(map(str, loop_kernels.loop_terms.signatures)) == before


def test_unpickled_loops_read_their_own_data():
    import pickle

    robot = _robot()
    q, _, _ = _state(robot, np.random.default_rng(5))
    loops = robot.source.loops
    copy = pickle.loads(pickle.dumps(loops))
    assert np.array_equal(copy.wrench_map(q), loops.wrench_map(q))


def test_a_solve_on_the_loop_closes_and_reports_the_loop_force_in_the_wrenches():
    """Case-1-like problem with an active cone on the sternoclavicular joint (which carries the loop
    force, and so a share of the girdle actuators' torques): the answer satisfies the reduced
    equation and the cone, its reported wrenches are those of the terms at the cables and torques,
    and Clarabel finds the same objective."""
    from mcdm_pin.inverse_dynamics import InverseDynamics

    robot = _robot(("clav_prot", "scapula_upward_rot"))
    rng = np.random.default_rng(5)
    q, v, a = _state(robot, rng)
    problem = Problem(robot, MinCableForces(), [InteractionCone("sternoclavicular", 40.0)])
    ident = InverseDynamics(robot, problem)
    res = ident.solve(q, v, a)
    assert res.status == "optimal", res.message
    assert abs(res.interaction_angle_deg[1] - 40.0) < 1e-6  # active
    ref = InverseDynamics(robot, problem, solver="clarabel").solve(q, v, a)
    assert ref.status == "optimal", ref.message
    assert abs(res.objective - ref.objective) <= 1e-6 * abs(ref.objective)
    t = ident.evaluate(q, v, a)
    x = np.concatenate([res.f, res.tau_act])
    assert np.abs(t.L.T @ res.f - t.actuation @ res.tau_act + t.tau).max() < 1e-6 * np.abs(t.tau).max()
    assert np.allclose(res.interaction_wrench, t.wrenches(x), rtol=0, atol=1e-9)
