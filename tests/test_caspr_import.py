"""CASPR XML -> URDF + sidecar (mcdm_pin.caspr), on CASPR's own model files.

The reference files are read in place from ``shared/reference/caspr`` (never copied into the repo).
Small synthetic XML files written into ``tmp_path`` cover the joint types the two reference models
do not use (S_FIXED_XYZ, U_*, R_Y), ``ref="joint"`` inertias, ``attachment_reference="joint"``, a tree,
and the error messages.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

CASPR = Path(__file__).resolve().parents[2] / "shared/reference/caspr"
SR = CASPR / "SR_model"
NECK = CASPR / "8S_neck"
REPO = Path(__file__).resolve().parents[1]

needs_caspr = pytest.mark.skipif(
    not (SR / "SR_model_bodies.xml").is_file() or not (NECK / "8S_neck_bodies.xml").is_file(),
    reason=f"CASPR reference models not found in {CASPR} (shared/reference/caspr is missing); "
           f"these tests read CASPR's XML files in place")


def _import(out, bodies, cables, trajectories=None, **kw):
    from mcdm_pin.caspr import import_caspr

    return import_caspr(bodies, cables, out, trajectories_xml=trajectories, **kw)


# ------------------------------------------------------------------------------ reference models
@pytest.fixture(scope="module")
def sr_import(tmp_path_factory):
    if not (SR / "SR_model_bodies.xml").is_file():
        pytest.skip(f"CASPR reference models not found in {CASPR}")
    out = tmp_path_factory.mktemp("sr")
    return _import(out, SR / "SR_model_bodies.xml", SR / "SR_model_cables.xml",
                   SR / "SR_model_trajectories.xml", name="sr")


@pytest.fixture(scope="module")
def neck_import(tmp_path_factory):
    if not (NECK / "8S_neck_bodies.xml").is_file():
        pytest.skip(f"CASPR reference models not found in {CASPR}")
    out = tmp_path_factory.mktemp("neck")
    return _import(out, NECK / "8S_neck_bodies.xml", NECK / "8S_neck_cables.xml",
                   NECK / "8S_neck_trajectories.xml")


@needs_caspr
def test_sr_default_cable_set_matches_hand_written_robot(sr_import, two_link):
    """The imported SR arm (default set SR_8_cables_2) has exactly the terms of the hand-written
    robots/two_link_sr.yaml: same q order, cable order, M, h, L, u, R^T and socket rotations."""
    from mcdm_pin import Robot, compute_terms

    sr = Robot.load(sr_import.sidecar)
    assert sr_import.cable_set == "SR_8_cables_2"
    assert sr_import.q_is_caspr_order
    assert sr.joint_names == ("Link_1", "Link_2")
    assert [j.type for j in sr.joints] == ["spherical", "revolute"]
    assert sr.cable_names == tuple(f"cable {i}" for i in range(1, 9))  # CASPR's names, in order
    rng = np.random.default_rng(4)
    for _ in range(5):
        q, qd, qdd = rng.uniform(-0.8, 0.8, (3, 4))
        a, b = compute_terms(sr, q, qd, qdd), compute_terms(two_link, q, qd, qdd)
        for name in ("M", "h", "L", "u", "RT", "R_socket", "lengths"):
            np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=1e-12, atol=1e-12,
                                       err_msg=name)
    # SR_trajectory is the hand-written traj1 (the XML has 9 significant digits of pi/6, pi/10)
    from mcdm_pin import load_trajectory

    t_imp, t_ref = load_trajectory(sr, "SR_trajectory"), load_trajectory(two_link, "traj1")
    np.testing.assert_allclose(t_imp.q, t_ref.q, atol=1e-9)
    np.testing.assert_allclose(t_imp.qdd, t_ref.qdd, atol=1e-8)


@needs_caspr
def test_sr_other_cable_sets(tmp_path):
    from mcdm_pin import Robot

    res = _import(tmp_path, SR / "SR_model_bodies.xml", SR / "SR_model_cables.xml", cable_set="SR_8_cables")
    sr = Robot.load(res.sidecar)
    c5 = sr.cables[4]  # base -> via-point on link 1 -> link 2: three points, two active segments
    assert c5.links == ("base", "Link_1", "Link_2")
    np.testing.assert_allclose(c5.points, [[0, 0.2, 0], [0, 0.1, 0.15], [0, 0.05, 0.1]], atol=1e-15)
    res6 = _import(tmp_path / "six", SR / "SR_model_bodies.xml", SR / "SR_model_cables.xml",
                   cable_set="SR_6_cables")
    assert Robot.load(res6.sidecar).m == 6


@needs_caspr
def test_neck_structure(neck_import):
    from mcdm_pin import Robot

    neck = Robot.load(neck_import.sidecar)
    assert neck.nv == 24 and len(neck.joints) == 8 and neck.m == 76
    assert all(j.type == "spherical" for j in neck.joints)
    assert neck.joint_names[0] == "C7_bone" and neck.joint_names[-1] == "Skull"
    assert neck_import.q_is_caspr_order
    # names and order kept; the two repeated CASPR names get a suffix (sidecar names are unique)
    xml_names = [c.get("name") for c in ET.parse(NECK / "8S_neck_cables.xml").getroot().iter("cable_ideal")]
    assert len(xml_names) == 76
    assert neck_import.renamed_cables == {33: ("supmult-C5/6-C2 (right)", "supmult-C5/6-C2 (right) #2"),
                                          71: ("supmult-C5/6-C2 (left)", "supmult-C5/6-C2 (left) #2")}
    for i, (ours, theirs) in enumerate(zip(neck.cable_names, xml_names), start=1):
        assert ours == (neck_import.renamed_cables[i][1] if i in neck_import.renamed_cables else theirs)
    by_name = {c.name: c for c in neck.cables}
    names = ["base"] + [j for j in neck.joint_names]
    # multi-link routes are kept, skipping links as CASPR's file does
    assert by_name["long-col-c1thx (right)"].links == tuple(names[0:8])
    assert by_name["long-col-c1c5 (right)"].links == tuple(names[k] for k in (3, 4, 6, 7))
    assert sum(len(c.links) > 2 for c in neck.cables) == 8
    # COM-referenced points move to the joint point: skull (link 8) COM at (0, 0, 0.1)
    np.testing.assert_allclose(by_name["cleid-mast (right)"].points[1], [-0.0051, -0.0643, -0.09307 + 0.1],
                               atol=1e-15)
    # masses and inertias (URDF inertial at the COM, link axes)
    skull = neck.model.inertias[neck.joints[-1].child_id]
    assert skull.mass == pytest.approx(1.0)
    np.testing.assert_allclose(skull.lever, [0, 0, 0.1], atol=1e-15)
    np.testing.assert_allclose(skull.inertia, np.diag([1e-3] * 3), atol=1e-15)
    assert sum(neck.model.inertias[j.child_id].mass for j in neck.joints) == pytest.approx(1.7)


@needs_caspr
def test_neck_trajectories(neck_import):
    """roll/pitch/yaw are single-segment rest-to-rest quintics; 'combined' (10 points, relative
    times) is sampled segment by segment and written as CSV."""
    from mcdm_pin import Robot, load_trajectory
    from mcdm_pin.caspr import caspr_trajectory

    neck = Robot.load(neck_import.sidecar)
    specs = neck.sidecar.trajectories
    assert [specs[k].type for k in ("roll", "pitch", "yaw", "combined")] == ["quintic"] * 3 + ["csv"]
    roll = load_trajectory(neck, "roll")
    assert len(roll) == 101
    # only alpha moves: joints 1-7 from -pi/45 to pi/45, the skull from -pi/30 to pi/30
    np.testing.assert_allclose(roll.q[0], [-0.06981317, 0, 0] * 7 + [-0.104719755, 0, 0], atol=1e-12)
    np.testing.assert_allclose(roll.q[50, 0], 0.0, atol=1e-12)
    ds = 30 * 0.25**2  # quintic at tau = 1/2: s = 1/2, ds/dt = 15/8 per second
    np.testing.assert_allclose(roll.qd[50, 0], 2 * 0.06981317 * ds, rtol=1e-10)

    comb = load_trajectory(neck, "combined")
    exact = caspr_trajectory(neck, neck_import.trajectories["combined"], neck_import.q_index)
    assert len(exact) == len(comb) == 901  # 9 segments of 1 s, junction samples kept once
    np.testing.assert_allclose(comb.t, exact.t, atol=1e-12)
    np.testing.assert_allclose(comb.q, exact.q, atol=1e-15)
    np.testing.assert_allclose(exact.qd[100::100], 0.0, atol=1e-12)  # at rest at every waypoint
    # the yaw segment 1 -> 2 s runs gamma from -pi/45 to +pi/45 with the scalar quintic
    np.testing.assert_allclose(exact.q[150, 2], 0.0, atol=1e-12)
    np.testing.assert_allclose(exact.q[200, [2, 23]], [0.06981317, 0.104719755], atol=1e-12)
    # the CSV's rates are re-derived by a spline through q: close, not exact
    assert np.max(np.abs(comb.qd - exact.qd)) < 1e-3 * np.max(np.abs(exact.qd))


# --------------------------------------------------------------------- independent Newton check
def _rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


class CasprNewton:
    """CASPR's kinematics written out from the README (not from mcdm_pin): R_0k = R_0,parent R_pe,
    P_k = P_parent + R_0,parent location, COM-referenced attachments. Parses the XML itself."""

    def __init__(self, bodies_xml, cables_xml):
        root = ET.parse(bodies_xml).getroot()
        self.links = []
        for el in root.iter("link_rigid"):
            ph = el.find("physical")
            self.links.append(dict(
                type=el.find("joint").get("type"), parent=int(el.find("parent/num").text),
                loc=np.array(el.find("parent/location").text.split(), float),
                m=float(ph.find("mass").text), com=np.array(ph.find("com_location").text.split(), float)))
        croot = ET.parse(cables_xml).getroot()
        cset = [s for s in croot.iter("cable_set") if s.get("id") == croot.get("default_cable_set")][0]
        self.cables = [[(int(a.find("link").text), np.array(a.find("location").text.split(), float))
                        for a in c.iter("attachment")] for c in cset.iter("cable_ideal")]

    def rotations(self, q, spherical_R=None):
        """Relative rotations from CASPR coordinates (or given 3x3 for spherical joints)."""
        out, k = [], 0
        for i, link in enumerate(self.links):
            if link["type"] == "S_EULER_XYZ":
                a, b, g = q[k:k + 3]
                out.append(spherical_R[i] if spherical_R and i in spherical_R else _rx(a) @ _ry(b) @ _rz(g))
                k += 3
            elif link["type"] == "R_X":
                out.append(_rx(q[k]))
                k += 1
            else:
                raise NotImplementedError(link["type"])
        return out

    def poses(self, rel):
        R, P = [np.eye(3)], [np.zeros(3)]
        for link, Rpe in zip(self.links, rel):
            p = link["parent"]
            P.append(P[p] + R[p] @ link["loc"])
            R.append(R[p] @ Rpe)
        return R, P

    def joint_forces(self, rel_of_t, t, f, g=np.array([0, 0, -9.81]), h=1e-3):
        """Force of the parent on each link's subtree, in the parent's frame (CASPR's convention)."""
        def coms(tt):
            R, P = self.poses(rel_of_t(tt))
            return np.array([P[k + 1] + R[k + 1] @ L["com"] for k, L in enumerate(self.links)])

        r = [coms(t + d * h) for d in (-2, -1, 0, 1, 2)]
        acc = (-r[0] + 16 * r[1] - 30 * r[2] + 16 * r[3] - r[4]) / (12 * h * h)
        R, P = self.poses(rel_of_t(t))
        n = len(self.links)
        body_force = np.array([L["m"] * (acc[k] - g) for k, L in enumerate(self.links)])  # m a - m g
        cable_on = np.zeros((n + 1, 3))
        for fc, atts in zip(f, self.cables):
            pts = [(b, P[b] + R[b] @ (self.links[b - 1]["com"] + loc) if b else loc) for b, loc in atts]
            for (a, pa), (b, pb) in zip(pts[:-1], pts[1:]):
                u = (pb - pa) / np.linalg.norm(pb - pa)
                cable_on[a] += fc * u
                cable_on[b] -= fc * u
        out = []
        for k in range(n):
            sub = [k]
            for j in range(k + 1, n):
                if self.links[j]["parent"] - 1 in sub:
                    sub.append(j)
            F = sum(body_force[j] - cable_on[j + 1] for j in sub)
            out.append(R[self.links[k]["parent"]].T @ F)
        return np.array(out)


def _quintic_s(t):
    tau = min(max(t, 0.0), 1.0)
    return tau**3 * (10 - 15 * tau + 6 * tau**2)


@needs_caspr
@pytest.mark.parametrize("traj", ["SR_trajectory", "SR_trajectory2"])
def test_sr_interaction_force_matches_newton(sr_import, traj):
    """Our socket-frame interaction force = Newton's law written independently (finite-differenced
    COM accelerations, CASPR's frames), at the cable forces case 1 finds. For SR_trajectory2 the
    shoulder rotation is R0 exp(s(t) phi) (CASPR's one-axis interpolation), built with scipy."""
    from scipy.spatial.transform import Rotation

    from mcdm_pin import InverseDynamics, Robot, load_trajectory

    sr = Robot.load(sr_import.sidecar)
    tr = load_trajectory(sr, traj)
    run = InverseDynamics.for_case(sr, 1).solve_trajectory(tr.subsample(11), progress=False)
    ref = CasprNewton(SR / "SR_model_bodies.xml", SR / "SR_model_cables.xml")
    q0, q1 = tr.q[0], tr.q[-1]
    R0, R1 = _rx(q0[0]) @ _ry(q0[1]) @ _rz(q0[2]), _rx(q1[0]) @ _ry(q1[1]) @ _rz(q1[2])
    phi = Rotation.from_matrix(R0.T @ R1).as_rotvec()

    def rel(t):
        s = _quintic_s(t)
        q = q0 + s * (q1 - q0)
        return ref.rotations(q, {0: R0 @ Rotation.from_rotvec(s * phi).as_matrix()})

    checked = 0
    for k, t in enumerate(run.t):
        if not run.found[k] or not 0.05 < t < 0.95:
            continue
        F = ref.joint_forces(rel, t, run.f[k])
        # finite differences with h = 1e-3 s at 4th order: error ~1e-9 N on forces up to ~600 N
        np.testing.assert_allclose(run.interaction_force_socket[k], F, atol=1e-6 * max(1, np.abs(F).max()))
        checked += 1
    assert checked >= 8


@needs_caspr
def test_neck_interaction_force_matches_newton(neck_import):
    from mcdm_pin import InverseDynamics, Robot, load_trajectory

    neck = Robot.load(neck_import.sidecar)
    tr = load_trajectory(neck, "roll")
    run = InverseDynamics.for_case(neck, 1).solve_trajectory(tr.subsample(5), progress=False)
    ref = CasprNewton(NECK / "8S_neck_bodies.xml", NECK / "8S_neck_cables.xml")

    def rel(t):  # roll: only alpha moves, so the per-coordinate quintic is CASPR's interpolation
        return ref.rotations(tr.q[0] + _quintic_s(t) * (tr.q[-1] - tr.q[0]))

    for k in (1, 2, 3):
        F = ref.joint_forces(rel, run.t[k], run.f[k])
        np.testing.assert_allclose(run.interaction_force_socket[k], F, atol=1e-6 * np.abs(F).max())


@needs_caspr
def test_force_frame_at_rest_is_parent_frame(sr_import):
    """README: at rest, the force at joint 2 is R_01^T (0, 0, m2 g) (parent frame), once the cables
    are slack (f = 0 by hand: u alone). Our socket-frame force reproduces it; the child-frame force
    differs by R_pe(q4)."""
    from mcdm_pin import Robot, compute_terms

    sr = Robot.load(sr_import.sidecar)
    q = np.array([0.3, -0.2, 0.4, 0.7])
    T = compute_terms(sr, q)
    F_socket = T.socket_forces(np.zeros(sr.m))
    R01 = _rx(q[0]) @ _ry(q[1]) @ _rz(q[2])
    np.testing.assert_allclose(F_socket[1], R01.T @ [0, 0, 0.1 * 9.81], atol=1e-12)
    np.testing.assert_allclose(F_socket[0], [0, 0, 0.2 * 9.81], atol=1e-12)
    np.testing.assert_allclose(T.u[1, :3], _rx(q[3]).T @ R01.T @ [0, 0, 0.1 * 9.81], atol=1e-12)


# ------------------------------------------------------------------------- synthetic XML models
BODY = """<link_rigid num="{num}" name="{name}">
  <joint type="{type}" q_initial="{q}" q_min="{qmin}" q_max="{qmax}"{extra}/>
  <physical><mass>{mass}</mass><com_location>{com}</com_location><end_location>0 0 0.2</end_location>
    <inertia ref="{ref}"><Ixx>{ixx}</Ixx><Iyy>{iyy}</Iyy><Izz>{izz}</Izz><Ixy>{ixy}</Ixy><Ixz>0</Ixz><Iyz>0</Iyz></inertia>
  </physical>
  <parent><num>{parent}</num><location>{loc}</location></parent>
</link_rigid>"""

NQ = {"S_FIXED_XYZ": 3, "S_EULER_XYZ": 3, "U_XY": 2, "U_XZ": 2, "U_YZ": 2, "R_X": 1, "R_Y": 1, "R_Z": 1}


def _placements(robot, q):
    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, robot.pin_q(q))
    return [data.oMi[j].homogeneous for j in range(robot.model.njoints)]


