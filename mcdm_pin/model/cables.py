r"""Cables on any ``pin.Model``: routes of points fixed in Pinocchio *frames*, over wrapping surfaces
and pulleys.

A cable runs from its first route point to its last through the others; each point is fixed in a frame
of the model (a link's body frame, a joint frame, an operational frame, the ``universe``), so a cable may
pass over several links. Between two points a route may pass over a :class:`Wrap` (a sphere or a
cylinder fixed in a frame: the cable takes the shortest path over it when the straight segment would
cut through it, MuJoCo's definition, :mod:`mcdm_pin.model.wrapping`); a :class:`Pulley` starts a new
branch whose length and tension count ``1/divisor`` (MuJoCo's ``pulley divisor``). A route may start or
end at a :class:`RotatingPulley` (a swivelling pulley fed from a winch on its body, optionally on a
screw-driven outlet, :class:`ScrewDrive`: CASPR's ``base_rotating_pulley`` and
``screw_base_rotating_pulley``, :mod:`mcdm_pin.model.pulleys`): its exit point moves with the cable's
other end. Such a route
depends on the configuration; its length, ``L`` and wrenches follow from its path at each instant
(:mod:`mcdm_pin.model.routes`). Cables can only pull: ``0 <= f_min <= f <= f_max``.

Routes read from OpenSim follow OpenSim's rules instead (:mod:`mcdm_pin.model.route_osim`): their
points may be :class:`ConditionalPoint` and :class:`MovingPoint`, and their wraps (kinds
``opensim_sphere``, ``opensim_cylinder``, ``opensim_ellipsoid``) follow all the points, each applying
over the span of points it names, as an OpenSim ``PathWrap`` does.

Build one in code::

    cables = CableSet(model, [
        Cable("c1", route=[("universe", (0.15, 0, 0)), ("link1", (0.05, 0, 0.1))], f_min=1e-3, f_max=1e3),
        Cable("c2", route=[("universe", (0, 0.1, 0)), Wrap("link1", "cylinder", 0.02),
                           ("link2", (0, 0, 0.1))], f_min=0.0, f_max=200.0),
        ...])

A :class:`CableSet` is bound to the model it was built for: the frames are resolved once, into the
Pinocchio joint that carries each point and the point's position in that joint's frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable

import numpy as np
import pinocchio as pin

from ..exceptions import ModelError
from ..limits import MIN_FORCE_BOUND
from .route_elements import (  # noqa: F401 (re-exported: the elements a route is built of)
    OPENSIM_WRAPS, PATH_WRAP_METHODS, QUADRANTS, WRAP_KINDS, ConditionalPoint, MovingPoint, PiecewiseCubic, Pulley,
    RotatingPulley, RoutePoint, ScrewDrive, Wrap)


@dataclass(frozen=True)
class Cable:
    """One cable: a name, an ordered route (points, and wraps and pulleys between them) of at least
    two points, force bounds in newtons."""

    name: str
    route: tuple
    f_min: float
    f_max: float

    @property
    def route_points(self) -> tuple[RoutePoint, ...]:
        """The route's fixed points (wraps, pulleys and rotating pulleys left out)."""
        return tuple(p for p in self.route if isinstance(p, RoutePoint))

    @property
    def links(self) -> tuple[str, ...]:
        """The frame of each route point."""
        return tuple(p.frame for p in self.route_points)

    @property
    def points(self) -> np.ndarray:
        """(k, 3) route points, each in its own frame."""
        return np.array([p.point for p in self.route_points], dtype=float).reshape(-1, 3)

    @property
    def configuration_dependent(self) -> bool:
        """The route holds a wrap, a pulley or a rotating pulley."""
        return any(not isinstance(p, RoutePoint) for p in self.route)


