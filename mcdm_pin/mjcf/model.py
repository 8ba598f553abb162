"""A Pinocchio model built from MuJoCo's compiled model (``mujoco.MjModel``), and the coordinate maps.

MuJoCo compiles the MJCF (defaults, includes, frames, inertias from geoms); this module reads the
compiled arrays and builds the same multibody in Pinocchio. Nothing of the MJCF text is parsed here.

Kinematics (MuJoCo's ``mj_kinematics``). Body ``b`` with parent ``p`` starts at
``B0 = X_p * (body_pos[b], body_quat[b])``; its joints then act in order, each in the current body
frame: a hinge turns by ``theta = qpos - qpos0`` about ``jnt_axis`` through the anchor ``jnt_pos``
(``B <- B * T(c) * Rot(axis, theta) * T(-c)``), a ball turns by the quaternion ``qpos`` about the
anchor, a slide moves by ``qpos - qpos0`` along ``jnt_axis``, and a free joint sets the world pose
to ``qpos`` (top-level bodies only). With ``c_0 = 0`` and ``c_k`` the anchor of joint ``k`` (a
slide keeps the previous anchor), the chain equals
``B0 * T(c_1) J_1 T(c_2 - c_1) J_2 ... J_n T(-c_n)``: one Pinocchio joint per body (a
``JointModelComposite`` when the body has several joints, placed at ``X_p * B0`` with sub-joint
placements ``T(c_k - c_{k-1})``; a single joint sits at ``X_p * B0 * T(c_1)``), and the body frame
at ``T(-c_n)`` in the joint frame. Hinges and slides along a unit axis become ``RX``/``RY``/``RZ``
(``PX``...), others ``RevoluteUnaligned`` (``PrismaticUnaligned``); balls ``Spherical``; free
joints ``FreeFlyer``. Bodies without joints are welded to their parent's joint. The Pinocchio joint
is named after the body (its ``JOINT`` frame too: look frames up with their type).

Frames. Every MuJoCo body gets a ``BODY`` frame named after it (``world`` for body 0); every
site and geom an ``OP_FRAME`` named ``site:NAME`` / ``geom:NAME``. Unnamed elements are named by
id: ``body:#5``, ``site:#3``, ``geom:#12`` (and unnamed joints ``joint:#2`` in
``coordinate_names``). Each body's inertia (mass ``body_mass`` at ``body_ipos``, principal moments
``body_inertia`` along ``body_iquat``) is stored in its ``BODY`` frame's ``inertia`` and added to the
joint that carries it (bodies welded to the world add to joint 0, the universe, which Pinocchio's
dynamics ignore).

Coordinates. Pinocchio's ``q``/``v`` differ from MuJoCo's ``qpos``/``qvel`` in three ways, all
handled by the maps of :class:`MjcfModel`: hinge and slide coordinates are measured from
``qpos0`` (MuJoCo's ``ref``, where the body frame is defined): ``q = qpos - qpos0``, and the
Pinocchio position limits are ``jnt_range - qpos0``; quaternions are ``w, x, y, z`` in MuJoCo and
``x, y, z, w`` in Pinocchio; a free joint's linear velocity is in world axes in MuJoCo
(``v_world``) and in body axes in Pinocchio (``R^T v_world``, ``R`` the body's world rotation).
Generalized forces map like velocities (the map is orthogonal, power is preserved).

Refused (``ModelError`` naming the element): mocap bodies, free joints below a moving body, joint
friction loss, stiffness on ball or free joints, polynomial stiffness or damping, spring yield,
gravity compensation, flexes, and armature on a free joint's translations.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from mcdm_pin.exceptions import ModelError, StateError

FREE, BALL, SLIDE, HINGE = 0, 1, 2, 3
_NQ = {FREE: 7, BALL: 4, SLIDE: 1, HINGE: 1}
_NV = {FREE: 6, BALL: 3, SLIDE: 1, HINGE: 1}
_KIND = {FREE: "free", BALL: "ball", SLIDE: "slide", HINGE: "hinge"}


def rotation_wxyz(quat) -> np.ndarray:
    """Rotation matrix of the quaternion ``(w, x, y, z)`` (normalised first, as MuJoCo does)."""
    w, x, y, z = np.asarray(quat, dtype=float) / np.linalg.norm(quat)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _se3(pos, quat) -> pin.SE3:
    return pin.SE3(rotation_wxyz(quat), np.asarray(pos, dtype=float).copy())


def _name(mj, objtype, i: int, kind: str) -> str:
    import mujoco

    name = mujoco.mj_id2name(mj, objtype, int(i))
    return name if name else f"{kind}:#{int(i)}"


@dataclass(frozen=True, eq=False)
class MjcfModel:
    """A Pinocchio model equal to a compiled MuJoCo model, with the coordinate maps between them.

    Attributes:
        model: the Pinocchio model (gravity from ``opt.gravity``, zero when the model disables
            gravity; armature from ``dof_armature``; limits of limited hinges and slides).
        source: where the MuJoCo model came from (a path or a label), for messages.
        coordinate_names: MuJoCo joint name per entry of Pinocchio's ``v`` (ball and free joints:
            ``NAME[0]``, ``NAME[1]``, ...).
        joint_names: MuJoCo joint name per MuJoCo joint id.
        body_frame, site_frame, geom_frame: Pinocchio frame id per MuJoCo body, site and geom id.
        body_joint: Pinocchio joint id carrying each MuJoCo body (0 for bodies welded to the world).
        jnt_idx_q, jnt_idx_v: first index in Pinocchio's ``q`` and ``v`` of each MuJoCo joint.
        jnt_type, jnt_qposadr, jnt_dofadr, qpos0, qpos_spring, jnt_stiffness, dof_damping: copies of
            MuJoCo's arrays (read-only) that the maps and :meth:`joint_passive` use.
    """

    model: pin.Model
    source: str
    coordinate_names: tuple
    joint_names: tuple
    body_frame: np.ndarray
    site_frame: np.ndarray
    geom_frame: np.ndarray
    body_joint: np.ndarray
    jnt_type: np.ndarray
    jnt_qposadr: np.ndarray
    jnt_dofadr: np.ndarray
    jnt_idx_q: np.ndarray
    jnt_idx_v: np.ndarray
    qpos0: np.ndarray
    qpos_spring: np.ndarray
    jnt_stiffness: np.ndarray
    dof_damping: np.ndarray

    # ---------------------------------------------------------------- positions
    def to_pin_q(self, qpos) -> np.ndarray:
        """Pinocchio ``q`` of MuJoCo's ``qpos`` (hinge/slide minus ``qpos0``; quaternions reordered
        ``w,x,y,z -> x,y,z,w`` and normalised as MuJoCo's kinematics normalise them)."""
        qpos = self._vector(qpos, len(self.qpos0), "qpos")
        q = np.empty(self.model.nq)
        for j, kind in enumerate(self.jnt_type):
            a, i = self.jnt_qposadr[j], self.jnt_idx_q[j]
            if kind in (HINGE, SLIDE):
                q[i] = qpos[a] - self.qpos0[a]
                continue
            if kind == FREE:
                q[i:i + 3] = qpos[a:a + 3]
                a, i = a + 3, i + 3
            w = qpos[a:a + 4] / self._norm(qpos[a:a + 4], j)
            q[i:i + 3], q[i + 3] = w[1:], w[0]
        return q

    def to_mj_qpos(self, q) -> np.ndarray:
        """MuJoCo ``qpos`` of Pinocchio's ``q`` (the inverse of :meth:`to_pin_q`)."""
        q = self._vector(q, self.model.nq, "q")
        qpos = np.empty(len(self.qpos0))
        for j, kind in enumerate(self.jnt_type):
            a, i = self.jnt_qposadr[j], self.jnt_idx_q[j]
            if kind in (HINGE, SLIDE):
                qpos[a] = q[i] + self.qpos0[a]
                continue
            if kind == FREE:
                qpos[a:a + 3] = q[i:i + 3]
                a, i = a + 3, i + 3
            qpos[a], qpos[a + 1:a + 4] = q[i + 3], q[i:i + 3]
        return qpos

    # --------------------------------------------------------------- velocities
    def to_pin_v(self, qvel, qpos=None) -> np.ndarray:
        """Pinocchio ``v`` of MuJoCo's ``qvel`` (also maps generalized forces ``qfrc -> tau``).

        A free joint's linear part becomes ``R^T v_world`` with ``R`` the body rotation of ``qpos``,
        which is then required; every other entry is copied.
        """
        return self._map_v(qvel, qpos, "qvel", "qpos", to_pin=True)

    def to_mj_qvel(self, v, q=None) -> np.ndarray:
        """MuJoCo ``qvel`` of Pinocchio's ``v`` (also ``tau -> qfrc``); ``q`` is needed with free joints."""
        return self._map_v(v, q, "v", "q", to_pin=False)

    def to_pin_a(self, qacc, qpos, qvel) -> np.ndarray:
        """Pinocchio ``a = dv/dt`` of MuJoCo's ``qacc``.

        For a free joint ``v_lin = R^T v_world`` so ``a_lin = R^T a_world - omega x v_lin`` with
        ``omega`` the body-axes angular velocity; every other entry is copied.
        """
        a = self.to_pin_v(qacc, qpos)
        v = self.to_pin_v(qvel, qpos)
        for j in np.flatnonzero(self.jnt_type == FREE):
            i = self.jnt_idx_v[j]
            a[i:i + 3] -= np.cross(v[i + 3:i + 6], v[i:i + 3])
        return a

    def _map_v(self, x, pos, xname, posname, to_pin):
        n = self.model.nv
        x = self._vector(x, n, xname)
        out = np.empty(n)
        src, dst = (self.jnt_dofadr, self.jnt_idx_v) if to_pin else (self.jnt_idx_v, self.jnt_dofadr)
        free = self.jnt_type == FREE
        if free.any():
            if pos is None:
                raise StateError(f"{self.source}: {posname} is needed to map {xname} of free joint "
                                 f"{self.joint_names[int(np.flatnonzero(free)[0])]!r}")
            qpos = self._vector(pos, len(self.qpos0), "qpos") if to_pin else self.to_mj_qpos(pos)
        for j, kind in enumerate(self.jnt_type):
            s, d, k = src[j], dst[j], _NV[kind]
            out[d:d + k] = x[s:s + k]
            if kind == FREE:
                a = self.jnt_qposadr[j]
                self._norm(qpos[a + 3:a + 7], j)
                rot = rotation_wxyz(qpos[a + 3:a + 7])
                out[d:d + 3] = (rot.T if to_pin else rot) @ x[s:s + 3]
        return out

    # ---------------------------------------------------------- passive forces
    def joint_passive(self, q, v) -> np.ndarray:
        """Generalized force (Pinocchio ``v`` order and axes, N or N m) of joint springs and dampers.

        MuJoCo's ``qfrc_spring + qfrc_damper`` without tendons: a hinge or slide joint with
        stiffness ``k`` gives ``-k (qpos - springref)`` with ``qpos = q + qpos0``; every dof gives
        ``-dof_damping * qvel`` (MuJoCo axes, then mapped like a velocity). Tendon springs and
        dampers, fluid forces and gravity compensation are not joint forces and are not included.
        """
        if self._hinges_and_slides:
            return self.joint_passive_checked(self._vector(q, self.model.nq, "q"),
                                              self._vector(v, self.model.nv, "v"))
        qpos = self.to_mj_qpos(q)
        qvel = self.to_mj_qvel(v, q)
        qfrc = -self.dof_damping * qvel
        for j in np.flatnonzero(self.jnt_stiffness):
            a, d = self.jnt_qposadr[j], self.jnt_dofadr[j]
            qfrc[d] -= self.jnt_stiffness[j] * (qpos[a] - self.qpos_spring[a])
        return self.to_pin_v(qfrc, qpos)

    def joint_passive_checked(self, q, v) -> np.ndarray:
        """:meth:`joint_passive` of a state already checked (float arrays of sizes nq and nv, finite:
        the terms evaluator's); where every coordinate is a hinge or slide, index arrays and no maps."""
        if not self._hinges_and_slides:
            return self.joint_passive(q, v)
        _, _, damping, (k, jq, jv, rest) = self._passive_tables
        out = -damping * v
        out[jv] -= k * (q[jq] - rest)
        return out

    @functools.cached_property
    def _hinges_and_slides(self) -> bool:
        return bool(np.all(np.isin(self.jnt_type, (HINGE, SLIDE))))

    @functools.cached_property
    def _passive_tables(self):
        """Pinocchio-ordered damping (nv,) and the springs ``(k, q index, v index, rest)``, where
        ``rest = springref - qpos0`` (Pinocchio's ``q`` is measured from ``qpos0``)."""
        iq, iv = np.asarray(self.jnt_idx_q), np.asarray(self.jnt_idx_v)
        damping = np.empty(self.model.nv)
        damping[iv] = self.dof_damping[self.jnt_dofadr]
        sj = np.flatnonzero(self.jnt_stiffness)
        a = self.jnt_qposadr[sj]
        rest = self.qpos_spring[a] - self.qpos0[a]
        return iq, iv, damping, (self.jnt_stiffness[sj], iq[sj], iv[sj], rest)

    # ----------------------------------------------------------------- helpers
    def _vector(self, x, n, name) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        if x.shape != (n,) or not np.all(np.isfinite(x)):
            raise StateError(f"{self.source}: {name} must be {n} finite numbers, got shape {x.shape}")
        return x

    def _norm(self, quat, j) -> float:
        norm = float(np.linalg.norm(quat))
        if norm == 0.0:
            raise StateError(f"{self.source}: joint {self.joint_names[j]!r} has a zero quaternion")
        return norm


