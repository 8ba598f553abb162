"""Cable sidecar (YAML) -> validated plain data.

This module knows nothing of Pinocchio: it checks types, ranges and key names, and returns frozen
dataclasses. Whether link and joint names exist in the URDF is checked by :mod:`mcdm_pin.robot`, which
raises the same :class:`~mcdm_pin.exceptions.SidecarError` with the same key paths.

The format is documented in ``docs/sidecar.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from . import yaml12
from .exceptions import SidecarError
from .limits import MAX_CABLES, MAX_ROUTE_POINTS, MAX_SAMPLES, MAX_SIDECAR_BYTES, MIN_FORCE_BOUND
from .sidecar_reader import TrajectorySpec, _join, _kind, _names, _parse_q, _Reader  # noqa: F401 (re-exported)
from .sidecar_pulleys import RotatingPulleySpec, parse_rotating  # noqa: F401 (RotatingPulleySpec: re-exported)
from .sidecar_springs import SpringSpec, parse_springs  # noqa: F401 (SpringSpec: a field's type, re-exported)
from .sidecar_task import parse_task
from .vocabulary import (SIDECAR_JOINT_TYPES, SPHERICAL_MODES, SPHERICAL_PARAMETRIZATIONS, URDF_JOINT_COUNTS,
                         WRAP_KINDS)

SUPPORTED_VERSIONS = (1,)
TRAJECTORY_TYPES = ("quintic", "csv", "task")


@dataclass(frozen=True)
class JointSpec:
    """One physical joint as the sidecar declares it (names not yet checked against the URDF)."""

    name: str
    type: str
    urdf_joints: tuple[str, ...]
    socket_axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    alpha: float = 1.0
    beta: float = 0.0
    cone_deg: float | None = None
    key: str = ""
    parametrization: str | None = None  # spherical joints: euler-xyz | quaternion | zyx
    actuated: "ActuatorSpec | None" = None


@dataclass(frozen=True)
class ActuatorSpec:
    """``actuated:`` of a joint (hybrid robots): bounds per degree of freedom and the weight of tau^2."""

    min: tuple[float, ...]
    max: tuple[float, ...]
    weight: float = 1.0
    key: str = ""


@dataclass(frozen=True)
class RoutePoint:
    link: str
    point: tuple[float, float, float]
    key: str = ""


@dataclass(frozen=True)
class WrapSpec:
    """A wrapping surface between two route points: a ``sphere`` or a ``cylinder`` fixed on ``link``
    (centre, and the cylinder's axis, in the link's frame), ``side`` an optional point of that frame on
    the side the cable passes."""

    kind: str
    link: str
    radius: float
    center: tuple[float, float, float] = (0.0, 0.0, 0.0)
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    side: tuple[float, float, float] | None = None
    key: str = ""


@dataclass(frozen=True)
class PulleySpec:
    """A pulley: the route's next branch counts ``1/divisor`` of its length and tension."""

    divisor: float
    key: str = ""


@dataclass(frozen=True)
class CableSpec:
    name: str
    f_min: float
    f_max: float
    route: tuple[RoutePoint, ...]
    key: str = ""


@dataclass(frozen=True)
class ReserveSpec:
    """A group of *reserve* actuators (biomechanics' coordinate actuators): one generalised force per
    named coordinate, within ``[-max, max]`` (N m or N), weighted ``weight`` in the objective."""

    coordinates: tuple[str, ...]
    max: float
    weight: float
    key: str = ""