def find_frame(model: pin.Model, frame) -> int:
    """A frame id from a frame name or id. A name shared by several frames resolves to its ``BODY``
    frame (a URDF link), else must be unique."""
    if isinstance(frame, (int, np.integer)) and not isinstance(frame, bool):
        if not 0 <= int(frame) < model.nframes:
            raise ModelError(f"frame id {int(frame)} is out of range: the model has {model.nframes} frames")
        return int(frame)
    if not isinstance(frame, str):
        raise ModelError(f"expected a frame name or id, got {frame!r}")
    ids = [i for i, f in enumerate(model.frames) if f.name == frame]
    if not ids:
        names = sorted({f.name for f in model.frames if f.type == pin.FrameType.BODY} | {"universe"})
        shown = ", ".join(repr(n) for n in names[:25]) + (f", ... ({len(names)} in all)" if len(names) > 25 else "")
        raise ModelError(f"unknown frame {frame!r}; expected a frame of the model, e.g. one of {shown}")
    body = [i for i in ids if model.frames[i].type == pin.FrameType.BODY]
    if len(body) == 1:
        return body[0]
    if len(ids) == 1:
        return ids[0]
    raise ModelError(f"frame name {frame!r} is ambiguous ({len(ids)} frames carry it); pass a frame id")


def _as_cable(model, item, k: int) -> tuple[Cable, list]:
    """The checked cable and its resolved route: per element ``("point", fid)``,
    ``("wrap", fid, side_fid or None)`` or ``("pulley",)``."""
    if isinstance(item, Cable):
        cable = item
    elif isinstance(item, dict):
        unknown = set(item) - {"name", "route", "f_min", "f_max"}
        if unknown:
            raise ModelError(f"cable {k}: unknown keys {sorted(unknown)}; expected name, route, f_min, f_max")
        cable = Cable(item.get("name", f"cable{k + 1}"), tuple(item.get("route", ())),
                      item.get("f_min", 0.0), item.get("f_max", math.inf))
    else:
        raise ModelError(f"cable {k}: expected a Cable or a mapping, got {type(item).__name__}")
    route, resolved = [], []
    for i, p in enumerate(cable.route):
        where = f"cable {cable.name!r}: route[{i}]"
        if isinstance(p, Wrap):
            w, fid, side_fid = _as_wrap(model, p, where)
            route.append(w)
            resolved.append(("wrap", fid, side_fid))
        elif isinstance(p, RotatingPulley):
            rp, fid = _as_rotating(model, p, where)
            route.append(rp)
            resolved.append(("rotating", fid))
        elif isinstance(p, Pulley):
            d = _number(p.divisor, f"{where}: pulley divisor")
            if not d > 0:
                raise ModelError(f"{where}: expected a pulley divisor > 0, got {p.divisor!r}")
            route.append(Pulley(d))
            resolved.append(("pulley",))
        else:
            rp, fid = _as_point(model, p, where)
            route.append(rp)
            resolved.append(("point", fid))
    f_min, f_max = float(cable.f_min), float(cable.f_max)
    if not (math.isfinite(f_min) and math.isfinite(f_max) and 0.0 <= f_min < f_max):
        raise ModelError(f"cable {cable.name!r}: expected finite bounds with 0 <= f_min < f_max, got "
                         f"f_min={cable.f_min!r}, f_max={cable.f_max!r}")
    if 0.0 < f_min < MIN_FORCE_BOUND or f_max < MIN_FORCE_BOUND:
        raise ModelError(f"cable {cable.name!r}: expected bounds of 0 or at least {MIN_FORCE_BOUND:g} N "
                         f"(docs/limits.md: smaller forces' squares underflow), got f_min={f_min!r}, "
                         f"f_max={f_max!r}")
    n_points = sum(1 for r in resolved if r[0] in ("point", "rotating"))
    if n_points < 2:
        raise ModelError(f"cable {cable.name!r}: expected a route of at least two points, got {n_points}")
    kinds = [r[0] for r in resolved]
    osim = [i for i, p in enumerate(route) if isinstance(p, Wrap) and p.kind in OPENSIM_WRAPS]
    if osim:
        if osim != list(range(len(kinds) - len(osim), len(kinds))) or "pulley" in kinds or len(osim) < sum(
                1 for k in kinds if k == "wrap"):
            raise ModelError(f"cable {cable.name!r}: OpenSim wraps ({', '.join(OPENSIM_WRAPS)}) must follow "
                             f"all of the route's points, with no other wrap or pulley in the route")
        kinds = kinds[:len(kinds) - len(osim)]
    for i, kind in enumerate(kinds):
        if kind == "rotating":
            end = i == 0 or i == len(kinds) - 1
            if not end or kinds[1 if i == 0 else i - 1] != "point":
                raise ModelError(f"cable {cable.name!r}: route[{i}]: a rotating pulley must be the first or the "
                                 f"last element of a route, next to a route point (its exit point faces it)")
        elif kind != "point" and (i == 0 or i == len(kinds) - 1 or kinds[i - 1] != "point"
                                  or kinds[i + 1] != "point"):
            raise ModelError(f"cable {cable.name!r}: route[{i}]: a {kind} must stand between two route points "
                             f"(MuJoCo's rule for spatial tendons: site, geom, site; site, pulley, site)")
    return Cable(str(cable.name), tuple(route), f_min, f_max), resolved


