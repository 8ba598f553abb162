r"""Physical joints: what the paper calls a joint, on any ``pin.Model``.

A physical joint is either one Pinocchio joint (a native ``JointModelSpherical``, a free-flyer, a
planar, a revolute joint of any axis...) or a *group* of Pinocchio joints in series that meet at one
point and are joined by massless bodies: three revolute joints with orthogonal axes (an xyz Euler
triple, the form a URDF can express), two revolute joints (a universal joint), two prismatic joints and
a revolute one (a planar joint), two or three prismatic joints (a translation).

Every physical joint has an **interaction wrench**: the force and moment the parent exerts on the child
through the joint, at the joint point, in the child frame (the last member's joint frame, where RNEA's
``data.f`` lives); the **socket frame** is fixed in the parent at the joint point and equals the child
frame at the joint's neutral configuration (the first member's placement). A ``free`` joint transmits
nothing: its wrench is zero whenever the equation of motion holds, and it takes no cone. Cones apply
to ``spherical`` joints, whose socket axis (default +z of the socket frame) is the direction in which the
socket pushes the ball.

Types: ``spherical``, ``revolute``, ``prismatic``, ``universal``, ``planar``, ``translation``,
``free``, ``helical``, ``ellipsoid``, ``composite`` (a ``JointModelComposite`` built in code).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Iterable

import numpy as np
import pinocchio as pin

from ..exceptions import ModelError
from ..vocabulary import CONE_TYPES, JOINT_TYPES

GEOM_TOL = 1e-9  # m and rad: members "meet" and axes are "orthogonal" within this
_MASS_TOL = 0.0  # intermediate bodies of a group must be exactly massless


@dataclass(frozen=True)
class PhysicalJoint:
    """One physical joint (module docstring).

    Attributes:
        name: its name.
        type: one of :data:`JOINT_TYPES`.
        pin_joints: the Pinocchio joint names, parent side first.
        pin_ids: their ids.
        child_id: the joint whose frame is the child frame (the last member).
        parent_id: the Pinocchio joint of the parent body (0 = the fixed base).
        socket_placement: the socket frame relative to ``parent_id``'s frame.
        idx_q, idx_v: the joint's entries in the configuration and in the velocity.
        parametrization: spherical joints: ``euler-xyz`` (a revolute triple), ``quaternion`` or ``zyx``.
        socket_axis: unit vector, socket frame (spherical joints).
        alpha, beta: weights of |F|^2 (N^-2) and |M|^2 (N^-2 m^-2) in the interaction objective.
        cone_deg: the largest interaction angle the joint tolerates (spherical joints), or ``None``.
    """

    name: str
    type: str
    pin_joints: tuple[str, ...]
    pin_ids: tuple[int, ...]
    child_id: int
    parent_id: int
    socket_placement: pin.SE3
    idx_q: np.ndarray
    idx_v: np.ndarray
    parametrization: str | None = None
    socket_axis: np.ndarray = dataclasses.field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    alpha: float = 1.0
    beta: float = 0.0
    cone_deg: float | None = None

    @property
    def nv(self) -> int:
        return len(self.idx_v)

    @property
    def nq(self) -> int:
        return len(self.idx_q)

    @property
    def urdf_joints(self) -> tuple[str, ...]:
        """The Pinocchio joints (URDF joint names for a model loaded from a URDF)."""
        return self.pin_joints

    def with_settings(self, *, alpha=None, beta=None, cone_deg=None, socket_axis=None, name=None) -> "PhysicalJoint":
        """A copy with other weights, cone or socket axis (checked)."""
        changes: dict = {}
        for key, value in (("alpha", alpha), ("beta", beta)):
            if value is not None:
                value = float(value)
                if not (math.isfinite(value) and value >= 0):
                    raise ModelError(f"joint {self.name!r}: {key} must be finite and >= 0, got {value!r}")
                changes[key] = value
        if cone_deg is not None:
            if self.type not in CONE_TYPES:
                raise ModelError(f"joint {self.name!r} is {self.type}: a stability cone applies to spherical "
                                 f"joints only (or a composite joint: a body's several joints in MJCF)")
            cone_deg = float(cone_deg)
            if not 0.0 < cone_deg < 90.0:
                raise ModelError(f"joint {self.name!r}: cone_deg must be in (0, 90) degrees, got {cone_deg!r}")
            changes["cone_deg"] = cone_deg
        if socket_axis is not None:
            axis = np.asarray(socket_axis, dtype=float).reshape(-1)
            norm = float(np.linalg.norm(axis)) if axis.shape == (3,) else 0.0
            if axis.shape != (3,) or not np.all(np.isfinite(axis)) or abs(norm - 1.0) > 1e-6:
                raise ModelError(f"joint {self.name!r}: socket_axis must be a unit 3-vector, got "
                                 f"{np.asarray(socket_axis).tolist()}")
            changes["socket_axis"] = axis / norm
        if name is not None:
            changes["name"] = str(name)
        return dataclasses.replace(self, **changes)


def classify(joint_model) -> tuple[str, str | None]:
    """``(type, parametrization)`` of a single Pinocchio joint model."""
    short = joint_model.shortname()
    if short in ("JointModelSpherical",):
        return "spherical", "quaternion"
    if short == "JointModelSphericalZYX":
        return "spherical", "zyx"
    if short.startswith(("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRUB")) or short in (
            "JointModelRevoluteUnaligned", "JointModelRevoluteUnboundedUnaligned"):
        return "revolute", None
    if short.startswith(("JointModelPX", "JointModelPY", "JointModelPZ")) or short == "JointModelPrismaticUnaligned":
        return "prismatic", None
    if short.startswith(("JointModelHX", "JointModelHY", "JointModelHZ")) or short == "JointModelHelicalUnaligned":
        return "helical", None
    simple = {"JointModelUniversal": "universal", "JointModelPlanar": "planar",
              "JointModelTranslation": "translation", "JointModelFreeFlyer": "free",
              "JointModelEllipsoid": "ellipsoid", "JointModelComposite": "composite"}
    if short in simple:
        return simple[short], None
    raise ModelError(f"Pinocchio joint type {short} is not supported (a mimic joint has no coordinate "
                     f"of its own)")


def _resolve(model: pin.Model, joint) -> int:
    if isinstance(joint, (int, np.integer)) and not isinstance(joint, bool):
        if not 0 < int(joint) < model.njoints:
            raise ModelError(f"joint id {int(joint)} is out of range 1..{model.njoints - 1}")
        return int(joint)
    if isinstance(joint, str) and model.existJointName(joint):
        return int(model.getJointId(joint))
    names = [model.names[j] for j in range(1, model.njoints)]
    shown = ", ".join(repr(n) for n in names[:25]) + (f", ... ({len(names)} in all)" if len(names) > 25 else "")
    raise ModelError(f"unknown joint {joint!r}; expected one of {shown}")


def _make(model, name, type_, ids, parametrization) -> PhysicalJoint:
    jms = [model.joints[j] for j in ids]
    idx_q = np.concatenate([np.arange(jm.idx_q, jm.idx_q + jm.nq) for jm in jms]).astype(int)
    idx_v = np.concatenate([np.arange(jm.idx_v, jm.idx_v + jm.nv) for jm in jms]).astype(int)
    free = type_ == "free"
    return PhysicalJoint(name=name, type=type_, pin_joints=tuple(model.names[j] for j in ids),
                         pin_ids=tuple(ids), child_id=ids[-1], parent_id=int(model.parents[ids[0]]),
                         socket_placement=model.jointPlacements[ids[0]].copy(), idx_q=idx_q, idx_v=idx_v,
                         parametrization=parametrization, alpha=0.0 if free else 1.0)


def single(model: pin.Model, joint, name: str | None = None) -> PhysicalJoint:
    """The physical joint of one Pinocchio joint (name or id)."""
    j = _resolve(model, joint)
    type_, par = classify(model.joints[j])
    return _make(model, name or model.names[j], type_, [j], par)


_GROUPS = {"spherical": ("R", "R", "R"), "universal": ("R", "R"), "revolute": ("R",), "prismatic": ("P",),
           "helical": ("H",), "free": None, "translation": None, "planar": None}


def group(model: pin.Model, name: str, type_: str, joints) -> PhysicalJoint:
    """A physical joint made of several Pinocchio joints (module docstring): checked to be in series,
    to meet at one point, to have massless bodies between them, and to have the axes its type needs.

    ``joints`` with a single entry is the same as :func:`single` (its type must match ``type_``)."""
    if type_ not in JOINT_TYPES:
        raise ModelError(f"joint {name!r}: unknown type {type_!r}; expected one of {', '.join(JOINT_TYPES)}")
    ids = [_resolve(model, j) for j in joints]
    if not ids:
        raise ModelError(f"joint {name!r}: no Pinocchio joint given")
    if len(set(ids)) != len(ids):
        raise ModelError(f"joint {name!r}: a Pinocchio joint is listed twice")
    if len(ids) == 1:
        found, par = classify(model.joints[ids[0]])
        if found != type_:
            raise ModelError(f"joint {name!r}: {model.names[ids[0]]!r} is a {model.joints[ids[0]].shortname()} "
                             f"({found}), not a {type_} joint")
        return _make(model, name, type_, ids, par)
    kinds = []
    for j in ids:
        t, _ = classify(model.joints[j])
        if t not in ("revolute", "prismatic"):
            raise ModelError(f"joint {name!r}: a group is made of revolute and prismatic joints; "
                             f"{model.names[j]!r} is a {model.joints[j].shortname()}")
        kinds.append("R" if t == "revolute" else "P")
    _check_series(model, name, ids)
    axes = _axes(model, ids)
    labels = [model.names[j] for j in ids]
    if type_ == "spherical":
        _need(name, type_, kinds == ["R", "R", "R"], "three revolute joints", labels)
        _orthogonal(name, labels, axes)
        return _make(model, name, type_, ids, "euler-xyz")
    if type_ == "universal":
        _need(name, type_, kinds == ["R", "R"], "two revolute joints", labels)
        _orthogonal(name, labels, axes)
    elif type_ == "translation":
        _need(name, type_, set(kinds) == {"P"} and len(ids) in (2, 3), "two or three prismatic joints", labels)
        if np.linalg.matrix_rank(np.array(axes), tol=1e-6) < len(ids):
            raise ModelError(f"joint {name!r}: the axes of {labels} are not linearly independent")
    elif type_ == "planar":
        _need(name, type_, sorted(kinds) == ["P", "P", "R"], "two prismatic joints and a revolute joint", labels)
        p = [a for a, k in zip(axes, kinds) if k == "P"]
        r = [a for a, k in zip(axes, kinds) if k == "R"][0]
        n = np.cross(p[0], p[1])
        if np.linalg.norm(n) < 1e-6 or abs(abs(float(n @ r)) / np.linalg.norm(n) - 1.0) > GEOM_TOL:
            raise ModelError(f"joint {name!r}: a planar joint's revolute axis must be normal to the plane of its "
                             f"two (non-parallel) prismatic axes ({labels})")
    else:
        raise ModelError(f"joint {name!r}: a {type_} joint cannot be made of several joints ({labels})")
    return _make(model, name, type_, ids, None)


def _need(name, type_, ok, what, labels):
    if not ok:
        raise ModelError(f"joint {name!r}: a {type_} joint made of several joints needs {what}, got {labels}")


def _check_series(model, name, ids):
    for k in range(1, len(ids)):
        if model.parents[ids[k]] != ids[k - 1]:
            raise ModelError(f"joint {name!r}: its joints must be in series; the parent of "
                             f"{model.names[ids[k]]!r} is {model.names[model.parents[ids[k]]]!r}, not "
                             f"{model.names[ids[k - 1]]!r}")
        t = model.jointPlacements[ids[k]].translation
        if np.linalg.norm(t) > GEOM_TOL:
            raise ModelError(f"joint {name!r}: its joints must meet at one point; {model.names[ids[k]]!r} sits "
                             f"{np.linalg.norm(t):.3g} m from {model.names[ids[k - 1]]!r}")
    for k in range(len(ids) - 1):
        j = ids[k]
        inertia = model.inertias[j]
        if inertia.mass > _MASS_TOL or np.abs(inertia.inertia).max() > 0:
            raise ModelError(f"joint {name!r}: the body between {model.names[j]!r} and {model.names[ids[k + 1]]!r} "
                             f"must be massless; it has mass {inertia.mass:.6g} kg (or inertia)")
        others = [c for c in range(1, model.njoints) if model.parents[c] == j and c != ids[k + 1]]
        if others:
            raise ModelError(f"joint {name!r}: the massless body after {model.names[j]!r} also carries joint "
                             f"{model.names[others[0]]!r}; nothing may hang between a joint's members")


def _axes(model, ids) -> list[np.ndarray]:
    """Each member's axis (rotation or translation) in the world frame at the neutral configuration."""
    data = model.createData()
    pin.computeJointJacobians(model, data, pin.neutral(model))
    out = []
    for j in ids:
        col = pin.getJointJacobian(model, data, j, pin.ReferenceFrame.WORLD)[:, model.joints[j].idx_v]
        kind, _ = classify(model.joints[j])
        v = col[3:] if kind == "revolute" else col[:3]
        out.append(v / np.linalg.norm(v))
    return out