@dataclass(frozen=True)
class Sidecar:
    """A validated sidecar. ``path`` is the YAML file (``None`` for data given in code)."""

    path: Path | None
    version: int
    name: str
    urdf: str
    urdf_path: Path | None
    gravity: tuple[float, float, float]
    joints: tuple[JointSpec, ...]
    cables: tuple[CableSpec, ...]
    locked_joints: dict[str, float] = field(default_factory=dict)
    trajectories: dict[str, TrajectorySpec] = field(default_factory=dict)
    description: str = ""
    mjcf_path: Path | None = None  # a sidecar over an MJCF file (``mjcf:`` instead of ``urdf:``)
    reserves: tuple = ()  # ReserveSpec: coordinate actuators of an MJCF robot
    springs: tuple = ()  # SpringSpec: passive springs (known tensions)
    osim_path: Path | None = None  # a sidecar over an OpenSim file (``osim:`` instead of ``urdf:``)
    # an .osim's CoordinateActuators: name -> w of w c^2; an MJCF's joint motors: name -> w of w |tau|^2
    actuator_weights: dict = field(default_factory=dict)


    def error(self, key: str, expected: str) -> SidecarError:
        return SidecarError(self.path, key, expected)


# --------------------------------------------------------------------------------------------------
# small typed readers: each one names the key path and what was expected


# --------------------------------------------------------------------------------------------------

TOP_KEYS = ("version", "name", "description", "urdf", "gravity", "joints", "cables", "springs", "locked_joints",
            "trajectories")
JOINT_KEYS = ("type", "urdf_joints", "parametrization", "socket_axis", "alpha", "beta", "cone_deg",
              "actuated")
ACTUATED_KEYS = ("min", "max", "weight")
CABLE_KEYS = ("name", "f_min", "f_max", "route")
POINT_KEYS = ("link", "point")
WRAP_KEYS = ("wrap", "link", "radius", "center", "axis", "side")
# a sidecar over an MJCF file: the robot (bodies, cables, muscles, couplings) comes from the MJCF; the
# sidecar adds what MJCF has no words for: joint weights, cones, trajectories, reserves, the weights of
# its joint motors
MJCF_TOP_KEYS = ("version", "name", "description", "mjcf", "joints", "trajectories", "reserves", "actuator_weights")
# a sidecar over an OpenSim file: the same, its CoordinateActuators weighed by name instead of reserves
OSIM_TOP_KEYS = ("version", "name", "description", "osim", "joints", "trajectories", "actuator_weights")
RESERVE_KEYS = ("coordinates", "max", "weight")
MJCF_JOINT_KEYS = ("socket_axis", "alpha", "beta", "cone_deg")
QUINTIC_KEYS = ("type", "q_start", "q_end", "duration", "dt", "spherical")
CSV_KEYS = ("type", "file")


def load_sidecar(path) -> Sidecar:
    """Read and validate a sidecar file.

    Raises:
        SidecarError: the file is missing, is not valid YAML, or breaks the format; the message
            names the file, the key path and what was expected.
    """
    path = Path(path)
    try:
        size = path.stat().st_size
        if size > MAX_SIDECAR_BYTES:
            raise SidecarError(path, "", f"the file has {size} bytes; a sidecar may have at most "
                                         f"{MAX_SIDECAR_BYTES} (docs/limits.md)")
        text = path.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise SidecarError(path, "", "file not found") from None
    except IsADirectoryError:
        raise SidecarError(path, "", "is a folder; expected a sidecar YAML file") from None
    except UnicodeDecodeError:
        raise SidecarError(path, "", "not UTF-8 text; expected a sidecar YAML file (is it a URDF, a CSV "
                                     "or a results file?)") from None
    except OSError as exc:
        raise SidecarError(path, "", f"cannot read the file ({exc.strerror or exc})") from None
    head = text.lstrip()[:200]
    if head.startswith("<"):
        kind = "a URDF" if "<robot" in text[:4096] else "an XML file"
        raise SidecarError(path, "", f"this is {kind}, not a sidecar: pass the sidecar YAML that names it "
                                     f"(docs/sidecar.md)")
    try:
        data = yaml12.load(text)
    except yaml12.YamlError as exc:
        where = f" at line {exc.line}" if exc.line else ""
        raise SidecarError(path, "", f"malformed YAML{where}: {exc.problem}") from None
    return parse_sidecar(data, path=path)