def build_model(mj, source: str) -> MjcfModel:
    """Build the Pinocchio model of the compiled MuJoCo model ``mj`` (see the module docstring).

    Raises:
        ModelError: naming the element (kind, name or id) MuJoCo has and this mapping cannot
            reproduce exactly.
    """
    _check_supported(mj, source)
    model = pin.Model()
    model.name = str(source)
    gravity_off = mj.opt.disableflags & _disable_bit("mjDSBL_GRAVITY")
    model.gravity = pin.Motion(np.zeros(3) if gravity_off else np.array(mj.opt.gravity), np.zeros(3))
    body_joint = np.zeros(mj.nbody, dtype=int)
    body_frame = np.zeros(mj.nbody, dtype=int)
    in_joint = [pin.SE3.Identity()] * mj.nbody
    body_frame[0] = model.addFrame(pin.Frame("world", 0, 0, pin.SE3.Identity(), pin.FrameType.BODY))
    for b in range(1, mj.nbody):
        p = int(mj.body_parentid[b])
        x0 = in_joint[p] * _se3(mj.body_pos[b], mj.body_quat[b])
        name = _name(mj, _obj("mjOBJ_BODY"), b, "body")
        prev = int(body_frame[p])
        if mj.body_jntnum[b] == 0:
            body_joint[b], in_joint[b] = body_joint[p], x0
        else:
            jmodel, placement, body_in_joint = _joint_of_body(mj, b, x0, int(body_joint[p]), source)
            jid = model.addJoint(int(body_joint[p]), jmodel, placement, name)
            prev = model.addJointFrame(jid, prev)
            body_joint[b], in_joint[b] = jid, body_in_joint
        frame = pin.Frame(name, int(body_joint[b]), prev, in_joint[b], pin.FrameType.BODY, _inertia(mj, b))
        body_frame[b] = model.addFrame(frame, True)
    site_frame = _attach(model, mj, "site", mj.nsite, mj.site_bodyid, mj.site_pos, mj.site_quat,
                         body_joint, body_frame, in_joint)
    geom_frame = _attach(model, mj, "geom", mj.ngeom, mj.geom_bodyid, mj.geom_pos, mj.geom_quat,
                         body_joint, body_frame, in_joint)
    idx_q, idx_v = _joint_indices(model, mj, body_joint)
    _set_limits_and_armature(model, mj, idx_q, idx_v)
    joint_names = tuple(_name(mj, _obj("mjOBJ_JOINT"), j, "joint") for j in range(mj.njnt))
    arrays = {key: _frozen(val) for key, val in dict(
        body_frame=body_frame, site_frame=site_frame, geom_frame=geom_frame, body_joint=body_joint,
        jnt_type=mj.jnt_type, jnt_qposadr=mj.jnt_qposadr, jnt_dofadr=mj.jnt_dofadr, jnt_idx_q=idx_q,
        jnt_idx_v=idx_v, qpos0=mj.qpos0, qpos_spring=mj.qpos_spring, jnt_stiffness=mj.jnt_stiffness,
        dof_damping=mj.dof_damping).items()}
    return MjcfModel(model=model, source=str(source), joint_names=joint_names,
                     coordinate_names=_velocity_names(mj, joint_names, idx_v), **arrays)