def _number(value, what: str) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ModelError(f"{what}: expected a number, got {value!r}") from None
    if not math.isfinite(x):
        raise ModelError(f"{what}: expected a finite number, got {value!r}")
    return x


def _as_point(model, p, where: str) -> tuple[RoutePoint, int]:
    if isinstance(p, RoutePoint):
        frame, point = p.frame, p.point
    else:
        try:
            frame, point = p
        except (TypeError, ValueError):
            raise ModelError(f"{where}: expected (frame, (x, y, z)), a Wrap or a Pulley, got {p!r}") from None
    fid = find_frame(model, frame)
    try:
        xyz = tuple(float(v) for v in point)
    except (TypeError, ValueError):
        raise ModelError(f"{where}: expected 3 numbers, got {point!r}") from None
    if len(xyz) != 3 or not all(math.isfinite(v) for v in xyz):
        raise ModelError(f"{where}: expected 3 finite numbers, got {point!r}")
    if isinstance(p, (ConditionalPoint, MovingPoint)):
        return _check_osim_point(model, p, xyz, where), fid
    return RoutePoint(frame if isinstance(frame, str) else model.frames[fid].name, xyz), fid


def _check_osim_point(model, p, xyz, where: str):
    """A checked :class:`ConditionalPoint` or :class:`MovingPoint` (coordinates in range, functions
    of the right shape)."""
    import dataclasses

    if not 0 <= int(p.q_index) < model.nq:
        raise ModelError(f"{where}: q_index {p.q_index!r} is out of range [0, {model.nq})")
    if isinstance(p, ConditionalPoint):
        lo, hi = (float(v) for v in p.range)
        if not lo <= hi:
            raise ModelError(f"{where}: expected a range lo <= hi, got {p.range!r}")
        return dataclasses.replace(p, point=xyz, range=(lo, hi))
    if not 0 <= int(p.v_index) < model.nv:
        raise ModelError(f"{where}: v_index {p.v_index!r} is out of range [0, {model.nv})")
    if len(p.functions) != 3 or not all(isinstance(f, PiecewiseCubic) for f in p.functions):
        raise ModelError(f"{where}: expected three PiecewiseCubic functions (x, y, z), got {p.functions!r}")
    for f in p.functions:
        arrs = [np.asarray(getattr(f, k), dtype=float) for k in ("x", "y", "b", "c", "d")]
        if len({a.shape for a in arrs}) != 1 or arrs[0].ndim != 1 or not arrs[0].size or not all(
                np.isfinite(a).all() for a in arrs) or np.any(np.diff(arrs[0]) <= 0):
            raise ModelError(f"{where}: a moving point's function needs knots x (increasing) and "
                             f"coefficients y, b, c, d of one length, all finite")
    return dataclasses.replace(p, point=xyz)


