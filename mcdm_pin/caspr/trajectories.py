"""CASPR's ``*_trajectories.xml``: every joint-trajectory type, read as CASPR's loaders read them.

``JointTrajectory.*LoadXmlObj`` at CASPR ``a6971ee``: the first point is at t = 0 (its ``time`` is
ignored); with ``time_definition="relative"`` a point's ``time`` is the duration since the previous one.
``quintic_spline_trajectory`` points give ``q``, ``q_dot``, ``q_ddot``; ``cubic_spline_trajectory``
points ``q``, ``q_dot``; ``linear_spline_trajectory`` and ``parabolic_blend_trajectory`` points ``q``
(the latter with ``blend_time_default`` and a per-point ``blend_time`` for the segment that ends
there); ``cubic_spline_average_velocity_trajectory`` points ``q``, the first and last also ``q_dot``
(inner velocities are the mean of the two neighbouring segments' slopes); ``file_trajectory`` names a
``.traj`` file next to the XML (``time_step,dt`` then ``t,T,p,q...,v,q_dot...,a,q_ddot...`` lines).

A trajectory that cannot be converted is refused alone (:attr:`TrajectoryFile.refused`, with its
reason); the others are kept.

``<operational_trajectories>`` (``OperationalTrajectory.*LoadXmlObj``): points give ``y`` (and, for
``quintic_spline_trajectory``, ``y_dot``, ``y_ddot``), the coordinates of the model's operational set
(:mod:`.operational`), one number per coordinate of the set; times as for joint trajectories. CASPR
implements the quintic and linear splines only (the other types raise "Function has not been
implemented yet" there): the others are refused. With no operational set they are refused too.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..exceptions import CasprError
from ._xml import number, numbers, parse_xml

TYPES = ("quintic_spline_trajectory", "cubic_spline_trajectory", "linear_spline_trajectory",
         "cubic_spline_average_velocity_trajectory", "parabolic_blend_trajectory", "file_trajectory")
RATES = {"quintic_spline_trajectory": ("q_dot", "q_ddot"), "cubic_spline_trajectory": ("q_dot",),
         "linear_spline_trajectory": (), "parabolic_blend_trajectory": (),
         "cubic_spline_average_velocity_trajectory": ()}
RATE_TOL = 0.0  # CASPR's isequal(q_dot, zeros): exactly zero
OPERATIONAL_TYPES = {"quintic_spline_trajectory": ("y_dot", "y_ddot"), "linear_spline_trajectory": ()}


@dataclass(frozen=True)
class CasprPoint:
    time: float  # absolute, s
    q: np.ndarray
    q_dot: np.ndarray
    q_ddot: np.ndarray


@dataclass(frozen=True)
class CasprTrajectory:
    """One joint trajectory, in CASPR's coordinates (q of every link's joint, in link order).

    ``points`` for the spline types (rates the type does not give are zero; the average-velocity
    type's inner velocities are filled in); ``blend`` per segment (parabolic blends); ``samples``
    ``(t, q, q_dot, q_ddot)`` for a file trajectory.
    """

    id: str
    type: str
    time_step: float | None
    points: tuple[CasprPoint, ...]
    element: str
    blend: tuple[float, ...] = ()
    samples: tuple | None = None

    @property
    def rest_to_rest_single(self) -> bool:
        """Two points, a quintic, every rate zero: exactly a sidecar ``quintic`` trajectory."""
        return (self.type == "quintic_spline_trajectory" and len(self.points) == 2
                and all(not np.any(p.q_dot) and not np.any(p.q_ddot) for p in self.points))


@dataclass(frozen=True)
class CasprOperationalTrajectory:
    """An operational-space trajectory: ``points`` hold ``y``, ``y_dot``, ``y_ddot`` (in the ``q``,
    ``q_dot``, ``q_ddot`` fields of :class:`CasprPoint`) in the coordinates of ``operational_set``
    (an :class:`~mcdm_pin.caspr.operational.OperationalSet`)."""

    id: str
    type: str
    time_step: float
    points: tuple[CasprPoint, ...]
    element: str
    operational_set: object


@dataclass(frozen=True)
class TrajectoryFile:
    """The joint trajectories of a file that can be converted, and the others with the reason."""

    path: Path
    trajectories: dict[str, CasprTrajectory]
    refused: dict[str, str] = field(default_factory=dict)


class _Refused(Exception):
    pass


def matlab_colon(a: float, d: float, b: float) -> np.ndarray:
    """MATLAB's ``a:d:b`` for d > 0 (CASPR's time grids): the number of steps is floor((b - a)/d)
    unless b is within 2 eps max(|a|, |b|) of the grid; the first half is a + k d, the second half is
    counted back from the last element, as MATLAB computes it."""
    tol = 2.0 * np.finfo(float).eps * max(abs(a), abs(b))
    n = int(np.floor((b - a) / d))
    if abs(a + (n + 1) * d - b) <= tol:
        n += 1
    if n < 0:
        return np.empty(0)
    end = b if abs(a + n * d - b) <= tol else a + n * d
    k = np.arange(n + 1)
    out = np.where(k <= n // 2, a + k * d, end - (n - k) * d)
    if n % 2 == 0 and n > 0:
        out[n // 2] = (a + end) / 2
    return out


def read_trajectories(path, bodies, only=None, operational=None) -> TrajectoryFile:
    """Read a CASPR ``*_trajectories.xml`` (``only``: the ids to keep, ``operational:ID`` for an
    operational-space trajectory; an unknown id is an error). ``operational``: the model's
    :class:`~mcdm_pin.caspr.operational.OperationalChoice` (its set, or why there is none)."""
    path, root = parse_xml(path)
    if root.tag != "trajectories":
        raise CasprError(path, f"<{root.tag}>", "expected the root element <trajectories>")
    jt = root.find("joint_trajectories")
    elements = list(jt) if jt is not None else []
    ids = [el.get("id") for el in elements]
    op_root = root.find("operational_trajectories")
    ids += [f"operational:{el.get('id')}" for el in (list(op_root) if op_root is not None else [])]
    if only is not None:
        missing = [i for i in only if i not in ids]
        if missing:
            raise CasprError(path, "joint_trajectories", f"no trajectory {missing[0]!r}; expected one of "
                                                         f"{', '.join(map(str, ids)) or '(none)'}")
    kept: dict[str, CasprTrajectory] = {}
    refused: dict[str, str] = {}
    for k, el in enumerate(elements, start=1):
        tid = el.get("id") or f"{el.tag}[{k}]"
        if only is not None and tid not in only:
            continue
        where = f"joint_trajectories/{el.tag}[id={tid!r}]"
        try:
            if not el.get("id"):
                raise _Refused(f"{where}: missing id attribute")
            if tid in kept or tid in refused:
                tid = f"{tid} (element {k})"
                raise _Refused(f"{where}: duplicate id (ids must be unique; element {k} of joint_trajectories)")
            kept[tid] = _read_one(path, el, tid, where, bodies)
        except _Refused as exc:
            refused.setdefault(tid, str(exc))
    op = root.find("operational_trajectories")
    for k, el in enumerate(list(op) if op is not None else [], start=1):
        tid = f"operational:{el.get('id') or f'{el.tag}[{k}]'}"
        if only is not None and tid not in only:
            continue
        where = f"operational_trajectories/{el.tag}[id={el.get('id')!r}]"
        try:
            if tid in kept or tid in refused:
                raise _Refused(f"{where}: duplicate id (ids must be unique)")
            kept[tid] = _read_operational(path, el, tid, where, operational)
        except _Refused as exc:
            refused.setdefault(tid, str(exc))
    return TrajectoryFile(path=path, trajectories=kept, refused=refused)


def _fail(where, message):
    raise _Refused(f"{where}: {message}")


def _num(path, value, where) -> float:
    try:
        return number(path, value, where)
    except CasprError as exc:
        raise _Refused(f"{exc.element}: {exc.expected}") from None


def _vec(path, el, tag, where, n) -> np.ndarray:
    found = el.find(tag)
    if found is None or found.text is None or not found.text.strip():
        _fail(f"{where}/{tag}", f"missing; expected {n} numbers (CASPR's loader needs it)")
    try:
        return np.array(numbers(path, found.text, f"{where}/{tag}", n))
    except CasprError as exc:
        raise _Refused(f"{exc.element}: {exc.expected}") from None


def _rotation_coords(bodies) -> np.ndarray:
    """Mask of CASPR coordinates that CASPR interpolates on SO(3) (zero rates only)."""
    mask = np.zeros(bodies.n_q, dtype=bool)
    for link, k in zip(bodies.links, bodies.offsets):
        if link.kind.rotation is not None:
            s = k + link.kind.rotation[1]
            mask[s:s + 3] = True
    return mask


def _read_one(path, el, tid, where, bodies) -> CasprTrajectory:
    if el.tag == "file_trajectory":
        return _read_file(path, el, tid, where, bodies)
    if el.tag not in TYPES:
        _fail(where, f"unknown trajectory type <{el.tag}>; expected one of {', '.join(TYPES)}")
    tdef, dt = _timing(path, el, where)
    blend_default = None
    if el.tag == "parabolic_blend_trajectory":
        blend_default = _num(path, el.get("blend_time_default"), f"{where}@blend_time_default")
    pts_el = el.find("points")
    if pts_el is None:
        _fail(where, "missing <points> element")
    n = bodies.n_q
    rot = _rotation_coords(bodies)
    points, blend = [], []
    for i, pt in enumerate(pts_el, start=1):
        pw = f"{where}/points/point[{i}]"
        if pt.tag != "point":
            _fail(pw, f"unknown element <{pt.tag}>; expected <point>")
        q = _vec(path, pt, "q", pw, n)
        rates = [np.zeros(n), np.zeros(n)]
        wanted = RATES[el.tag]
        if el.tag == "cubic_spline_average_velocity_trajectory" and (i == 1 or i == len(pts_el)):
            wanted = ("q_dot",)  # CASPR asserts the first and last velocities are given
        for j, tag in enumerate(wanted):
            rates[j] = _vec(path, pt, tag, pw, n)
        if np.any(rates[0][rot] != 0) or np.any(rates[1][rot] != 0):
            _fail(pw, "non-zero q_dot/q_ddot on a spherical joint's angles: CASPR splines spherical joints "
                      "from rest to rest only (it refuses this trajectory)")
        t = _point_time(path, pt, pw, i, points, tdef)
        if i > 1:
            if blend_default is not None:
                b = pt.get("blend_time")
                b = blend_default if b is None else _num(path, b, f"{pw}@blend_time")
                if not 0 < 2 * b < t - points[-1].time:
                    _fail(f"{pw}@blend_time", f"the blend time {b:g} s must be positive and less than half the "
                                              f"segment ({t - points[-1].time:g} s), as CASPR asserts")
                blend.append(b)
        points.append(CasprPoint(time=t, q=q, q_dot=rates[0], q_ddot=rates[1]))
    if len(points) < 2:
        _fail(f"{where}/points", f"expected at least two <point>, got {len(points)}")
    if el.tag == "cubic_spline_average_velocity_trajectory":
        points = _average_velocities(points, rot, where)
    return CasprTrajectory(id=tid, type=el.tag, time_step=dt, points=tuple(points), element=where,
                           blend=tuple(blend))


def _timing(path, el, where: str) -> tuple[str, float]:
    """A trajectory element's ``(time_definition, time_step)``: ``absolute`` or ``relative``, and a
    positive step (s)."""
    tdef = el.get("time_definition")
    if tdef not in ("absolute", "relative"):
        _fail(f"{where}@time_definition", f"expected 'absolute' or 'relative', got {tdef!r}")
    dt = _num(path, el.get("time_step"), f"{where}@time_step")
    if not dt > 0:
        _fail(f"{where}@time_step", f"expected a positive time step, got {dt}")
    return tdef, dt


def _point_time(path, pt, pw: str, i: int, points, tdef: str) -> float:
    """The time of the ``i``-th point (1-based) ``pt``: 0 for the first (CASPR ignores its time), else
    its ``time`` (absolute, or relative to the previous point's), after the previous point's."""
    if i == 1:
        return 0.0
    raw = pt.get("time")
    if raw is None:
        _fail(f"{pw}@time", "missing; every point after the first needs a time")
    tv = _num(path, raw, f"{pw}@time")
    t = tv if tdef == "absolute" else points[-1].time + tv
    if not t > points[-1].time:
        _fail(f"{pw}@time", f"expected a time after {points[-1].time:g} s (time_definition={tdef!r}), got {raw}")
    return t


def _average_velocities(points, rot, where):
    """CASPR's inner velocities: the mean of the slopes of the two segments that meet there."""
    out = [points[0]]
    for p in range(1, len(points) - 1):
        a, b, c = points[p - 1], points[p], points[p + 1]
        v = ((b.q - a.q) / (b.time - a.time) + (c.q - b.q) / (c.time - b.time)) / 2
        if np.any(v[rot] != 0):
            _fail(f"{where}/points/point[{p + 1}]", "the mean velocity of a spherical joint's angles is not zero "
                                                     "here, and CASPR splines spherical joints from rest to rest "
                                                     "only (it refuses this trajectory)")
        out.append(CasprPoint(time=b.time, q=b.q, q_dot=v, q_ddot=np.zeros_like(v)))
    out.append(points[-1])
    return out


def _read_file(path, el, tid, where, bodies) -> CasprTrajectory:
    name = el.get("filename")
    if not name:
        _fail(f"{where}@filename", "missing; expected the name of a .traj file next to the XML")
    file = path.parent / name
    try:
        lines = file.read_text(encoding="utf-8").splitlines()
    except FileNotFoundError:
        _fail(f"{where}@filename", f"the file {name!r} is not next to {path.name} (not found)")
    except (OSError, UnicodeDecodeError) as exc:
        _fail(f"{where}@filename", f"cannot read {name!r} ({type(exc).__name__})")
    fw = f"{name}"
    head = lines[0].split("time_step,") if lines else []
    if len(head) != 2:
        _fail(fw, "line 1: expected 'time_step,DT'")
    dt = _num(path, head[1], f"{fw} line 1")
    n = bodies.n_q
    ts, qs, vs, accs = [], [], [], []
    time = 0.0
    for k, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        parts = [s.strip() for s in line.split(",")]
        try:
            ip, iv, ia = parts.index("p"), parts.index("v"), parts.index("a")
            if parts[0] != "t" or not 1 < ip < iv < ia:
                raise ValueError
            t = float(parts[1])
            q, v, a = (np.array([float(x) for x in parts[s + 1:e]]) for s, e in ((ip, iv), (iv, ia), (ia, len(parts))))
        except ValueError:
            _fail(f"{fw} line {k}", "expected 't,TIME,p,q...,v,q_dot...,a,q_ddot...'")
        if not (len(q) == len(v) == len(a) == n):
            _fail(f"{fw} line {k}", f"expected {n} values after each of p, v and a, got {len(q)}, {len(v)}, {len(a)}")
        if abs(t - time) > 1e-9:  # CASPR's check: the times are 0, dt, 2 dt, ...
            _fail(f"{fw} line {k}", f"time {t} is not {time:.9g} (the previous time plus time_step)")
        ts.append(time)
        time += dt
        qs.append(q), vs.append(v), accs.append(a)
    if len(ts) < 1:
        _fail(fw, "no samples")
    samples = (matlab_colon(0.0, dt, (len(ts) - 1) * dt), np.array(qs), np.array(vs), np.array(accs))
    return CasprTrajectory(id=tid, type=el.tag, time_step=dt, points=(), element=where, samples=samples)


def _read_operational(path, el, tid, where, operational) -> CasprOperationalTrajectory:
    """An operational-space trajectory's points, checked against the model's operational set."""
    if el.tag not in OPERATIONAL_TYPES:
        _fail(where, f"CASPR's OperationalTrajectory implements {' and '.join(OPERATIONAL_TYPES)} only (for "
                     f"<{el.tag}> it raises 'Function has not been implemented yet')")
    opset = getattr(operational, "set", None)
    if opset is None:
        _fail(where, "an operational-space trajectory is solved by inverse kinematics on the model's operational "
                     f"space, and there is none: {getattr(operational, 'reason', 'no operational-spaces file given')}")
    tdef, dt = _timing(path, el, where)
    pts_el = el.find("points")
    if pts_el is None:
        _fail(where, "missing <points> element")
    n = opset.dim
    points = []
    for i, pt in enumerate(pts_el, start=1):
        pw = f"{where}/points/point[{i}]"
        if pt.tag != "point":
            _fail(pw, f"unknown element <{pt.tag}>; expected <point>")
        try:
            y = _vec(path, pt, "y", pw, n)
            rates = [_vec(path, pt, tag, pw, n) for tag in OPERATIONAL_TYPES[el.tag]] or [np.zeros(n)] * 2
        except _Refused as exc:
            raise _Refused(f"{exc} (operational set {opset.id!r}: {n} coordinates, {opset.coordinates})") from None
        t = _point_time(path, pt, pw, i, points, tdef)
        points.append(CasprPoint(time=t, q=y, q_dot=rates[0], q_ddot=rates[1]))
    if len(points) < 2:
        _fail(f"{where}/points", f"expected at least two <point>, got {len(points)}")
    return CasprOperationalTrajectory(id=tid, type=el.tag, time_step=dt, points=tuple(points), element=where,
                                      operational_set=opset)