def parse_sidecar(data, path: Path | None = None, base_dir: Path | None = None) -> Sidecar:
    """Validate sidecar data already parsed from YAML (or built in code).

    Args:
        data: the YAML document as Python objects.
        path: the file it came from, for messages and to resolve relative paths.
        base_dir: folder relative paths are resolved against (default: the file's folder, or the
            current directory).
    """
    r = _Reader(path)
    if base_dir is None:
        base_dir = path.parent if path is not None else Path.cwd()
    if isinstance(data, dict) and ("mjcf" in data or "osim" in data):
        return _parse_mjcf_sidecar(r, data, path, base_dir)
    data = r.mapping(data, "", TOP_KEYS, required=("version", "urdf", "joints", "cables"))

    version = data["version"]
    if isinstance(version, bool) or version not in SUPPORTED_VERSIONS:
        raise r.fail("version", f"expected one of {list(SUPPORTED_VERSIONS)}, got {version!r}")

    urdf = r.string(data["urdf"], "urdf")
    urdf_path = None if urdf.startswith("package://") else (base_dir / urdf).resolve()
    name = r.string(data.get("name", path.stem if path else "robot"), "name")
    description = data.get("description", "")
    if not isinstance(description, str):
        raise r.fail("description", f"expected a string, got {_kind(description)}")
    gravity = r.vector(data.get("gravity", [0.0, 0.0, -9.81]), "gravity")

    joints = _parse_joints(r, data["joints"])
    cables = _parse_cables(r, data["cables"])
    springs = parse_springs(r, data.get("springs", []), _parse_route_element)

    locked_raw = data.get("locked_joints", {}) or {}
    if not isinstance(locked_raw, dict):
        raise r.fail("locked_joints", f"expected a mapping urdf_joint: value, got {_kind(locked_raw)}")
    locked = {}
    for k, v in locked_raw.items():
        key = f"locked_joints.{k}"
        r.string(k, key)
        locked[k] = r.number(v, key)

    trajs_raw = data.get("trajectories", {}) or {}
    if not isinstance(trajs_raw, dict):
        raise r.fail("trajectories", f"expected a mapping name: trajectory, got {_kind(trajs_raw)}")
    trajectories = {}
    for tname, spec in trajs_raw.items():
        trajectories[tname] = _parse_trajectory(r, tname, spec, base_dir)

    return Sidecar(path=path, version=int(version), name=name, urdf=urdf, urdf_path=urdf_path,
                   gravity=gravity, joints=joints, cables=cables, locked_joints=locked,
                   trajectories=trajectories, description=description, springs=springs)


