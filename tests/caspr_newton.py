r"""CASPR's model semantics written out a second time, sharing no code with mcdm_pin: the reference
the imported robots are checked against (``tests/test_caspr_library.py``, ``tools/caspr_library.py``).

It reads CASPR's XML itself, applies CASPR's kinematics (``src/Model/Bodies/Joints`` at ``a6971ee``:
:math:`R_{0k} = R_{0p} R_{pe}(q)`, :math:`P_k = P_p + R_{0p}(\text{location} + r_{rel}(q))`), samples
CASPR's trajectories (``JointTrajectory``, ``Spline``, ``Quaternion``) and computes the equation of
motion by Newton's and Euler's laws for each body, in world coordinates:

.. math:: M(q)\ddot q + h(q, \dot q) = -L^T f + A\tau, \qquad
   M = \sum_k J_{G,k}^T m_k J_{G,k} + J_{\omega,k}^T I_k J_{\omega,k},

:math:`h` the same sum applied to the bias accelerations and gravity (:math:`g = 9.81` m/s^2 along -z),
:math:`L = \partial \dot l / \partial \dot q` from the attachment points' velocities (a rotating pulley's
exit point, computed by CASPR's formulas, counts as a base point: CASPR's ``V``). The interaction
wrench of joint k is the force and moment that link k's subtree needs from its parent (Newton and
Euler for the subtree, the cables pulling): force in the parent's frame, moment about the joint point
in the child's frame, CASPR's convention (``SystemModel.interactionWrench``).

Passive springs (``cable_passive_linear_spring``, ``CableModelPassiveLinearSpring``) pull with the
known tension :math:`K (l - l_0)` (not clipped): they are kept apart from the cables (``springs``), and
their generalised force :math:`L_s^T f_s` joins the right-hand side as CASPR's
``IDSolverBase.GetEoMConstraints`` adds it (``b = M q_ddot + C + G + L_passive' f_passive``); they pull on
the bodies in every interaction wrench (``IDObjectiveMinInteractions``: ``a + H_passive' f_passive``).
Every other cable element (ideal, linear-spring and variable-stiffness cables) is a cable: its tension is
the unknown. :meth:`Model.residual` is Newton-Euler's residual of an answer ``(f, tau)``.

Coordinates are CASPR's (``q``, ``q_dot``, ``q_ddot`` of every joint in link order).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

G = 9.81
EX, EY, EZ = np.eye(3)

# type -> (translation [(axis, coordinate)], rotation factors [(axis, coordinate)], number of coordinates)
JOINTS = {
    "R_X": ([], [(EX, 0)], 1), "R_Y": ([], [(EY, 0)], 1), "R_Z": ([], [(EZ, 0)], 1),
    "R_AXIS": ([], [(None, 0)], 1), "P_X": ([(EX, 0)], [], 1), "P_AXIS": ([(None, 0)], [], 1),
    "P_XY": ([(EX, 0), (EY, 1)], [], 2), "P_XZ": ([(EX, 0), (EZ, 1)], [], 2),
    "T_XYZ": ([(EX, 0), (EY, 1), (EZ, 2)], [], 3),
    "PLANAR_XY": ([(EX, 0), (EY, 1)], [(EZ, 2)], 3), "PLANAR_XZ": ([(EX, 0), (EZ, 1)], [(EY, 2)], 3),
    "PLANAR_YZ": ([(EY, 0), (EZ, 1)], [(EX, 2)], 3),
    "U_XY": ([], [(EX, 0), (EY, 1)], 2), "U_XZ": ([], [(EX, 0), (EZ, 1)], 2), "U_YZ": ([], [(EY, 0), (EZ, 1)], 2),
    "S_EULER_XYZ": ([], [(EX, 0), (EY, 1), (EZ, 2)], 3), "S_FIXED_XYZ": ([], [(EZ, 2), (EY, 1), (EX, 0)], 3),
    "SPATIAL_EULER_XYZ": ([(EX, 0), (EY, 1), (EZ, 2)], [(EX, 3), (EY, 4), (EZ, 5)], 6),
}
# the joints CASPR interpolates on SO(3): (first angle, order of the factors) (S_FIXED: R = Rz Ry Rx)
SPHERICAL = {"S_EULER_XYZ": (0, "xyz"), "S_FIXED_XYZ": (0, "zyx"), "SPATIAL_EULER_XYZ": (3, "xyz")}


def rot(axis, angle) -> np.ndarray:
    """Rodrigues' formula."""
    k = np.asarray(axis, dtype=float)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def _vec(text) -> np.ndarray:
    return np.array([float(x) for x in text.split()])


