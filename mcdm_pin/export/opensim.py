r"""A :class:`~mcdm_pin.robot.Robot` written as an OpenSim model (``.osim``, OpenSim 4.6).

What is written:

- **bodies**: one per Pinocchio joint that carries mass (fixed URDF links already merged in by
  Pinocchio), named after its URDF link, with mass, centre of mass and inertia about the centre of mass
  in the body frame. The body frame *is* Pinocchio's joint frame (origin at the joint point), so every
  point, inertia and wrench reads the same in both models. The massless links inside a grouped joint
  (an xyz Euler triple) are not written: one OpenSim joint replaces the group.
- **joints**: a ``PinJoint`` per revolute joint (OpenSim turns about the joint frames' z axis, so the
  parent and child offset frames carry the rotation that takes z onto the URDF axis); a
  ``SliderJoint`` per prismatic joint (along x, likewise); a ``CustomJoint`` per spherical joint made
  of three revolute URDF joints (and per universal joint, two). Pinocchio's chain
  :math:`P_1 R(a_1,q_1) P_2 R(a_2,q_2) P_3 R(a_3,q_3)` (placements :math:`P_k`, the last two pure
  rotations since the members meet at one point) equals
  :math:`P_1\,R(b_1,q_1) R(b_2,q_2) R(b_3,q_3)\,C` with :math:`b_1 = a_1`, :math:`b_2 = P_2 a_2`,
  :math:`b_3 = P_2 P_3 a_3` and :math:`C = P_2 P_3`: the custom joint's rotation axes are the
  :math:`b_k` (a body-fixed sequence, each turning with the previous ones), in the same order, with
  the same coordinates (``q1_x``, ``q2_y``, ``q3_z``: our coordinate names), its parent offset frame is
  :math:`P_1` and its child offset frame :math:`C^T`. For the paper's arm this is
  :math:`R = R_x(q_1) R_y(q_2) R_z(q_3)`.
- **gravity**; **cables**: one ``PathActuator`` per cable whose path is the route as fixed
  ``PathPoint``\ s on the bodies (route points on the base are on ``ground``), with one optimal force
  :math:`F_0` for every cable (default: the largest ``f_max``) and control bounds
  :math:`[f_{min}/F_0,\ f_{max}/F_0]`, so that a control :math:`c` means a tension :math:`c F_0`.

Joint types that have no OpenSim counterpart written here yet (native ball and free joints, planar and
translation groups, helical...) are refused with a :class:`~mcdm_pin.exceptions.ModelError`.

OpenSim is an optional dependency (``pip install 'mcdm-pin[opensim]'``); :func:`describe` does not need
it. :mod:`.opensim_eval` evaluates the written model (states from our coordinates, mass matrix, inverse
dynamics, cable lengths and moment arms) for the tests and the benchmark peer.
"""

from __future__ import annotations

import math
import os
import tempfile
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..exceptions import MissingPackageError, ModelError  # noqa: F401 (MissingPackageError: re-exported)
from ..extras import optional
from .osim_names import check_written, legal_names

INSTALL_HINT = "pip install 'mcdm-pin[opensim]'  (or: pip install opensim)"
GROUND = "ground"


def require_opensim():
    """The ``opensim`` module, or :class:`MissingPackageError` with the install command."""
    opensim = optional("opensim", "the OpenSim export and peer (OpenSim 4.6)")
    opensim.Logger.setLevelString("error")  # OpenSim logs every model it builds at 'info'
    opensim.Logger.removeFileSink()  # and would leave an opensim.log in the working directory
    return opensim


# ---------------------------------------------------------------------------------- plain data
@dataclass(frozen=True)
class BodySpec:
    """A rigid body: ``name``, the Pinocchio joint ``pin_id`` that carries it, ``mass`` (kg), ``com``
    (3,) m and ``inertia`` (3, 3) kg m^2 about the centre of mass, both in the body (joint) frame."""

    name: str
    pin_id: int
    mass: float
    com: np.ndarray
    inertia: np.ndarray


@dataclass(frozen=True)
class JointSpec:
    """An OpenSim joint.

    Attributes:
        name: the physical joint's name; ``kind``: ``pin``, ``slider`` or ``custom``.
        parent, child: body names (``ground`` for the base).
        parent_offset: the joint frame F in the parent body frame.
        child_rotation: the moving joint frame M in the child body frame (a rotation; the origins
            coincide).
        axes: (k, 3) unit axes in F at zero (``custom``: the body-fixed rotation sequence).
        coordinates: k coordinate names (ours); ``idx_v``: their indices in our coordinates.
        lower, upper: (k,) coordinate ranges.
    """

    name: str
    kind: str
    parent: str
    child: str
    parent_offset: pin.SE3
    child_rotation: np.ndarray
    axes: np.ndarray
    coordinates: tuple[str, ...]
    idx_v: tuple[int, ...]
    lower: np.ndarray
    upper: np.ndarray


