"""CASPR XML -> URDF + sidecar (mcdm_pin.caspr), on CASPR-format files the tests write themselves
(tests/caspr_xml.py), checked against tests/caspr_newton.py, an implementation of CASPR's kinematics,
trajectories and Newton-Euler equations that shares no code with the package.

Tolerances: both sides are exact to rounding (differences of 1e-14 relative are seen), so terms and
kinematics are compared at ``TOL`` = 1e-9 relative, the issue's bar; samples of trajectories that both
sides compute in closed form at 1e-12.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

from mcdm_pin import compute_terms

from . import caspr_newton as cn
from . import caspr_xml as X
from .caspr_library_check import TOL, compare, ours_from_caspr, reference_state, worst

QUINTIC, CUBIC, LINEAR = "quintic_spline_trajectory", "cubic_spline_trajectory", "linear_spline_trajectory"
AVERAGE, BLEND = "cubic_spline_average_velocity_trajectory", "parabolic_blend_trajectory"


def _import(tmp_path, b, c, t=None, **kw):
    from mcdm_pin import Robot
    from mcdm_pin.caspr import import_caspr

    res = import_caspr(b, c, tmp_path / "out", trajectories_xml=t, **kw)
    return res, Robot.load(res.sidecar)


def _check_states(robot, res, model, b, states):
    """compare() at CASPR states (q, qd, qdd), our state by the importer's conversion."""
    errors = []
    for q, qd, qdd in states:
        x, v, a = ours_from_caspr(b, robot, q, qd, qdd)
        st = reference_state(model, q, qd, qdd)
        errors.append(compare(robot, [link.ident for link in res.bodies.links], st, robot.configuration(x), v, a))
    return worst(errors)


# ------------------------------------------------------------------------------------ joint types
JOINTS = ["R_X", "R_Y", "R_Z", "R_AXIS", "P_X", "P_AXIS", "P_XY", "P_XZ", "T_XYZ", "PLANAR_XY", "PLANAR_XZ",
          "PLANAR_YZ", "U_XY", "U_XZ", "U_YZ", "S_EULER_XYZ", "S_FIXED_XYZ", "SPATIAL_EULER_XYZ"]


@pytest.mark.parametrize("jtype", JOINTS)
def test_every_joint_type_matches_caspr_newton(tmp_path, jtype):
    """Each CASPR joint type as the root of a 3-link tree (an R_Y child on it, an S_EULER_XYZ child on
    that), inertias off-diagonal and about the joint, joint-referenced attachments: frames, velocities,
    accelerations, lengths, L, M, M qdd + h and the interaction maps equal CASPR's at random states."""
    root = dict(type=jtype, ixx=0.05, iyy=0.06, izz=0.03, ixy=0.003, ref="joint", com="0.02 -0.01 0.1")
    if jtype in ("R_AXIS", "P_AXIS"):
        root["axis"] = "0.6 0.0 0.8"
    links = [root, dict(type="R_Y", loc="0.05 0 0.2"), dict(type="S_EULER_XYZ", parent=2, loc="0 0.03 0.2")]
    b = X.bodies(tmp_path / "b.xml", links)
    c = X.cables(tmp_path / "c.xml", {"s": X.star(3, 8, 0.5, -0.3)})
    res, robot = _import(tmp_path, b, c)
    assert robot.nv == X.N_Q[jtype] + 4 and [j.type for j in robot.joints][0] == res.bodies.links[0].kind.sidecar
    model = cn.Model.from_xml(b, c)
    rng = np.random.default_rng(len(jtype))
    states = [(rng.uniform(-0.6, 0.6, model.n), rng.uniform(-1, 1, model.n), rng.uniform(-1, 1, model.n))
              for _ in range(3)]
    errors = _check_states(robot, res, model, b, states)
    assert max(errors.values()) < TOL, errors


