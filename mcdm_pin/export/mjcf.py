r"""A robot written as a MuJoCo model (MJCF): the plant of a closed-loop simulation.

**Bodies.** Pinocchio joints in series whose intermediate bodies are massless (a spherical joint as
three revolute joints, a universal joint) become *one* MuJoCo body with several joints: MuJoCo
refuses massless moving bodies, and its bodies may carry joints in series. The MuJoCo body frame is the
frame of the group's last Pinocchio joint at ``q = 0``, placed in its parent body's frame at
``P_1 P_2 ... P_n`` (``P_k`` the ``jointPlacements``). Joint ``k`` of the group then turns about the
axis ``R_k a_k`` through the anchor ``t_k``, both in the body frame, with
``(R_k, t_k) = (P_{k+1} ... P_n)^{-1}``: MuJoCo applies a body's joints in order, each about its axis
through its anchor in the body frame, and

.. math:: P_1 J_1 P_2 J_2 \cdots P_n J_n = (P_1 \cdots P_n)\, \prod_k T_k^{-1} J_k T_k,
          \qquad T_k = P_{k+1} \cdots P_n ,

where :math:`T_k^{-1} J_k T_k` is the rotation :math:`J_k` about the conjugated axis and point. Each
body's inertia (mass, centre of mass and inertia about it, Pinocchio's ``model.inertias`` of the
group's last joint) is its ``<inertial fullinertia>`` in that frame. A free-flyer becomes a ``free``
joint (top-level bodies only, as MuJoCo requires), a native ball joint a ``ball`` (last of its group).
Pinocchio's joint limits are not written: the plant has no joint limits, no damping and no contacts.

**Cables.** Every route point is a ``<site>`` on the body carrying it (in the world body for points on
the base); every cable a ``<spatial>`` tendon through its sites in route order, so that MuJoCo's
``ten_length`` and ``ten_J`` are our cable lengths and ``L = d l / d q`` (in MuJoCo's velocity
coordinates, below). Every cable drives a ``<motor>`` on its tendon with ``gear = -1``: MuJoCo's
actuator force acts along ``+ten_J`` (it lengthens the tendon), so with ``gear = -1`` a positive
control ``f`` (N) gives ``qfrc_actuator = -ten_J^T f``, our ``-L^T f``: a positive command pulls.
Routes that wrap over surfaces or pass pulleys are refused.

**Coordinates.** Hinge and slide positions and rates are Pinocchio's, reordered into MuJoCo's order.
A ball's quaternion is ``(w, x, y, z)`` in MuJoCo and ``(x, y, z, w)`` in Pinocchio. A free joint's
``qpos`` is the body's world position and quaternion, ``X_w = P_1 X(q)``; its ``qvel`` is the linear
velocity in *world* axes, then the angular velocity in body axes, where Pinocchio's ``v`` has both in
body axes: ``qvel = T(q) v`` with ``T = diag(R_w, I)`` on the free joint (identity elsewhere, then
the reordering). Generalised forces map with the transpose, ``tau = T^T qfrc``, and the bias terms as

.. math:: h = T^T (c_{mj} + M_{mj} \dot T v), \qquad \dot T v = (R_w (\omega \times v_{lin}), 0),

(Pinocchio's ``M = T^T M_{mj} T``), which :class:`MjcfExport` gives with :meth:`MjcfExport.to_pin_force`.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..exceptions import MissingPackageError, ModelError

_HINGE = {"JointModelRX": (0, "hinge"), "JointModelRY": (1, "hinge"), "JointModelRZ": (2, "hinge"),
          "JointModelPX": (0, "slide"), "JointModelPY": (1, "slide"), "JointModelPZ": (2, "slide")}


@dataclass(frozen=True, eq=False)
class MjcfExport:
    """A robot as MJCF text, with the maps between Pinocchio's ``(q, v)`` and MuJoCo's ``(qpos, qvel)``.

    Attributes:
        xml: the MJCF document.
        nq, nv: Pinocchio's sizes; ``nq_mj``, ``nv_mj``: MuJoCo's (the same numbers).
        q_index: (nq,) position in ``qpos`` of each ``q`` entry (quaternions reordered).
        v_index: (nv,) position in ``qvel`` of each ``v`` entry.
        free: per free joint, ``(idx_q, idx_v, adr_q, adr_v, P)``: its Pinocchio indices, MuJoCo
            addresses and joint placement ``P`` (a ``pin.SE3``).
        cable_names: the tendons' (and motors') names, in cable order.
    """

    xml: str
    nq: int
    nv: int
    q_index: np.ndarray
    v_index: np.ndarray
    free: tuple
    cable_names: tuple

    def compile(self):
        """The compiled ``mujoco.MjModel``."""
        return _mujoco().MjModel.from_xml_string(self.xml)

    def write(self, path) -> Path:
        path = Path(path)
        path.write_text(self.xml)
        return path

    # ------------------------------------------------------------------------------- state maps
    def qpos(self, q) -> np.ndarray:
        """MuJoCo's ``qpos`` of Pinocchio's configuration ``q``."""
        q = np.asarray(q, dtype=float)
        out = np.empty(self.nq)
        out[self.q_index] = q
        for iq, _, aq, _, P in self.free:
            M = P * pin.XYZQUATToSE3(q[iq])
            out[aq:aq + 3] = M.translation
            x, y, z, w = pin.Quaternion(M.rotation).coeffs()
            out[aq + 3:aq + 7] = (w, x, y, z)
        return out

    def q(self, qpos) -> np.ndarray:
        """Pinocchio's configuration of MuJoCo's ``qpos``."""
        qpos = np.asarray(qpos, dtype=float)
        q = qpos[self.q_index].copy()
        for iq, _, aq, _, P in self.free:
            w, x, y, z = qpos[aq + 3:aq + 7]
            M = P.inverse() * pin.SE3(pin.Quaternion(w, x, y, z).normalized().matrix(), qpos[aq:aq + 3].copy())
            q[iq] = pin.SE3ToXYZQUAT(M)
        return q

    def T(self, q) -> np.ndarray:
        """(nv, nv) ``d qvel / d v`` at ``q`` (module docstring)."""
        T = np.zeros((self.nv, self.nv))
        T[self.v_index, np.arange(self.nv)] = 1.0
        for iq, iv, _, av, P in self.free:
            R = self._world_rotation(q, iq, P)
            T[av:av + 3, iv[0]:iv[0] + 3] = R
        return T

    def qvel(self, q, v) -> np.ndarray:
        """MuJoCo's ``qvel`` of Pinocchio's ``(q, v)``."""
        v = np.asarray(v, dtype=float)
        out = np.empty(self.nv)
        out[self.v_index] = v
        for iq, iv, _, av, P in self.free:
            out[av:av + 3] = self._world_rotation(q, iq, P) @ v[iv[:3]]
        return out

    def v(self, qpos, qvel) -> np.ndarray:
        """Pinocchio's velocity of MuJoCo's ``(qpos, qvel)``."""
        qvel = np.asarray(qvel, dtype=float)
        v = qvel[self.v_index].copy()
        for _, iv, aq, av, _ in self.free:
            w, x, y, z = qpos[aq + 3:aq + 7]
            R = pin.Quaternion(w, x, y, z).normalized().matrix()
            v[iv[:3]] = R.T @ qvel[av:av + 3]
        return v

    def to_pin_force(self, q, qfrc) -> np.ndarray:
        """Pinocchio's generalised force ``T^T qfrc`` of a MuJoCo one (power preserved)."""
        return self.T(q).T @ np.asarray(qfrc, dtype=float)

    def bias_correction(self, q, v) -> np.ndarray:
        """``T_dot v`` in MuJoCo's coordinates (module docstring): add ``M_mj`` times it to
        ``qfrc_bias`` before mapping it with :meth:`to_pin_force` to get Pinocchio's ``h``."""
        out = np.zeros(self.nv)
        for iq, iv, _, av, P in self.free:
            R = self._world_rotation(q, iq, P)
            vl, w = np.asarray(v)[iv[:3]], np.asarray(v)[iv[3:]]
            out[av:av + 3] = R @ np.cross(w, vl)
        return out

    @staticmethod
    def _world_rotation(q, iq, P) -> np.ndarray:
        x, y, z, w = np.asarray(q, dtype=float)[iq[3:]]
        return P.rotation @ pin.Quaternion(w, x, y, z).normalized().matrix()


