"""An OpenSim ``.osim`` file read as plain data: bodies, frames, joints, coordinates, constraints.

Nothing here knows Pinocchio (:mod:`mcdm_pin.osim.model` builds the model). Only OpenSim 4 files
(``<OpenSimDocument Version="40000">`` or later: sockets and ``PhysicalOffsetFrame``) are read; a
file from OpenSim 3 is refused (open and save it in OpenSim 4 to convert it).

Frames are named by their OpenSim path: the ground ``/ground``, body ``B`` ``/bodyset/B``, a frame
``F`` a body owns ``/bodyset/B/F``, a frame a joint ``J`` owns ``/jointset/J/F``. A socket path is
read relative to the component that holds the socket (``..`` is its owner), or absolute.
Orientations are OpenSim's body-fixed x-y-z angles: ``R = Rx(a) Ry(b) Rz(c)``.
"""

from __future__ import annotations

import posixpath
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..exceptions import ModelError
from .functions import FUNCTION_TAGS, read_function

# sets the skeleton reader leaves to others (the forces: mcdm_pin.osim.paths) or has no use for
# (listed in the notes when not empty)
IGNORED_SETS = ("ForceSet", "ContactGeometrySet", "ProbeSet", "ControllerSet", "ComponentSet")


@dataclass(frozen=True)
class Coordinate:
    """One OpenSim ``Coordinate`` (values in rad or m)."""

    name: str
    joint: str
    default: float
    range: tuple
    clamped: bool
    locked: bool


@dataclass(frozen=True)
class Axis:
    """A ``CustomJoint``'s ``TransformAxis``: ``rotation1..3`` or ``translation1..3``."""

    name: str
    coordinates: tuple
    axis: np.ndarray
    function: object

    @property
    def rotation(self) -> bool:
        return self.name.startswith("rotation")


@dataclass(frozen=True)
class Joint:
    """One joint: its tag (``PinJoint``, ``CustomJoint``...), frames (paths) and coordinates.
    ``axes``: a ``CustomJoint``'s transform axes; ``extra``: the ``ScapulothoracicJoint``'s
    ellipsoid radii and winging axis."""

    tag: str
    name: str
    parent: str
    child: str
    coordinates: tuple
    axes: tuple = ()
    extra: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Constraint:
    """``PointConstraint`` (``frames``, ``points``) or ``CoordinateCouplerConstraint``
    (``independent``, ``dependent``, ``function``, ``scale``)."""

    tag: str
    name: str
    fields: dict


@dataclass
class Document:
    """What :func:`read_osim` reads."""

    source: str
    name: str
    ground: str
    gravity: np.ndarray
    bodies: dict        # name -> (mass, com (3,), inertia (3, 3) about the com, body axes)
    frames: dict        # path -> (parent path, rotation (3, 3), translation (3,))
    joints: list
    constraints: list
    notes: list
    root: object = None  # the parsed ``<Model>`` element (the forces' reader reads it)
    markers: dict = field(default_factory=dict)  # name -> (frame path, location (3,))


def rotation_xyz(angles) -> np.ndarray:
    """``Rx(a) Ry(b) Rz(c)`` (OpenSim's body-fixed x-y-z orientation)."""
    out = np.eye(3)
    for k, t in enumerate(angles):
        c, s = np.cos(t), np.sin(t)
        i, j = [(1, 2), (2, 0), (0, 1)][k]
        r = np.eye(3)
        r[i, i], r[i, j], r[j, i], r[j, j] = c, -s, s, c
        out = out @ r
    return out


def _text(el, tag, where, default=None):
    node = el.find(tag)
    if node is None or node.text is None:
        if default is not None:
            return default
        raise ModelError(f"{where}: missing <{tag}>")
    return node.text.strip()


def _vec(el, tag, where, n=3, default=None, finite=True):
    text = _text(el, tag, where, None if default is None else " ".join(map(str, default)))
    try:
        v = np.array([float(t) for t in text.split()])
    except ValueError:
        raise ModelError(f"{where}: <{tag}> must hold {n} numbers, got {text!r}") from None
    if v.shape != (n,) or not np.all(np.isfinite(v) if finite else ~np.isnan(v)):
        raise ModelError(f"{where}: <{tag}> must hold {n} {'finite ' if finite else ''}numbers, got {text!r}")
    return v


def _flag(el, tag, where) -> bool:
    text = _text(el, tag, where, "false").lower()
    if text not in ("true", "false", "1", "0"):
        raise ModelError(f"{where}: <{tag}> must be true or false, got {text!r}")
    return text in ("true", "1")