def _vector(value, what: str) -> tuple[float, float, float]:
    try:
        xyz = tuple(_number(v, what) for v in value)
    except TypeError:
        raise ModelError(f"{what}: expected 3 numbers, got {value!r}") from None
    if len(xyz) != 3:
        raise ModelError(f"{what}: expected 3 numbers, got {value!r}")
    return xyz


def _as_rotating(model, p: RotatingPulley, where: str) -> tuple[RotatingPulley, int]:
    radius = _number(p.radius, f"{where}: rotating pulley radius")
    if not radius > 0:
        raise ModelError(f"{where}: expected a rotating pulley radius > 0, got {p.radius!r}")
    fid = find_frame(model, p.frame)
    entry = _vector(p.entry, f"{where}: rotating pulley entry")
    axis = _vector(p.axis, f"{where}: rotating pulley axis")
    if not math.hypot(*axis) > 1e-12:
        raise ModelError(f"{where}: expected a nonzero rotating pulley axis (the cable's entry direction), got "
                         f"{p.axis!r}")
    screw = None
    if p.screw is not None:
        sd = p.screw
        if not isinstance(sd, ScrewDrive):
            raise ModelError(f"{where}: expected the rotating pulley's screw to be a ScrewDrive or None, got "
                             f"{type(sd).__name__}")
        direction = _vector(sd.direction, f"{where}: screw direction")
        lead = _number(sd.lead, f"{where}: screw lead")
        reference = _number(sd.reference, f"{where}: screw reference")
        outlet = _number(sd.outlet, f"{where}: screw outlet")
        if not (lead >= 0 and lead * math.hypot(*direction) < 1):
            raise ModelError(f"{where}: expected a screw lead with 0 <= lead * |direction| < 1, got lead "
                             f"{sd.lead!r} and direction {sd.direction!r}")
        if not reference > 0:
            raise ModelError(f"{where}: expected a screw reference length > 0 (metres), got {sd.reference!r}")
        screw = ScrewDrive(direction, lead, reference, outlet)
    frame = p.frame if isinstance(p.frame, str) else model.frames[fid].name
    return RotatingPulley(frame, entry, axis, radius, screw, str(p.name)), fid


def _as_wrap(model, w: Wrap, where: str) -> tuple[Wrap, int, int | None]:
    if w.kind not in WRAP_KINDS:
        raise ModelError(f"{where}: expected a wrap kind in {WRAP_KINDS}, got {w.kind!r}")
    if w.kind in OPENSIM_WRAPS and (w.quadrant not in QUADRANTS or w.side is not None or (
            w.kind == "opensim_cylinder" and not float(w.length) > 0) or len(w.span) != 2 or (
            w.kind == "opensim_ellipsoid" and (len(w.radii) != 3 or not min(w.radii) > 0
                                               or w.method not in PATH_WRAP_METHODS))):
        raise ModelError(f"{where}: an OpenSim wrap needs a quadrant in {QUADRANTS}, no side point, a "
                         f"span of two point indices, (cylinder) a length > 0, (ellipsoid) three radii > 0 and a "
                         f"method in {PATH_WRAP_METHODS}; got quadrant={w.quadrant!r}, length={w.length!r}, "
                         f"span={w.span!r}, radii={w.radii!r}, method={w.method!r}")
    radius = _number(w.radius, f"{where}: wrap radius")
    if not radius > 0:
        raise ModelError(f"{where}: expected a wrap radius > 0, got {w.radius!r}")
    fid = find_frame(model, w.frame)
    center = tuple(_number(v, f"{where}: wrap center") for v in w.center)
    rot = np.array([_number(v, f"{where}: wrap rotation") for v in w.rotation])
    if len(center) != 3 or rot.shape != (9,):
        raise ModelError(f"{where}: expected a wrap center of 3 numbers and a rotation of 9")
    R = rot.reshape(3, 3)
    if not (np.allclose(R @ R.T, np.eye(3), atol=1e-9) and np.linalg.det(R) > 0):
        raise ModelError(f"{where}: the wrap rotation is not a rotation matrix: {R.tolist()}")
    side, side_fid = None, None
    if w.side is not None:
        side, side_fid = _as_point(model, w.side, f"{where}: side")
    frame = w.frame if isinstance(w.frame, str) else model.frames[fid].name
    return Wrap(frame, w.kind, radius, center, tuple(rot), side, str(w.name), w.quadrant, float(w.length),
                tuple(int(i) for i in w.span), tuple(float(r) for r in w.radii), w.method), fid, side_fid


