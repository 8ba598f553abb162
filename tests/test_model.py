"""The layer below Robot (:mod:`mcdm_pin.model`) on ``pin.Model``s built in code, with every joint type.

References that share no code with the package's cable terms:

- ``L`` against central differences of the cable lengths along ``pin.integrate`` (the tangent space);
- the interaction wrenches ``p = u + R^T f`` and ``M a + h + L^T f`` against Pinocchio's own RNEA with
  the cables' forces applied as external forces (``fext``), each cable force computed here from the
  frames' placements (``pin.updateFramePlacements``) and the route points;
- a free-flyer's wrench equals its rows of ``M a + h + L^T f``, hence vanishes whenever the equation of
  motion holds.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from mcdm_pin import Robot
from mcdm_pin.exceptions import ModelError
from mcdm_pin.model import (Cable, CableSet, cable_generalized_force, cable_jacobian, cable_lengths,
                            cable_terms, group, interaction_map, physical_joints)
from mcdm_pin.model import charts

from .conftest import REPO

RNG = np.random.default_rng(11)


def _body(mass=0.5, length=0.3):
    return pin.Inertia(mass, np.array([0.0, 0.0, length / 2]), np.diag([0.01, 0.012, 0.008]) * mass)


def _body_frame(model, name, joint):
    model.addFrame(pin.Frame(name, joint, 0, pin.SE3.Identity(), pin.FrameType.BODY))


def mixed_model() -> pin.Model:
    """A tree with a free-flying platform carrying every other native joint type and a group."""
    m = pin.Model()
    up = pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.3]))
    side = pin.SE3(pin.rpy.rpyToMatrix(0.2, -0.1, 0.3), np.array([0.1, 0.05, 0.25]))
    ff = m.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "platform")
    m.appendBodyToJoint(ff, _body(2.0, 0.1), pin.SE3.Identity())
    ball = m.addJoint(ff, pin.JointModelSpherical(), up, "ball")
    m.appendBodyToJoint(ball, _body(), pin.SE3.Identity())
    zyx = m.addJoint(ball, pin.JointModelSphericalZYX(), side, "zyx")
    m.appendBodyToJoint(zyx, _body(0.4), pin.SE3.Identity())
    pl = m.addJoint(ff, pin.JointModelPlanar(), side, "planar")
    m.appendBodyToJoint(pl, _body(0.3), pin.SE3.Identity())
    cont = m.addJoint(pl, pin.JointModelRUBZ(), up, "cont")
    m.appendBodyToJoint(cont, _body(0.2), pin.SE3.Identity())
    ru = m.addJoint(cont, pin.JointModelRevoluteUnaligned(np.array([0.6, 0.0, 0.8])), up, "ru")
    m.appendBodyToJoint(ru, _body(0.2), pin.SE3.Identity())
    pu = m.addJoint(zyx, pin.JointModelPrismaticUnaligned(np.array([0.0, 0.6, 0.8])), up, "pu")
    m.appendBodyToJoint(pu, _body(0.2), pin.SE3.Identity())
    tr = m.addJoint(pu, pin.JointModelTranslation(), up, "trans")
    m.appendBodyToJoint(tr, _body(0.2), pin.SE3.Identity())
    uni = m.addJoint(tr, pin.JointModelUniversal(np.array([1.0, 0, 0]), np.array([0, 1.0, 0])), up, "uni")
    m.appendBodyToJoint(uni, _body(0.2), pin.SE3.Identity())
    comp = pin.JointModelComposite(pin.JointModelRX())
    comp.addJoint(pin.JointModelPY(), pin.SE3.Identity())
    c = m.addJoint(uni, comp, up, "comp")
    m.appendBodyToJoint(c, _body(0.2), pin.SE3.Identity())
    # an Euler triple (three revolute joints with massless bodies) on the planar branch
    r1 = m.addJoint(ru, pin.JointModelRX(), up, "tx")
    r2 = m.addJoint(r1, pin.JointModelRY(), pin.SE3.Identity(), "ty")
    r3 = m.addJoint(r2, pin.JointModelRZ(), pin.SE3.Identity(), "tz")
    m.appendBodyToJoint(r3, _body(0.3), pin.SE3.Identity())
    for j in range(1, m.njoints):
        _body_frame(m, f"body_{m.names[j]}", j)
    return m


def mixed_cables(model: pin.Model, n: int = 40) -> CableSet:
    bodies = [f"body_{model.names[j]}" for j in range(1, model.njoints) if model.names[j] not in ("tx", "ty")]
    frames = ["universe"] + bodies
    cables = []
    for k in range(n):
        count = int(RNG.integers(2, 5))
        route = [(frames[int(RNG.integers(len(frames)))], tuple(RNG.uniform(-0.2, 0.2, 3))) for _ in range(count)]
        if len({f for f, _ in route}) < 2:
            route[-1] = ("universe" if route[0][0] != "universe" else bodies[0], route[-1][1])
        cables.append(Cable(f"c{k}", tuple(route), 0.0, 100.0))
    return CableSet(model, cables)


@pytest.fixture(scope="module")
def mixed():
    model = mixed_model()
    cables = mixed_cables(model)
    joints = physical_joints(model, groups=[("triple", "spherical", ["tx", "ty", "tz"])])
    return model, cables, joints


def _state(model):
    q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
    return q, RNG.normal(size=model.nv), RNG.normal(size=model.nv)


def test_joint_types_are_classified(mixed):
    model, _, joints = mixed
    types = {j.name: (j.type, j.parametrization) for j in joints}
    assert types == {
        "platform": ("free", None), "ball": ("spherical", "quaternion"), "zyx": ("spherical", "zyx"),
        "planar": ("planar", None), "cont": ("revolute", None), "ru": ("revolute", None),
        "pu": ("prismatic", None), "trans": ("translation", None), "uni": ("universal", None),
        "comp": ("composite", None), "triple": ("spherical", "euler-xyz")}
    assert sum(j.nv for j in joints) == model.nv


def test_jacobian_is_the_tangent_derivative_of_the_lengths(mixed):
    model, cables, _ = mixed
    data = model.createData()
    for _ in range(5):
        q, _, _ = _state(model)
        L = cable_jacobian(model, data, cables, q)
        assert L.shape == (cables.m, model.nv)
        for _ in range(3):
            v = RNG.normal(size=model.nv)
            h = 1e-6
            lp = cable_lengths(model, data, cables, pin.integrate(model, q, h * v))
            lm = cable_lengths(model, data, cables, pin.integrate(model, q, -h * v))
            # central differences: error O(h^2 |l'''|) ~ 1e-12 m, rounding ~1e-16 / 1e-6 = 1e-10
            np.testing.assert_allclose(L @ v, (lp - lm) / (2 * h), atol=1e-8)


def _fext(model, data, cables, f):
    """Each cable's pull on the bodies as Pinocchio external forces (local joint frames)."""
    pin.updateFramePlacements(model, data)
    fext = [pin.Force.Zero() for _ in range(model.njoints)]
    for k, cable in enumerate(cables):
        pts, jids = [], []
        for p in cable.route:
            fid = model.getFrameId(p.frame)
            pts.append(data.oMf[fid].act(np.array(p.point)))
            jids.append(model.frames[fid].parentJoint)
        for a in range(len(pts) - 1):
            u = (pts[a + 1] - pts[a]) / np.linalg.norm(pts[a + 1] - pts[a])
            for x, j, force in ((pts[a], jids[a], f[k] * u), (pts[a + 1], jids[a + 1], -f[k] * u)):
                M = data.oMi[j]
                F_local = M.rotation.T @ force
                fext[j] += pin.Force(F_local, np.cross(M.actInv(x), F_local))
    return fext