@dataclass(frozen=True)
class CableSpec:
    """A cable: ``name``, ``points`` ((body, (x, y, z)) in the body frame, m), bounds in newtons."""

    name: str
    points: tuple[tuple[str, tuple[float, float, float]], ...]
    f_min: float
    f_max: float


@dataclass(frozen=True)
class RobotSpec:
    """Everything the OpenSim model is made of (no OpenSim objects; :func:`describe`)."""

    name: str
    gravity: np.ndarray
    bodies: tuple[BodySpec, ...]
    joints: tuple[JointSpec, ...]
    cables: tuple[CableSpec, ...]
    coordinate_names: tuple[str, ...]
    renamed: tuple[tuple[str, str, str], ...] = ()  # (kind, our name, OpenSim's) where they differ


# ------------------------------------------------------------------------------ reading the robot
def describe(robot) -> RobotSpec:
    """Read a :class:`~mcdm_pin.robot.Robot` into plain data: the one place that reads the robot
    (its ``model``, ``joints`` and ``cables``), so a change of the robot's layout touches only here.

    Raises:
        ModelError: a joint type without an OpenSim counterpart here (module docstring).
    """
    model = robot.model
    cables = robot.cables
    unsupported = [what for what, present in (
        ("routes over wrapping surfaces or rotating pulleys", cables.configuration_dependent),
        ("pulleys", bool(np.any(cables.seg_scale != 1.0))), ("muscles", cables.muscles is not None),
        ("coupled coordinates", getattr(robot, "couplings", None) is not None)) if present]
    if unsupported:
        raise ModelError(f"robot {robot.name!r} has {', '.join(unsupported)}: the OpenSim export writes "
                         f"straight cables between fixed points only (a PathWrap and muscle export is not "
                         f"written yet); nothing was exported")
    names = _body_names(model)
    joints = []
    for j in robot.joints:
        try:
            joints.append(_joint_spec(model, j, names))
        except ModelError as exc:
            if getattr(robot, "sidecar", None) is None:
                raise
            raise robot.sidecar.error(f"joints.{j.name}", str(exc)) from None
    joints = tuple(joints)
    used = {j.child for j in joints}
    bodies = []
    for jid in range(1, model.njoints):
        if names[jid] not in used:
            continue  # a massless link inside a grouped joint
        inertia = model.inertias[jid]
        bodies.append(BodySpec(names[jid], jid, float(inertia.mass), np.array(inertia.lever),
                               np.array(inertia.inertia)))
    cs = robot.cables
    cables, taken = [], set()
    for k, cable in enumerate(cs.cables):
        rows = np.flatnonzero(cs.point_cable == k)
        pts = tuple((names[int(cs.point_joint[r])], tuple(float(x) for x in cs.point_local[r])) for r in rows)
        cables.append(CableSpec(str(cable.name), pts, float(cable.f_min), float(cable.f_max)))
    raw = RobotSpec(str(robot.name), np.array(model.gravity.linear), tuple(bodies), joints, tuple(cables),
                    tuple(robot.coordinate_names))
    return _legal_spec(raw)


def _legal_spec(spec: RobotSpec) -> RobotSpec:
    """``spec`` with every name OpenSim will see made legal (:mod:`.osim_names`), the changes listed."""
    body = legal_names([b.name for b in spec.bodies], taken={GROUND})  # no link is named ground
    body[GROUND] = GROUND
    joint = legal_names([j.name for j in spec.joints])
    coord = legal_names(spec.coordinate_names)
    cable = legal_names([c.name for c in spec.cables])  # unique: the cable model refuses duplicates
    renamed = [(kind, a, b) for kind, m in (("body", body), ("joint", joint), ("coordinate", coord),
                                            ("cable", cable)) for a, b in m.items() if a != b]
    cables = [replace(c, name=cable[c.name], points=tuple((body[b], p) for b, p in c.points))
              for c in spec.cables]
    joints = [replace(j, name=joint[j.name], parent=body[j.parent], child=body[j.child],
                      coordinates=tuple(coord[c] for c in j.coordinates)) for j in spec.joints]
    bodies = [replace(b, name=body[b.name]) for b in spec.bodies]
    return replace(spec, name=legal_names([spec.name])[spec.name], bodies=tuple(bodies), joints=tuple(joints),
                   cables=tuple(cables), coordinate_names=tuple(coord[c] for c in spec.coordinate_names),
                   renamed=tuple(renamed))