class CableSet:
    """Cables bound to one Pinocchio model (module docstring).

    Args:
        model: the ``pin.Model`` the route frames belong to.
        cables: :class:`Cable` objects, or mappings ``{name, route, f_min, f_max}``, where a route is a
            sequence of :class:`RoutePoint` or ``(frame, (x, y, z))`` with frame a name or an id, and
            :class:`Wrap`, :class:`Pulley` or (first or last) :class:`RotatingPulley` elements.

    Raises:
        ModelError: an unknown frame, a bad bound, a route of fewer than two points, a duplicate name, a
            rotating pulley elsewhere than at an end next to a route point, or a cable whose points all
            sit on one body (it could not move anything).

    Attributes:
        cables: the cables, in order; ``names``, ``f_min`` (m,), ``f_max`` (m,).
        point_frame, point_cable: (P,) the frame id and the cable of each route point (a rotating
            pulley's exit point counts as one: its slot holds the entry point until an instant's pass).
        point_joint: (P,) the Pinocchio joint carrying each route point (all cables, in order).
        point_local: (P, 3) each point in its joint's frame; ``point_frame_rotation`` (P, 3, 3) and
            ``point_frame_translation`` (P, 3) the placement of its frame in that joint's frame.
        seg_a, seg_b, seg_cable: (S,) each segment's start and end point and its cable.
        seg_active: (S,) the segment spans two bodies (a segment within one body adds length only).
        seg_scale: (S,) the share of length and tension of each segment (``1/divisor`` past a pulley).
        wraps: the :class:`ResolvedWrap` of every wrap, in route order; the segment ``seg`` each one
            sits on is the straight segment its path replaces when it engages (:mod:`.routes`).
        osim_wraps: the :class:`ResolvedWrap` of every OpenSim wrap (``a`` the cable's first point,
            ``seg`` -1), in route order; ``osim_cables`` the cables whose path follows OpenSim's rules
            (:mod:`mcdm_pin.model.route_osim`).
        rotating: the :class:`ResolvedRotatingPulley` of every rotating pulley, in route order; each
            has a route point slot (on the pulley's body) that holds its exit point at each instant.
        muscles: the :class:`~mcdm_pin.model.muscles.MuscleParams` of the cables that are muscles
            (``None``: none), ``muscle_index`` (k,) those cables; a muscle's tension range at an
            instant follows its length and speed, and its ``f_min``/``f_max`` here only bound it.
    """

    def __init__(self, model: pin.Model, cables: Iterable, muscles=None, muscle_cables=()):
        self.model_signature = _signature(model)
        resolved = [_as_cable(model, c, k) for k, c in enumerate(cables)]
        self.cables = tuple(c for c, _ in resolved)
        if not self.cables:
            raise ModelError("a cable set needs at least one cable")
        self.names = _unique_names(self.cables)
        self.f_min = np.array([c.f_min for c in self.cables])
        self.f_max = np.array([c.f_max for c in self.cables])
        jid, local, seg_a, seg_b, seg_c, seg_s, fids_all, wraps = [], [], [], [], [], [], [], []
        osim_wraps, frame_R, frame_p = [], [], []
        rotating = []
        for k, (cable, res) in enumerate(resolved):
            start = len(jid)
            bodies = set()
            scale = 1.0
            prev = None  # index of the last point, None right after a pulley
            for i, (elem, r) in enumerate(zip(cable.route, res)):
                if r[0] in ("point", "rotating"):  # a rotating pulley's slot holds its exit point
                    frame = model.frames[r[1]]
                    frame_R.append(frame.placement.rotation.copy())
                    frame_p.append(frame.placement.translation.copy())
                    jid.append(int(frame.parentJoint))
                    local.append(frame.placement.act(np.array(elem.point if r[0] == "point" else elem.entry)))
                    if r[0] == "rotating":
                        b = len(jid) if i == 0 else len(jid) - 2  # the neighbouring route point
                        rotating.append(_resolve_rotating(model, k, elem, r[1], len(jid) - 1, b, scale))
                    fids_all.append(r[1])
                    bodies.add(jid[-1])
                    if prev is not None:
                        seg_a.append(prev)
                        seg_b.append(len(jid) - 1)
                        seg_c.append(k)
                        seg_s.append(scale)
                    prev = len(jid) - 1
                elif r[0] == "pulley":
                    scale = 1.0 / elem.divisor
                    prev = None
                elif elem.kind in OPENSIM_WRAPS:
                    osim_wraps.append(_resolve_wrap(model, k, elem, r, start, -1, 1.0))
                    bodies.add(osim_wraps[-1].joint)
                else:
                    wraps.append(_resolve_wrap(model, k, elem, r, len(jid) - 1, len(seg_a), scale))
                    bodies.add(wraps[-1].joint)
            if len(bodies) < 2:
                raise ModelError(f"cable {cable.name!r} has no segment spanning two different bodies (every "
                                 f"point is fixed to the body of joint {model.names[jid[start]]!r}), so it "
                                 f"cannot move anything")
        self.point_frame = np.array(fids_all, dtype=int)
        self.point_cable = np.repeat(np.arange(len(resolved)),
                                     [sum(r[0] in ("point", "rotating") for r in res) for _, res in resolved])
        self.point_joint = np.array(jid, dtype=int)
        self.point_frame_rotation = np.array(frame_R, dtype=float).reshape(-1, 3, 3)
        self.point_frame_translation = np.array(frame_p, dtype=float).reshape(-1, 3)
        self.point_local = np.array(local, dtype=float).reshape(-1, 3)
        self.seg_a = np.array(seg_a, dtype=int)
        self.seg_b = np.array(seg_b, dtype=int)
        self.seg_cable = np.array(seg_c, dtype=int)
        self.seg_scale = np.array(seg_s, dtype=float)
        self.seg_active = self.point_joint[self.seg_a] != self.point_joint[self.seg_b]
        self.wraps = tuple(wraps)
        self.osim_wraps = tuple(osim_wraps)
        self.osim_cables = tuple(k for k, c in enumerate(self.cables) if any(
            isinstance(p, (ConditionalPoint, MovingPoint)) or (isinstance(p, Wrap) and p.kind in OPENSIM_WRAPS)
            for p in c.route))
        self.rotating = tuple(rotating)
        self.muscles, self.muscle_index = None, np.zeros(0, dtype=int)
        self.all_muscles = False  # every cable a muscle, in the muscles' order (muscle_index = 0 .. m-1)
        if muscles is not None:
            self._bind_muscles(muscles, list(muscle_cables))
        self._evaluators: dict = {}

    def _bind_muscles(self, muscles, names: list) -> None:
        """The muscles (their force ranges per instant) of the cables ``names``, one per muscle."""
        unknown = [n for n in names if n not in self.names]
        if unknown or len(names) != muscles.size or len(set(names)) != len(names):
            raise ModelError(f"muscles: expected {muscles.size} distinct cable names of this set, one per "
                             f"muscle, got {names!r}" + (f" ({unknown} are not cables)" if unknown else ""))
        self.muscles = muscles
        self.muscle_index = np.array([self.names.index(n) for n in names], dtype=int)
        self.all_muscles = bool(np.array_equal(self.muscle_index, np.arange(len(self.cables))))

    @property
    def configuration_dependent(self) -> bool:
        """Some route wraps over a surface, leaves a rotating pulley or follows OpenSim's conditional or
        moving points (its path depends on the configuration)."""
        return bool(self.wraps or self.rotating or self.osim_cables)

    @property
    def m(self) -> int:
        """Number of cables."""
        return len(self.cables)

    def __len__(self) -> int:
        return len(self.cables)

    def __iter__(self):
        return iter(self.cables)

    def __getitem__(self, key) -> Cable:
        if isinstance(key, str):
            try:
                return self.cables[self.names.index(key)]
            except ValueError:
                raise KeyError(key) from None
        return self.cables[key]

    def check_model(self, model: pin.Model) -> None:
        """Raise :class:`ModelError` unless ``model`` is (structurally) the one this set was built for."""
        if _signature(model) != self.model_signature:
            raise ModelError("this CableSet was built for another model (different joints or frames); "
                             "build it with CableSet(model, cables) for the model you pass")

    def __repr__(self) -> str:
        return f"CableSet({self.m} cables: {', '.join(self.names[:6])}{', ...' if self.m > 6 else ''})"