def test_joint_groups_and_coordinates(tmp_path):
    """What each type becomes in the sidecar, and the coordinates: CASPR's q unchanged for chains of
    Euler, revolute, universal and planar joints; S_FIXED_XYZ reversed; a free joint a position and a
    rotation vector."""
    b = X.bodies(tmp_path / "b.xml", [dict(type="SPATIAL_EULER_XYZ"), dict(type="U_XZ"), dict(type="PLANAR_YZ"),
                                      dict(type="S_FIXED_XYZ"), dict(type="P_XZ")])
    c = X.cables(tmp_path / "c.xml", {"s": X.star(5, 6)})
    res, robot = _import(tmp_path, b, c)
    assert [(j.name, j.type, len(j.pin_joints)) for j in robot.joints] == [
        ("L1", "free", 1), ("L2", "universal", 2), ("L3", "planar", 3), ("L4", "spherical", 3), ("L5", "translation", 2)]
    assert robot.coordinate_names[:6] == tuple(f"L1_free.{s}" for s in ("x", "y", "z", "rx", "ry", "rz"))
    assert robot.coordinate_names[6:] == ("L2_x", "L2_z", "L3_py", "L3_pz", "L3_x", "L4_z", "L4_y", "L4_x",
                                          "L5_px", "L5_pz")
    q_c = np.array([0.1, 0.2, 0.3, 0.4, -0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2, 1.3, 1.4, 1.5, 1.6])
    x = res.coordinates_from_caspr(q_c)
    np.testing.assert_allclose(x[:3], [0.1, 0.2, 0.3])
    R = cn.rot(cn.EX, 0.4) @ cn.rot(cn.EY, -0.5) @ cn.rot(cn.EZ, 0.6)
    import pinocchio as pin

    np.testing.assert_allclose(pin.exp3(x[3:6]), R, atol=1e-15)
    np.testing.assert_allclose(x[6:], [0.7, 0.8, 0.9, 1.0, 1.1, 1.4, 1.3, 1.2, 1.5, 1.6])
    assert not res.q_is_caspr_order
    with pytest.raises(Exception, match="free joint"):
        res.q_index
    assert "rotation vector" in robot.sidecar.description


def test_axis_normalised_within_1e3_refused_beyond(tmp_path):
    c = X.cables(tmp_path / "c.xml", {"s": X.star(1, 6)})
    b = X.bodies(tmp_path / "b.xml", [dict(type="R_AXIS", axis="0.05101 -0.9984 0.02231")])  # Roboy's, 0.99995
    res, robot = _import(tmp_path, b, c)
    assert len(res.notes) == 1 and "normalised" in res.notes[0] and "0.999951157" in res.notes[0]
    from mcdm_pin.exceptions import CasprError

    X.bodies(b, [dict(type="R_AXIS", axis="0 0 1.002")])
    with pytest.raises(CasprError, match=r"joint@axis: expected a unit vector \(norm within 0.001 of 1\), got norm 1.002"):
        _import(tmp_path, b, c)


# ------------------------------------------------------------------------------------ trajectories
def _mixed(tmp_path):
    """A planar base, a spherical joint and a universal joint: every way CASPR interpolates."""
    b = X.bodies(tmp_path / "b.xml", [dict(type="PLANAR_XZ", q=[0, 0, 0]), dict(type="S_EULER_XYZ"),
                                      dict(type="U_YZ")])
    c = X.cables(tmp_path / "c.xml", {"s": X.star(3, 8, 0.6, -0.2)})
    return b, c


def _assert_like_caspr(tmp_path, b, c, t, tid, model=None):
    """Our exact samples (and the trajectory loaded back from the sidecar or CSV) at CASPR's times, with
    CASPR's q, q_dot, q_ddot and with its bodies' motion at a few samples."""
    from mcdm_pin import load_trajectory

    res, robot = _import(tmp_path, b, c, t)
    model = model or cn.Model.from_xml(b, c)
    tc, Q, QD, QDD = cn.sample(model, cn.read_trajectory(t, tid, model.n))
    s = res.samples(tid)
    np.testing.assert_allclose(s.t, tc, rtol=0, atol=1e-12)
    scalar = ~np.isnan(s.q[0])
    for ours, ref in ((s.q, Q), (s.qd, QD), (s.qdd, QDD)):
        np.testing.assert_allclose(ours[:, scalar], ref[:, scalar], rtol=0, atol=1e-12 * max(1, np.abs(ref).max()))
    loaded = load_trajectory(robot, tid)
    exact = res.exact_trajectory(robot, tid)
    for k in ("t", "q", "qd", "qdd"):
        np.testing.assert_allclose(getattr(loaded, k), getattr(exact, k), rtol=0, atol=1e-12)
    errors = []
    links = [link.ident for link in res.bodies.links]
    for k in np.unique(np.linspace(0, len(tc) - 1, 6).round().astype(int)):
        st = reference_state(model, Q[k], QD[k], QDD[k])
        errors.append(compare(robot, links, st, loaded.q[k], loaded.qd[k], loaded.qdd[k]))
    w = worst(errors)
    assert max(w.values()) < TOL, w
    return res, robot, loaded