def export_mjcf(robot, timestep: float = 1e-3, integrator: str = "RK4") -> MjcfExport:
    """Write ``robot`` (a :class:`~mcdm_pin.robot.Robot`) as MJCF (module docstring).

    Args:
        timestep: MuJoCo's ``option/timestep``, s.
        integrator: MuJoCo's ``option/integrator`` (``Euler``, ``RK4``, ``implicit``, ``implicitfast``).

    Raises:
        ModelError: a Pinocchio joint type MuJoCo cannot express here, a massive body inside a group,
            a free joint below a moving body, a massless moving body, a route point on a massless
            intermediate body, a route with wraps or pulleys, or a robot with actuated joints,
            couplings or joint springs and dampers (they are not written).
    """
    if robot.actuators or robot.couplings is not None or getattr(robot, "passive", None) is not None:
        raise ModelError(f"robot {robot.name!r}: export_mjcf writes cable-driven robots only (no joint actuators, "
                         f"no couplings, no joint springs or dampers)")
    model = robot.model
    groups = _groups(model)
    root = ET.Element("mujoco", model=robot.name)
    ET.SubElement(root, "compiler", angle="radian", autolimits="true")
    option = ET.SubElement(root, "option", timestep=_f(timestep), integrator=integrator,
                           gravity=_v(model.gravity.linear))
    ET.SubElement(option, "flag", contact="disable")
    world = ET.SubElement(root, "worldbody")
    body_of = {0: world}  # Pinocchio joint (a group's last) -> its MuJoCo body element
    last_of = {}  # Pinocchio joint -> the last joint of its group
    joint_order = []  # (pin joint id, MuJoCo kind), in MuJoCo's order
    for ids in groups:
        for j in ids:
            last_of[j] = ids[-1]
        parent = model.parents[ids[0]]
        if parent not in body_of:
            raise ModelError(f"joint {model.names[ids[0]]!r}: its parent {model.names[parent]!r} is inside a "
                             f"group of joints joined by massless bodies")
        body_of[ids[-1]] = _body(model, ids, body_of[parent], joint_order)
    sites = _sites(robot, body_of, last_of)
    _tendons(root, robot, sites)
    q_index, v_index, free = _maps(model, joint_order)
    xml = ET.tostring(root, encoding="unicode")
    return MjcfExport(xml, model.nq, model.nv, q_index, v_index, tuple(free), tuple(robot.cable_names))


