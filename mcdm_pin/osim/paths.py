r"""OpenSim muscles' paths as cables: ``PathPoint``, ``ConditionalPathPoint``, ``MovingPathPoint`` and
``PathWrap`` over ``WrapSphere``, ``WrapCylinder`` and ``WrapEllipsoid``, read from the ``.osim`` XML.

A muscle becomes a :class:`~mcdm_pin.model.cables.Cable` of the same name whose route is its path
points, each ``(body name, location in the body's frame)`` (the pin model carries one frame per
OpenSim body and ``ground``, named as the body and placed at the body frame), followed by its
``PathWrap``\ s in order as ``opensim_*`` :class:`~mcdm_pin.model.cables.Wrap`\ s fixed on the wrap
object's body (``translation``, ``xyz_body_rotation`` a body-fixed X-Y-Z sequence: ``R = R_x R_y R_z``,
``quadrant``, ``radius``, ``length``, ``dimensions``, and the ``PathWrap``'s ``range`` and ``method``). The path is computed by our
route pass (:mod:`mcdm_pin.model.route_osim`), not by OpenSim.

Coordinates (conditional and moving points) are OpenSim coordinate names resolved through
``coordinates``: a mapping ``name -> (q index, v index)`` into the pin model, the coordinate's value
being ``q[q index]`` (radians or metres); by default the pin joints with one degree of freedom whose
name is the coordinate's. A moving point's location functions may be ``SimmSpline``, ``Constant``,
``LinearFunction``, ``PiecewiseLinearFunction`` and ``MultiplierFunction`` of these (written as one
piecewise cubic each, SIMM's spline coefficients); OpenSim clamps the coordinate to its ``range``
there.

Refused, naming the element and the reason (:class:`~mcdm_pin.exceptions.ModelError`): a muscle or
path-based force of another kind, a path point on a frame other than a body or ground, a wrap object
kind other than sphere, cylinder and ellipsoid (``WrapTorus``, ``WrapDoubleCylinderObst``), a
function kind not listed.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np

from ..exceptions import ModelError
from ..model.cables import Cable, ConditionalPoint, MovingPoint, PiecewiseCubic, Wrap
from ..model.muscles_osim import KINDS as MODELLED
from ..model.muscles_osim import OpenSimMuscles
from .muscles import read_muscle

MUSCLE_KINDS = MODELLED  # Millard2012EquilibriumMuscle, DeGrooteFregly2016Muscle, Thelen2003Muscle
WRAP_KINDS = {"WrapSphere": "opensim_sphere", "WrapCylinder": "opensim_cylinder",
              "WrapEllipsoid": "opensim_ellipsoid"}
TINY = 1e-7  # SIMM's TINY_NUMBER: the floor of a spline's knot spacing


def _text(el, tag: str, where: str, default=None) -> str:
    child = el.find(tag)
    if child is None or child.text is None:
        if default is not None:
            return default
        raise ModelError(f"{where}: missing <{tag}>")
    return child.text.strip()


def _floats(text: str, n: int | None, where: str) -> list[float]:
    try:
        vals = [float(v) for v in text.split()]
    except ValueError:
        raise ModelError(f"{where}: expected numbers, got {text!r}") from None
    if (n is not None and len(vals) != n) or not all(math.isfinite(v) for v in vals):
        raise ModelError(f"{where}: expected {n or 'some'} finite numbers, got {text!r}")
    return vals


def _frame_name(text: str, where: str) -> str:
    """A body or ground from a socket path (``/bodyset/<name>``, ``/ground``, or a bare name)."""
    parts = [p for p in text.strip().split("/") if p]
    if len(parts) == 2 and parts[0] == "bodyset":
        return parts[1]
    if len(parts) == 1:
        return parts[0]
    raise ModelError(f"{where}: path points on {text!r} are not supported; expected a body "
                     f"(/bodyset/<name>) or /ground")


def simm_spline(x, y) -> PiecewiseCubic:
    """OpenSim's ``SimmSpline`` coefficients (``SimmSpline::calcCoefficients``: a cubic spline whose end
    conditions take the third derivatives from divided differences; two knots give a line)."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    n = len(x)
    if n < 2 or len(y) != n:
        raise ModelError(f"SimmSpline: expected x and y of one length >= 2, got {len(x)} and {len(y)}")
    if n == 2:
        slope = (y[1] - y[0]) / max(TINY, x[1] - x[0])
        return PiecewiseCubic(tuple(x), tuple(y), (slope, slope), (0.0, 0.0), (0.0, 0.0))
    b, c, d = np.zeros(n), np.zeros(n), np.zeros(n)
    nm1, nm2 = n - 1, n - 2
    d[0] = max(TINY, x[1] - x[0])
    c[1] = (y[1] - y[0]) / d[0]
    for i in range(1, nm1):
        d[i] = max(TINY, x[i + 1] - x[i])
        b[i] = 2.0 * (d[i - 1] + d[i])
        c[i + 1] = (y[i + 1] - y[i]) / d[i]
        c[i] = c[i + 1] - c[i]
    b[0], b[nm1] = -d[0], -d[nm2]
    c[0] = c[nm1] = 0.0
    if n > 3:
        d31, d20 = max(TINY, x[3] - x[1]), max(TINY, x[2] - x[0])
        d1, d2 = max(TINY, x[nm1] - x[n - 3]), max(TINY, x[nm2] - x[n - 4])
        d30, d3 = max(TINY, x[3] - x[0]), max(TINY, x[nm1] - x[n - 4])
        c[0] = (c[2] / d31 - c[1] / d20) * d[0] * d[0] / d30
        c[nm1] = -(c[nm2] / d1 - c[n - 3] / d2) * d[nm2] * d[nm2] / d3
    for i in range(1, n):
        t = d[i - 1] / b[i - 1]
        b[i] -= t * d[i - 1]
        c[i] -= t * c[i - 1]
    c[nm1] /= b[nm1]
    for j in range(nm1):
        i = nm2 - j
        c[i] = (c[i] - d[i] * c[i + 1]) / b[i]
    b[nm1] = (y[nm1] - y[nm2]) / d[nm2] + d[nm2] * (c[nm2] + 2.0 * c[nm1])
    for i in range(nm1):
        b[i] = (y[i + 1] - y[i]) / d[i] - d[i] * (c[i + 1] + 2.0 * c[i])
        d[i] = (c[i + 1] - c[i]) / d[i]
        c[i] *= 3.0
    c[nm1] *= 3.0
    d[nm1] = d[nm2]
    return PiecewiseCubic(tuple(x), tuple(y), tuple(b), tuple(c), tuple(d))