SPH0 = [0.1, -0.2, 0.3]


@pytest.mark.parametrize("case", ["quintic", "cubic", "linear", "average", "blend"])
def test_every_trajectory_type_follows_caspr(tmp_path, case):
    b, c = _mixed(tmp_path)
    p0, p1, p2 = [0.1, 0.2, 0.0], [0.3, -0.1, 0.4], [0.0, 0.2, -0.3]
    sph = [SPH0, [0.4, 0.5, -0.6], [-0.3, 0.2, 0.1]]
    uni = [[0, 0], [0.3, -0.2], [0.1, 0.4]]
    q = [p + s + u for p, s, u in zip((p0, p1, p2), sph, uni)]
    if case == "quintic":  # rates at the middle point, except on the spherical joint's angles
        v1, a1 = [0.2, -0.1, 0.3, 0, 0, 0, 0.5, -0.4], [1, 0, -1, 0, 0, 0, 0.2, 0.1]
        pts = [X.point(q[0], [0] * 8, [0] * 8), X.point(q[1], v1, a1, time=0.6), X.point(q[2], [0] * 8, [0] * 8, time=0.5)]
        tr = X.trajectory(QUINTIC, "tr", pts, dt=0.05, time_definition="relative")
    elif case == "cubic":
        v1 = [0.2, -0.1, 0.3, 0, 0, 0, 0.5, -0.4]
        pts = [X.point(q[0], [0] * 8), X.point(q[1], v1, time=0.6), X.point(q[2], [0] * 8, time=1.1)]
        tr = X.trajectory(CUBIC, "tr", pts, dt=0.05)
    elif case == "linear":
        tr = X.trajectory(LINEAR, "tr", [X.point(q[0]), X.point(q[1], time=0.6), X.point(q[2], time=1.1)], dt=0.05)
    elif case == "average":  # the spherical joint stays put (CASPR refuses non-zero mean rates on it)
        qa = [p + SPH0 + u for p, u in zip((p0, p1, p2), uni)]
        tr = X.trajectory(AVERAGE, "tr", [X.point(qa[0], [0] * 8), X.point(qa[1], time=0.6),
                                          X.point(qa[2], [0.1] * 3 + [0] * 3 + [0.2, 0.1], time=1.1)], dt=0.05)
    else:
        tr = X.trajectory(BLEND, "tr", [X.point(q[0]), X.point(q[1], time=1.0), X.point(q[2], time=2.0, blend_time=0.3)],
                          dt=0.05, blend_time_default=0.2)
    t = X.trajectories(tmp_path / "t.xml", [tr])
    res, robot, loaded = _assert_like_caspr(tmp_path, b, c, t, "tr")
    assert robot.sidecar.trajectories["tr"].type == "csv"
    if case == "linear":  # a junction keeps the earlier segment's (constant) rates
        k = int(np.argmin(np.abs(loaded.t - 0.6)))
        np.testing.assert_allclose(loaded.qd[k, 0], (0.3 - 0.1) / 0.6, rtol=1e-12)