def _bodies(path, links):
    parts = []
    for i, L in enumerate(links, start=1):
        n = NQ.get(L["type"], 1)
        d = dict(num=i, name=f"L{i}", q=" ".join(["0"] * n), qmin=" ".join(["-3"] * n),
                 qmax=" ".join(["3"] * n), extra="", mass=1.0, com="0 0 0.1", ref="com", ixx=0.01,
                 iyy=0.02, izz=0.03, ixy=0.0, parent=i - 1, loc="0 0 0.2" if i > 1 else "0 0 0")
        d.update(L)
        parts.append(BODY.format(**d))
    path.write_text('<?xml version="1.0"?>\n<!DOCTYPE bodies_system SYSTEM "nowhere/bodies.dtd">\n'
                    f'<bodies_system><links>{"".join(parts)}</links></bodies_system>')
    return path


def _cables(path, cables, ref="com", default="s1", extra_sets=""):
    out = []
    for i, atts in enumerate(cables, start=1):
        a = "".join(f"<attachment><link>{k}</link><location>{x}</location></attachment>" for k, x in atts)
        out.append(f'<cable_ideal name="c{i}" attachment_reference="{ref}"><properties>'
                   f"<force_min>0.1</force_min><force_max>100</force_max></properties>"
                   f"<attachments>{a}</attachments></cable_ideal>")
    path.write_text(f'<cables default_cable_set="{default}"><cable_set id="s1">{"".join(out)}</cable_set>'
                    f"{extra_sets}</cables>")
    return path