def test_interaction_wrenches_match_rnea_with_external_forces(mixed):
    model, cables, joints = mixed
    data, ref = model.createData(), model.createData()
    for _ in range(5):
        q, v, a = _state(model)
        f = RNG.uniform(0, 50, cables.m)
        t = cable_terms(model, data, cables, q, v, a, joints=joints)
        pin.forwardKinematics(model, ref, q)
        tau_ext = pin.rnea(model, ref, q, v, a, _fext(model, ref, cables, f))
        scale = max(1.0, np.abs(tau_ext).max())
        # M a + h - J^T fext = M a + h + L^T f
        np.testing.assert_allclose(t.tau + t.L.T @ f, tau_ext, atol=1e-10 * scale)
        np.testing.assert_allclose(cable_generalized_force(model, data, cables, q, f),
                                   -t.L.T @ f, atol=1e-12 * scale)
        p = t.wrenches(f)
        for k, j in enumerate(joints):
            np.testing.assert_allclose(p[k], ref.f[j.child_id].vector, atol=1e-10 * scale, err_msg=j.name)
        u, RT = interaction_map(model, data, cables, joints, q, v, a, frame="socket")
        np.testing.assert_allclose(u + RT @ f, t.wrenches_socket(f), atol=1e-12 * scale)


def test_free_flyer_wrench_is_its_equation_of_motion(mixed):
    """A free-flyer transmits nothing: its wrench equals its rows of M a + h + L^T f (its motion
    subspace is the identity), so it is zero whenever the equation of motion holds."""
    model, cables, joints = mixed
    data = model.createData()
    ff = [j for j in joints if j.type == "free"][0]
    q, v, a = _state(model)
    f = RNG.uniform(0, 50, cables.m)
    t = cable_terms(model, data, cables, q, v, a, joints=[ff])
    np.testing.assert_allclose(t.wrenches(f)[0], (t.tau + t.L.T @ f)[ff.idx_v], atol=1e-10)