def test_spatial_platform_follows_caspr_as_a_free_flyer(tmp_path):
    """SPATIAL_EULER_XYZ: CASPR interpolates the position per coordinate and the orientation about one
    axis; as a free-flyer the platform has the same poses, velocities and accelerations."""
    b = X.bodies(tmp_path / "b.xml", [dict(type="SPATIAL_EULER_XYZ", q=[0, 0, 1, 0, 0, 0], com="0 0 0")])
    c = X.cables(tmp_path / "c.xml", {"s": [X.cable(f"c{k}", [a, (1, [p[1][0] / 8, p[1][1] / 8, 0])])
                                            for k, (a, p) in enumerate(zip(X.ring(0, 2.0, 2.0, 8), X.ring(1, 0, 1, 8)))]})
    pts = [X.point([0, 0, 1, 0.1, -0.2, 0.3], [0] * 6, [0] * 6),
           X.point([0.3, -0.2, 1.2, -0.4, 0.3, 0.5], [0.1, 0.2, 0, 0, 0, 0], [0, 0, 0.5, 0, 0, 0], time=1.5),
           X.point([0.1, 0.1, 0.9, 0.2, 0.1, -0.2], [0] * 6, [0] * 6, time=3.0)]
    t = X.trajectories(tmp_path / "t.xml", [X.trajectory(QUINTIC, "tour", pts, dt=0.01),
                                            X.trajectory(QUINTIC, "p2p", [pts[0], X.point([0.3, -0.2, 1.2, -0.4, 0.3, 0.5],
                                                                                          [0] * 6, [0] * 6, time=1.0)])])
    res, robot, loaded = _assert_like_caspr(tmp_path, b, c, t, "tour")
    assert robot.sidecar.trajectories["p2p"].type == "quintic"  # rest to rest: a sidecar quintic
    _assert_like_caspr(tmp_path, b, c, t, "p2p")


def test_set_points_hold_still(tmp_path):
    """CASPR's set-point trajectories (Example_2R_planar_XZ's setpoint_eMPC*): a quintic segment of one
    time step then a hold. Sampled as CASPR samples them, every sample is at rest: no rate is invented
    at the jump, and the hold is a static pose."""
    b = X.bodies(tmp_path / "b.xml", [dict(type="R_Y", com="0 0 0.5"), dict(type="R_Y", loc="0 0 1", com="0 0 0.5")])
    c = X.cables(tmp_path / "c.xml", {"s": X.star(2, 4, 1.0)})
    zero = [0.0, 0.0]
    t = X.trajectories(tmp_path / "t.xml", [
        X.trajectory(QUINTIC, "setpoint_finer", [X.point(zero, zero, zero), X.point([0.5, 0.3], zero, zero, time=0.01),
                                                 X.point([0.5, 0.3], zero, zero, time=2)], dt=0.01, time_definition="relative"),
        X.trajectory(QUINTIC, "hold", [X.point([-0.4, -0.3], zero, zero), X.point([-0.4, -0.3], zero, zero, time=1)])])
    res, robot, loaded = _assert_like_caspr(tmp_path, b, c, t, "setpoint_finer")
    assert len(loaded) == 202 and loaded.t[1] == pytest.approx(0.01)
    np.testing.assert_array_equal(loaded.qd, 0.0)
    np.testing.assert_array_equal(loaded.qdd, 0.0)
    np.testing.assert_allclose(loaded.q[1:], [[0.5, 0.3]] * 201, atol=1e-15)
    from mcdm_pin import load_trajectory

    hold = load_trajectory(robot, "hold")
    assert robot.sidecar.trajectories["hold"].type == "quintic"
    np.testing.assert_array_equal(hold.qd, 0.0)
    np.testing.assert_allclose(hold.q, [[-0.4, -0.3]] * 101, atol=1e-15)


def test_segments_that_are_not_whole_time_steps(tmp_path):
    """BioBiped_one_leg's traj1 has segments of 0.01326 s at dt = 0.001 s: CASPR's spline ends at the
    segment's last sample and the next segment starts at its nominal time."""
    b, c = _mixed(tmp_path)
    q0, q1, q2 = [0.0] * 3 + SPH0 + [0, 0], [0.1] * 3 + SPH0 + [0.2, 0], [0.2] * 3 + SPH0 + [0, 0.1]
    pts = [X.point(q0, [0] * 8, [0] * 8), X.point(q1, [0.5] * 3 + [0] * 5, [0] * 8, time=0.01326),
           X.point(q2, [0] * 8, [0] * 8, time=0.01326)]
    t = X.trajectories(tmp_path / "t.xml", [X.trajectory(QUINTIC, "tr", pts, dt=0.001, time_definition="relative")])
    res, robot, loaded = _assert_like_caspr(tmp_path, b, c, t, "tr")
    np.testing.assert_allclose(loaded.t[12:16], [0.012, 0.013, 0.01426, 0.01526], atol=1e-12)
    np.testing.assert_allclose(loaded.qd[13, 0], 0.5, rtol=1e-12)  # the end rate, at the last sample
    assert len(res.notes) == 2 and "not a whole number of time steps" in res.notes[0]