def _ring(link, z, r=0.1, n=8):
    return [(link, f"{r * math.cos(2 * math.pi * k / n)} {r * math.sin(2 * math.pi * k / n)} {z}")
            for k in range(n)]


def _star_cables(n_links, n=8):
    base = _ring(0, 0.0, 0.3, n)
    return [[base[k], _ring(link, 0.0, 0.05, n)[k]] for link in range(1, n_links + 1) for k in range(n)]


def test_s_fixed_xyz_keeps_caspr_rotation_and_maps_q(tmp_path):
    """S_FIXED_XYZ: R = Rz(g) Ry(b) Rx(a). The URDF chain is z, y, x, so our q holds (g, b, a): the
    import reports q_index = [2, 1, 0] and writes trajectories in our order."""
    from mcdm_pin import Robot, load_trajectory

    b = _bodies(tmp_path / "b.xml", [dict(type="S_FIXED_XYZ")])
    c = _cables(tmp_path / "c.xml", _star_cables(1))
    t = tmp_path / "t.xml"
    t.write_text("""<trajectories><joint_trajectories>
      <quintic_spline_trajectory id="move" time_definition="absolute" time_step="0.1"><points>
        <point><q>0.1 0.2 0.3</q><q_dot>0 0 0</q_dot><q_ddot>0 0 0</q_ddot></point>
        <point time="1"><q>-0.2 0.1 0.4</q><q_dot>0 0 0</q_dot><q_ddot>0 0 0</q_ddot></point>
      </points></quintic_spline_trajectory></joint_trajectories></trajectories>""")
    res = _import(tmp_path / "out", b, c, t, name="fixed")
    robot = Robot.load(res.sidecar)
    assert res.q_index.tolist() == [2, 1, 0] and not res.q_is_caspr_order
    a_, b_, g_ = 0.3, -0.5, 0.7
    q = res.q_from_caspr([a_, b_, g_])
    np.testing.assert_allclose(q, [g_, b_, a_])
    R = _placements(robot, q)[robot.joints[0].child_id][:3, :3]
    np.testing.assert_allclose(R, _rz(g_) @ _ry(b_) @ _rx(a_), atol=1e-14)
    traj = load_trajectory(robot, "move")
    np.testing.assert_allclose(res.q_to_caspr(traj.q[0]), [0.1, 0.2, 0.3], atol=1e-14)
    np.testing.assert_allclose(res.q_to_caspr(traj.q[-1]), [-0.2, 0.1, 0.4], atol=1e-12)
    assert "q_index" in robot.sidecar.description