def test_charts_round_trip_and_rates(mixed):
    model, _, _ = mixed
    parts = charts.chart_parts(model)
    names = charts.coordinate_names(model)
    assert len(names) == model.nv and "platform.rz" in names and "planar.theta" in names and "cont" in names
    assert len(charts.configuration_names(model)) == model.nq and "ball.qw" in charts.configuration_names(model)
    C = RNG.normal(scale=0.4, size=(3, model.nv))

    def path(t):
        return C[0] + C[1] * np.sin(t) + C[2] * t * t, C[1] * np.cos(t) + 2 * C[2] * t, -C[1] * np.sin(t) + 2 * C[2]

    x = path(0.0)[0]
    np.testing.assert_allclose(charts.coordinates(model, charts.configuration(model, x, parts), parts), x, atol=1e-12)
    t, h = 0.3, 1e-5
    q, v, a = charts.tangent(model, *path(t))
    qp, qm = charts.configuration(model, path(t + h)[0]), charts.configuration(model, path(t - h)[0])
    np.testing.assert_allclose(v, pin.difference(model, qm, qp) / (2 * h), atol=1e-8)
    vp, vm = charts.tangent(model, *path(t + h))[1], charts.tangent(model, *path(t - h))[1]
    np.testing.assert_allclose(a, (vp - vm) / (2 * h), atol=1e-7)


def test_cable_set_errors_name_the_cable_and_the_frame(mixed):
    model, _, _ = mixed
    with pytest.raises(ModelError, match="unknown frame 'nowhere'"):
        CableSet(model, [Cable("x", (("universe", (0, 0, 0)), ("nowhere", (0, 0, 1))), 0.0, 1.0)])
    with pytest.raises(ModelError, match="cable 'x'.*0 <= f_min < f_max"):
        CableSet(model, [Cable("x", (("universe", (0, 0, 0)), ("body_ball", (0, 0, 1))), 5.0, 1.0)])
    with pytest.raises(ModelError, match="cable 'x' has no segment spanning two different bodies"):
        CableSet(model, [Cable("x", (("body_ball", (0, 0, 0)), ("body_ball", (0, 0, 1))), 0.0, 1.0)])
    other = pin.Model()
    cables = mixed_cables(model, 3)
    with pytest.raises(ModelError, match="built for another model"):
        cable_jacobian(other, other.createData(), cables, pin.neutral(other))


def test_group_checks():
    m = pin.Model()
    a = m.addJoint(0, pin.JointModelRX(), pin.SE3.Identity(), "a")
    b = m.addJoint(a, pin.JointModelRX(), pin.SE3.Identity(), "b")
    m.appendBodyToJoint(b, _body(), pin.SE3.Identity())
    with pytest.raises(ModelError, match="must be orthogonal"):
        group(m, "u", "universal", ["a", "b"])
    m2 = pin.Model()
    a = m2.addJoint(0, pin.JointModelRX(), pin.SE3.Identity(), "a")
    m2.appendBodyToJoint(a, _body(), pin.SE3.Identity())
    b = m2.addJoint(a, pin.JointModelRY(), pin.SE3.Identity(), "b")
    with pytest.raises(ModelError, match="must be massless"):
        group(m2, "u", "universal", ["a", "b"])