def _parse_mjcf_sidecar(r: _Reader, data: dict, path: Path | None, base_dir: Path) -> Sidecar:
    """A sidecar over an MJCF file (``MJCF_TOP_KEYS``) or an OpenSim file (``OSIM_TOP_KEYS``): joints are
    the source's physical joints (MuJoCo bodies, OpenSim joints), by name, and take weights, a socket
    axis and a cone only."""
    osim = "osim" in data
    if osim and "mjcf" in data:
        raise r.fail("osim", "expected one of 'mjcf' and 'osim', got both")
    data = r.mapping(data, "", OSIM_TOP_KEYS if osim else MJCF_TOP_KEYS, required=("version", "osim" if osim else "mjcf"))
    version = data["version"]
    if isinstance(version, bool) or version not in SUPPORTED_VERSIONS:
        raise r.fail("version", f"expected one of {list(SUPPORTED_VERSIONS)}, got {version!r}")
    mjcf = r.string(data["osim" if osim else "mjcf"], "osim" if osim else "mjcf")
    name = r.string(data.get("name", path.stem if path else "robot"), "name")
    description = data.get("description", "")
    if not isinstance(description, str):
        raise r.fail("description", f"expected a string, got {_kind(description)}")
    joints = []
    raw = data.get("joints", {}) or {}
    if not isinstance(raw, dict):
        raise r.fail("joints", f"expected a mapping body_name: {{alpha, beta, cone_deg, socket_axis}}, got "
                               f"{_kind(raw)}")
    for jname, spec in raw.items():
        key = f"joints.{jname}"
        r.string(jname, key)
        spec = r.mapping(spec, key, MJCF_JOINT_KEYS)
        axis = r.vector(spec.get("socket_axis", [0.0, 0.0, 1.0]), f"{key}.socket_axis")
        norm = math.sqrt(sum(a * a for a in axis))
        if abs(norm - 1.0) > 1e-6:
            raise r.fail(f"{key}.socket_axis", f"expected a unit vector, got norm {norm:.6g}")
        cone = spec.get("cone_deg")
        if cone is not None:
            cone = r.number(cone, f"{key}.cone_deg", lo=0.0, hi=90.0, lo_open=True, hi_open=True)
        joints.append(JointSpec(name=jname, type="", urdf_joints=(), socket_axis=tuple(a / norm for a in axis),
                                alpha=r.number(spec.get("alpha", 1.0), f"{key}.alpha", lo=0.0),
                                beta=r.number(spec.get("beta", 0.0), f"{key}.beta", lo=0.0), cone_deg=cone,
                                key=key))
    trajs_raw = data.get("trajectories", {}) or {}
    if not isinstance(trajs_raw, dict):
        raise r.fail("trajectories", f"expected a mapping name: trajectory, got {_kind(trajs_raw)}")
    trajectories = {t: _parse_trajectory(r, t, spec, base_dir) for t, spec in trajs_raw.items()}
    source = (base_dir / mjcf).resolve()
    weights_raw = data.get("actuator_weights", {}) or {}
    if not isinstance(weights_raw, dict):
        what = "CoordinateActuator" if osim else "joint motor (MuJoCo actuator)"
        raise r.fail("actuator_weights", f"expected a mapping {what} name: weight, got {_kind(weights_raw)}")
    weights = {r.string(k, f"actuator_weights.{k}"): r.number(v, f"actuator_weights.{k}", lo=0.0)
               for k, v in weights_raw.items()}
    if osim:
        return Sidecar(path=path, version=int(version), name=name, urdf="", urdf_path=None,
                       gravity=(0.0, 0.0, 0.0), joints=tuple(joints), cables=(), trajectories=trajectories,
                       description=description, osim_path=source, actuator_weights=weights)
    return Sidecar(path=path, version=int(version), name=name, urdf="", urdf_path=None, gravity=(0.0, 0.0, 0.0),
                   joints=tuple(joints), cables=(), trajectories=trajectories, description=description,
                   mjcf_path=source, reserves=_parse_reserves(r, data.get("reserves", [])),
                   actuator_weights=weights)


def _parse_reserves(r: _Reader, raw) -> tuple[ReserveSpec, ...]:
    if not isinstance(raw, list):
        raise r.fail("reserves", f"expected a list of {{coordinates: [...], max: N m, weight: w}}, got {_kind(raw)}")
    out, seen = [], {}
    for i, item in enumerate(raw):
        key = f"reserves[{i}]"
        item = r.mapping(item, key, RESERVE_KEYS, required=("coordinates", "max"))
        names = item["coordinates"]
        if not isinstance(names, list) or not names:
            raise r.fail(f"{key}.coordinates", f"expected a non-empty list of coordinate names, got {_kind(names)}")
        for k, n in enumerate(names):
            r.string(n, f"{key}.coordinates[{k}]")
            if n in seen:
                raise r.fail(f"{key}.coordinates[{k}]", f"coordinate {n!r} already has a reserve ({seen[n]})")
            seen[n] = key
        out.append(ReserveSpec(tuple(names), r.number(item["max"], f"{key}.max", lo=0.0, lo_open=True),
                               r.number(item.get("weight", 1.0), f"{key}.weight", lo=0.0), key))
    return tuple(out)


