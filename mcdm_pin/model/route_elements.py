"""The elements of a cable's route, as data: points fixed in frames (OpenSim's conditional and moving
points among them), wrapping surfaces, pulleys and rotating pulleys (:mod:`mcdm_pin.model.cables`
checks them against a model and resolves them)."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class RoutePoint:
    """A point fixed in a frame: ``frame`` (a frame name of the model), ``point`` (3,) metres."""

    frame: str
    point: tuple[float, float, float]


WRAP_KINDS = ("sphere", "cylinder", "opensim_sphere", "opensim_cylinder", "opensim_ellipsoid")
OPENSIM_WRAPS = ("opensim_sphere", "opensim_cylinder", "opensim_ellipsoid")
PATH_WRAP_METHODS = ("hybrid", "midpoint", "axial")
"""Wraps with OpenSim's semantics (:mod:`mcdm_pin.model.route_osim`): they follow the route's points
and apply over the span of points their ``span`` names, as an OpenSim ``PathWrap`` does."""
QUADRANTS = ("all", "+x", "-x", "+y", "-y", "+z", "-z")


@dataclass(frozen=True)
class ConditionalPoint(RoutePoint):
    """OpenSim's ``ConditionalPathPoint``: on the path only while ``q[q_index]`` lies in ``range``
    (widened by 1e-5 each side, as OpenSim does)."""

    q_index: int = 0
    range: tuple[float, float] = (-math.inf, math.inf)


@dataclass(frozen=True)
class MovingPoint(RoutePoint):
    """OpenSim's ``MovingPathPoint``: its position in ``frame`` is ``(f_x(c), f_y(c), f_z(c))`` with
    ``c = q[q_index]`` clamped to ``clamp`` (OpenSim clamps the coordinate to its range); the
    functions' slopes at the unclamped ``c`` give the point's own term of ``L`` in column
    ``v_index`` (OpenSim's ``getdPointdQ``). ``point`` holds the position at ``c = 0`` (for display).
    ``functions``: three :class:`PiecewiseCubic`."""

    q_index: int = 0
    v_index: int = 0
    clamp: tuple[float, float] = (-math.inf, math.inf)
    functions: tuple = ()


@dataclass(frozen=True)
class PiecewiseCubic:
    """``y_k + dx (b_k + dx (c_k + dx d_k))`` with ``dx = x - x_k`` on ``[x_k, x_{k+1}]``, linear with
    slope ``b`` beyond the ends (SIMM's spline evaluation; a constant or a line is one knot)."""

    x: tuple
    y: tuple
    b: tuple
    c: tuple
    d: tuple


@dataclass(frozen=True)
class Wrap:
    """A wrapping surface fixed in a frame, between two route points.

    Attributes:
        frame: the frame it is fixed in.
        kind: ``sphere`` or ``cylinder`` (infinite, its axis the local z axis of ``rotation``).
        radius: metres, > 0.
        center: (3,) its centre in ``frame``, metres.
        rotation: 3x3 rotation (row-major, 9 numbers) of the surface's frame in ``frame``.
        side: a :class:`RoutePoint` on the side the cable must pass (MuJoCo's ``sidesite``), or
            ``None`` (the shorter way round).
        name: the surface's name (MuJoCo's geom name), for messages.
        quadrant, length, span, radii, method: for the ``opensim_*`` kinds only: OpenSim's
            ``quadrant``, the cylinder's ``length`` (m), the ``PathWrap``'s ``range`` (1-based route
            point indices, -1: the first or the last point), the ellipsoid's semi-axes ``radii`` (m;
            ``radius`` then their largest) and the ``PathWrap``'s ``method`` (ellipsoids).
    """

    frame: str
    kind: str
    radius: float
    center: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotation: tuple[float, ...] = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
    side: RoutePoint | None = None
    name: str = ""
    quadrant: str = "all"
    length: float = 0.0
    span: tuple[int, int] = (-1, -1)
    radii: tuple = ()
    method: str = "hybrid"


@dataclass(frozen=True)
class Pulley:
    """The start of a new branch of the route: the following segments count ``1/divisor`` of their
    length and carry ``f/divisor`` (MuJoCo's ``pulley divisor``)."""

    divisor: float


@dataclass(frozen=True)
class ScrewDrive:
    """A screw-driven winch outlet carrying a :class:`RotatingPulley`'s entry point (CASPR's
    ``screw_base_rotating_pulley``; the rule is in :mod:`mcdm_pin.model.pulleys`).

    Attributes:
        direction: (3,) the drum's travel direction ``v`` in the pulley's frame (used as given, not
            normalised, as CASPR does).
        lead: ``k``, metres of travel per metre of cable paid out (groove width / (pi * drum
            diameter)), ``0 <= k |v| < 1``.
        reference: ``l_0``, metres: the distance from the winch point to the cable's other end at the
            model's initial configuration.
        outlet: ``t_0``, metres along ``v``: the outlet's position at that configuration.
    """

    direction: tuple[float, float, float]
    lead: float
    reference: float
    outlet: float


@dataclass(frozen=True)
class RotatingPulley:
    """A pulley that swivels about its entry line, at the start or the end of a route (its exit point
    faces the neighbouring route point at every instant: :mod:`mcdm_pin.model.pulleys`).

    Attributes:
        frame: the frame it is fixed in (with the winch that feeds it).
        entry: (3,) the entry point ``F`` in ``frame``, metres (with ``screw``: the fixed winch point
            ``W``; the entry point then rides on the screw).
        axis: (3,) the direction the cable runs in as it reaches ``F`` (the swivel axis), in ``frame``.
        radius: metres, > 0.
        screw: a :class:`ScrewDrive` moving the entry point, or ``None``.
        name: for messages.
    """

    frame: str
    entry: tuple[float, float, float]
    axis: tuple[float, float, float]
    radius: float
    screw: ScrewDrive | None = None
    name: str = ""