# ------------------------------------------------------------------ the 2-link arm, three ways
def two_link_in_code() -> Robot:
    """The paper's 2-link arm built in Pinocchio directly (no file): a native ball joint and a revolute."""
    m = pin.Model()
    link = pin.Inertia(0.1, np.array([0.0, 0.0, 0.1]), np.eye(3))
    s = m.addJoint(0, pin.JointModelSpherical(), pin.SE3.Identity(), "shoulder")
    m.appendBodyToJoint(s, link, pin.SE3.Identity())
    _body_frame(m, "link1", s)
    e = m.addJoint(s, pin.JointModelRX(), pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.2])), "elbow")
    m.appendBodyToJoint(e, link, pin.SE3.Identity())
    _body_frame(m, "link2", e)
    base = [(0.15, 0, 0), (0, 0.15, 0), (-0.15, 0, 0), (0, -0.15, 0), (0.2, 0, 0), (0, 0.2, 0), (-0.2, 0, 0),
            (0, -0.2, 0)]
    top = [(0.05, 0, 0.1), (0, 0.05, 0.1), (-0.05, 0, 0.1), (0, -0.05, 0.1)] * 2
    cables = [Cable(f"cable{k + 1}", (("universe", base[k]), ("link1" if k < 4 else "link2", top[k])), 0.001, 1000.0)
              for k in range(8)]
    joints = [j.with_settings(alpha=1.0 if j.name == "shoulder" else 0.0, cone_deg=30.0 if j.name == "shoulder" else None)
              for j in physical_joints(m)]
    return Robot.from_model(m, cables, joints, name="two_link_in_code")


def _native_state(euler_robot, q, qd, qdd):
    """The Euler-triple state as the native robot's: the same rotation, body rates (Pinocchio's)."""
    model = euler_robot.model
    data = model.createData()
    pin.forwardKinematics(model, data, q, qd, qdd)
    link1 = model.getJointId("q3_z")
    R = data.oMi[link1].rotation
    quat = pin.Quaternion(R).coeffs()
    w, wd = data.v[link1].angular, data.a[link1].angular
    return (np.concatenate([quat, q[3:]]), np.concatenate([w, qd[3:]]), np.concatenate([wd, qdd[3:]]))


def test_two_link_three_ways_give_the_same_wrenches_and_forces(two_link):
    from mcdm_pin import InverseDynamics, load_trajectory

    ball = Robot.load(REPO / "robots" / "two_link_sr_ball.yaml")
    code = two_link_in_code()
    assert ball.nq == code.nq == 5 and ball.nv == code.nv == 4
    tr = load_trajectory(two_link, "traj2")
    for k in (10, 37, 64, 90):
        q, qd, qdd = tr.q[k], tr.qd[k], tr.qdd[k]
        qn, vn, an = _native_state(two_link, q, qd, qdd)
        for case in (1, 2, 3):
            answers = [InverseDynamics.for_case(r, case).solve(*state) for r, state in
                       ((two_link, (q, qd, qdd)), (ball, (qn, vn, an)), (code, (qn, vn, an)))]
            ref = answers[0]
            assert ref.found, (k, case, ref.message)
            for other in answers[1:]:
                assert other.status == ref.status
                scale = max(1.0, np.abs(ref.f).max())
                np.testing.assert_allclose(other.f, ref.f, atol=1e-9 * scale, err_msg=f"t[{k}] case {case}")
                w_scale = max(1.0, np.abs(ref.interaction_wrench).max())
                np.testing.assert_allclose(other.interaction_wrench, ref.interaction_wrench, atol=1e-9 * w_scale)
                np.testing.assert_allclose(other.interaction_force_socket, ref.interaction_force_socket,
                                           atol=1e-9 * w_scale)


def test_native_ball_trajectory_turns_about_one_axis(two_link):
    """traj1 of the native-ball sidecar: rotation about x only, so the rotation vector is (angle, 0, 0)
    and the same poses, body rates and accelerations as the Euler-triple arm's traj1."""
    from mcdm_pin import load_trajectory

    ball = Robot.load(REPO / "robots" / "two_link_sr_ball.yaml")
    tb, te = load_trajectory(ball, "traj1"), load_trajectory(two_link, "traj1")
    for k in range(0, len(tb), 7):
        qn, vn, an = _native_state(two_link, te.q[k], te.qd[k], te.qdd[k])
        rotation = [pin.Quaternion(x[3], *x[:3]).toRotationMatrix() for x in (tb.q[k][:4], qn[:4])]
        np.testing.assert_allclose(rotation[0], rotation[1], atol=1e-12)
        np.testing.assert_allclose(tb.q[k][4], qn[4], atol=1e-15)
        np.testing.assert_allclose(ball.coordinates(tb.q[k])[1:3], 0.0, atol=1e-15)
        np.testing.assert_allclose(tb.qd[k], vn, atol=1e-12)
        np.testing.assert_allclose(tb.qdd[k], an, atol=1e-11)