def _function(el, where: str) -> PiecewiseCubic:
    """One OpenSim function element (the child of ``x_location`` etc.) as a piecewise cubic."""
    kids = list(el)
    if len(kids) != 1:
        raise ModelError(f"{where}: expected one function element, got {len(kids)}")
    f = kids[0]
    tag = f.tag
    if tag == "SimmSpline":
        return simm_spline(_floats(_text(f, "x", where), None, where), _floats(_text(f, "y", where), None, where))
    if tag == "Constant":
        v = _floats(_text(f, "value", where), 1, where)[0]
        return PiecewiseCubic((0.0,), (v,), (0.0,), (0.0,), (0.0,))
    if tag == "LinearFunction":
        slope, intercept = _floats(_text(f, "coefficients", where), 2, where)
        return PiecewiseCubic((0.0,), (intercept,), (slope,), (0.0,), (0.0,))
    if tag == "PiecewiseLinearFunction":
        x = _floats(_text(f, "x", where), None, where)
        y = _floats(_text(f, "y", where), None, where)
        if len(x) < 2 or len(x) != len(y):
            raise ModelError(f"{where}: PiecewiseLinearFunction needs x and y of one length >= 2")
        s = [(y[i + 1] - y[i]) / (x[i + 1] - x[i]) for i in range(len(x) - 1)]
        z = (0.0,) * len(x)
        return PiecewiseCubic(tuple(x), tuple(y), tuple(s + s[-1:]), z, z)
    if tag == "MultiplierFunction":
        inner = _function(f.find("function") if f.find("function") is not None else ET.Element("x"), where)
        k = _floats(_text(f, "scale", where, "1"), 1, where)[0]
        return PiecewiseCubic(inner.x, tuple(k * v for v in inner.y), tuple(k * v for v in inner.b),
                              tuple(k * v for v in inner.c), tuple(k * v for v in inner.d))
    raise ModelError(f"{where}: function {tag!r} is not supported; expected SimmSpline, Constant, "
                     f"LinearFunction, PiecewiseLinearFunction or MultiplierFunction")


def _coordinate_ranges(root) -> dict:
    """OpenSim coordinate name -> (q index, v index, (range min, range max))."""
    ranges = {}
    for c in root.iter("Coordinate"):
        r = c.find("range")
        vals = _floats(r.text, 2, f"Coordinate {c.get('name')!r}: <range>") if r is not None and r.text else None
        ranges[c.get("name")] = tuple(vals) if vals else (-math.inf, math.inf)
    return ranges


def _resolve(coordinates, ranges, name: str, where: str):
    if name not in coordinates:
        raise ModelError(f"{where}: coordinate {name!r} is not a coordinate of the pin model (known: "
                         f"{', '.join(sorted(coordinates)[:20])})")
    iq, iv = coordinates[name]
    return int(iq), int(iv), ranges.get(name, (-math.inf, math.inf))