def _parse_joints(r: _Reader, raw) -> tuple[JointSpec, ...]:
    if not isinstance(raw, dict) or not raw:
        raise r.fail("joints", f"expected a non-empty mapping joint_name: {{type, urdf_joints, ...}}, "
                               f"got {_kind(raw)}")
    joints = []
    seen_urdf: dict[str, str] = {}
    for jname, spec in raw.items():
        key = f"joints.{jname}"
        r.string(jname, key)
        spec = r.mapping(spec, key, JOINT_KEYS, required=("type", "urdf_joints"))
        jtype = r.choice(spec["type"], f"{key}.type", SIDECAR_JOINT_TYPES)
        uj = spec["urdf_joints"]
        counts = URDF_JOINT_COUNTS[jtype]
        if isinstance(uj, str) and 1 in counts:
            uj = [uj]
        if not isinstance(uj, list) or len(uj) not in counts:
            want = " or ".join(str(c) for c in counts)
            raise r.fail(f"{key}.urdf_joints",
                         f"a {jtype} joint needs a list of {want} URDF joint name(s), got {_kind(uj)}")
        names = tuple(r.string(u, f"{key}.urdf_joints[{i}]") for i, u in enumerate(uj))
        for i, u in enumerate(names):
            if u in seen_urdf:
                raise r.fail(f"{key}.urdf_joints[{i}]",
                             f"URDF joint {u!r} is already used by joint {seen_urdf[u]!r}")
            seen_urdf[u] = jname
        axis = r.vector(spec.get("socket_axis", [0.0, 0.0, 1.0]), f"{key}.socket_axis")
        norm = math.sqrt(sum(a * a for a in axis))
        if abs(norm - 1.0) > 1e-6:
            raise r.fail(f"{key}.socket_axis", f"expected a unit vector, got norm {norm:.6g}")
        axis = tuple(a / norm for a in axis)
        alpha = r.number(spec.get("alpha", 1.0), f"{key}.alpha", lo=0.0)
        beta = r.number(spec.get("beta", 0.0), f"{key}.beta", lo=0.0)
        parametrization = None
        if jtype == "spherical":
            allowed = SPHERICAL_PARAMETRIZATIONS[len(uj)]
            parametrization = r.choice(spec.get("parametrization", allowed[0]), f"{key}.parametrization", allowed)
        elif "parametrization" in spec:
            raise r.fail(f"{key}.parametrization", "a parametrization is chosen for spherical joints only")
        actuated = None
        if spec.get("actuated") is not None:
            actuated = _parse_actuated(r, spec["actuated"], f"{key}.actuated")
        cone = spec.get("cone_deg")
        if cone is not None:
            if jtype != "spherical":
                raise r.fail(f"{key}.cone_deg", "a stability cone is defined for spherical joints only")
            cone = r.number(cone, f"{key}.cone_deg", lo=0.0, hi=90.0, lo_open=True, hi_open=True)
        joints.append(JointSpec(name=jname, type=jtype, urdf_joints=names, socket_axis=axis,
                                alpha=alpha, beta=beta, cone_deg=cone, key=key,
                                parametrization=parametrization, actuated=actuated))
    return tuple(joints)