def _velocity_names(mj, joint_names, idx_v) -> tuple:
    """MuJoCo joint name per entry of Pinocchio's ``v`` (``NAME[k]`` for ball and free joints)."""
    names = [""] * mj.nv
    for j in range(mj.njnt):
        k = _NV[int(mj.jnt_type[j])]
        for e in range(k):
            names[idx_v[j] + e] = joint_names[j] if k == 1 else f"{joint_names[j]}[{e}]"
    return tuple(names)


def _joint_of_body(mj, b, x0, parent_joint, source):
    """The Pinocchio joint of body ``b``: ``(joint model, placement in the parent joint, body
    placement in the new joint)``, following the anchor chain of the module docstring."""
    jids = range(int(mj.body_jntadr[b]), int(mj.body_jntadr[b] + mj.body_jntnum[b]))
    if any(int(mj.jnt_type[j]) == FREE for j in jids):
        if len(jids) != 1 or parent_joint != 0:
            raise ModelError(f"{source}: body {_name(mj, _obj('mjOBJ_BODY'), b, 'body')!r}: a free "
                             f"joint must be the only joint of a body welded to the world")
        return pin.JointModelFreeFlyer(), pin.SE3.Identity(), pin.SE3.Identity()
    anchors, subjoints = [np.zeros(3)], []
    for j in jids:
        kind = int(mj.jnt_type[j])
        anchors.append(np.array(mj.jnt_pos[j]) if kind in (HINGE, BALL) else anchors[-1])
        subjoints.append(_simple_joint(kind, np.array(mj.jnt_axis[j])))
    body_in_joint = pin.SE3(np.eye(3), -anchors[-1])
    if len(subjoints) == 1:
        return subjoints[0], x0 * pin.SE3(np.eye(3), anchors[1]), body_in_joint
    composite = pin.JointModelComposite()
    for k, sub in enumerate(subjoints):
        composite.addJoint(sub, pin.SE3(np.eye(3), anchors[k + 1] - anchors[k]))
    return composite, x0, body_in_joint