def _socket(el, tag: str, legacy: str) -> str | None:
    node = el.find(tag)
    if node is None:
        node = el.find(legacy)
    return None if node is None or node.text is None else node.text.strip()


def _point(el, coordinates, ranges, where: str):
    frame_text = _socket(el, "socket_parent_frame", "body")
    if frame_text is None:
        raise ModelError(f"{where}: missing <socket_parent_frame>")
    frame = _frame_name(frame_text, where)
    if el.tag in ("PathPoint", "ConditionalPathPoint"):
        loc = tuple(_floats(_text(el, "location", where), 3, f"{where}: <location>"))
        if el.tag == "PathPoint":
            return (frame, loc)
        coord = _socket(el, "socket_coordinate", "coordinate")
        if coord is None:
            raise ModelError(f"{where}: a ConditionalPathPoint needs <socket_coordinate>")
        iq, _, _ = _resolve(coordinates, ranges, coord.split("/")[-1], where)
        lo, hi = _floats(_text(el, "range", where), 2, f"{where}: <range>")
        return ConditionalPoint(frame, loc, q_index=iq, range=(lo, hi))
    if el.tag == "MovingPathPoint":
        names = {_socket(el, f"socket_{a}_coordinate", f"{a}_coordinate") for a in "xyz"}
        names.discard(None)
        if len(names) != 1:
            raise ModelError(f"{where}: a MovingPathPoint's x, y and z must follow one coordinate (OpenSim's "
                             f"own rule), got {sorted(names)}")
        iq, iv, clamp = _resolve(coordinates, ranges, names.pop().split("/")[-1], where)
        funcs = []
        for a in "xyz":
            node = el.find(f"{a}_location")
            if node is None:
                raise ModelError(f"{where}: missing <{a}_location>")
            funcs.append(_function(node, f"{where}: <{a}_location>"))
        at0 = tuple(_eval(f, min(max(0.0, clamp[0]), clamp[1])) for f in funcs)
        return MovingPoint(frame, at0, q_index=iq, v_index=iv, clamp=clamp, functions=tuple(funcs))
    raise ModelError(f"{where}: path point kind {el.tag!r} is not supported; expected PathPoint, "
                     f"ConditionalPathPoint or MovingPathPoint")


def _eval(f: PiecewiseCubic, x: float) -> float:
    if x < f.x[0]:
        return f.y[0] + (x - f.x[0]) * f.b[0]
    if x > f.x[-1]:
        return f.y[-1] + (x - f.x[-1]) * f.b[-1]
    k = max(0, int(np.searchsorted(f.x, x, side="right")) - 1)
    k = min(k, max(0, len(f.x) - 2))
    dx = x - f.x[k]
    return f.y[k] + dx * (f.b[k] + dx * (f.c[k] + dx * f.d[k]))


def wrap_objects(root, file) -> dict:
    """Every wrap object of the model: name -> (body name, element)."""
    out = {}
    for holder in list(root.iter("Body")) + list(root.iter("Ground")):
        body = holder.get("name") or "ground"
        ws = holder.find("WrapObjectSet")
        if ws is None:
            continue
        for obj in ws.iter():
            if obj.tag.startswith("Wrap") and obj.tag != "WrapObjectSet" and obj.get("name"):
                out[obj.get("name")] = (body, obj)
    return out


def _rotation_xyz(a, b, c) -> tuple:
    """Body-fixed X-Y-Z Euler angles (SimTK's BodyRotationSequence): ``R_x(a) R_y(b) R_z(c)``, row-major."""
    ca, sa, cb, sb, cc, sc = math.cos(a), math.sin(a), math.cos(b), math.sin(b), math.cos(c), math.sin(c)
    Rx = np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]])
    Ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    Rz = np.array([[cc, -sc, 0], [sc, cc, 0], [0, 0, 1]])
    return tuple((Rx @ Ry @ Rz).reshape(9))


def _wrap(pw, objects, file, where: str):
    name = _text(pw, "wrap_object", where)
    if name not in objects:
        raise ModelError(f"{file}: {where}: wrap object {name!r} is not defined on any body")
    body, obj = objects[name]
    w = f"{file}: {obj.tag} {name!r} (on {body!r})"
    if obj.tag not in WRAP_KINDS:
        raise ModelError(f"{w}: {obj.tag} is not supported; expected WrapSphere, WrapCylinder or WrapEllipsoid")
    if _text(obj, "active", w, "true").lower() != "true":
        return None
    rot = _floats(_text(obj, "xyz_body_rotation", w, "0 0 0"), 3, f"{w}: <xyz_body_rotation>")
    tr = tuple(_floats(_text(obj, "translation", w, "0 0 0"), 3, f"{w}: <translation>"))
    quadrant = _text(obj, "quadrant", w, "all")
    q = {"x": "+x", "y": "+y", "z": "+z", "unassigned": "all"}.get(quadrant.lower(), quadrant.lower())
    radii = ()
    if obj.tag == "WrapEllipsoid":
        radii = tuple(_floats(_text(obj, "dimensions", w), 3, f"{w}: <dimensions>"))
        radius = max(radii)
    else:
        radius = _floats(_text(obj, "radius", w), 1, f"{w}: <radius>")[0]
    length = _floats(_text(obj, "length", w, "1"), 1, f"{w}: <length>")[0] if obj.tag == "WrapCylinder" else 0.0
    span = _floats(_text(pw, "range", where, "-1 -1"), 2, f"{where}: <range>")
    method = _text(pw, "method", where, "hybrid").lower()
    method = method if method in ("hybrid", "midpoint", "axial") else "hybrid"  # OpenSim's fallback
    return Wrap(body, WRAP_KINDS[obj.tag], radius, tr, _rotation_xyz(*rot), name=name, quadrant=q, length=length,
                span=(int(span[0]), int(span[1])), radii=radii, method=method)