def test_universal_revolute_joint_ref_and_tree(tmp_path):
    """U_XY = two revolute joints (x then y) at one point; R_Y; an inertia given about the joint; a
    tree (links 2 and 3 both on link 1) whose depth-first order differs from CASPR's numbering;
    joint-referenced attachments."""
    from mcdm_pin import Robot

    links = [dict(type="U_XY"),
             dict(type="R_Y", parent=1, loc="0.05 0 0.2", ref="joint", ixx=0.02, iyy=0.03, izz=0.01,
                  ixy=0.001, com="0 0 0.1"),
             dict(type="S_EULER_XYZ", parent=1, loc="-0.05 0 0.2"),
             dict(type="R_Z", parent=2, loc="0 0 0.2")]
    b = _bodies(tmp_path / "b.xml", links)
    c = _cables(tmp_path / "c.xml", _star_cables(4, 6), ref="joint")
    res = _import(tmp_path / "out", b, c, name="tree")
    robot = Robot.load(res.sidecar)
    assert robot.joint_names == ("L1_x", "L1_y", "L2", "L3", "L4")
    assert [j.type for j in robot.joints] == ["revolute", "revolute", "revolute", "spherical", "revolute"]
    # CASPR order: L1(a,b), L2, L3(a,b,g), L4; Pinocchio goes depth-first: L1, L2, L4, L3
    names = list(robot.coordinate_names)
    assert [names[i] for i in res.q_index] == ["L1_x", "L1_y", "L2_y", "L3_x", "L3_y", "L3_z", "L4_z"]
    assert not res.q_is_caspr_order
    # U_XY rotation Rx(a) Ry(b) at link 1; R_Y at link 2
    qc = np.array([0.3, -0.4, 0.5, 0.1, 0.2, 0.3, 0.9])
    oMi = _placements(robot, res.q_from_caspr(qc))
    R1 = oMi[robot.joints[1].child_id][:3, :3]
    np.testing.assert_allclose(R1, _rx(0.3) @ _ry(-0.4), atol=1e-14)
    R2 = oMi[robot.joints[2].child_id][:3, :3]
    np.testing.assert_allclose(R2, R1 @ _ry(0.5), atol=1e-14)
    np.testing.assert_allclose(oMi[robot.joints[2].child_id][:3, 3], R1 @ [0.05, 0, 0.2], atol=1e-14)
    # inertia about the joint -> about the COM: I_G = I_O - m (|r|^2 I - r r^T), r = (0, 0, 0.1)
    inert = robot.model.inertias[robot.joints[2].child_id]
    np.testing.assert_allclose(inert.inertia, [[0.02 - 0.01, 0.001, 0], [0.001, 0.03 - 0.01, 0], [0, 0, 0.01]],
                               atol=1e-15)
    # joint-referenced points are used as written
    np.testing.assert_allclose(robot.cables[0].points[1], [0.05, 0, 0], atol=1e-15)