def test_file_trajectory(tmp_path):
    """``file_trajectory``: CASPR's .traj file (time_step, then t, p, v, a per line) taken as written."""
    b, c = _mixed(tmp_path)
    model = cn.Model.from_xml(b, c)
    src = X.trajectories(tmp_path / "src.xml", [X.trajectory(
        QUINTIC, "tr", [X.point([0] * 3 + SPH0 + [0, 0], [0] * 8, [0] * 8),
                        X.point([0.2] * 3 + [0.5, 0.1, -0.2, 0.3, 0.1], [0] * 8, [0] * 8, time=1)], dt=0.1)])
    tc, Q, QD, QDD = cn.sample(model, cn.read_trajectory(src, "tr", model.n))
    lines = ["time_step,0.100000"] + [
        f"t,{t:.6f},p," + ",".join(f"{x:.6f}" for x in q) + ",v," + ",".join(f"{x:.6f}" for x in qd) + ",a,"
        + ",".join(f"{x:.6f}" for x in qdd) for t, q, qd, qdd in zip(tc, Q, QD, QDD)]
    (tmp_path / "motion.traj").write_text("\n".join(lines))
    t = X.trajectories(tmp_path / "t.xml", ['<file_trajectory id="f" filename="motion.traj"/>'])
    from mcdm_pin import load_trajectory

    res, robot = _import(tmp_path, b, c, t)
    loaded = load_trajectory(robot, "f")
    assert len(loaded) == 11
    # the file's 6 decimals are what CASPR uses: its poses and rates, converted, give its motion
    read = [np.array([[float(x) for x in line.split(",")[s:e]] for line in lines[1:]]) for s, e in ((3, 11), (12, 20), (21, 29))]
    errors = [compare(robot, [link.ident for link in res.bodies.links], reference_state(model, read[0][k], read[1][k], read[2][k]),
                      loaded.q[k], loaded.qd[k], loaded.qdd[k]) for k in (2, 5, 8)]
    assert max(worst(errors).values()) < TOL


def test_a_bad_trajectory_is_refused_alone(tmp_path):
    b, c = _mixed(tmp_path)
    z, q = [0] * 8, [0.1] * 3 + SPH0 + [0.1, 0.2]
    good = X.trajectory(QUINTIC, "good", [X.point(z, z, z), X.point(q, z, z, time=1)])
    bad = {
        "spherical_rates": (X.trajectory(QUINTIC, "spherical_rates", [X.point(z, z, z), X.point(q, [0, 0, 0, 1, 0, 0, 0, 0], z, time=1)]),
                            "non-zero q_dot/q_ddot on a spherical joint"),
        "no_rates": (X.trajectory(QUINTIC, "no_rates", [X.point(z), X.point(q, time=1)]), "q_dot: missing"),
        "too_short": (X.trajectory(QUINTIC, "too_short", [X.point(z, z, z), X.point(q, z, z, time=0.005)]),
                      "shorter than time_step"),
        "long_blend": (X.trajectory(BLEND, "long_blend", [X.point(z), X.point(q, time=1.0)], blend_time_default=0.6),
                       "less than half the segment"),
        "nofile": ('<file_trajectory id="nofile" filename="gone.traj"/>', "'gone.traj' is not next to t.xml"),
        "other": ('<bspline_trajectory id="other" time_definition="absolute" time_step="0.1"/>',
                  "unknown trajectory type <bspline_trajectory>"),
        "backwards": (X.trajectory(QUINTIC, "backwards", [X.point(z, z, z), X.point(q, z, z, time=1), X.point(z, z, z, time=0.5)]),
                      "expected a time after 1 s"),
    }
    op = '<quintic_spline_trajectory id="ee" time_definition="relative" time_step="0.1"><points/></quintic_spline_trajectory>'
    t = X.trajectories(tmp_path / "t.xml", [good] + [v[0] for v in bad.values()] + [good.replace('"good"', '"good"')], [op])
    res, robot = _import(tmp_path, b, c, t)
    assert list(res.trajectories) == ["good"] and list(robot.sidecar.trajectories) == ["good"]
    for tid, (_, reason) in bad.items():
        assert tid in res.refused and reason in res.refused[tid], (tid, res.refused.get(tid))
        assert f"[id={tid!r}]" in res.refused[tid]
    dup = [k for k in res.refused if k.startswith("good (element")]
    assert len(dup) == 1 and "duplicate id" in res.refused[dup[0]]
    assert "inverse kinematics" in res.refused["operational:ee"]
    assert not list((tmp_path / "out").glob("*_nofile*")) and len(list((tmp_path / "out").glob("*.csv"))) == 0