@dataclass
class Link:
    type: str
    parent: int
    loc: np.ndarray
    mass: float
    com: np.ndarray
    inertia: np.ndarray  # about the COM, link axes
    axis: np.ndarray | None
    actuated: bool
    q_initial: np.ndarray

    @property
    def n(self) -> int:
        return JOINTS[self.type][2]


@dataclass
class Model:
    links: list
    cables: list  # per cable: [(link, point from the joint point in the link frame, or base point)]
    offsets: list = field(default_factory=list)
    pulleys: list = field(default_factory=list)  # per cable: None or its first attachment, a pulley (dict)
    springs: list = field(default_factory=list)  # per passive spring: (route as a cable's, K, l0)

    def __post_init__(self):
        k = 0
        for link in self.links:
            self.offsets.append(k)
            k += link.n
        self.n = k

    @classmethod
    def from_xml(cls, bodies_xml, cables_xml, cable_set=None) -> "Model":
        links = []
        for el in ET.parse(bodies_xml).getroot().iter("link_rigid"):
            j, ph = el.find("joint"), el.find("physical")
            m, com = float(ph.find("mass").text), _vec(ph.find("com_location").text)
            it = ph.find("inertia")
            v = {k: float(it.find(k).text) for k in ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")}
            I = np.array([[v["Ixx"], v["Ixy"], v["Ixz"]], [v["Ixy"], v["Iyy"], v["Iyz"]], [v["Ixz"], v["Iyz"], v["Izz"]]])
            if it.get("ref") == "joint":  # parallel axis theorem, back to the COM
                I = I - m * (com @ com * np.eye(3) - np.outer(com, com))
            axis = _vec(j.get("axis")) if j.get("axis") else None
            links.append(Link(type=j.get("type"), parent=int(el.find("parent/num").text),
                              loc=_vec(el.find("parent/location").text), mass=m, com=com, inertia=I,
                              axis=None if axis is None else axis / np.linalg.norm(axis),
                              actuated=j.get("actuated") == "true", q_initial=_vec(j.get("q_initial"))))
        root = ET.parse(cables_xml).getroot()
        wanted = cable_set or root.get("default_cable_set")
        cset = next(s for s in root.iter("cable_set") if s.get("id") == wanted)
        cables, pulleys, springs = [], [], []
        for c in cset:
            pts = []
            pulley = _pulley(c)
            for a in c.iter("attachment"):
                k, loc = int(a.find("link").text), _vec(a.find("location").text)
                if k and c.get("attachment_reference") == "com":
                    loc = loc + links[k - 1].com
                pts.append((k, loc))
            if c.tag == "cable_passive_linear_spring":
                props = c.find("properties")
                springs.append((pts, float(props.find("K").text), float(props.find("l0").text)))
            else:
                cables.append(pts)
                pulleys.append(pulley)
        return cls(links, cables, pulleys=pulleys, springs=springs)

    # --------------------------------------------------------------------------------- kinematics
    def joint(self, k, q, qd, qdd):
        """Relative motion of joint k: R_pe, translation d (parent frame, from the parent's joint point)
        with its first and second derivatives, angular velocity and acceleration (child frame)."""
        link = self.links[k]
        trans, rots, n = JOINTS[link.type]
        s = self.offsets[k]
        x, xd, xdd = q[s:s + n], qd[s:s + n], qdd[s:s + n]
        d, dd, ddd = link.loc.copy(), np.zeros(3), np.zeros(3)
        for axis, c in trans:
            a = link.axis if axis is None else axis
            d, dd, ddd = d + a * x[c], dd + a * xd[c], ddd + a * xdd[c]
        R, w, wd = np.eye(3), np.zeros(3), np.zeros(3)
        for axis, c in rots:  # a serial chain of rotations about the moving axes
            a = link.axis if axis is None else axis
            Ri = rot(a, x[c])
            w_in = Ri.T @ w
            w = w_in + a * xd[c]
            wd = Ri.T @ wd + np.cross(w_in, a) * xd[c] + a * xdd[c]
            R = R @ Ri
        return R, d, dd, ddd, w, wd

    def kinematics(self, q, qd, qdd):
        """Per link (world frame): R_0k, joint point P, angular velocity and acceleration, and the
        joint point's velocity and acceleration. Index 0 is the base."""
        p = len(self.links)
        R, P = [np.eye(3)] + [None] * p, [np.zeros(3)] + [None] * p
        w, wd, v, a = ([np.zeros(3)] + [None] * p for _ in range(4))
        for k, link in enumerate(self.links, start=1):
            j = link.parent
            Rpe, d, dd, ddd, wr, wrd = self.joint(k - 1, q, qd, qdd)
            r = R[j] @ d
            R[k] = R[j] @ Rpe
            P[k] = P[j] + r
            w[k] = w[j] + R[k] @ wr
            wd[k] = wd[j] + np.cross(w[j], R[k] @ wr) + R[k] @ wrd
            v[k] = v[j] + np.cross(w[j], r) + R[j] @ dd
            a[k] = (a[j] + np.cross(wd[j], r) + np.cross(w[j], np.cross(w[j], r))
                    + 2 * np.cross(w[j], R[j] @ dd) + R[j] @ ddd)
        return R, P, w, wd, v, a

    def point_motion(self, kin, k, point):
        """World position, velocity, acceleration of a point fixed in link k (link frame, from P_k)."""
        R, P, w, wd, v, a = kin
        r = R[k] @ point
        return P[k] + r, v[k] + np.cross(w[k], r), a[k] + np.cross(wd[k], r) + np.cross(w[k], np.cross(w[k], r))

    # ---------------------------------------------------------------------------------- dynamics
    def body_forces(self, kin):
        """Per link: the force and the moment about the COM needed for its motion (m a_G - m g,
        I w_dot + w x I w), world frame."""
        R, P, w, wd, v, a = kin
        out = []
        for k, link in enumerate(self.links, start=1):
            _, _, aG = self.point_motion(kin, k, link.com)
            I = R[k] @ link.inertia @ R[k].T
            out.append((link.mass * (aG - np.array([0, 0, -G])), I @ wd[k] + np.cross(w[k], I @ w[k])))
        return out

    def generalized(self, q, qd, qdd):
        """Generalized force needed, sum over bodies of J^T (force, moment): M qdd + h."""
        kin = self.kinematics(q, qd, qdd)
        forces = self.body_forces(kin)
        tau = np.zeros(self.n)
        for i in range(self.n):
            e = np.zeros(self.n)
            e[i] = 1.0
            kin_i = self.kinematics(q, e, np.zeros(self.n))
            for k, link in enumerate(self.links, start=1):
                _, vG, _ = self.point_motion(kin_i, k, link.com)
                tau[i] += vG @ forces[k - 1][0] + kin_i[2][k] @ forces[k - 1][1]
        return tau

    def terms(self, q, qd, qdd):
        """``(M, h)`` with ``M qdd + h`` the generalized force the motion needs (CASPR's M and C + G)."""
        z = np.zeros(self.n)
        h = self.generalized(q, qd, z)
        M = np.column_stack([self.generalized(q, z, np.eye(self.n)[i]) - self.generalized(q, z, z)
                             for i in range(self.n)])
        return M, h

    def _routes(self, routes):
        """``(routes, pulleys)``: the cables with their pulleys (``routes`` None, or starting with the
        cables themselves), other routes (springs) without."""
        routes = self.cables if routes is None else list(routes)
        n = len(self.cables)
        pulleys = [None] * len(routes)
        if len(routes) >= n and all(a is b for a, b in zip(routes, self.cables)):
            pulleys[:n] = self.pulleys or [None] * n
        return routes, pulleys

    def cable_points(self, kin, routes=None):
        """World position of every attachment point, per cable (or per route of ``routes``); a cable
        that starts at a pulley starts at its exit point (on the base, CASPR's ``r_OA`` of the pulley
        attachment)."""
        out = []
        for c, pulley in zip(*self._routes(routes)):
            pts = [(k, self.point_motion(kin, k, pt)[0] if k else pt) for k, pt in c]
            if pulley is not None:
                pts.insert(0, (0, self.pulley_exit(pulley, pts[0][1])[0]))
            out.append(pts)
        return out

    def pulley_exit(self, p, r_B):
        """``(exit point, arc length)`` of CASPR's pulley attachment ``p`` facing ``r_B`` (world)."""
        if p["tag"] == "base_rotating_pulley":
            return base_pulley_exit(p["fixed_location"], p["cable_entry_vector"], r_B, p["pulley_radius"])
        if "l0_offset" not in p:  # CASPR's first update, at q_initial
            q0 = np.concatenate([link.q_initial for link in self.links])
            kin0 = self.kinematics(q0, np.zeros(self.n), np.zeros(self.n))
            c = self.cables[self.pulleys.index(p)]
            B0 = self.point_motion(kin0, c[0][0], c[0][1])[0] if c[0][0] else c[0][1]
            p["l0_offset"] = float(np.linalg.norm(B0 - p["constant_winch_point"]))
        return screw_pulley_exit(p, r_B)

    def lengths(self, q, routes=None):
        kin = self.kinematics(q, np.zeros(self.n), np.zeros(self.n))
        out = []
        for c, pulley in zip(self.cable_points(kin, routes), self._routes(routes)[1]):
            arc = 0.0 if pulley is None else self.pulley_exit(pulley, c[1][1])[1]
            out.append(arc + sum(np.linalg.norm(b - a) for (_, a), (_, b) in zip(c[:-1], c[1:])))
        return np.array(out)

    def spring_forces(self, q):
        """(s,) the passive springs' tensions ``K (l - l0)`` (N), CASPR's, not clipped."""
        if not self.springs:
            return np.zeros(0)
        lengths = self.lengths(q, [r for r, _, _ in self.springs])
        return np.array([K * (ln - l0) for (_, K, l0), ln in zip(self.springs, lengths)])

    def spring_generalized(self, q):
        """(n,) ``L_s^T f_s``: the springs' share of the right-hand side (CASPR's ``L_passive' f_passive``)."""
        if not self.springs:
            return np.zeros(self.n)
        return self.cable_jacobian(q, [r for r, _, _ in self.springs]).T @ self.spring_forces(q)

    def cable_jacobian(self, q, routes=None):
        """L = d(lengths)/dq: each segment's unit vector times its ends' relative velocity."""
        routes = self.cables if routes is None else routes
        zero = np.zeros(self.n)
        pts = self.cable_points(self.kinematics(q, zero, zero), routes)
        L = np.zeros((len(routes), self.n))
        for i in range(self.n):
            e = np.zeros(self.n)
            e[i] = 1.0
            kin_i = self.kinematics(q, e, zero)
            for c, (route, world) in enumerate(zip(routes, pts)):
                vel = [self.point_motion(kin_i, k, pt)[1] if k else np.zeros(3) for k, pt in route]
                vel = [np.zeros(3)] * (len(world) - len(route)) + vel  # a pulley's exit point: on the base
                for s in range(len(world) - 1):
                    u = world[s + 1][1] - world[s][1]
                    L[c, i] += u @ (vel[s + 1] - vel[s]) / np.linalg.norm(u)
        return L

    def twists(self, q, qd):
        """Per link, in its own frame: velocity of the joint point and angular velocity (6p,)."""
        R, P, w, wd, v, a = self.kinematics(q, qd, np.zeros(self.n))
        return np.concatenate([np.concatenate([R[k].T @ v[k], R[k].T @ w[k]]) for k in range(1, len(R))])

    def twist_jacobian(self, q):
        return np.column_stack([self.twists(q, np.eye(self.n)[i]) for i in range(self.n)])

    def actuation(self):
        """CASPR's A: one column per actuated coordinate (link order)."""
        cols = [self.offsets[k] + i for k, link in enumerate(self.links) if link.actuated for i in range(link.n)]
        A = np.zeros((self.n, len(cols)))
        A[cols, np.arange(len(cols))] = 1.0
        return A

    def interaction(self, q, qd, qdd, f):
        """Per joint (6p,): the force of the parent on link k's subtree (parent frame) and the moment
        about the joint point (child frame), with cable forces ``f``."""
        kin = self.kinematics(q, qd, qdd)
        R, P = kin[0], kin[1]
        forces = self.body_forces(kin)
        on = [[] for _ in range(len(self.links) + 1)]  # (point, force) the cables apply on each body
        routes = self.cables + [r for r, _, _ in self.springs]  # the springs at their known tensions
        tensions = np.concatenate([np.asarray(f, dtype=float), self.spring_forces(q)])
        for fc, world in zip(tensions, self.cable_points(kin, routes)):
            for (ka, pa), (kb, pb) in zip(world[:-1], world[1:]):
                u = (pb - pa) / np.linalg.norm(pb - pa)
                on[ka].append((pa, fc * u))
                on[kb].append((pb, -fc * u))
        out = []
        for k, link in enumerate(self.links, start=1):
            sub = self.subtree(k)
            F, M = np.zeros(3), np.zeros(3)
            for j in sub:
                xG = self.point_motion(kin, j, self.links[j - 1].com)[0]
                Fj, Mj = forces[j - 1]
                F += Fj
                M += Mj + np.cross(xG - P[k], Fj)
                for pt, fv in on[j]:
                    F -= fv
                    M -= np.cross(pt - P[k], fv)
            out.append(np.concatenate([R[link.parent].T @ F, R[k].T @ M]))
        return np.concatenate(out)

    def residual(self, q, qd, qdd, f, tau):
        """Newton-Euler's residual of an answer: ``M qdd + h + L^T f + L_s^T f_s - A tau`` (n,), with
        cable tensions ``f`` (N) and actuator forces ``tau`` (CASPR's order), and its scale (the
        largest of ``|M qdd + h|``, ``|L^T f|`` entry by entry, ``|L_s^T f_s|`` and ``|A tau|``)."""
        need = self.generalized(q, qd, qdd)
        cab = self.cable_jacobian(q).T @ np.asarray(f, dtype=float)
        spr = self.spring_generalized(q)
        act = self.actuation() @ np.asarray(tau, dtype=float).reshape(-1)
        scale = max(np.abs(need).max(initial=0.0), (np.abs(self.cable_jacobian(q).T) @ np.abs(f)).max(initial=0.0),
                    np.abs(spr).max(initial=0.0), np.abs(act).max(initial=0.0), 1e-300)
        return need + cab + spr - act, scale

    def subtree(self, k):
        sub = [k]
        for j in range(k + 1, len(self.links) + 1):
            if self.links[j - 1].parent in sub:
                sub.append(j)
        return sub

    def interaction_map(self, q, qd, qdd):
        """``(a, RT)``: interaction = a + RT f (the map is affine in f)."""
        m = len(self.cables)
        a = self.interaction(q, qd, qdd, np.zeros(m))
        RT = np.column_stack([self.interaction(q, qd, qdd, np.eye(m)[i]) - a for i in range(m)])
        return a, RT


# ------------------------------------------------------------------------------------------ pulleys
# CASPR's BaseRotatingPulleyAttachment and ScrewDriveRotatingPulleyAttachment (src/Model/Cables/
# CableAttachments at a6971ee), written out as CASPR computes them: the exit point r_A from the pulley
# centre and the tangent formula, the arc R acos(.) (its length_offset, added to the cable's length),
# and for the screw the paid-out length from MATLAB's roots() with CASPR's root selection and its
# plane-intersection construction of the exit point.
PULLEY_TAGS = ("base_rotating_pulley", "screw_base_rotating_pulley")
SCREW_OUTLET = 28032e-6 + 0.038819  # obtainInitialOutletPose


def _pulley(cable_el):
    atts = cable_el.find("attachments")
    first = atts[0] if atts is not None and len(atts) else None
    if first is None or first.tag not in PULLEY_TAGS:
        return None
    p = {"tag": first.tag}
    for el in first:
        p[el.tag] = float(el.text) if len(el.text.split()) == 1 else _vec(el.text)
    return p


def base_pulley_exit(r_F, v_F, r_B, R):
    """BaseRotatingPulleyAttachment.ComputePulleyLeavingLocation: ``(r_A, l_arc)``."""
    n_plane = np.cross(v_F, r_B - r_F)
    n_unit = n_plane / np.linalg.norm(n_plane)
    v_FC = np.cross(n_plane, v_F)
    r_C = r_F + R * v_FC / np.linalg.norm(v_FC)
    rho = R / np.linalg.norm(r_B - r_C)
    r_A = r_C + rho ** 2 * (r_B - r_C) - rho * math.sqrt(1 - rho ** 2) * np.cross(n_unit, r_B - r_C)
    n1 = (r_F - r_C) / np.linalg.norm(r_F - r_C)
    n2 = (r_A - r_C) / np.linalg.norm(r_A - r_C)
    return r_A, R * math.acos(np.clip(n1 @ n2, -1.0, 1.0))


def _plane_intersection(N1, A1, N2, A2):
    """PlaneOperations.PlaneIntersection: a point of the line and its direction."""
    N = np.cross(N1, N2)
    d1, d2 = -N1 @ A1, -N2 @ A2
    P = np.zeros(3)
    m = int(np.flatnonzero(np.abs(N) == np.abs(N).max())[0])
    if m == 0:
        P[1], P[2] = (d2 * N1[2] - d1 * N2[2]) / N[0], (d1 * N2[1] - d2 * N1[1]) / N[0]
    elif m == 1:
        P[0], P[2] = (d1 * N2[2] - d2 * N1[2]) / N[1], (d2 * N1[0] - d1 * N2[0]) / N[1]
    else:
        P[0], P[1] = (d2 * N1[1] - d1 * N2[1]) / N[2], (d1 * N2[0] - d2 * N1[0]) / N[2]
    return P, N


def _line_circle(P, V, R):
    a, b, c = V @ V, 2 * P @ V, P @ P - R ** 2
    return P + (-b - math.sqrt(b * b - 4 * a * c)) / (2 * a) * V


def screw_pulley_exit(p, r_B):
    """ScrewDriveRotatingPulleyAttachment.update after its first call: ComputeVaryingPulleyPoint, then
    its own ComputePulleyLeavingLocation. ``(r_D, l_arc)``."""
    h, D = p["winch_groove_width"], 2 * p["winch_radius"]
    r_A0, v, l0 = p["constant_winch_point"], p["winch_vector"], p["l0_offset"]
    c = r_B - r_A0
    k = h / math.pi / D
    roots = np.roots([1 - k ** 2 * (v @ v), 2 * l0 + 2 * k * (c @ v), l0 ** 2 - c @ c])
    delta = float(np.real(roots[np.argmin(-np.real(roots))]))  # deltaSelection: min(approx - l0 - delta)
    r_A = r_A0 + (SCREW_OUTLET + delta * k) * v
    v_A, R = p["cable_pulley_entry_vector"], p["pulley_radius"]
    n_plane = np.cross(v_A, r_B - r_A)
    P, V = _plane_intersection(v_A, np.zeros(3), n_plane, np.zeros(3))
    r_C = r_A + _line_circle(P, V, R)
    n_d = r_C - r_B
    P, V = _plane_intersection(n_d, np.array([0.0, 0.0, -R ** 2 / n_d[2]]), n_plane, np.zeros(3))
    r_D = r_C + _line_circle(P, V, R)
    n1 = (r_B - r_D) / np.linalg.norm(r_B - r_D)
    return r_D, R * math.acos(np.clip(n1 @ (v_A / np.linalg.norm(v_A)), -1.0, 1.0))


# ------------------------------------------------------------------------------------- trajectories
def colon(a, d, b):
    """MATLAB's a:d:b (d > 0)."""
    n = math.floor((b - a) / d + 1e-10)
    return np.array([a + i * d for i in range(n + 1)])


def _hermite(kind, T, x0, v0, a0, x1, v1, a1, tau):
    """Value, rate, acceleration at tau in [0, T] of CASPR's polynomial spline, from Hermite bases."""
    s = tau / T
    if kind == "linear":
        return x0 + (x1 - x0) * s, (x1 - x0) / T + 0 * s, 0 * s
    if kind == "cubic":
        h = [(1 - 3 * s**2 + 2 * s**3, -6 * s + 6 * s**2, -6 + 12 * s),
             (s - 2 * s**2 + s**3, 1 - 4 * s + 3 * s**2, -4 + 6 * s),
             (3 * s**2 - 2 * s**3, 6 * s - 6 * s**2, 6 - 12 * s),
             (-s**2 + s**3, -2 * s + 3 * s**2, -2 + 6 * s)]
        c = [x0, v0 * T, x1, v1 * T]
    else:
        h = [(1 - 10 * s**3 + 15 * s**4 - 6 * s**5, -30 * s**2 + 60 * s**3 - 30 * s**4, -60 * s + 180 * s**2 - 120 * s**3),
             (s - 6 * s**3 + 8 * s**4 - 3 * s**5, 1 - 18 * s**2 + 32 * s**3 - 15 * s**4, -36 * s + 96 * s**2 - 60 * s**3),
             (s**2 / 2 - 1.5 * s**3 + 1.5 * s**4 - s**5 / 2, s - 4.5 * s**2 + 6 * s**3 - 2.5 * s**4,
              1 - 9 * s + 18 * s**2 - 10 * s**3),
             (10 * s**3 - 15 * s**4 + 6 * s**5, 30 * s**2 - 60 * s**3 + 30 * s**4, 60 * s - 180 * s**2 + 120 * s**3),
             (-4 * s**3 + 7 * s**4 - 3 * s**5, -12 * s**2 + 28 * s**3 - 15 * s**4, -24 * s + 84 * s**2 - 60 * s**3),
             (s**3 / 2 - s**4 + s**5 / 2, 1.5 * s**2 - 4 * s**3 + 2.5 * s**4, 3 * s - 12 * s**2 + 10 * s**3)]
        c = [x0, v0 * T, a0 * T**2, x1, v1 * T, a1 * T**2]
    x = sum(ci * hi[0] for ci, hi in zip(c, h))
    xd = sum(ci * hi[1] for ci, hi in zip(c, h)) / T
    xdd = sum(ci * hi[2] for ci, hi in zip(c, h)) / T**2
    return x, xd, xdd


def _blend(t, ts, te, x0, x1, tb):
    """Spline.ParabolicBlend, written from its description: accelerate for tb, cruise, decelerate."""
    T = te - ts
    acc = (x1 - x0) / (tb * (T - tb))  # reaches the cruise speed acc*tb after tb
    if t < ts + tb:
        return x0 + acc * (t - ts) ** 2 / 2, acc * (t - ts), acc
    if t < te - tb:
        return x0 + acc * tb**2 / 2 + acc * tb * (t - ts - tb), acc * tb, 0.0
    return x1 - acc * (te - t) ** 2 / 2, acc * (te - t), -acc


@dataclass
class Trajectory:
    kind: str
    dt: float
    times: list
    q: list
    qd: list
    qdd: list
    blend: list


def read_trajectory(path, traj_id, n) -> Trajectory:
    root = ET.parse(path).getroot()
    el = next(e for e in root.find("joint_trajectories") if e.get("id") == traj_id)
    kind = {"quintic_spline_trajectory": "quintic", "cubic_spline_trajectory": "cubic",
            "linear_spline_trajectory": "linear", "cubic_spline_average_velocity_trajectory": "average",
            "parabolic_blend_trajectory": "blend"}[el.tag]
    times, q, qd, qdd, blend = [], [], [], [], []
    for i, pt in enumerate(el.find("points")):
        t = 0.0 if i == 0 else float(pt.get("time"))
        times.append(t if i == 0 or el.get("time_definition") == "absolute" else times[-1] + t)
        q.append(_vec(pt.find("q").text))
        qd.append(_vec(pt.find("q_dot").text) if pt.find("q_dot") is not None else np.zeros(n))
        qdd.append(_vec(pt.find("q_ddot").text) if pt.find("q_ddot") is not None else np.zeros(n))
        if i and kind == "blend":
            blend.append(float(pt.get("blend_time", el.get("blend_time_default"))))
    if kind in ("linear", "blend"):
        qd = [np.zeros(n) for _ in q]
    if kind == "average":
        for i in range(1, len(q) - 1):
            qd[i] = ((q[i] - q[i - 1]) / (times[i] - times[i - 1]) + (q[i + 1] - q[i]) / (times[i + 1] - times[i])) / 2
        kind = "cubic"
    if kind != "quintic":
        qdd = [np.zeros(n) for _ in q]
    return Trajectory(kind, float(el.get("time_step")), times, q, qd, qdd, blend)


def _euler(order, R):
    """Angles (a, b, g) of R = Rx(a) Ry(b) Rz(g) (``xyz``) or Rz(g) Ry(b) Rx(a) (``zyx``)."""
    if order == "xyz":
        return np.array([math.atan2(-R[1, 2], R[2, 2]), math.asin(R[0, 2]), math.atan2(-R[0, 1], R[0, 0])])
    return np.array([math.atan2(R[2, 1], R[2, 2]), -math.asin(R[2, 0]), math.atan2(R[1, 0], R[0, 0])])


def _rotation_factors(order):
    return [(EX, 0), (EY, 1), (EZ, 2)] if order == "xyz" else [(EZ, 2), (EY, 1), (EX, 0)]


def _euler_R(order, ang):
    R = np.eye(3)
    for axis, c in _rotation_factors(order):
        R = R @ rot(axis, ang[c])
    return R


def _omega_map(order, ang):
    """Child-frame angular velocity per angle rate (columns)."""
    def w_of(xd):
        w = np.zeros(3)
        for axis, c in _rotation_factors(order):
            w = rot(axis, ang[c]).T @ w + axis * xd[c]
        return w
    return np.column_stack([w_of(np.eye(3)[i]) for i in range(3)])


def sample(model: Model, traj: Trajectory):
    """CASPR's samples ``(t, q, q_dot, q_ddot)``: MATLAB grids per segment (first sample dropped after the
    first segment), splines from the segment's first to last sample, spherical joints turned about one
    axis, R_s exp(theta k), their Euler angles and exact rates."""
    ts, Q, QD, QDD = [], [], [], []
    for p in range(len(traj.times) - 1):
        grid = colon(traj.times[p], traj.dt, traj.times[p + 1])
        T = grid[-1] - grid[0]
        for i, t in enumerate(grid):
            if p and i == 0:
                continue
            x, xd, xdd = (np.zeros(model.n) for _ in range(3))
            for c in range(model.n):
                if traj.kind == "blend":
                    x[c], xd[c], xdd[c] = _blend(t, grid[0], grid[-1], traj.q[p][c], traj.q[p + 1][c], traj.blend[p])
                else:
                    x[c], xd[c], xdd[c] = _hermite(traj.kind, T, traj.q[p][c], traj.qd[p][c], traj.qdd[p][c],
                                                   traj.q[p + 1][c], traj.qd[p + 1][c], traj.qdd[p + 1][c], t - grid[0])
            for k, link in enumerate(model.links):
                if link.type in SPHERICAL:
                    first, order = SPHERICAL[link.type]
                    s = slice(model.offsets[k] + first, model.offsets[k] + first + 3)
                    x[s], xd[s], xdd[s] = _spherical(traj, p, s, order, grid, t)
            ts.append(t), Q.append(x), QD.append(xd), QDD.append(xdd)
    return np.array(ts), np.array(Q), np.array(QD), np.array(QDD)


def _spherical(traj, p, s, order, grid, t):
    Rs, Re = _euler_R(order, traj.q[p][s]), _euler_R(order, traj.q[p + 1][s])
    Rse = Rs.T @ Re
    c = max(-1.0, min(1.0, (np.trace(Rse) - 1) / 2))
    th = math.acos(c)
    axis = (np.array([Rse[2, 1] - Rse[1, 2], Rse[0, 2] - Rse[2, 0], Rse[1, 0] - Rse[0, 1]]) / (2 * math.sin(th))
            if th > 1e-12 else np.zeros(3))
    if traj.kind == "blend":
        a, ad, add = _blend(t, grid[0], grid[-1], 0.0, th, traj.blend[p])
    else:
        a, ad, add = _hermite(traj.kind, grid[-1] - grid[0], 0.0, 0.0, 0.0, th, 0.0, 0.0, t - grid[0])
    R = Rs @ rot(axis, a) if th > 1e-12 else Rs
    ang = _euler(order, R)
    S = _omega_map(order, ang)
    rates = np.linalg.solve(S, ad * axis)
    # d/dt (S rates) = S accs + (dS/dt) rates, the second term being the angular acceleration of the
    # Euler chain at zero angle accelerations
    accs = np.linalg.solve(S, add * axis - _dS_rates(order, ang, rates))
    return ang, rates, accs


def _dS_rates(order, ang, rates):
    """Angular acceleration (child frame) of the Euler chain at zero angle accelerations."""
    w, wd = np.zeros(3), np.zeros(3)
    for axis, c in _rotation_factors(order):
        Ri = rot(axis, ang[c])
        w_in = Ri.T @ w
        wd = Ri.T @ wd + np.cross(w_in, axis) * rates[c]
        w = w_in + axis * rates[c]
    return wd
