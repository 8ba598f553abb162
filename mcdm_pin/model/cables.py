r"""Cables on any ``pin.Model``: routes of points fixed in Pinocchio *frames*.

A cable runs from its first route point to its last through the others, in straight segments; each
point is fixed in a frame of the model (a link's body frame, a joint frame, an operational frame, the
``universe``), so a cable may pass over several links. Cables can only pull:
``0 <= f_min <= f <= f_max``.

Build one in code::

    cables = CableSet(model, [
        Cable("c1", route=[("universe", (0.15, 0, 0)), ("link1", (0.05, 0, 0.1))], f_min=1e-3, f_max=1e3),
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


@dataclass(frozen=True)
class RoutePoint:
    """A point fixed in a frame: ``frame`` (a frame name of the model), ``point`` (3,) metres."""

    frame: str
    point: tuple[float, float, float]


@dataclass(frozen=True)
class Cable:
    """One cable: a name, an ordered route of at least two points, force bounds in newtons."""

    name: str
    route: tuple[RoutePoint, ...]
    f_min: float
    f_max: float

    @property
    def links(self) -> tuple[str, ...]:
        """The frame of each route point."""
        return tuple(p.frame for p in self.route)

    @property
    def points(self) -> np.ndarray:
        """(k, 3) route points, each in its own frame."""
        return np.array([p.point for p in self.route], dtype=float).reshape(-1, 3)


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


def _as_cable(model, item, k: int) -> tuple[Cable, list[int]]:
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
    route, fids = [], []
    for i, p in enumerate(cable.route):
        if isinstance(p, RoutePoint):
            frame, point = p.frame, p.point
        else:
            try:
                frame, point = p
            except (TypeError, ValueError):
                raise ModelError(f"cable {cable.name!r}: route[{i}]: expected (frame, (x, y, z)), got {p!r}") from None
        fid = find_frame(model, frame)
        try:
            xyz = tuple(float(v) for v in point)
        except (TypeError, ValueError):
            raise ModelError(f"cable {cable.name!r}: route[{i}]: expected 3 numbers, got {point!r}") from None
        if len(xyz) != 3 or not all(math.isfinite(v) for v in xyz):
            raise ModelError(f"cable {cable.name!r}: route[{i}]: expected 3 finite numbers, got {point!r}")
        route.append(RoutePoint(frame if isinstance(frame, str) else model.frames[fid].name, xyz))
        fids.append(fid)
    f_min, f_max = float(cable.f_min), float(cable.f_max)
    if not (math.isfinite(f_min) and math.isfinite(f_max) and 0.0 <= f_min < f_max):
        raise ModelError(f"cable {cable.name!r}: expected finite bounds with 0 <= f_min < f_max, got "
                         f"f_min={cable.f_min!r}, f_max={cable.f_max!r}")
    if len(route) < 2:
        raise ModelError(f"cable {cable.name!r}: expected a route of at least two points, got {len(route)}")
    return Cable(str(cable.name), tuple(route), f_min, f_max), fids


class CableSet:
    """Cables bound to one Pinocchio model (module docstring).

    Args:
        model: the ``pin.Model`` the route frames belong to.
        cables: :class:`Cable` objects, or mappings ``{name, route, f_min, f_max}``, where a route is a
            sequence of :class:`RoutePoint` or ``(frame, (x, y, z))`` with frame a name or an id.

    Raises:
        ModelError: an unknown frame, a bad bound, a route of fewer than two points, a duplicate name, or
            a cable whose points all sit on one body (it could not move anything).

    Attributes:
        cables: the cables, in order; ``names``, ``f_min`` (m,), ``f_max`` (m,).
        point_frame, point_cable: (P,) the frame id and the cable of each route point.
        point_joint: (P,) the Pinocchio joint carrying each route point (all cables, in order).
        point_local: (P, 3) each point in its joint's frame.
        seg_a, seg_b, seg_cable: (S,) each segment's start and end point and its cable.
        seg_active: (S,) the segment spans two bodies (a segment within one body adds length only).
    """

    def __init__(self, model: pin.Model, cables: Iterable):
        self.model_signature = _signature(model)
        resolved = [_as_cable(model, c, k) for k, c in enumerate(cables)]
        self.cables = tuple(c for c, _ in resolved)
        if not self.cables:
            raise ModelError("a cable set needs at least one cable")
        seen: dict[str, int] = {}
        for k, c in enumerate(self.cables):
            if c.name in seen:
                raise ModelError(f"cable {k}: name {c.name!r} is already used by cable {seen[c.name]}")
            seen[c.name] = k
        self.names = tuple(c.name for c in self.cables)
        self.f_min = np.array([c.f_min for c in self.cables])
        self.f_max = np.array([c.f_max for c in self.cables])
        jid, local, seg_a, seg_b, seg_c = [], [], [], [], []
        for k, (cable, fids) in enumerate(resolved):
            start = len(jid)
            for p, fid in zip(cable.route, fids):
                frame = model.frames[fid]
                jid.append(int(frame.parentJoint))
                local.append(frame.placement.act(np.array(p.point)))
            if len(set(jid[start:])) < 2:
                raise ModelError(f"cable {cable.name!r} has no segment spanning two different bodies (every "
                                 f"point is fixed to the body of joint {model.names[jid[start]]!r}), so it "
                                 f"cannot move anything")
            n = len(cable.route)
            seg_a.extend(range(start, start + n - 1))
            seg_b.extend(range(start + 1, start + n))
            seg_c.extend([k] * (n - 1))
        self.point_frame = np.array([f for _, fids in resolved for f in fids], dtype=int)
        self.point_cable = np.repeat(np.arange(len(resolved)), [len(c.route) for c, _ in resolved])
        self.point_joint = np.array(jid, dtype=int)
        self.point_local = np.array(local, dtype=float).reshape(-1, 3)
        self.seg_a = np.array(seg_a, dtype=int)
        self.seg_b = np.array(seg_b, dtype=int)
        self.seg_cable = np.array(seg_c, dtype=int)
        self.seg_active = self.point_joint[self.seg_a] != self.point_joint[self.seg_b]
        self._evaluators: dict = {}

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


def _signature(model: pin.Model) -> tuple:
    return (model.nq, model.nv, model.njoints, model.nframes, tuple(model.names))