def _groups(model) -> list[list[int]]:
    """Pinocchio joints in MuJoCo bodies: a joint whose body is massless and has exactly one child
    joint is merged into its child's body."""
    children = {j: [] for j in range(model.njoints)}
    for j in range(1, model.njoints):
        children[model.parents[j]].append(j)
    groups, current = [], {}
    for j in range(1, model.njoints):  # parents come before children in Pinocchio's order
        chain = current.pop(model.parents[j], []) + [j]
        if model.inertias[j].mass == 0.0 and len(children[j]) == 1 and _mergeable(model, j, children[j][0]):
            current[j] = chain
        else:
            groups.append(chain)
    return groups


def _mergeable(model, j, child) -> bool:
    """A free joint stays alone in its body (MuJoCo: a free joint is its body's only joint)."""
    return "JointModelFreeFlyer" not in (model.joints[j].shortname(), model.joints[child].shortname())


def _body(model, ids, parent_el, joint_order):
    """The MuJoCo body of the group ``ids`` (module docstring), appended to ``parent_el``."""
    last = ids[-1]
    name = model.names[last]
    if model.inertias[last].mass <= 0.0:
        raise ModelError(f"joint {name!r}: its body is massless and moves; MuJoCo refuses massless moving "
                         f"bodies (give it a mass, or lock the joint)")
    X = pin.SE3.Identity()
    for j in ids:
        X = X * model.jointPlacements[j]
    free = model.joints[ids[0]].shortname() == "JointModelFreeFlyer"
    if free and model.parents[ids[0]] != 0:
        raise ModelError(f"joint {model.names[ids[0]]!r}: MuJoCo allows free joints on top-level bodies only")
    body = ET.SubElement(parent_el, "body", name=name, pos=_v(X.translation), quat=_quat(X.rotation))
    inertia = model.inertias[last]
    I = inertia.inertia
    ET.SubElement(body, "inertial", pos=_v(inertia.lever), mass=_f(inertia.mass),
                  fullinertia=_v([I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]]))
    for k, j in enumerate(ids):
        Tk = pin.SE3.Identity()
        for i in ids[k + 1:]:
            Tk = Tk * model.jointPlacements[i]
        Tinv = Tk.inverse()
        short = model.joints[j].shortname()
        jname = model.names[j]
        if short == "JointModelFreeFlyer":
            ET.SubElement(body, "freejoint", name=jname)
            kind = "free"
        elif short == "JointModelSpherical":
            if k != len(ids) - 1:
                raise ModelError(f"joint {jname!r}: a ball joint must be the last of its group of massless bodies")
            ET.SubElement(body, "joint", name=jname, type="ball", pos="0 0 0")
            kind = "ball"
        else:
            axis = _axis(model, j)
            kind = "slide" if short.startswith("JointModelP") else "hinge"
            ET.SubElement(body, "joint", name=jname, type=kind, pos=_v(Tinv.translation),
                          axis=_v(Tinv.rotation @ axis))
        joint_order.append((j, kind))
    return body