def _simple_joint(kind, axis):
    """Pinocchio joint model of one hinge, slide or ball (aligned models for the unit axes x, y, z)."""
    if kind == BALL:
        return pin.JointModelSpherical()
    unit = [k for k in range(3) if np.array_equal(axis, np.eye(3)[k])]
    if kind == HINGE:
        if unit:
            return (pin.JointModelRX, pin.JointModelRY, pin.JointModelRZ)[unit[0]]()
        return pin.JointModelRevoluteUnaligned(axis)
    if unit:
        return (pin.JointModelPX, pin.JointModelPY, pin.JointModelPZ)[unit[0]]()
    return pin.JointModelPrismaticUnaligned(axis)


def _inertia(mj, b) -> pin.Inertia:
    """Spatial inertia of body ``b`` in its body frame (mass at ``body_ipos``, principal moments
    ``body_inertia`` along the axes of ``body_iquat``)."""
    rot = rotation_wxyz(mj.body_iquat[b])
    inertia = rot @ np.diag(mj.body_inertia[b]) @ rot.T
    return pin.Inertia(float(mj.body_mass[b]), np.array(mj.body_ipos[b]), 0.5 * (inertia + inertia.T))


def _attach(model, mj, kind, count, bodyid, pos, quat, body_joint, body_frame, in_joint):
    """Add an ``OP_FRAME`` ``kind:NAME`` per site or geom; return the frame id per element id."""
    objtype = _obj("mjOBJ_SITE" if kind == "site" else "mjOBJ_GEOM")
    frames = np.zeros(count, dtype=int)
    for i in range(count):
        b = int(bodyid[i])
        name = _name(mj, objtype, i, kind)
        name = name if name.startswith(f"{kind}:#") else f"{kind}:{name}"
        placement = in_joint[b] * _se3(pos[i], quat[i])
        frames[i] = model.addFrame(pin.Frame(name, int(body_joint[b]), int(body_frame[b]), placement,
                                             pin.FrameType.OP_FRAME), False)
    return frames