def _objects(root, set_tag):
    node = root.find(set_tag)
    if node is None:
        return []
    objs = node.find("objects")
    return list(objs) if objs is not None else []


def read_osim(path) -> Document:
    """Read the ``.osim`` file ``path`` (module docstring). Raises :class:`ModelError` naming the
    file and the element for what the file lacks or holds in a form this reader does not take."""
    path = Path(path)
    src = str(path)
    if not path.is_file():
        raise ModelError(f"{src}: OpenSim model file not found")
    try:
        doc = ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise ModelError(f"{src}: not readable XML: {exc}") from None
    version = int(doc.get("Version", "0") or 0)
    model = doc.find("Model")
    if doc.tag != "OpenSimDocument" or model is None:
        raise ModelError(f"{src}: expected <OpenSimDocument><Model>, got <{doc.tag}>")
    if version < 40000:
        raise ModelError(f"{src}: OpenSimDocument Version={version}: files before OpenSim 4 (40000) have no "
                         f"sockets; open and save the model in OpenSim 4 to convert it")
    for tag, unit in (("length_units", "meters"), ("force_units", "N")):
        got = _text(model, tag, src, unit)
        if got != unit:
            raise ModelError(f"{src}: <{tag}> {got!r}: only {unit!r} is read")
    ground_el = model.find("Ground")
    ground = ground_el.get("name", "ground") if ground_el is not None else "ground"
    out = Document(src, model.get("name", path.stem), ground, _vec(model, "gravity", src, default=(0, -9.80665, 0)),
                   {}, {f"/{ground}": None}, [], [], [], model)
    if ground_el is not None:
        _owned_frames(out, ground_el, f"/{ground}")
    for el in _objects(model, "BodySet"):
        _read_body(out, el)
    for el in _objects(model, "JointSet"):
        out.joints.append(_read_joint(out, el))
    for el in _objects(model, "ConstraintSet"):
        c = _read_constraint(out, el)
        if c is not None:
            out.constraints.append(c)
    for el in _objects(model, "MarkerSet"):
        where = f"{src}: Marker {el.get('name')!r}"
        frame = _resolve(f"/markerset/{el.get('name')}", _text(el, "socket_parent_frame", where))
        out.markers[el.get("name")] = (frame, _vec(el, "location", where, default=(0, 0, 0)))
    for el in model:
        count = len(_objects(model, el.tag)) if el.tag.endswith("Set") else 0
        if el.tag in ("BodySet", "JointSet", "ConstraintSet", "MarkerSet") or not count:
            continue
        if el.tag not in IGNORED_SETS:
            raise ModelError(f"{src}: <{el.tag}> holds {count} component(s); the reader does not take them")
        if el.tag != "ForceSet":
            out.notes.append(f"{el.tag}: {count} component(s) not read (no use for the cable forces)")
    return out


def _owned_frames(doc, el, owner_path):
    """The ``PhysicalOffsetFrame``s in an element's ``<components>`` or ``<frames>``."""
    for holder in ("components", "frames"):
        node = el.find(holder)
        for child in (node if node is not None else []):
            where = f"{doc.source}: {child.tag} {child.get('name')!r} (in {owner_path})"
            if child.tag != "PhysicalOffsetFrame":
                raise ModelError(f"{where}: only PhysicalOffsetFrame components are read")
            path = f"{owner_path}/{child.get('name')}"
            parent = _resolve(owner_path + "/" + child.get("name"), _text(child, "socket_parent", where))
            R = rotation_xyz(_vec(child, "orientation", where, default=(0, 0, 0)))
            doc.frames[path] = (parent, R, _vec(child, "translation", where, default=(0, 0, 0)))


def _resolve(holder_path: str, socket: str) -> str:
    """The absolute path of ``socket`` read from the component at ``holder_path``."""
    if socket.startswith("/"):
        return posixpath.normpath(socket)
    return posixpath.normpath(posixpath.join(holder_path, socket))


def _read_body(doc, el):
    name = el.get("name")
    where = f"{doc.source}: Body {name!r}"
    if el.tag != "Body":
        raise ModelError(f"{where}: <{el.tag}> in the BodySet is not supported (expected <Body>)")
    mass = float(_text(el, "mass", where))
    I6 = _vec(el, "inertia", where, 6)
    if not np.isfinite(mass) or mass < 0:
        raise ModelError(f"{where}: <mass> must be finite and >= 0, got {mass}")
    I = np.array([[I6[0], I6[3], I6[4]], [I6[3], I6[1], I6[5]], [I6[4], I6[5], I6[2]]])
    doc.bodies[name] = (mass, _vec(el, "mass_center", where, default=(0, 0, 0)), I)
    doc.frames[f"/bodyset/{name}"] = None
    _owned_frames(doc, el, f"/bodyset/{name}")


