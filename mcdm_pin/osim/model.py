r"""A Pinocchio model of an OpenSim model's skeleton (:class:`~mcdm_pin.osim.document.Document`).

One Pinocchio joint per moving OpenSim joint, named after it (a ``JointModelComposite`` of the
sub-joints of :mod:`mcdm_pin.osim.joints` when there are several), placed at the joint's parent frame
``F`` in the parent body; a ``WeldJoint``'s child body is fixed to its parent's Pinocchio joint.

Frames: every OpenSim body, and the ground, has a ``BODY`` frame named exactly as the body, placed at
the OpenSim body frame and carrying the body's inertia (mass at ``mass_center``, inertia about the
mass centre in body axes). Every ``PhysicalOffsetFrame`` has an ``OP_FRAME`` named by its OpenSim
path (``/bodyset/scapula/cp_in_scapula``, ``/jointset/GlenoHumeral/scapula_offset``), and so does
every ``Marker`` (``/markerset/Glenoid_Center``, at its location, axes of its frame).

Coordinates: every entry of Pinocchio's ``v`` either carries an OpenSim coordinate (its value in
OpenSim's units, rad or m) or follows one through a function (a coupling, named
``JOINT/AXIS``: a ``CustomJoint``'s second axis on a coordinate, e.g. a knee's translation spline).
``CoordinateCouplerConstraint`` couples the entries of two coordinates; a ``locked`` coordinate is
fixed at its ``default_value`` (a coupling to nothing). A clamped coordinate's ``range`` bounds its
entry (Pinocchio's position limits); others are unbounded. ``PointConstraint``s are kept as loops
(:mod:`mcdm_pin.osim.constraints`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..exceptions import ModelError
from ..model.couplings import Coupling
from .document import Document
from .functions import Constant, Multiplier
from .joints import plan


@dataclass(frozen=True, eq=False)
class OsimModel:
    """A Pinocchio model of an OpenSim skeleton and the maps to OpenSim's coordinates.

    Attributes:
        model: the Pinocchio model (gravity from the file).
        source: the file, for messages.
        velocity_names: name of each ``v`` entry (nv): OpenSim coordinate names, ``JOINT/AXIS`` for
            entries that follow a function.
        coordinates: OpenSim coordinate names in the file's order.
        coordinate_v: the ``v`` entry carrying each coordinate (same order).
        defaults: each coordinate's ``default_value``.
        couplings: :class:`~mcdm_pin.model.couplings.Coupling` list (entries that follow functions,
            coupler constraints, locked coordinates).
        angular: ``v`` indices (3,) of each ``BallJoint``/``FreeJoint``/``ScapulothoracicJoint``
            rotation whose OpenSim speeds are an angular velocity (:mod:`mcdm_pin.osim.speeds`).
        loops: the ``PointConstraint`` elements as ``(name, frame 1 id, frame 2 id)`` (OP_FRAMEs at the two
            points).
        q_index: the ``q`` entry of each ``v`` entry (every joint built here has ``nq == nv``).
        notes: joints whose Pinocchio joint frame is not OpenSim's child frame (a constant
            transform after the last moving axis): their interaction wrench is at the joint frame.
    """

    model: pin.Model
    source: str
    velocity_names: tuple
    coordinates: tuple
    coordinate_v: np.ndarray
    defaults: np.ndarray
    couplings: tuple
    angular: tuple
    loops: tuple
    q_index: np.ndarray
    notes: tuple = ()


def build(doc: Document) -> OsimModel:
    """The :class:`OsimModel` of a read document (module docstring)."""
    model = pin.Model()
    model.name = doc.name
    model.gravity = pin.Motion(np.asarray(doc.gravity, dtype=float), np.zeros(3))
    placed = {doc.ground: (0, pin.SE3.Identity())}  # body -> (pin joint, body frame in it)
    body_frame = {doc.ground: model.addFrame(pin.Frame(doc.ground, 0, 0, pin.SE3.Identity(), pin.FrameType.BODY))}
    names, carriers, dependents, angular, notes = [], {}, [], [], []
    for joint in _ordered(doc):
        where = f"{doc.source}: {joint.tag} {joint.name!r}"
        pbody, X_PF = _frame_in_body(doc, joint.parent, where)
        cbody, X_CM = _frame_in_body(doc, joint.child, where)
        pj, X_jP = placed[pbody]
        p = plan(joint, where)
        if not p.subs:
            jid, X_jC = pj, X_jP * X_PF * p.end * X_CM.inverse()
        else:
            jm, first = _joint_model(p)
            jid = model.addJoint(pj, jm, X_jP * X_PF * first, joint.name)
            X_jC = p.end * X_CM.inverse()
            v0 = model.joints[jid].idx_v
            names += [n for s in p.subs for n in s[2]]
            carriers.update({c: v0 + e for c, e in p.carriers.items()})
            dependents += [(v0 + e, c, f, label) for e, c, f, label in p.dependents]
            angular += [tuple(v0 + p.carriers[c] for c in triple) for triple in p.angular]
            if not p.end.isIdentity(0.0):
                notes.append(f"{joint.tag} {joint.name!r}: a constant transform follows its last moving axis, so "
                             f"its interaction wrench is at the Pinocchio joint frame, not at OpenSim's child frame")
        placed[cbody] = (jid, X_jC)
        mass, com, inertia = doc.bodies[cbody]
        frame = pin.Frame(cbody, jid, body_frame[pbody], X_jC, pin.FrameType.BODY,
                          pin.Inertia(mass, com, 0.5 * (inertia + inertia.T)))
        body_frame[cbody] = model.addFrame(frame, True)
    unplaced = [b for b in doc.bodies if b not in placed]
    if unplaced:
        raise ModelError(f"{doc.source}: body(ies) {unplaced} are the child of no joint reachable from "
                         f"{doc.ground!r}")
    _offset_frames(model, doc, placed, body_frame)
    coords = [c for j in doc.joints for c in j.coordinates]
    if model.nq != model.nv:  # every sub-joint built here has nq == nv: q_i is the i-th v entry's
        raise ModelError(f"{doc.source}: internal: a joint with nq != nv was built")
    q_index = np.arange(model.nv)
    _set_limits(model, coords, carriers, q_index)
    couplings = _couplings(doc, coords, carriers, dependents)
    loops = _loops(model, doc, placed, body_frame)
    return OsimModel(model, doc.source, tuple(names), tuple(c.name for c in coords),
                     np.array([carriers[c.name] for c in coords], dtype=int),
                     np.array([c.default for c in coords]), tuple(couplings), tuple(angular), loops, q_index,
                     tuple(notes))


def _joint_model(p):
    """The joint model of a plan's sub-joints and the placement of the first (a composite takes the
    later placements)."""
    if len(p.subs) == 1:
        return p.subs[0][0], p.subs[0][1]
    comp = pin.JointModelComposite()
    for k, (jm, placement, _) in enumerate(p.subs):
        comp.addJoint(jm, pin.SE3.Identity() if k == 0 else placement)
    return comp, p.subs[0][1]


def _ordered(doc):
    """Joints ordered so that every parent body is placed before its child."""
    by_child, out, placed = {}, [], {doc.ground}
    for j in doc.joints:
        body = _body_of(doc, j.child, f"{doc.source}: {j.tag} {j.name!r}")
        if body in by_child:
            raise ModelError(f"{doc.source}: body {body!r} is the child of two joints ({by_child[body].name!r}, "
                             f"{j.name!r}): closed loops are read as constraints, not joints")
        if body == doc.ground:
            raise ModelError(f"{doc.source}: {j.tag} {j.name!r}: the ground is its child (reversed joints are not read)")
        by_child[body] = j
    pending = list(doc.joints)
    while pending:
        ready = [j for j in pending if _body_of(doc, j.parent, "") in placed]
        if not ready:
            raise ModelError(f"{doc.source}: joint(s) {[j.name for j in pending]} do not connect to "
                             f"{doc.ground!r} (a cycle, or a parent that is no joint's child)")
        for j in ready:
            out.append(j)
            placed.add(_body_of(doc, j.child, ""))
            pending.remove(j)
    return out


def _body_of(doc, path, where) -> str:
    return _frame_in_body(doc, path, where)[0]


def _frame_in_body(doc, path, where):
    """``(body name, placement of the frame in the body)`` of an OpenSim frame path."""
    X = pin.SE3.Identity()
    seen = 0
    while path in doc.frames and doc.frames[path] is not None:
        parent, R, t = doc.frames[path]
        X = pin.SE3(R, t) * X
        path, seen = parent, seen + 1
        if seen > 100:
            raise ModelError(f"{where}: frame {path!r}: offset frames form a cycle")
    if path == f"/{doc.ground}":
        return doc.ground, X
    if path.startswith("/bodyset/") and path[len("/bodyset/"):] in doc.bodies:
        return path[len("/bodyset/"):], X
    raise ModelError(f"{where}: frame {path!r} is no body, ground or PhysicalOffsetFrame of the model")


def _offset_frames(model, doc, placed, body_frame):
    """``OP_FRAME``s of the offset frames and the markers (module docstring)."""
    frames = [(path, path, pin.SE3.Identity()) for path in doc.frames if doc.frames[path] is not None]
    frames += [(f"/markerset/{name}", path, pin.SE3(np.eye(3), np.asarray(p, dtype=float)))
               for name, (path, p) in doc.markers.items()]
    for name, path, offset in frames:
        body, X = _frame_in_body(doc, path, f"{doc.source}: {name}")
        jid, X_jB = placed[body]
        model.addFrame(pin.Frame(name, jid, body_frame[body], X_jB * X * offset, pin.FrameType.OP_FRAME), False)


def _set_limits(model, coords, carriers, q_index):
    lower, upper = model.lowerPositionLimit.copy(), model.upperPositionLimit.copy()
    lower[:], upper[:] = -np.inf, np.inf
    for c in coords:
        if c.clamped and q_index[carriers[c.name]] >= 0:
            lower[q_index[carriers[c.name]]], upper[q_index[carriers[c.name]]] = c.range
    model.lowerPositionLimit, model.upperPositionLimit = lower, upper


def _couplings(doc, coords, carriers, dependents):
    """Couplings: function-driven entries, coordinate couplers, locked coordinates."""
    out = [Coupling(v, carriers[c], (0.0,) * 5, label, f) for v, c, f, label in dependents]
    known = {c.name for c in coords}
    for con in doc.constraints:
        if con.tag != "CoordinateCouplerConstraint":
            continue
        fx = con.fields
        for key in ("independent", "dependent"):
            if fx[key] not in known:
                raise ModelError(f"{doc.source}: CoordinateCouplerConstraint {con.name!r}: unknown {key} coordinate "
                                 f"{fx[key]!r}")
        f = Multiplier(fx["scale"], fx["function"]) if fx["scale"] != 1.0 else fx["function"]
        out.append(Coupling(carriers[fx["dependent"]], carriers[fx["independent"]], (0.0,) * 5, con.name, f))
    for c in coords:
        if c.locked:
            out.append(Coupling(carriers[c.name], -1, (c.default, 0.0, 0.0, 0.0, 0.0), f"{c.name} (locked)",
                                Constant(c.default)))
    return out


def _loops(model, doc, placed, body_frame):
    out = []
    for con in doc.constraints:
        if con.tag != "PointConstraint":
            continue
        where = f"{doc.source}: PointConstraint {con.name!r}"
        ids = []
        for k, (path, point) in enumerate(zip(con.fields["frames"], con.fields["points"])):
            body, X = _frame_in_body(doc, path, where)
            jid, X_jB = placed[body]
            X_point = X_jB * X * pin.SE3(np.eye(3), np.asarray(point, dtype=float))
            ids.append(model.addFrame(pin.Frame(f"{con.name}/body_{k + 1}", jid, body_frame[body], X_point,
                                                pin.FrameType.OP_FRAME), False))
        out.append((con.name, ids[0], ids[1]))
    return tuple(out)