def test_multipoint_trajectory_with_end_rates(tmp_path):
    """A 3-point quintic with non-zero rates at the middle point on a revolute joint: each segment's
    quintic meets the given q, q_dot and q_ddot."""
    from mcdm_pin.caspr import caspr_trajectory, read_bodies, read_trajectories
    from mcdm_pin import Robot

    b = _bodies(tmp_path / "b.xml", [dict(type="R_X"), dict(type="R_Y", parent=1)])
    c = _cables(tmp_path / "c.xml", _star_cables(2, 6))
    t = tmp_path / "t.xml"
    t.write_text("""<trajectories><joint_trajectories>
      <quintic_spline_trajectory id="wave" time_definition="relative" time_step="0.05"><points>
        <point><q>0 0</q><q_dot>0 0</q_dot><q_ddot>0 0</q_ddot></point>
        <point time="0.5"><q>0.3 -0.1</q><q_dot>0.4 0</q_dot><q_ddot>-1 0</q_ddot></point>
        <point time="1.0"><q>0 0.2</q><q_dot>0 0</q_dot><q_ddot>0 0</q_ddot></point>
      </points></quintic_spline_trajectory></joint_trajectories></trajectories>""")
    res = _import(tmp_path / "out", b, c, t, name="wave")
    robot = Robot.load(res.sidecar)
    assert robot.sidecar.trajectories["wave"].type == "csv"
    tr = caspr_trajectory(robot, read_trajectories(t, read_bodies(b))["wave"], res.q_index)
    assert len(tr) == 31 and tr.t[-1] == pytest.approx(1.5)
    k = 10  # t = 0.5 s, the junction
    np.testing.assert_allclose([tr.q[k, 0], tr.qd[k, 0], tr.qdd[k, 0]], [0.3, 0.4, -1.0], atol=1e-12)
    np.testing.assert_allclose(tr.q[-1], [0, 0.2], atol=1e-12)