def _orthogonal(name, labels, axes):
    for a in range(len(axes)):
        for b in range(a + 1, len(axes)):
            c = abs(float(axes[a] @ axes[b]))
            if c > GEOM_TOL:
                raise ModelError(f"joint {name!r}: the axes of {labels[a]!r} and {labels[b]!r} must be orthogonal; "
                                 f"they make {np.degrees(np.arccos(min(c, 1.0))):.6g} deg")


def physical_joints(model: pin.Model, groups: Iterable = ()) -> tuple[PhysicalJoint, ...]:
    """Every Pinocchio joint of ``model`` as a physical joint, except those gathered by ``groups``
    (``(name, type, [joint names or ids])`` each, see :func:`group`), in the order of their first
    Pinocchio joint. Weights and cones: :meth:`PhysicalJoint.with_settings`."""
    made = [group(model, name, type_, members) for name, type_, members in groups]
    taken: dict[int, str] = {}
    for pj in made:
        for j in pj.pin_ids:
            if j in taken:
                raise ModelError(f"Pinocchio joint {model.names[j]!r} belongs to both {taken[j]!r} and {pj.name!r}")
            taken[j] = pj.name
    made += [single(model, j) for j in range(1, model.njoints) if j not in taken]
    made.sort(key=lambda pj: pj.pin_ids[0])
    names = [pj.name for pj in made]
    if len(set(names)) != len(names):
        raise ModelError(f"physical joint names must be unique, got {names}")
    return tuple(made)


def resolve_joints(model: pin.Model, joints) -> tuple[PhysicalJoint, ...]:
    """Physical joints from physical joints, Pinocchio joint names or ids (``None``: every joint)."""
    if joints is None:
        return physical_joints(model)
    return tuple(j if isinstance(j, PhysicalJoint) else single(model, j) for j in joints)


def massless_members(joints: Iterable[PhysicalJoint]) -> dict[int, str]:
    """Pinocchio joints whose (massless) body lies inside a physical joint: ``{joint id: joint name}``."""
    return {pid: j.name for j in joints for pid in j.pin_ids[:-1]}