def _axis(model, j) -> np.ndarray:
    joint = model.joints[j]
    short = joint.shortname()
    if short in _HINGE:
        return np.eye(3)[_HINGE[short][0]]
    if short in ("JointModelRevoluteUnaligned", "JointModelPrismaticUnaligned"):
        return np.asarray(joint.extract().axis, dtype=float)
    raise ModelError(f"joint {model.names[j]!r}: Pinocchio joint type {short} has no MJCF counterpart here "
                     f"(expected revolute, prismatic, spherical or free-flyer)")


def _sites(robot, body_of, last_of) -> list[str]:
    """One site per route point (route order), named ``CABLE#k``; returns their names."""
    cables = robot.cables
    model = robot.model
    for c in cables.cables:
        if c.configuration_dependent or len(c.route_points) != len(c.route):
            raise ModelError(f"cable {c.name!r}: export_mjcf writes straight routes only (no wraps, no pulleys)")
    names = []
    count: dict[int, int] = {}
    for p, (jid, local) in enumerate(zip(cables.point_joint, cables.point_local)):
        jid = int(jid)
        ci = int(cables.point_cable[p])
        k = count.get(ci, 0)
        count[ci] = k + 1
        name = f"{cables.names[ci]}#{k}"
        if jid != 0 and last_of[jid] != jid:
            raise ModelError(f"cable {cables.names[ci]!r}: route point {k} sits on the massless body of joint "
                             f"{model.names[jid]!r}, inside a MuJoCo body")
        ET.SubElement(body_of[jid], "site", name=name, pos=_v(local))
        names.append(name)
    return names


def _tendons(root, robot, sites) -> None:
    cables = robot.cables
    tendon = ET.SubElement(root, "tendon")
    actuator = ET.SubElement(root, "actuator")
    for ci, name in enumerate(cables.names):
        spatial = ET.SubElement(tendon, "spatial", name=name)
        for p in np.flatnonzero(cables.point_cable == ci):
            ET.SubElement(spatial, "site", site=sites[int(p)])
        ET.SubElement(actuator, "motor", name=name, tendon=name, gear="-1",
                      ctrlrange=f"{_f(cables.f_min[ci])} {_f(cables.f_max[ci])}")


def _maps(model, joint_order):
    """``q_index``, ``v_index`` and the free joints (see :class:`MjcfExport`)."""
    q_index = np.empty(model.nq, dtype=int)
    v_index = np.empty(model.nv, dtype=int)
    free = []
    aq = av = 0
    for j, kind in joint_order:
        iq, iv = model.idx_qs[j], model.idx_vs[j]
        nq, nv = model.nqs[j], model.nvs[j]
        if kind == "ball":  # (x, y, z, w) -> (w, x, y, z)
            q_index[iq:iq + 4] = [aq + 1, aq + 2, aq + 3, aq]
        else:
            q_index[iq:iq + nq] = np.arange(aq, aq + nq)
        v_index[iv:iv + nv] = np.arange(av, av + nv)
        if kind == "free":
            free.append((np.arange(iq, iq + 7), np.arange(iv, iv + 6), aq, av, model.jointPlacements[j].copy()))
        aq += nq
        av += nv
    return q_index, v_index, free


def _f(x) -> str:
    return repr(float(x))


def _v(x) -> str:
    return " ".join(repr(float(a)) for a in np.asarray(x, dtype=float).reshape(-1))


def _quat(R) -> str:
    x, y, z, w = pin.Quaternion(np.asarray(R)).coeffs()
    return _v([w, x, y, z])


def _mujoco():
    try:
        import mujoco
    except ImportError as exc:
        raise MissingPackageError("MuJoCo is not installed: pip install 'mcdm-pin[mjcf]'") from exc
    return mujoco