def _joint_indices(model, mj, body_joint):
    """First index in Pinocchio's ``q`` and ``v`` of each MuJoCo joint (sub-joints in body order)."""
    idx_q = np.zeros(mj.njnt, dtype=int)
    idx_v = np.zeros(mj.njnt, dtype=int)
    for b in range(1, mj.nbody):
        if mj.body_jntnum[b] == 0:
            continue
        jid = int(body_joint[b])
        iq, iv = model.joints[jid].idx_q, model.joints[jid].idx_v
        for j in range(int(mj.body_jntadr[b]), int(mj.body_jntadr[b] + mj.body_jntnum[b])):
            idx_q[j], idx_v[j] = iq, iv
            iq, iv = iq + _NQ[int(mj.jnt_type[j])], iv + _NV[int(mj.jnt_type[j])]
    return idx_q, idx_v


def _set_limits_and_armature(model, mj, idx_q, idx_v):
    """Position limits of limited hinges and slides (``jnt_range - qpos0``; others infinite) and
    the armature of every dof."""
    lower, upper = model.lowerPositionLimit.copy(), model.upperPositionLimit.copy()
    armature = np.zeros(model.nv)
    for j in range(mj.njnt):
        kind = int(mj.jnt_type[j])
        dof = int(mj.jnt_dofadr[j])
        armature[idx_v[j]:idx_v[j] + _NV[kind]] = mj.dof_armature[dof:dof + _NV[kind]]
        if kind in (HINGE, SLIDE):
            ref = mj.qpos0[mj.jnt_qposadr[j]]
            limited = bool(mj.jnt_limited[j])
            lower[idx_q[j]] = mj.jnt_range[j, 0] - ref if limited else -np.inf
            upper[idx_q[j]] = mj.jnt_range[j, 1] - ref if limited else np.inf
    model.lowerPositionLimit, model.upperPositionLimit = lower, upper
    model.armature = armature