def default_coordinates(model) -> dict:
    """Pin joints with one degree of freedom, by name: ``name -> (q index, v index)``."""
    return {model.names[j]: (model.joints[j].idx_q, model.joints[j].idx_v)
            for j in range(1, model.njoints) if model.joints[j].nq == 1 and model.joints[j].nv == 1}


def read_path(force, file, coordinates, ranges, objects) -> tuple:
    """One path force's route: path points then its active wraps (``(route, notes)``)."""
    name = force.get("name")
    where = f"{file}: {force.tag} {name!r}"
    gp = force.find("GeometryPath")
    if gp is None:
        raise ModelError(f"{where}: missing <GeometryPath>")
    pps = gp.find("PathPointSet")
    points = [p for p in (pps.find("objects") if pps is not None and pps.find("objects") is not None else [])]
    if len(points) < 2:
        raise ModelError(f"{where}: expected at least two path points, got {len(points)}")
    route = [_point(p, coordinates, ranges, f"{where}: {p.tag} {p.get('name')!r}") for p in points]
    notes = []
    pws = gp.find("PathWrapSet")
    for pw in (pws.find("objects") if pws is not None and pws.find("objects") is not None else []):
        w = _wrap(pw, objects, file, f"{where}: PathWrap {pw.get('name')!r}")
        if w is None:
            notes.append(f"{name}: wrap object {_text(pw, 'wrap_object', where)!r} is inactive (as in OpenSim)")
        else:
            route.append(w)
    return route, notes


def read_paths(root, file, model, coordinates=None):
    r"""The muscles of an ``<OpenSimDocument>`` as cables on ``model``.

    Args:
        root: the parsed ``<OpenSimDocument>`` (``xml.etree`` element).
        file: its path, for messages.
        model: the ``pin.Model`` with one frame per OpenSim body and ``ground``, named as the body.
        coordinates: OpenSim coordinate name -> ``(q index, v index)`` (default:
            :func:`default_coordinates`).

    Returns:
        ``(cables, muscles, notes)``: :class:`~mcdm_pin.model.cables.Cable`\ s named after the muscles
        (static bounds ``[0, 10 F0]``, as for MuJoCo's muscles a ceiling: a modelled muscle's range at
        an instant follows its length and speed), the muscles (Millard, De Groote, Thelen) as
        :class:`~mcdm_pin.model.muscles_osim.OpenSimMuscles` in cable order
        (``None`` without muscles; pass them as ``CableSet(model, cables, muscles=muscles,
        muscle_cables=muscles.names)``), and notes on what was left aside (forces without a path,
        inactive wrap objects).
    """
    coordinates = default_coordinates(model) if coordinates is None else dict(coordinates)
    ranges = _coordinate_ranges(root)
    objects = wrap_objects(root, file)
    cables, muscles, notes = [], [], []
    for fs in root.iter("ForceSet"):
        objs = fs.find("objects")
        for force in (objs if objs is not None else []):
            name = force.get("name")
            if force.find("GeometryPath") is None:
                notes.append(f"{force.tag} {name!r}: not a path force (left to the loader)")
                continue
            if force.tag not in MUSCLE_KINDS:
                raise ModelError(f"{file}: {force.tag} {name!r}: path force kind {force.tag!r} is not supported; "
                                 f"expected one of {', '.join(MUSCLE_KINDS)}")
            route, more = read_path(force, file, coordinates, ranges, objects)
            notes += more
            f0 = _floats(_text(force, "max_isometric_force", f"{file}: {force.tag} {name!r}"), 1,
                         f"{file}: {force.tag} {name!r}: <max_isometric_force>")[0]
            cables.append(Cable(name, tuple(route), 0.0, max(10.0 * f0, 1.0)))
            muscles.append(read_muscle(force, file))
    return cables, (OpenSimMuscles(muscles) if muscles else None), notes