@dataclass(frozen=True)
class ResolvedWrap:
    """A wrap bound to the model: on cable ``cable``, between route points ``a`` and ``b`` (indices into
    the set's points), replacing segment ``seg`` when it engages. ``joint``: the Pinocchio joint
    carrying the surface; ``placement``: the surface's frame in that joint's frame; ``side_joint``,
    ``side_local``: the side point's joint and position in its frame (``side_joint`` -1: none);
    ``scale``: the branch's share (``1/divisor``)."""

    cable: int
    a: int
    b: int
    seg: int
    joint: int
    placement: pin.SE3
    kind: str
    radius: float
    side_joint: int
    side_local: np.ndarray
    scale: float
    name: str


def _resolve_wrap(model, k: int, w: Wrap, r, a: int, seg: int, scale: float) -> ResolvedWrap:
    frame = model.frames[r[1]]
    placement = frame.placement * pin.SE3(np.array(w.rotation).reshape(3, 3), np.array(w.center))
    side_joint, side_local = -1, np.zeros(3)
    if w.side is not None:
        sframe = model.frames[r[2]]
        side_joint = int(sframe.parentJoint)
        side_local = sframe.placement.act(np.array(w.side.point))
    return ResolvedWrap(k, a, a + 1, seg, int(frame.parentJoint), placement, w.kind, float(w.radius),
                        side_joint, side_local, scale, w.name)