def _parse_actuated(r: _Reader, raw, key: str) -> ActuatorSpec:
    """``{min: [...], max: [...], weight: w}``: one bound per degree of freedom (checked against the
    joint by the loader), a single number meaning one degree of freedom. A bound may be ``-.inf``
    (``min``) or ``.inf`` (``max``): that side is unbounded; ``min`` and ``max`` left out both mean an
    unbounded motor (CASPR's default), which needs ``weight > 0``."""
    raw = r.mapping(raw, key, ACTUATED_KEYS)
    weight = r.number(raw.get("weight", 1.0), f"{key}.weight", lo=0.0)
    if "min" not in raw and "max" not in raw:
        if weight == 0:
            raise r.fail(f"{key}.weight", "an unbounded motor (no min, no max) needs a weight > 0: nothing "
                                          "else keeps its torque finite")
        return ActuatorSpec(min=(), max=(), weight=weight, key=key)
    for k in ("min", "max"):
        if k not in raw:
            raise r.fail(_join(key, k), f"missing required key {k!r} (give both bounds, or neither for an "
                                        f"unbounded motor)")
    lo = raw["min"] if isinstance(raw["min"], list) else [raw["min"]]
    hi = raw["max"] if isinstance(raw["max"], list) else [raw["max"]]
    lo = tuple(-math.inf if _is_inf(v, -1) else r.number(v, f"{key}.min[{i}]") for i, v in enumerate(lo))
    if len(hi) != len(lo):
        raise r.fail(f"{key}.max", f"expected a list of {len(lo)} numbers, got {len(hi)}")
    hi = tuple(math.inf if _is_inf(v, 1) else r.number(v, f"{key}.max[{i}]") for i, v in enumerate(hi))
    for i, (a, b) in enumerate(zip(lo, hi)):
        if not a < b:
            raise r.fail(f"{key}.max[{i}]", f"expected max > min = {a!r}, got {b!r}")
    if weight == 0 and not all(math.isfinite(x) for x in lo + hi):
        raise r.fail(f"{key}.weight", "a motor with an unbounded side needs a weight > 0: nothing else keeps "
                                      "its torque finite")
    return ActuatorSpec(min=lo, max=hi, weight=weight, key=key)


def _is_inf(value, sign: int) -> bool:
    """``value`` is the float infinity of ``sign`` (YAML's ``.inf`` / ``-.inf``)."""
    return isinstance(value, float) and math.isinf(value) and (value > 0) == (sign > 0)


def _parse_cables(r: _Reader, raw) -> tuple[CableSpec, ...]:
    if not isinstance(raw, list) or not raw:
        raise r.fail("cables", f"expected a non-empty list of cables, got {_kind(raw)}")
    if len(raw) > MAX_CABLES:
        raise r.fail("cables", f"expected at most {MAX_CABLES} cables (docs/limits.md), got {len(raw)}")
    cables = []
    names: dict[str, int] = {}
    for i, spec in enumerate(raw):
        key = f"cables[{i}]"
        spec = r.mapping(spec, key, CABLE_KEYS, required=CABLE_KEYS)
        name = r.string(spec["name"], f"{key}.name")
        if name in names:
            raise r.fail(f"{key}.name", f"cable name {name!r} is already used by cables[{names[name]}]")
        names[name] = i
        f_min = r.number(spec["f_min"], f"{key}.f_min", lo=0.0)
        f_max = r.number(spec["f_max"], f"{key}.f_max")
        for which, value in (("f_min", f_min), ("f_max", f_max)):
            if 0.0 < abs(value) < MIN_FORCE_BOUND:
                raise r.fail(f"{key}.{which}", f"expected 0 or at least {MIN_FORCE_BOUND:g} N (docs/limits.md: "
                                               f"smaller forces' squares underflow), got {value!r}")
        if not f_max > f_min:
            raise r.fail(f"{key}.f_max", f"expected f_max > f_min = {f_min!r}, got {f_max!r}")
        route = spec["route"]
        if isinstance(route, list) and len(route) > MAX_ROUTE_POINTS:
            raise r.fail(f"{key}.route", f"expected at most {MAX_ROUTE_POINTS} points (docs/limits.md), "
                                         f"got {len(route)}")
        if not isinstance(route, list) or len(route) < 2:
            got = f"{len(route)} point(s)" if isinstance(route, list) else _kind(route)
            raise r.fail(f"{key}.route", f"expected a list of at least two {{link, point}}, got {got}")
        points = [_parse_route_element(r, p, f"{key}.route[{k}]") for k, p in enumerate(route)]
        cables.append(CableSpec(name=name, f_min=f_min, f_max=f_max, route=tuple(points), key=key))
    return tuple(cables)


