"""Model terms against finite differences, Pinocchio's RNEA with external forces, a hand-computed
statics case and Pinocchio's own spherical joint (issue 2, item 5)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from mcdm_pin import InverseDynamics, compute_terms
from mcdm_pin.trajectory import SphericalKinematics

from .fd import lengths_jacobian

RNG = np.random.default_rng(20141121)


def random_state(robot, scale=0.6):
    return (RNG.uniform(-scale, scale, robot.nv), RNG.normal(size=robot.nv),
            RNG.normal(size=robot.nv))


def cable_external_forces(robot, terms, f):
    """Independent reference: loop over every cable segment and apply +-f u at its end points as
    Pinocchio external forces (local joint frames, moment about the joint origin)."""
    model = robot.model
    data = model.createData()
    pin.forwardKinematics(model, data, robot.pin_q(terms.q))
    fext = [pin.Force.Zero() for _ in range(model.njoints)]
    for c, cable in enumerate(robot.cables):
        placements = [robot.link_placement(link) for link in cable.links]
        world = [data.oMi[j].act(P.act(p)) for (j, P), p in zip(placements, cable.points)]
        for k in range(len(world) - 1):
            d = world[k + 1] - world[k]
            u = d / np.linalg.norm(d)
            for (j, P), p, force in ((placements[k], cable.points[k], f[c] * u),
                                     (placements[k + 1], cable.points[k + 1], -f[c] * u)):
                R = data.oMi[j].rotation
                local_point = P.act(p)
                local_force = R.T @ force
                fext[j] += pin.Force(local_force, np.cross(local_point, local_force))
    return fext


def test_L_matches_central_differences(two_link):
    for _ in range(5):
        q, _, _ = random_state(two_link)
        terms = compute_terms(two_link, q)
        fd = lengths_jacobian(lambda x: compute_terms(two_link, x).lengths, q)
        assert np.abs(fd - terms.L).max() <= 1e-7 * np.abs(terms.L).max()


def test_lengths_are_sum_of_segments(two_link):
    terms = compute_terms(two_link, np.zeros(4))
    # cable 1: (0.15, 0, 0) -> (0.05, 0, 0.1); cable 5: (0.2, 0, 0) -> (0.05, 0, 0.3)
    assert terms.lengths[0] == pytest.approx(np.hypot(0.1, 0.1), rel=1e-15)
    assert terms.lengths[4] == pytest.approx(np.hypot(0.15, 0.3), rel=1e-15)


def test_mass_matrix_symmetric_positive_definite(two_link):
    for _ in range(5):
        q, _, _ = random_state(two_link)
        M = compute_terms(two_link, q).M
        assert np.array_equal(M, M.T)
        assert np.linalg.eigvalsh(M).min() > 0


def test_joint_space_part_of_wrench_is_generalised_force(two_link):
    """S_a^T p_a = (M qdd + h + L^T f)_a for passive joints, any f."""
    model = two_link.model
    data = model.createData()
    for _ in range(5):
        q, qd, qdd = random_state(two_link)
        terms = compute_terms(two_link, q, qd, qdd)
        f = RNG.uniform(0, 50, two_link.m)
        p = terms.wrenches(f)
        expected = terms.M @ qdd + terms.h + terms.L.T @ f
        J = pin.computeJointJacobians(model, data, two_link.pin_q(q))
        for a, joint in enumerate(two_link.joints):
            S = pin.getJointJacobian(model, data, joint.child_id, pin.ReferenceFrame.LOCAL)[:, joint.idx_v]
            tau = S.T @ p[a]
            assert np.abs(tau - expected[joint.idx_v]).max() <= 1e-10 * max(1.0, np.abs(expected).max())


def test_wrench_equals_rnea_with_cable_forces(two_link):
    model = two_link.model
    data = model.createData()
    for _ in range(5):
        q, qd, qdd = random_state(two_link)
        terms = compute_terms(two_link, q, qd, qdd)
        f = RNG.uniform(0, 100, two_link.m)
        fext = cable_external_forces(two_link, terms, f)
        pin.rnea(model, data, two_link.pin_q(q), qd, qdd, fext)
        ref = np.array([data.f[j.child_id].vector for j in two_link.joints])
        ours = terms.wrenches(f)
        assert np.abs(ours - ref).max() <= 1e-10 * max(1.0, np.abs(ref).max())


def test_spherical_joint_carries_no_moment_when_motion_is_met(two_link):
    from mcdm_pin import load_trajectory

    traj = load_trajectory(two_link, "traj1")
    ident = InverseDynamics.for_case(two_link, 1)
    for k in (10, 50, 90):
        res = ident.solve(traj.q[k], traj.qd[k], traj.qdd[k])
        assert res.status == "optimal"
        M_shoulder = res.interaction_wrench[0, 3:]
        F_scale = np.abs(res.interaction_wrench[:, :3]).max()
        assert np.linalg.norm(M_shoulder) <= 1e-8 * max(F_scale, 1.0)


def test_hand_computed_statics(two_link):
    """At q = 0 at rest: cables 1-4 pull link 1 down with f/sqrt(2) each (segments at 45 deg),
    cables 5-8 pull link 2 down with f * 0.3/sqrt(0.15^2 + 0.3^2); the weight is 0.1 kg * 9.81."""
    terms = compute_terms(two_link, np.zeros(4))
    s45, s5 = 1 / np.sqrt(2), 0.3 / np.hypot(0.15, 0.3)
    f = np.ones(8)
    p = terms.wrenches(f)
    assert p[0] == pytest.approx([0, 0, 0.2 * 9.81 + 4 * s45 + 4 * s5, 0, 0, 0], abs=1e-12)
    assert p[1] == pytest.approx([0, 0, 0.1 * 9.81 + 4 * s5, 0, 0, 0], abs=1e-12)
    # one more newton on cable 1: its force (+0.1, 0, -0.1)/|.| acts at (0.05, 0, 0.1) on link 1;
    # the joint then supplies the opposite force and moment r x F = (0, 0.15 s45, 0)
    f[0] = 2.0
    p = terms.wrenches(f)
    assert p[0] == pytest.approx([-s45, 0, 0.2 * 9.81 + 5 * s45 + 4 * s5, 0, -0.15 * s45, 0], abs=1e-12)
    assert terms.tau == pytest.approx(np.zeros(4), abs=1e-15)
    assert terms.angles_deg(f)[0] == pytest.approx(np.degrees(np.arctan2(s45, p[0, 2])), abs=1e-12)


def test_socket_frame_force_is_child_force_rotated_back(two_link):
    q = np.array([0.3, -0.2, 0.4, 0.5])
    terms = compute_terms(two_link, q)
    kin = SphericalKinematics(two_link, two_link.joints[0])
    R = kin.rotation(q[:3])  # socket -> child
    f = RNG.uniform(0, 10, 8)
    F_child = terms.wrenches(f)[0, :3]
    assert terms.socket_forces(f)[0] == pytest.approx(R @ F_child, abs=1e-12)
    # Rx Ry Rz convention (xyz Euler, CASPR S_EULER_XYZ)
    Rx = pin.exp3(np.array([q[0], 0, 0]))
    Ry = pin.exp3(np.array([0, q[1], 0]))
    Rz = pin.exp3(np.array([0, 0, q[2]]))
    assert np.abs(R - Rx @ Ry @ Rz).max() < 1e-15


def test_revolute_triple_equals_pinocchio_spherical_joint(two_link):
    """Build the same arm with JointModelSpherical and compare the joint wrenches under the same
    motion and cable forces."""
    model = pin.Model()
    model.gravity.linear = np.array([0, 0, -9.81])
    inertia = pin.Inertia(0.1, np.array([0, 0, 0.1]), np.eye(3))
    j1 = model.addJoint(0, pin.JointModelSpherical(), pin.SE3.Identity(), "ball")
    model.appendBodyToJoint(j1, inertia, pin.SE3.Identity())
    j2 = model.addJoint(j1, pin.JointModelRX(), pin.SE3(np.eye(3), np.array([0, 0, 0.2])), "elbow")
    model.appendBodyToJoint(j2, inertia, pin.SE3.Identity())
    data = model.createData()
    kin = SphericalKinematics(two_link, two_link.joints[0])
    for _ in range(5):
        q, qd, qdd = random_state(two_link)
        terms = compute_terms(two_link, q, qd, qdd)
        f = RNG.uniform(0, 100, two_link.m)
        S = kin.S(q[:3])
        w = S @ qd[:3]
        # angular acceleration = S qdd + dS/dt qd: from rates() with omega_dot = 0 we get the bias
        _, thdd_bias = kin.rates(q[:3], w, np.zeros(3))
        wdot = S @ (qdd[:3] - thdd_bias)
        quat = pin.Quaternion(kin.rotation(q[:3]))
        qs = np.concatenate([quat.coeffs(), [q[3]]])
        vs = np.concatenate([w, [qd[3]]])
        as_ = np.concatenate([wdot, [qdd[3]]])
        fext = [pin.Force.Zero() for _ in range(model.njoints)]
        ext = cable_external_forces(two_link, terms, f)
        fext[j1] = ext[two_link.joints[0].child_id]
        fext[j2] = ext[two_link.joints[1].child_id]
        pin.rnea(model, data, qs, vs, as_, fext)
        ours = terms.wrenches(f)
        assert np.abs(ours[0] - data.f[j1].vector).max() <= 1e-10 * np.abs(ours).max()
        assert np.abs(ours[1] - data.f[j2].vector).max() <= 1e-10 * np.abs(ours).max()


def test_terms_reuse_gives_identical_results(two_link):
    from mcdm_pin import TermsEvaluator

    ev = TermsEvaluator(two_link)
    q1, qd1, qdd1 = random_state(two_link)
    a = ev(q1, qd1, qdd1)
    ev(*random_state(two_link))
    b = ev(q1, qd1, qdd1)
    assert np.array_equal(a.L, b.L) and np.array_equal(a.RT, b.RT) and np.array_equal(a.u, b.u)