# ------------------------------------------------------------------------------------- refusals
@pytest.mark.parametrize("links, needle", [
    ([dict(type="S_QUATERNION", q=[1, 0, 0, 0], qmin=[-1] * 4, qmax=[1] * 4)], "'S_QUATERNION' is commented out of CASPR's JointType"),
    ([dict(type="SPHERICAL")], "'SPHERICAL' is commented out"),
    ([dict(type="S_EULER")], "unknown joint type 'S_EULER'"),
    ([dict(type="R_X", axis="1 0 0")], "joint@axis: an axis is allowed only for R_AXIS and P_AXIS"),
    ([dict(type="R_X", q=[0, 0])], "joint@q_initial: expected 1 number, got 2"),
    ([dict(type="R_X", ref="CoM")], "inertia@ref: expected 'com' or 'joint', got 'CoM'"),
    ([dict(type="R_X", parent=1)], "parent/num: expected a parent number in 0..0"),
])
def test_bodies_refused_naming_the_element(tmp_path, links, needle):
    from mcdm_pin.exceptions import CasprError, McdmError

    b = X.bodies(tmp_path / "b.xml", links)
    c = X.cables(tmp_path / "c.xml", {"s": X.star(1, 6)})
    with pytest.raises(CasprError) as exc:
        _import(tmp_path, b, c)
    assert needle in str(exc.value) and str(b) in str(exc.value) and "link_rigid[num='1', name='L1']" in str(exc.value)
    assert isinstance(exc.value, McdmError)


@pytest.mark.parametrize("tag", ["muscle_hill_type", "pneumatic_artificial_muscle"])
def test_other_cable_types_refused_naming_element_and_type(tmp_path, tag):
    from mcdm_pin.exceptions import CasprError

    b = X.bodies(tmp_path / "b.xml", [dict(type="R_X")])
    cs = X.star(1, 4)
    cs[2] = X.cable("spring 1", [(0, [1, 0, 0]), (1, [0, 0, 0])], tag=tag)
    c = X.cables(tmp_path / "c.xml", {"s": cs})
    with pytest.raises(CasprError, match=rf"cable_set\[id='s'\]/{tag}\[3, name='spring 1'\]: unsupported cable type <{tag}>"):
        _import(tmp_path, b, c)


@pytest.mark.parametrize("tag", ["cable_linear_spring", "cable_vsd_torsion_spring", "cable_vsd_flexure_linear",
                                 "cable_vsd_polynomial"])
def test_stiffness_cables_are_cables(tmp_path, tag):
    """CASPR's linear-spring and variable-stiffness cables are active: their tension is the unknown
    within [force_min, force_max]; their stiffness parameters are read, named, and not used."""
    from mcdm_pin.caspr import STIFFNESS_CABLES

    b = X.bodies(tmp_path / "b.xml", [dict(type="R_X")])
    cs = X.star(1, 4)
    params = "".join(f"<{k}>1 2 3</{k}>" if k == "vsd_force_deformation_relation" else f"<{k}>4</{k}>"
                     for k in STIFFNESS_CABLES[tag])
    cs[2] = X.cable("vs 1", [(0, [1, 0, 0]), (1, [0, 0, 0])], tag=tag, f_min=2.0, f_max=70.0).replace(
        "<properties>", f"<properties>{params}")
    c = X.cables(tmp_path / "c.xml", {"s": cs})
    res, robot = _import(tmp_path, b, c)
    assert robot.m == 4 and robot.cables["vs 1"].f_min == 2.0 and robot.cables["vs 1"].f_max == 70.0
    assert f"<{tag}>" in robot.sidecar.description and STIFFNESS_CABLES[tag][0] in robot.sidecar.description