# ------------------------------------------------------------------------------------- errors
@pytest.mark.parametrize("links, cables_kw, needle", [
    ([dict(type="SPATIAL_EULER_XYZ", q="0 0 0 0 0 0", qmin="-1 -1 -1 -1 -1 -1", qmax="1 1 1 1 1 1")], {},
     "link_rigid[num='1', name='L1']/joint@type: joint type 'SPATIAL_EULER_XYZ' is not supported"),
    ([dict(type="R_X", extra=' actuated="true"')], {}, "joint@actuated: actuated"),
    ([dict(type="R_X", q="0 0")], {}, "joint@q_initial: expected 1 number, got 2"),
    ([dict(type="R_X", ref="CoM")], {}, "inertia@ref: expected 'com' or 'joint', got 'CoM'"),
    ([dict(type="R_X", parent=1)], {}, "parent/num: expected a parent number in 0..0"),
])
def test_bodies_errors(tmp_path, links, cables_kw, needle):
    from mcdm_pin.exceptions import CasprError, McdmError

    b = _bodies(tmp_path / "b.xml", links)
    c = _cables(tmp_path / "c.xml", _star_cables(1))
    with pytest.raises(CasprError) as exc:
        _import(tmp_path / "out", b, c)
    assert needle in str(exc.value) and str(b) in str(exc.value)
    assert isinstance(exc.value, McdmError)