@dataclass(frozen=True)
class ResolvedRotatingPulley:
    """A rotating pulley bound to the model: on cable ``cable``, its exit point is route point ``point``
    (on Pinocchio joint ``joint``), facing route point ``b``. ``entry``, ``axis`` (and the screw's
    ``screw_direction``) in that joint's frame; ``scale``: the branch's share (``1/divisor``);
    ``screw`` ``None`` or ``(lead, reference, outlet)``."""

    cable: int
    point: int
    b: int
    joint: int
    entry: np.ndarray
    axis: np.ndarray
    radius: float
    scale: float
    screw_direction: np.ndarray
    screw: tuple | None
    name: str


def _resolve_rotating(model, k: int, p: RotatingPulley, fid: int, point: int, b: int,
                      scale: float) -> ResolvedRotatingPulley:
    placement = model.frames[fid].placement
    R = placement.rotation
    screw, direction = None, np.zeros(3)
    if p.screw is not None:
        screw, direction = (p.screw.lead, p.screw.reference, p.screw.outlet), R @ np.array(p.screw.direction)
    return ResolvedRotatingPulley(k, point, b, int(model.frames[fid].parentJoint), placement.act(np.array(p.entry)),
                                  R @ np.array(p.axis), float(p.radius), scale, direction, screw, p.name)


def _unique_names(cables) -> tuple[str, ...]:
    """The cables' names, or :class:`ModelError` naming the first repeated one."""
    seen: dict[str, int] = {}
    for k, c in enumerate(cables):
        if c.name in seen:
            raise ModelError(f"cable {k}: name {c.name!r} is already used by cable {seen[c.name]}")
        seen[c.name] = k
    return tuple(seen)


def _signature(model: pin.Model) -> tuple:
    return (model.nq, model.nv, model.njoints, model.nframes, tuple(model.names))