def test_passive_springs_become_sidecar_springs(tmp_path):
    """``cable_passive_linear_spring``: a known tension K (l - l0) (the spring's attachments as a
    cable's, here relative to the COM); a spring without K is refused by element."""
    from mcdm_pin.exceptions import CasprError

    b = X.bodies(tmp_path / "b.xml", [dict(type="R_X")])
    cs = X.star(1, 4) + [X.cable("spring 1", [(0, [1, 0, 0]), (1, [0, 0.1, 0])]).replace(
        "cable_ideal", "cable_passive_linear_spring").replace(
        "<force_min>0.1</force_min><force_max>100.0</force_max>", "<K>7.5</K><l0>0.25</l0>")]
    c = X.cables(tmp_path / "c.xml", {"s": cs})
    res, robot = _import(tmp_path, b, c)
    assert robot.m == 4 and robot.springs.names == ("spring 1",)
    assert robot.springs.stiffness[0] == 7.5 and robot.springs.rest_length[0] == 0.25
    model = cn.Model.from_xml(b, c)
    q = np.array([0.3])
    np.testing.assert_allclose(compute_terms(robot, q).spring_forces, model.spring_forces(q), rtol=1e-13)
    c = X.cables(tmp_path / "c2.xml", {"s": cs[:4] + [cs[4].replace("<K>7.5</K>", "")]})
    with pytest.raises(CasprError, match=r"cable_passive_linear_spring\[5, name='spring 1'\]/properties: missing <K>"):
        _import(tmp_path, b, c)


def test_pulleys_and_empty_sets_refused(tmp_path):
    from mcdm_pin.exceptions import CasprError

    b = X.bodies(tmp_path / "b.xml", [dict(type="R_X")])
    cs = X.star(1, 4)
    cs[0] = cs[0].replace("<attachment><link>0</link>", "<base_rotating_pulley><link>0</link>", 1).replace(
        "</attachment><attachment><link>1", "</base_rotating_pulley><attachment><link>1", 1)
    c = X.cables(tmp_path / "c.xml", {"pulleys": cs, "Empty": [], "plain": X.star(1, 4)}, default="pulleys")
    # a pulley is converted (tests/test_pulleys.py); this one lacks its fields
    with pytest.raises(CasprError, match=r"cable_ideal\[1, name='c1_0'\]/attachments/base_rotating_pulley\[1\]: "
                                         r"missing <fixed_location> element"):
        _import(tmp_path, b, c)
    with pytest.raises(CasprError, match=r"cable_set\[id='Empty'\]: the set has no cable; mcdm-pin needs at least one; "
                                         r"choose another set \(pulleys, plain\) with --cable-set"):
        _import(tmp_path, b, c, cable_set="Empty")
    res, robot = _import(tmp_path, b, c, cable_set="plain")
    assert robot.m == 4 and res.cable_set == "plain"
    # an empty *default* set (PlanarSnakeArm's): the first set with cables, said in the notes
    c = X.cables(tmp_path / "c3.xml", {"Empty": [], "plain": X.star(1, 4)}, default="Empty")
    res, robot = _import(tmp_path, b, c)
    assert res.cable_set == "plain" and any("'Empty' has no cable; took the first set with cables, 'plain'" in n
                                            for n in res.notes)