def test_cable_and_trajectory_errors(tmp_path):
    from mcdm_pin.exceptions import CasprError

    b = _bodies(tmp_path / "b.xml", [dict(type="R_X")])
    c = _cables(tmp_path / "c.xml", _star_cables(1))
    with pytest.raises(CasprError, match=r"no cable set 'nope'; expected one of s1"):
        _import(tmp_path / "o", b, c, cable_set="nope")
    text = c.read_text()
    c.write_text(text.replace("<attachment><link>0</link>",
                              "<base_rotating_pulley><link>0</link>", 1).replace(
        "</attachment><attachment><link>1", "</base_rotating_pulley><attachment><link>1", 1))
    with pytest.raises(CasprError, match=r"cable_ideal\[1, name='c1'\]/attachments/base_rotating_pulley\[1\]: "
                                         r"<base_rotating_pulley> is not supported \(pulleys"):
        _import(tmp_path / "o", b, c)
    c.write_text(text.replace("cable_ideal", "cable_linear_spring", 2))
    with pytest.raises(CasprError, match=r"unsupported cable type <cable_linear_spring>"):
        _import(tmp_path / "o", b, c)
    c.write_text(text)
    t = tmp_path / "t.xml"
    t.write_text('<trajectories><joint_trajectories><cubic_spline_trajectory id="a" '
                 'time_definition="absolute" time_step="0.1"/></joint_trajectories></trajectories>')
    with pytest.raises(CasprError, match=r"cubic_spline_trajectory\[id='a'\]: unsupported trajectory type"):
        _import(tmp_path / "o", b, c, t)
    t.write_text("<trajectories><joint_trajectories>"
                 '<quintic_spline_trajectory id="a" time_definition="absolute" time_step="0.3"><points>'
                 "<point><q>0</q><q_dot>0</q_dot><q_ddot>0</q_ddot></point>"
                 '<point time="1"><q>1</q><q_dot>0</q_dot><q_ddot>0</q_ddot></point>'
                 "</points></quintic_spline_trajectory></joint_trajectories></trajectories>")
    with pytest.raises(CasprError, match=r"point\[2\]@time: the segment lasts 1 s, not a multiple of time_step"):
        _import(tmp_path / "o", b, c, t)
    (tmp_path / "bad.xml").write_text("<bodies_system><links>")
    with pytest.raises(CasprError, match=r"bad.xml: malformed XML"):
        _import(tmp_path / "o", tmp_path / "bad.xml", c)


@needs_caspr
def test_cli_import_caspr(tmp_path, capsys):
    from mcdm_pin.cli import main

    rc = main(["import-caspr", str(SR / "SR_model_bodies.xml"), str(SR / "SR_model_cables.xml"),
               "--trajectories", str(SR / "SR_model_trajectories.xml"), "--out", str(tmp_path), "--name", "sr",
               "--cone-deg", "30"])
    out = capsys.readouterr().out
    assert rc == 0 and "cable set 'SR_8_cables_2'" in out and "q lines up with CASPR's q" in out
    assert (tmp_path / "sr.urdf").is_file() and (tmp_path / "sr.yaml").is_file()
    rc = main(["import-caspr", str(SR / "SR_model_bodies.xml"), str(SR / "SR_model_cables.xml"),
               "--out", str(tmp_path), "--cable-set", "SR_9_cables"])
    err = capsys.readouterr().err
    assert rc == 2 and "no cable set 'SR_9_cables'; expected one of SR_8_cables_2, SR_8_cables, SR_6_cables" in err