def _body_names(model: pin.Model) -> dict[int, str]:
    """Pinocchio joint id -> the name of its body: the first URDF link (BODY frame) it carries."""
    names = {0: GROUND}
    for f in model.frames:
        j = int(f.parentJoint)
        if j and j not in names and f.type == pin.FrameType.BODY:
            names[j] = f.name
    for j in range(1, model.njoints):
        names.setdefault(j, model.names[j])  # a model built in code may have no BODY frame
    if GROUND in [names[j] for j in range(1, model.njoints)]:
        raise ModelError(f"a link is named {GROUND!r}, the name OpenSim keeps for the base; rename it")
    return names


def _local_axis(model: pin.Model, jid: int) -> np.ndarray:
    """The unit axis (rotation or translation) of a 1-DoF joint in its own frame."""
    data = model.createData()
    J = np.asarray(pin.computeJointJacobian(model, data, pin.neutral(model), jid)).reshape(6, -1)  # LOCAL
    col = J[:, model.joints[jid].idx_v]
    v = col[3:] if np.linalg.norm(col[3:]) > 0 else col[:3]
    return v / np.linalg.norm(v)


def _align(target: np.ndarray, axis: int) -> np.ndarray:
    """A rotation taking unit basis vector ``axis`` (0 x, 2 z) onto ``target``."""
    t = target / np.linalg.norm(target)
    helper = np.eye(3)[int(np.argmin(np.abs(t)))]
    u = np.cross(helper, t)
    u /= np.linalg.norm(u)
    w = np.cross(t, u)
    # columns: (u, w, t) is right-handed with t third; rotate the columns so that t is column `axis`
    cols = {2: (u, w, t), 0: (t, u, w)}[axis]
    return np.column_stack(cols)


def _joint_spec(model: pin.Model, joint, names: dict[int, str]) -> JointSpec:
    """The OpenSim joint of one physical joint (module docstring)."""
    ids = list(joint.pin_ids)
    kinds = [model.joints[j].shortname() for j in ids]
    ok = (joint.type in ("revolute", "prismatic") and len(ids) == 1) or (
        joint.type in ("spherical", "universal") and joint.parametrization in (None, "euler-xyz")
        and len(ids) in (2, 3))
    if not ok:
        form = f"{joint.type}" + (f" ({joint.parametrization})" if joint.parametrization else "")
        raise ModelError(f"joint {joint.name!r}: a {form} joint made of {', '.join(kinds)} has no OpenSim "
                         f"counterpart in this export; supported: revolute, prismatic, and spherical (three "
                         f"revolute URDF joints) or universal (two) joints")
    lower = np.array([_limit(model.lowerPositionLimit, model.joints[j], -1) for j in ids])
    upper = np.array([_limit(model.upperPositionLimit, model.joints[j], +1) for j in ids])
    coords = tuple(model.names[j] for j in ids)
    idx_v = tuple(int(model.joints[j].idx_v) for j in ids)
    placement = model.jointPlacements[ids[0]]
    parent, child = names[int(model.parents[ids[0]])], names[ids[-1]]
    if len(ids) == 1:
        axis = _local_axis(model, ids[0])
        kind = "pin" if joint.type == "revolute" else "slider"
        R = _align(axis, 2 if kind == "pin" else 0)
        return JointSpec(joint.name, kind, parent, child, placement * pin.SE3(R, np.zeros(3)), R,
                         axis[None, :], coords, idx_v, lower, upper)
    C = np.eye(3)
    axes = []
    for k, j in enumerate(ids):
        if k:
            C = C @ model.jointPlacements[j].rotation  # members meet at one point: rotations only
        axes.append(C @ _local_axis(model, j))
    return JointSpec(joint.name, "custom", parent, child, placement.copy(), C.T, np.array(axes), coords, idx_v,
                     lower, upper)


def _limit(limits: np.ndarray, jm, sign: int) -> float:
    """The URDF position limit of a 1-DoF joint (a continuous joint or no limit: +-2 pi or +-10 m)."""
    value = float(limits[jm.idx_q]) if jm.nq == 1 else math.inf
    if not math.isfinite(value) or abs(value) > 1e6:
        value = sign * (2 * math.pi if jm.shortname().startswith(("JointModelR", "JointModelRUB")) else 10.0)
    return value


def default_optimal_force(spec: RobotSpec) -> float:
    """The optimal force every cable shares by default: the largest ``f_max`` (controls in [0, 1])."""
    return max(c.f_max for c in spec.cables)


# ------------------------------------------------------------------------------ building the model
def euler_xyz(R: np.ndarray) -> tuple[float, float, float]:
    """Body-fixed X-Y-Z Euler angles of ``R`` (``R = Rx(a) Ry(b) Rz(c)``), OpenSim's orientation."""
    b = math.asin(max(-1.0, min(1.0, float(R[0, 2]))))
    if math.hypot(R[0, 0], R[0, 1]) > 1e-12:
        a = math.atan2(-R[1, 2], R[2, 2])
        c = math.atan2(-R[0, 1], R[0, 0])
    else:  # gimbal lock: only a +- c is defined; take c = 0
        a = math.atan2(R[2, 1], R[1, 1])
        c = 0.0
    return a + 0.0, b + 0.0, c + 0.0  # no "-0" in the file