def test_actuated_joints_become_motors(tmp_path):
    """HCDM: CASPR's actuated joints have unbounded motors weighted like a cable in its case-1 objective
    (IDObjectiveMinQuadCableForce(ones(numActuatorsActive))); by default the sidecar gets -.inf/.inf and
    weight 1, with --actuator-limit +-limit."""
    b = X.bodies(tmp_path / "b.xml", [dict(type="PLANAR_XY", actuated=True), dict(type="R_X"),
                                      dict(type="R_Z", actuated=True, parent=1)])
    c = X.cables(tmp_path / "c.xml", {"s": X.star(3, 4)})
    res, robot = _import(tmp_path, b, c)
    specs = {j.name: j.actuated for j in robot.sidecar.joints}
    assert specs["L1"].min == (-np.inf,) * 3 and specs["L1"].max == (np.inf,) * 3 and specs["L1"].weight == 1.0
    assert "-.inf" in res.sidecar.read_text()
    res, robot = _import(tmp_path, b, c, actuator_limit=250.0)
    specs = {j.name: j.actuated for j in robot.sidecar.joints}
    assert specs["L1"].min == (-250.0,) * 3 and specs["L1"].max == (250.0,) * 3 and specs["L1"].weight == 1.0
    assert specs["L2"] is None and specs["L3"].max == (250.0,)
    assert robot.n_act == 4
    model = cn.Model.from_xml(b, c)
    np.testing.assert_array_equal(robot.actuation, model.actuation())  # chains in CASPR's order here
    from mcdm_pin.exceptions import CasprError

    with pytest.raises(CasprError, match=r"--actuator-limit: expected a finite bound > 0"):
        _import(tmp_path, b, c, actuator_limit=-1.0)


# ----------------------------------------------------------------------------- writing, the CLI
def test_failed_import_leaves_the_output_folder_alone(tmp_path, monkeypatch):
    b, c = _mixed(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    (out / "b.yaml").write_text("keep me")
    import mcdm_pin.robot as robot_mod

    def broken(sidecar):
        raise RuntimeError("late failure")

    monkeypatch.setattr(robot_mod.Robot, "from_sidecar", classmethod(lambda cls, sc: broken(sc)))
    with pytest.raises(RuntimeError, match="late failure"):
        _import(tmp_path, b, c)
    assert sorted(p.name for p in out.iterdir()) == ["b.yaml"] and (out / "b.yaml").read_text() == "keep me"
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".import-caspr-")]


def test_names_with_double_dashes_give_valid_xml(tmp_path):
    b = X.bodies(tmp_path / "arm--v2--_bodies.xml", [dict(type="R_X", name="upper--arm-")])
    c = X.cables(tmp_path / "c.xml", {"s": X.star(1, 4)})
    res, robot = _import(tmp_path, b, c, name="arm")
    text = res.urdf.read_text()
    ET.fromstring(text)  # parses: no "--" inside a comment
    assert "arm- -v2- -_bodies.xml" in text and "upper- -arm- " in text


def test_output_is_deterministic(tmp_path):
    b, c = _mixed(tmp_path)
    z, q = [0] * 8, [0.1] * 3 + SPH0 + [0.1, 0.2]
    t = X.trajectories(tmp_path / "t.xml", [X.trajectory(CUBIC, "tr", [X.point(z, z), X.point(q, z, time=1)])])
    from mcdm_pin.caspr import import_caspr

    a = import_caspr(b, c, tmp_path / "a", trajectories_xml=t)
    b2 = import_caspr(b, c, tmp_path / "b", trajectories_xml=t)
    for f in (a.urdf, a.sidecar, a.csv_files["tr"]):
        assert f.read_bytes() == (tmp_path / "b" / f.name).read_bytes()
    assert b2.csv_files["tr"].name == "b_tr.csv"


def test_cli_import_caspr(tmp_path, capsys):
    from mcdm_pin.cli import main

    b, c = _mixed(tmp_path)
    z = [0] * 8
    t = X.trajectories(tmp_path / "t.xml", [X.trajectory(QUINTIC, "ok", [X.point(z, z, z), X.point([0.1] * 8, z, z, time=1)]),
                                            X.trajectory(LINEAR, "short", [X.point(z), X.point(z, time=0.001)])])
    rc = main(["import-caspr", str(b), str(c), "--trajectories", str(t), "--out", str(tmp_path / "o"), "--name", "m"])
    out = capsys.readouterr().out
    assert rc == 0 and "cable set 's'" in out and "trajectories: ok (quintic)" in out
    assert "refused trajectory 'short'" in out and "shorter than time_step" in out
    rc = main(["import-caspr", str(b), str(c), "--out", str(tmp_path / "o"), "--cable-set", "nope"])
    assert rc == 2 and "no cable set 'nope'; expected one of s" in capsys.readouterr().err
