r"""Each OpenSim joint as Pinocchio sub-joints: the kinematics of OpenSim's (Simbody's) mobilizers.

An OpenSim joint moves its child frame ``M`` (``socket_child_frame``) relative to its parent frame
``F`` (``socket_parent_frame``) by ``X_FM(q)``; the child body frame is ``X_FM X_BM^{-1}`` with
``X_BM`` the child frame in the child body. :func:`plan` gives, per joint, the Pinocchio sub-joints
in series (each with its placement in the previous one's frame, the first in ``F``), the transform
``end`` from the last sub-joint's frame to ``M``, and which sub-joint entry carries which OpenSim
coordinate:

=======================  ==========================================================================
``WeldJoint``            no sub-joint: ``X_FM = I``
``PinJoint``             ``RZ`` (rotation about ``F``'s z)
``SliderJoint``          ``PX``
``UniversalJoint``       ``RX, RY`` (body-fixed)
``GimbalJoint``          ``RX, RY, RZ`` (body-fixed x-y-z)
``BallJoint``            ``RX, RY, RZ``; OpenSim's speeds are the angular velocity (see below)
``FreeJoint``            ``PX, PY, PZ, RX, RY, RZ`` (translation in ``F``); speeds as ``BallJoint``
``CustomJoint``          per ``TransformAxis`` with a coordinate: translations first (prismatic along
                         the axis, in ``F``), then rotations (revolute about the axis, body-fixed, in
                         the order rotation1, 2, 3); constant functions are fixed offsets/rotations
``ScapulothoracicJoint`` ``JointModelEllipsoid`` then a revolute (winging), below
=======================  ==========================================================================

``CustomJoint`` coordinates: a coordinate is *carried* by its first transform axis whose function is
``f(x) = x`` (its Pinocchio entry is the coordinate itself); every other axis it drives is a
dependent Pinocchio entry ``y = f(x)`` (a coupling, :mod:`mcdm_pin.model.couplings`). A coordinate
that no axis carries with ``f(x) = x``, or an axis with several coordinates, is refused.

``ScapulothoracicJoint`` (OpenSim's ``ScapulothoracicJoint.cpp``): a Simbody ellipsoid mobilizer
whose frame ``F'`` is ``F`` turned by ``Rz(pi/2)``, radii ``(r_y, r_x, r_z)`` (swapped to that
frame), coordinates abduction, elevation, upward rotation (body-fixed x-y-z angles); its moving
frame ``E`` carries a massless body ``B1 = E Rz(-pi/2)``; the winging pin turns ``B1`` about the unit
axis ``d = (-sin w, cos w, 0)`` through ``o = (o_x, o_y, 0)`` (``w``, ``o``: the winging axis
direction and origin), and ``M`` is the pin's moving frame. Pinocchio's ``JointModelEllipsoid``
has Simbody's map (rotation ``Rx(q0) Ry(q1) Rz(q2)``, origin ``diag(r) Rx(q0) Ry(q1) e_z``), so the
sub-joints are: the ellipsoid (radii swapped) placed at ``F Rz(pi/2)``, then a revolute about ``d``
placed at ``Rz(-pi/2) T(o)``, with ``end = T(-o)``. The speeds differ: OpenSim's three are the
angular velocity of ``E`` in ``F'``, in ``F'`` axes (as for ``BallJoint`` and ``FreeJoint``),
Pinocchio's the angle rates (:mod:`mcdm_pin.osim.speeds` maps them).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..exceptions import ModelError
from .functions import constant_value, is_identity

_UNIT = np.eye(3)


@dataclass
class Plan:
    """The Pinocchio form of one OpenSim joint (module docstring).

    Attributes:
        subs: ``(joint model, placement, entry names)`` per sub-joint.
        end: last sub-joint frame -> ``M``.
        carriers: OpenSim coordinate -> index into the joint's velocity entries.
        dependents: ``(entry index, coordinate, function, label)`` of entries ``y = f(coordinate)``.
        angular: triples of coordinates whose OpenSim speeds are an angular velocity in ``F'``.
    """

    subs: list = field(default_factory=list)
    end: pin.SE3 = field(default_factory=pin.SE3.Identity)
    carriers: dict = field(default_factory=dict)
    dependents: list = field(default_factory=list)
    angular: list = field(default_factory=list)

    def add(self, jmodel, placement, name) -> int:
        """Append a one-entry sub-joint; return its entry index."""
        self.subs.append((jmodel, placement, (name,)))
        return sum(len(s[2]) for s in self.subs) - 1


def revolute(axis):
    unit = [k for k in range(3) if np.allclose(axis, _UNIT[k], rtol=0, atol=0)]
    return (pin.JointModelRX, pin.JointModelRY, pin.JointModelRZ)[unit[0]]() if unit else \
        pin.JointModelRevoluteUnaligned(np.asarray(axis, dtype=float))


def prismatic(axis):
    unit = [k for k in range(3) if np.allclose(axis, _UNIT[k], rtol=0, atol=0)]
    return (pin.JointModelPX, pin.JointModelPY, pin.JointModelPZ)[unit[0]]() if unit else \
        pin.JointModelPrismaticUnaligned(np.asarray(axis, dtype=float))


def _rot(axis, angle) -> pin.SE3:
    return pin.SE3(pin.AngleAxis(angle, np.asarray(axis, dtype=float)).matrix(), np.zeros(3))


def plan(joint, where: str) -> Plan:
    """The :class:`Plan` of a :class:`~mcdm_pin.osim.document.Joint` (``where`` prefixes messages)."""
    names = [c.name for c in joint.coordinates]
    simple = {"WeldJoint": (), "PinJoint": ("RZ",), "SliderJoint": ("PX",), "UniversalJoint": ("RX", "RY"),
              "GimbalJoint": ("RX", "RY", "RZ"), "BallJoint": ("RX", "RY", "RZ"),
              "FreeJoint": ("PX", "PY", "PZ", "RX", "RY", "RZ")}
    if joint.tag in simple:
        kinds = simple[joint.tag]
        if len(names) != len(kinds):
            raise ModelError(f"{where}: expected {len(kinds)} coordinate(s), got {len(names)}")
        p = Plan()
        order = names[3:] + names[:3] if joint.tag == "FreeJoint" else names  # OpenSim: rotations first
        for kind, cname in zip(kinds, order):
            axis = _UNIT["XYZ".index(kind[1])]
            p.carriers[cname] = p.add(revolute(axis) if kind[0] == "R" else prismatic(axis), pin.SE3.Identity(), cname)
        if joint.tag in ("BallJoint", "FreeJoint"):
            p.angular.append(tuple(names[:3]))
        return p
    if joint.tag == "CustomJoint":
        return _custom(joint, names, where)
    if joint.tag == "ScapulothoracicJoint":
        return _scapulothoracic(joint, names, where)
    raise ModelError(f"{where}: joint type {joint.tag} is not supported; expected one of WeldJoint, PinJoint, "
                     f"SliderJoint, UniversalJoint, GimbalJoint, BallJoint, FreeJoint, CustomJoint, "
                     f"ScapulothoracicJoint")


def _custom(joint, names, where) -> Plan:
    axes = joint.axes
    if len(axes) != 6 or [a.name for a in axes] != ["rotation1", "rotation2", "rotation3", "translation1",
                                                     "translation2", "translation3"]:
        raise ModelError(f"{where}: a SpatialTransform needs the 6 TransformAxis rotation1..3, translation1..3, "
                         f"got {[a.name for a in axes]}")
    carrier_axis = {}
    for k, ax in enumerate(axes):
        if len(ax.coordinates) > 1:
            raise ModelError(f"{where}, TransformAxis {ax.name!r}: {len(ax.coordinates)} coordinates; a function "
                             f"of one coordinate is read (multivariate functions are not)")
        for c in ax.coordinates:
            if c not in names:
                raise ModelError(f"{where}, TransformAxis {ax.name!r}: coordinate {c!r} is not one of the joint's "
                                 f"coordinates {names}")
            if ax.function is None:
                raise ModelError(f"{where}, TransformAxis {ax.name!r}: no function")
            if c not in carrier_axis and is_identity(ax.function):
                carrier_axis[c] = k
    missing = [c for c in names if c not in carrier_axis]
    if missing:
        raise ModelError(f"{where}: coordinate(s) {missing} drive no TransformAxis by f(x) = x (a LinearFunction "
                         f"with coefficients 1 0); such joints are not read")
    p = Plan()
    pending = pin.SE3.Identity()  # the fixed transform before the next sub-joint
    for k in (3, 4, 5, 0, 1, 2):  # translations (in F: they commute) then rotations, body-fixed, in order
        ax = axes[k]
        if not ax.coordinates:
            value = 0.0 if ax.function is None else constant_value(ax.function)
            if value is None:
                raise ModelError(f"{where}, TransformAxis {ax.name!r}: a function of no coordinate must be constant")
            step = _rot(ax.axis, value) if ax.rotation else pin.SE3(np.eye(3), value * ax.axis)
            pending = pending * step
            continue
        c = ax.coordinates[0]
        label = f"{joint.name}/{ax.name}"
        entry = p.add(revolute(ax.axis) if ax.rotation else prismatic(ax.axis), pending,
                      c if carrier_axis[c] == k else label)
        pending = pin.SE3.Identity()
        if carrier_axis[c] == k:
            p.carriers[c] = entry
        else:
            p.dependents.append((entry, c, ax.function, label))
    p.end = pending
    if not p.subs and names:
        raise ModelError(f"{where}: coordinates {names} move no axis")
    return p


def _scapulothoracic(joint, names, where) -> Plan:
    if len(names) != 4:
        raise ModelError(f"{where}: expected 4 coordinates (abduction, elevation, upward rotation, winging), "
                         f"got {len(names)}")
    rx, ry, rz = joint.extra["radii"]
    if not all(np.isfinite([rx, ry, rz])) or min(rx, ry, rz) <= 0:
        raise ModelError(f"{where}: thoracic_ellipsoid_radii_x_y_z must be 3 positive numbers, got {joint.extra['radii']}")
    w = joint.extra["winging_direction"]
    o = np.array([*joint.extra["winging_origin"], 0.0])
    d = np.array([-np.sin(w), np.cos(w), 0.0])
    turn = pin.SE3(pin.AngleAxis(np.pi / 2, np.array([0.0, 0.0, 1.0])).matrix(), np.zeros(3))
    p = Plan()
    p.subs.append((pin.JointModelEllipsoid(ry, rx, rz), turn, tuple(names[:3])))
    for k in range(3):
        p.carriers[names[k]] = k
    p.carriers[names[3]] = p.add(revolute(d), turn.inverse() * pin.SE3(np.eye(3), o), names[3])
    p.end = pin.SE3(np.eye(3), -o)
    p.angular.append(tuple(names[:3]))
    return p