def _parse_route_element(r: _Reader, p, pkey: str):
    """``{link, point}``, ``{wrap: sphere|cylinder, link, radius, center, axis, side}``, ``{pulley: d}``
    or ``{rotating_pulley: radius, link, entry, axis, screw}``."""
    if isinstance(p, dict) and "rotating_pulley" in p:
        return parse_rotating(r, p, pkey)
    if isinstance(p, dict) and "pulley" in p:
        p = r.mapping(p, pkey, ("pulley",), required=("pulley",))
        return PulleySpec(r.number(p["pulley"], f"{pkey}.pulley", lo=0.0, lo_open=True), key=pkey)
    if isinstance(p, dict) and "wrap" in p:
        p = r.mapping(p, pkey, WRAP_KEYS, required=("wrap", "link", "radius"))
        axis = r.vector(p.get("axis", [0.0, 0.0, 1.0]), f"{pkey}.axis")
        norm = math.sqrt(sum(a * a for a in axis))
        if abs(norm - 1.0) > 1e-6:
            raise r.fail(f"{pkey}.axis", f"expected a unit vector, got norm {norm:.6g}")
        side = r.vector(p["side"], f"{pkey}.side") if p.get("side") is not None else None
        return WrapSpec(kind=r.choice(p["wrap"], f"{pkey}.wrap", WRAP_KINDS), link=r.string(p["link"], f"{pkey}.link"),
                        radius=r.number(p["radius"], f"{pkey}.radius", lo=0.0, lo_open=True),
                        center=r.vector(p.get("center", [0.0, 0.0, 0.0]), f"{pkey}.center"),
                        axis=tuple(a / norm for a in axis), side=side, key=pkey)
    p = r.mapping(p, pkey, POINT_KEYS, required=POINT_KEYS)
    return RoutePoint(link=r.string(p["link"], f"{pkey}.link"), point=r.vector(p["point"], f"{pkey}.point"),
                      key=pkey)


def _parse_trajectory(r: _Reader, name, spec, base_dir: Path) -> TrajectorySpec:
    key = f"trajectories.{name}"
    r.string(name, key)
    if not isinstance(spec, dict) or "type" not in spec:
        raise r.fail(key, f"expected a mapping with a 'type' of {_names(TRAJECTORY_TYPES)}, "
                          f"got {_kind(spec)}")
    ttype = r.choice(spec["type"], f"{key}.type", TRAJECTORY_TYPES)
    if ttype == "task":
        return parse_task(r, name, spec, base_dir, key)
    if ttype == "csv":
        spec = r.mapping(spec, key, CSV_KEYS, required=CSV_KEYS)
        file = (base_dir / r.string(spec["file"], f"{key}.file")).resolve()
        return TrajectorySpec(name=name, type="csv", file=file, key=key)
    spec = r.mapping(spec, key, QUINTIC_KEYS, required=("type", "q_start", "q_end", "duration", "dt"))
    q0 = _parse_q(r, spec["q_start"], f"{key}.q_start")
    q1 = _parse_q(r, spec["q_end"], f"{key}.q_end")
    duration = r.number(spec["duration"], f"{key}.duration", lo=0.0, lo_open=True)
    dt = r.number(spec["dt"], f"{key}.dt", lo=0.0, lo_open=True)
    if dt > duration:
        raise r.fail(f"{key}.dt", f"expected dt <= duration = {duration!r}, got {dt!r}")
    if duration / dt + 1 > MAX_SAMPLES:
        raise r.fail(f"{key}.dt", f"expected at most {MAX_SAMPLES} samples (docs/limits.md), got "
                                  f"duration/dt + 1 = {duration / dt + 1:.3g}")
    mode = r.choice(spec.get("spherical", "axis-angle"), f"{key}.spherical", SPHERICAL_MODES)
    return TrajectorySpec(name=name, type="quintic", q_start=q0, q_end=q1, duration=duration, dt=dt,
                          spherical=mode, key=key)