def _read_coordinates(doc, el, jname):
    node = el.find("coordinates")
    out = []
    for c in (node if node is not None else []):
        cname = c.get("name")
        where = f"{doc.source}: Coordinate {cname!r} of joint {jname!r}"
        if _flag(c, "prescribed", where) and c.find("prescribed_function") is not None and len(c.find("prescribed_function")):
            raise ModelError(f"{where}: prescribed=true: a motion prescribed as a function of time is not "
                             f"read; give that motion as the trajectory instead")
        out.append(Coordinate(cname, jname, float(_text(c, "default_value", where, "0")),
                              tuple(_vec(c, "range", where, 2, default=(-np.inf, np.inf), finite=False)),
                              _flag(c, "clamped", where), _flag(c, "locked", where)))
    return tuple(out)


def _read_joint(doc, el) -> Joint:
    name = el.get("name")
    where = f"{doc.source}: {el.tag} {name!r}"
    _owned_frames(doc, el, f"/jointset/{name}")
    parent = _resolve(f"/jointset/{name}", _text(el, "socket_parent_frame", where))
    child = _resolve(f"/jointset/{name}", _text(el, "socket_child_frame", where))
    coords = _read_coordinates(doc, el, name)
    axes, extra = (), {}
    if el.tag == "CustomJoint":
        st = el.find("SpatialTransform")
        if st is None:
            raise ModelError(f"{where}: missing <SpatialTransform>")
        axes = tuple(_read_axis(doc, ax, where) for ax in st.findall("TransformAxis"))
    elif el.tag == "ScapulothoracicJoint":
        extra = dict(radii=_vec(el, "thoracic_ellipsoid_radii_x_y_z", where),
                     winging_origin=_vec(el, "scapula_winging_axis_origin", where, 2, default=(0, 0)),
                     winging_direction=float(_text(el, "scapula_winging_axis_direction", where, "0")))
    return Joint(el.tag, name, parent, child, coords, axes, extra)


def _read_axis(doc, ax, where) -> Axis:
    aname = ax.get("name")
    here = f"{where}, TransformAxis {aname!r}"
    coords = tuple(_text(ax, "coordinates", here, "").split())
    funcs = [c for c in ax if c.tag in FUNCTION_TAGS]
    others = [c.tag for c in ax if c.tag not in FUNCTION_TAGS and c.tag not in ("coordinates", "axis")]
    if others or len(funcs) > 1:
        raise ModelError(f"{here}: function <{(others or [funcs[1].tag])[0]}> is not supported; expected one of "
                         f"{', '.join(FUNCTION_TAGS)}")
    axis = _vec(ax, "axis", here)
    if np.linalg.norm(axis) == 0:
        raise ModelError(f"{here}: <axis> is the zero vector")
    func = read_function(funcs[0], here) if funcs else None
    return Axis(aname, coords, axis / np.linalg.norm(axis), func)


def _read_constraint(doc, el):
    name = el.get("name")
    where = f"{doc.source}: {el.tag} {name!r}"
    if el.find("isEnforced") is not None and not _flag(el, "isEnforced", where):
        doc.notes.append(f"{el.tag} {name!r}: isEnforced=false, left out")
        return None
    if el.tag == "PointConstraint":
        frames = tuple(_resolve(f"/constraintset/{name}", _text(el, f"socket_body_{k}", where)) for k in (1, 2))
        points = tuple(_vec(el, f"location_body_{k}", where) for k in (1, 2))
        return Constraint(el.tag, name, dict(frames=frames, points=points))
    if el.tag == "CoordinateCouplerConstraint":
        indep = tuple(_text(el, "independent_coordinate_names", where).split())
        dep = _text(el, "dependent_coordinate_name", where)
        holder = el.find("coupled_coordinates_function")
        funcs = [c for c in (holder if holder is not None else [])]
        if len(funcs) != 1:
            raise ModelError(f"{where}: expected one function in <coupled_coordinates_function>")
        if len(indep) != 1:
            raise ModelError(f"{where}: {len(indep)} independent coordinates; a coupling of one coordinate on "
                             f"one other is read (multivariate functions are not)")
        scale = float(_text(el, "scale_factor", where, "1"))
        return Constraint(el.tag, name, dict(independent=indep[0], dependent=dep,
                                             function=read_function(funcs[0], where), scale=scale))
    raise ModelError(f"{where}: constraint type {el.tag} is not supported; expected PointConstraint or "
                     f"CoordinateCouplerConstraint")