def opensim_model(robot_or_spec, optimal_force: float | None = None):
    """The OpenSim model (``opensim.Model``, connections finalised, system not yet initialised) of a
    robot or of its :func:`describe` data. ``optimal_force``: :math:`F_0` of every cable (default
    :func:`default_optimal_force`)."""
    osim = require_opensim()
    spec = robot_or_spec if isinstance(robot_or_spec, RobotSpec) else describe(robot_or_spec)
    F0 = default_optimal_force(spec) if optimal_force is None else float(optimal_force)
    if not (math.isfinite(F0) and F0 > 0):
        raise ModelError(f"optimal_force: expected a finite force > 0 N, got {optimal_force!r}")
    model = osim.Model()
    model.setName(spec.name)
    model.setGravity(osim.Vec3(*spec.gravity))
    for b in spec.bodies:
        I = b.inertia
        model.addBody(osim.Body(b.name, b.mass, osim.Vec3(*b.com),
                                osim.Inertia(I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2])))

    def frame(name):
        return model.getGround() if name == GROUND else model.getBodySet().get(name)

    for j in spec.joints:
        args = (j.name, frame(j.parent), osim.Vec3(*j.parent_offset.translation),
                osim.Vec3(*euler_xyz(j.parent_offset.rotation)), frame(j.child), osim.Vec3(0, 0, 0),
                osim.Vec3(*euler_xyz(j.child_rotation)))
        if j.kind == "custom":  # its coordinates are named by the spatial transform
            joint = osim.CustomJoint(*args, _spatial_transform(osim, j))
        else:
            joint = (osim.PinJoint if j.kind == "pin" else osim.SliderJoint)(*args)
            joint.upd_coordinates(0).setName(j.coordinates[0])
        model.addJoint(joint)
    model.finalizeFromProperties()
    coords = model.updCoordinateSet()
    for j in spec.joints:
        for k, name in enumerate(j.coordinates):
            coord = coords.get(name)
            coord.setRangeMin(float(j.lower[k]))
            coord.setRangeMax(float(j.upper[k]))
            coord.set_clamped(False)
    for c in spec.cables:
        actuator = osim.PathActuator()
        actuator.setName(c.name)
        actuator.setOptimalForce(F0)
        actuator.setMinControl(c.f_min / F0)
        actuator.setMaxControl(c.f_max / F0)
        for i, (body, xyz) in enumerate(c.points):
            actuator.addNewPathPoint(f"{c.name}-P{i + 1}", frame(body), osim.Vec3(*xyz))
        model.addForce(actuator)
    model.finalizeConnections()
    return model


def _spatial_transform(osim, j: JointSpec):
    """The custom joint's transform: rotations about ``j.axes`` (body-fixed sequence, coordinates in
    order, identity functions), no translation. Functions go in with ``set_function`` (a copy):
    ``setFunction`` adopts the Python-owned object, which later crashes the joint's constructor."""
    st = osim.SpatialTransform()
    for k in range(3):
        axis = st.updTransformAxis(k)
        if k < len(j.coordinates):
            axis.setCoordinateNames(osim.ArrayStr(j.coordinates[k], 1))
            axis.setAxis(osim.Vec3(*j.axes[k]))
            axis.set_function(osim.LinearFunction(1.0, 0.0))
        else:  # an unused rotation (universal joint): any axis independent of the others, never turned
            free = np.cross(j.axes[0], j.axes[1])
            axis.setAxis(osim.Vec3(*(free / np.linalg.norm(free))))
            axis.set_function(osim.Constant(0.0))
    for k in range(3, 6):
        axis = st.updTransformAxis(k)
        axis.setAxis(osim.Vec3(*np.eye(3)[k - 3]))
        axis.set_function(osim.Constant(0.0))
    return st


def export_opensim(robot, path, optimal_force: float | None = None) -> Path:
    """Write ``robot`` as an OpenSim model file (``.osim``); returns the path (module docstring). The
    file is written beside ``path`` under a temporary name, read back as XML with the names it must
    hold (:func:`~.osim_names.check_written`), and only then renamed to ``path``."""
    path = Path(path)
    spec = robot if isinstance(robot, RobotSpec) else describe(robot)
    model = opensim_model(spec, optimal_force)
    model.initSystem()  # let OpenSim check the model before it is written
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=".osim", dir=path.parent)
    os.close(fd)
    try:
        model.printToXML(tmp)
        check_written(tmp, dict(BodySet=[b.name for b in spec.bodies], JointSet=[j.name for j in spec.joints],
                                ForceSet=[c.name for c in spec.cables]), shown=path)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return path