def _check_supported(mj, source):
    """Raise ModelError for what the Pinocchio model or the maps cannot reproduce exactly."""
    def refuse(kind, objtype, i, why):
        raise ModelError(f"{source}: {kind} {_name(mj, _obj(objtype), i, kind)!r}: {why}")

    for b in np.flatnonzero(mj.body_mocapid >= 0):
        refuse("body", "mjOBJ_BODY", b, "mocap bodies are posed by mocap_pos, not by joints")
    for b in np.flatnonzero(mj.body_gravcomp != 0):
        refuse("body", "mjOBJ_BODY", b, f"gravcomp={mj.body_gravcomp[b]} is not mapped (expected 0)")
    if getattr(mj, "nflex", 0):
        raise ModelError(f"{source}: {mj.nflex} flex(es): deformable bodies have no Pinocchio joint")
    if np.any(mj.dof_frictionloss != 0):
        d = int(np.flatnonzero(mj.dof_frictionloss != 0)[0])
        refuse("joint", "mjOBJ_JOINT", mj.dof_jntid[d],
               f"frictionloss={mj.dof_frictionloss[d]} is not mapped (expected 0 on every joint)")
    for field in ("jnt_stiffnesspoly", "jnt_springyield"):
        for j in _nonzero_rows(mj, field):
            refuse("joint", "mjOBJ_JOINT", j, f"{field} is not mapped (expected 0)")
    for d in _nonzero_rows(mj, "dof_dampingpoly"):
        refuse("joint", "mjOBJ_JOINT", mj.dof_jntid[d], "dof_dampingpoly is not mapped (expected 0)")
    for j in range(mj.njnt):
        kind = int(mj.jnt_type[j])
        if kind in (BALL, FREE) and mj.jnt_stiffness[j] != 0:
            refuse("joint", "mjOBJ_JOINT", j, f"stiffness={mj.jnt_stiffness[j]} on a {_KIND[kind]} "
                   f"joint is not mapped (expected 0)")
        d = int(mj.jnt_dofadr[j])
        if kind == FREE and np.any(mj.dof_armature[d:d + 3] != 0):
            refuse("joint", "mjOBJ_JOINT", j, f"armature {mj.dof_armature[d:d + 3]} on the world-axes "
                   f"translations is not mapped (MuJoCo's arm * qacc_world differs from Pinocchio's "
                   f"arm * dv/dt by arm * omega x v; expected 0)")


def _nonzero_rows(mj, field: str) -> np.ndarray:
    """Indices of the rows of the per-joint or per-dof array ``field`` with a nonzero entry (none
    when this MuJoCo has no such field)."""
    values = np.asarray(getattr(mj, field, np.zeros(0)))
    if values.size == 0:
        return np.zeros(0, dtype=int)
    return np.flatnonzero(np.any(values.reshape(values.shape[0], -1) != 0, axis=1))


def _obj(name: str) -> int:
    import mujoco

    return int(getattr(mujoco.mjtObj, name))


def _disable_bit(name: str) -> int:
    import mujoco

    return int(getattr(mujoco.mjtDisableBit, name))


def _frozen(values) -> np.ndarray:
    out = np.array(values, copy=True)
    out.flags.writeable = False
    return out
