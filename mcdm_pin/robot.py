"""A loader: URDF + sidecar (or a ``pin.Model`` built in code) -> :class:`Robot`.

A :class:`Robot` is what the layers above need and nothing more: the Pinocchio model, the
:class:`~mcdm_pin.model.cables.CableSet`, the physical joints (:mod:`mcdm_pin.model.joints`) and, for
hybrid robots, the actuators. Every computation on it goes through :mod:`mcdm_pin.model`, the layer in
Pinocchio's idiom that a Pinocchio user may call directly.

**Configuration and coordinates.** ``q`` is Pinocchio's configuration vector (``nq`` entries); users may
also give *coordinates*, one number per degree of freedom (``nv``; a rotation vector for a native ball
joint: :mod:`mcdm_pin.model.charts`). :meth:`Robot.check_configuration` accepts either; for robots whose
joints all have ``nq == nv`` the two are the same vector.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin

from .exceptions import ModelError, ProblemError, SidecarError, StateError
from .model import charts
from .model.actuators import Actuator, actuation_matrix
from .model.cables import Cable, CableSet, RoutePoint
from .model.joints import PhysicalJoint, group, massless_members, physical_joints
from .model.terms import check_vector
from .mjcf.load import compile_mjcf, is_mjcf, mjcf_parts
from .osim.load import is_osim, osim_parts
from .sidecar import Sidecar, _names, load_sidecar
from .urdf import check_model_inertias, load_model, package_share_dirs, replace_joints, urdf_joint_axes

__all__ = ["Robot", "package_share_dirs", "resolve_package_uri"]


def resolve_package_uri(uri: str, sidecar_path=None, key: str = "urdf") -> Path:
    """Resolve ``package://NAME/rest`` to a file through installed packages (no network)."""
    rest = uri[len("package://"):]
    package, _, inner = rest.partition("/")
    if not package or not inner:
        raise SidecarError(sidecar_path, key, f"expected package://PACKAGE/PATH, got {uri!r}")
    if package in (".", "..") or "\\" in rest:
        raise SidecarError(sidecar_path, key, f"expected package://PACKAGE/PATH, got {uri!r}")
    tried = []
    for share in package_share_dirs():
        root = (share / package).resolve()
        candidate = (share / package / inner).resolve()
        tried.append(str(share))
        if root != candidate and root not in candidate.parents:
            raise SidecarError(sidecar_path, key, f"{uri!r} leaves the package {package!r}: a package:// path "
                                                  f"must stay inside its package's folder")
        if candidate.is_file():
            return candidate
    raise SidecarError(sidecar_path, key,
                       f"cannot resolve {uri!r}: no installed package {package!r} holds {inner!r} "
                       f"(searched {', '.join(tried) or 'no package folders'}; install the package, "
                       f"e.g. pip install {package})")


class Robot:
    """A cable-driven manipulator: Pinocchio model + cables + physical joints (+ actuators).

    Build one with :meth:`Robot.load` (a sidecar file), :meth:`Robot.from_sidecar` or
    :meth:`Robot.from_model` (a ``pin.Model`` built in code, no file).

    Attributes:
        model: the Pinocchio model (reduced, if the sidecar locks joints).
        cables: the :class:`~mcdm_pin.model.cables.CableSet`.
        joints: the physical joints (sidecar order, or Pinocchio's joint order for ``from_model``).
        actuators: the actuated joints' motors (hybrid robots), possibly empty.
        name: the robot's name; ``sidecar`` and ``urdf_path`` are ``None`` for a robot built in code.
        nq, nv: sizes of the configuration and of the velocity; ``m`` cables; ``n_act`` actuator
            components.
        coordinate_names (nv), configuration_names (nq): see :mod:`mcdm_pin.model.charts` (a robot
            loaded from MJCF names its coordinates after MuJoCo's joints).
        couplings: the :class:`~mcdm_pin.model.couplings.Couplings` of coupled coordinates, or ``None``.
        springs: the passive springs (:class:`~mcdm_pin.model.springs.SpringSet`), or ``None``: known
            tensions on the right-hand side of the equation of motion and in the interaction wrenches.
        source: what a loader keeps of its source format (an MJCF robot's maps), or ``None``.
        notes: what the loader left out of the source and why (shown by ``mcdm-pin info``).
    """

    def __init__(self, model: pin.Model, cables: CableSet, joints, actuators=(), name: str = "robot",
                 sidecar: Sidecar | None = None, urdf_path: Path | None = None, couplings=None,
                 coordinate_names=None, source=None, notes=(), springs=None):
        cables.check_model(model)
        if springs is not None:
            springs.check_model(model)
        self.model = model
        self.cables = cables
        self.joints = tuple(joints)
        self.actuators = tuple(actuators)
        self.name = name
        self.sidecar = sidecar
        self.urdf_path = urdf_path
        self.couplings = couplings
        self.source = source
        # known joint forces (N, N m) at (q, v): an MJCF model's joint springs and dampers
        self.passive = getattr(source, "passive", None)
        # passive springs: known tensions that follow their lengths (mcdm_pin.model.springs), or None
        self.springs = springs if springs is not None and len(springs) else None
        self.notes = tuple(notes)
        self.nq, self.nv = model.nq, model.nv
        self._parts = charts.chart_parts(model)
        self.coordinate_names = (charts.coordinate_names(model) if coordinate_names is None
                                 else tuple(coordinate_names))
        if couplings is not None:
            free = set(couplings.independent.tolist())
            for a in self.actuators:
                bad = [self.coordinate_names[i] for i in a.idx_v if int(i) not in free]
                if bad:
                    raise ModelError(f"actuator of joint {a.joint!r}: coordinate(s) {bad} follow couplings; an "
                                     f"actuator drives independent coordinates only")
        self.configuration_names = charts.configuration_names(model)
        self.link_names = tuple(dict.fromkeys(f.name for f in model.frames if f.type == pin.FrameType.BODY))
        self.f_min, self.f_max = cables.f_min, cables.f_max
        self._check_joints()

    def _check_joints(self) -> None:
        covered = {pid for j in self.joints for pid in j.pin_ids}
        missing = [self.model.names[j] for j in range(1, self.model.njoints) if j not in covered]
        if missing:
            raise ModelError(f"Pinocchio joint(s) {_names(missing)} belong to no physical joint")
        names = [j.name for j in self.joints]
        if len(set(names)) != len(names):
            raise ModelError(f"physical joint names must be unique, got {names}")
        inside = massless_members(self.joints)
        for k, jid in enumerate(self.cables.point_joint):
            if int(jid) in inside:
                cable = self.cables.cables[int(self.cables.point_cable[k])]
                raise ModelError(f"cable {cable.name!r}: a route point is fixed to the massless body inside "
                                 f"joint {inside[int(jid)]!r}; attach it to the parent or the child link")
        for a in self.actuators:
            if a.joint not in names:
                raise ModelError(f"actuator on unknown joint {a.joint!r}; expected one of {_names(names)}")

    # ----------------------------------------------------------------------------------------- load
    @classmethod
    def load(cls, path) -> "Robot":
        """Load a robot from a sidecar YAML file (which names its URDF or MJCF), a MuJoCo MJCF file or an
        OpenSim ``.osim`` file (:mod:`mcdm_pin.osim`)."""
        if is_osim(path):
            return cls(**osim_parts(path)._asdict())
        if is_mjcf(path):
            return cls.from_mujoco(compile_mjcf(path), str(path), Path(path).stem)
        return cls.from_sidecar(load_sidecar(path))

    @classmethod
    def from_mujoco(cls, mj, source: str = "mujoco model", name: str = "robot") -> "Robot":
        """A robot from a compiled ``mujoco.MjModel`` (:mod:`mcdm_pin.mjcf`; ``source`` names it in
        messages)."""
        try:
            return cls(**mjcf_parts(mj, source, name)._asdict())
        except ModelError as exc:
            msg = str(exc)
            raise ModelError(msg if msg.startswith(source) else f"{source}: {msg}") from None

    @classmethod
    def from_model(cls, model: pin.Model, cables, joints=None, actuators=(), name: str = "robot",
                   springs=None) -> "Robot":
        """A robot from a model built in code. ``cables``: a :class:`CableSet` or what its constructor
        takes; ``joints``: physical joints (default: every Pinocchio joint on its own,
        :func:`~mcdm_pin.model.joints.physical_joints`). Bodies whose inertia no body can have are
        refused (:func:`~mcdm_pin.urdf.check_model_inertias`). ``springs``: a
        :class:`~mcdm_pin.model.springs.SpringSet` or :class:`~mcdm_pin.model.springs.Spring` objects."""
        from .model.springs import SpringSet

        check_model_inertias(model)
        if not isinstance(cables, CableSet):
            cables = CableSet(model, cables)
        if springs is not None and not isinstance(springs, SpringSet):
            springs = SpringSet(model, springs)
        return cls(model, cables, physical_joints(model) if joints is None else joints, actuators, name,
                   springs=springs)

    @classmethod
    def from_sidecar(cls, sidecar: Sidecar) -> "Robot":
        sc = sidecar
        if sc.mjcf_path is not None or sc.osim_path is not None:
            return _from_model_file_sidecar(sc)
        if sc.urdf_path is None:
            urdf_path = resolve_package_uri(sc.urdf, sc.path)
        else:
            urdf_path = sc.urdf_path
            if not urdf_path.is_file():
                raise sc.error("urdf", f"URDF file not found: {urdf_path}")
        model = load_model(urdf_path)
        model.gravity.linear = np.array(sc.gravity, dtype=float)
        model = _lock_joints(model, sc)
        model = _native_joints(model, sc, urdf_path)
        joints = _physical_joints(model, sc, urdf_path)
        cables = _cables(model, sc, joints)
        springs = _springs(model, sc, joints)
        actuators = _actuators(sc, joints)
        try:
            return cls(model, cables, joints, actuators, sc.name, sc, urdf_path, springs=springs)
        except ModelError as exc:
            raise sc.error("joints", str(exc)) from None

    # ------------------------------------------------------------------------------------ structure
    @property
    def m(self) -> int:
        """Number of cables."""
        return self.cables.m

    @property
    def n_act(self) -> int:
        """Number of actuator components (hybrid robots; 0 otherwise)."""
        return sum(len(a.idx_v) for a in self.actuators)

    @property
    def cable_names(self) -> tuple[str, ...]:
        return self.cables.names

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(j.name for j in self.joints)

    @property
    def actuation(self) -> np.ndarray:
        """(nv, n_act) the actuation matrix ``S`` (:func:`~mcdm_pin.model.actuators.actuation_matrix`); with
        coupled coordinates, its rows of the independent ones (the equation of motion's rows)."""
        S = actuation_matrix(self.nv, self.actuators)
        return S if self.couplings is None else S[self.couplings.independent]

    def joint(self, name: str) -> PhysicalJoint:
        for j in self.joints:
            if j.name == name:
                return j
        raise ProblemError(f"unknown joint {name!r}; expected one of {_names(self.joint_names)}")

    def link_placement(self, link: str):
        """(Pinocchio joint id, placement of the frame ``link`` in that joint's frame)."""
        from .model.cables import find_frame

        frame = self.model.frames[find_frame(self.model, link)]
        return int(frame.parentJoint), frame.placement

    # ---------------------------------------------------------------------------------------- state
    def configuration(self, coords) -> np.ndarray:
        """Coordinates (nv) -> Pinocchio's configuration (nq); or ``{name: value}`` in the source's names
        and units (MJCF: MuJoCo's joint values, all of them or the independent ones only)."""
        if isinstance(coords, dict):
            if self.source is None:
                x = np.zeros(self.nv)
                for key, value in coords.items():
                    if key not in self.coordinate_names:
                        raise StateError(f"unknown coordinate {key!r}; expected one of {_names(self.coordinate_names)}")
                    x[self.coordinate_names.index(key)] = value
                return charts.configuration(self.model, x, self._parts)
            return self.source.configuration(coords)
        return charts.configuration(self.model, coords, self._parts)

    def coordinates(self, q) -> np.ndarray:
        """Pinocchio's configuration (nq) -> coordinates (nv)."""
        return charts.coordinates(self.model, q, self._parts)

    def pin_q(self, q) -> np.ndarray:
        """The configuration of ``q`` given as a configuration (nq) or as coordinates (nv)."""
        return self.check_configuration(q)

    def check_configuration(self, q, name: str = "q") -> np.ndarray:
        """``q`` as Pinocchio's configuration: a finite vector of length nq, or of length nv
        (coordinates, converted); :class:`StateError` otherwise. A quaternion must have unit norm
        (to 1e-6; it is normalised): :func:`mcdm_pin.model.charts.check_configuration`, the one check
        of every entry point."""
        return charts.check_configuration(self.model, q, name, self._parts, coordinates=True)

    def reference_coordinates(self) -> np.ndarray:
        """(nv,) the source's reference pose as coordinates: zeros, or an MJCF model's ``qpos0`` with
        its coupled coordinates following their couplings."""
        if self.source is None:
            return np.zeros(self.nv)
        return self.coordinates(self.source.configuration({}))

    def follow_couplings(self, x: np.ndarray) -> np.ndarray:
        """Coordinates ``x`` ((nv,) or (n, nv)) with every coupled coordinate computed from the
        independent ones (:mod:`mcdm_pin.model.couplings`); unchanged without couplings."""
        if self.couplings is None:
            return x
        rows = np.atleast_2d(x)
        out = np.array([self.coordinates(self.couplings.fill(self.configuration(r))[0]) for r in rows])
        return out.reshape(np.shape(x))

    def check_vector(self, x, name: str, n: int | None = None) -> np.ndarray:
        """Return ``x`` as a float array of length ``n`` (default: nv), or raise :class:`StateError`."""
        return check_vector(x, name, self.nv if n is None else n)

    # compatibility: the flattened routes, as the layers above read them
    point_joint = property(lambda self: self.cables.point_joint)
    point_local = property(lambda self: self.cables.point_local)
    seg_a = property(lambda self: self.cables.seg_a)
    seg_b = property(lambda self: self.cables.seg_b)
    seg_cable = property(lambda self: self.cables.seg_cable)
    seg_active = property(lambda self: self.cables.seg_active)

    def __repr__(self) -> str:
        where = f", urdf={str(self.urdf_path)!r}" if self.urdf_path is not None else ""
        act = f", {self.n_act} actuators" if self.actuators else ""
        spr = f", {len(self.springs)} springs" if self.springs is not None else ""
        return f"Robot({self.name!r}: {len(self.joints)} joints, {self.nv} DoF, {self.m} cables{spr}{act}{where})"


# ------------------------------------------------------------------------------------ sidecar helpers
def _from_model_file_sidecar(sc: Sidecar) -> Robot:
    """The MJCF (or OpenSim) file's robot with the sidecar's joint settings, reserves and trajectories:
    the file is read (MuJoCo compiles an MJCF) once and the robot is built once, from its parts
    (:func:`~mcdm_pin.mjcf.load.mjcf_parts`, :func:`~mcdm_pin.osim.load.osim_parts`) with the sidecar's
    changes applied."""
    key, path = ("osim", sc.osim_path) if sc.osim_path is not None else ("mjcf", sc.mjcf_path)
    if not path.is_file():
        raise sc.error(key, f"{'OpenSim' if key == 'osim' else 'MJCF'} file not found: {path}")
    source = str(path)
    try:
        if sc.osim_path is not None:
            parts = osim_parts(path, sc.name, sc.actuator_weights)
        else:
            parts = mjcf_parts(compile_mjcf(path), source, sc.name, sc.actuator_weights)
    except ModelError as exc:
        raise sc.error(key, str(exc)) from None
    joints = {j.name: j for j in parts.joints}
    for spec in sc.joints:
        if spec.name not in joints:
            raise sc.error(spec.key, f"unknown joint {spec.name!r}; the {key.upper()} file's physical joints are "
                                     f"{_names(list(joints))}")
        try:
            joints[spec.name] = joints[spec.name].with_settings(alpha=spec.alpha, beta=spec.beta,
                                                                cone_deg=spec.cone_deg,
                                                                socket_axis=spec.socket_axis)
        except ModelError as exc:
            raise sc.error(spec.key, str(exc)) from None
    reserves = _reserves(sc, tuple(joints.values()), parts.coordinate_names, parts.couplings)
    try:
        return Robot(**{**parts._asdict(), "joints": tuple(joints.values()),
                        "actuators": parts.actuators + reserves}, sidecar=sc)
    except ModelError as exc:
        msg = str(exc)
        raise sc.error(key, msg if msg.startswith(source) else f"{source}: {msg}") from None


def _reserves(sc: Sidecar, joints, coordinate_names, couplings) -> tuple[Actuator, ...]:
    """The sidecar's reserve actuators: one per named coordinate, on the physical joint that holds it (an
    independent coordinate: one that follows couplings is driven through them)."""
    free = None if couplings is None else set(couplings.independent.tolist())
    out = []
    for spec in sc.reserves:
        for k, name in enumerate(spec.coordinates):
            key = f"{spec.key}.coordinates[{k}]"
            if name not in coordinate_names:
                raise sc.error(key, f"unknown coordinate {name!r}; expected one of {_names(coordinate_names)}")
            i = coordinate_names.index(name)
            if free is not None and i not in free:
                raise sc.error(key, f"coordinate {name!r} follows couplings; a reserve drives an independent "
                                    f"coordinate only")
            out.append(Actuator.on_coordinate(joints, i, -spec.max, spec.max, spec.weight, label=name))
    return tuple(out)


def _lock_joints(model: pin.Model, sc: Sidecar) -> pin.Model:
    if not sc.locked_joints:
        return model
    q_ref = pin.neutral(model)
    ids = []
    for name, value in sc.locked_joints.items():
        if not model.existJointName(name):
            names = [model.names[j] for j in range(1, model.njoints)]
            raise sc.error(f"locked_joints.{name}", f"unknown URDF joint {name!r}; expected one of "
                                                    f"{_names(names)}")
        j = model.getJointId(name)
        jm = model.joints[j]
        if jm.nv != 1:
            raise sc.error(f"locked_joints.{name}", f"cannot lock a {jm.shortname()}")
        if jm.nq == 1:
            q_ref[jm.idx_q] = value
        else:
            q_ref[jm.idx_q:jm.idx_q + 2] = np.cos(value), np.sin(value)
        ids.append(int(j))
    return pin.buildReducedModel(model, ids, q_ref)


def _urdf_joint(model: pin.Model, sc: Sidecar, spec, i: int) -> int:
    uname = spec.urdf_joints[i]
    key = f"{spec.key}.urdf_joints[{i}]"
    if uname in sc.locked_joints:
        raise sc.error(key, f"URDF joint {uname!r} is also listed in locked_joints")
    if not model.existJointName(uname):
        names = [model.names[j] for j in range(1, model.njoints)]
        raise sc.error(key, f"unknown URDF joint {uname!r}; expected one of {_names(names)}")
    return int(model.getJointId(uname))


def _native_joints(model: pin.Model, sc: Sidecar, urdf_path) -> pin.Model:
    """Single-URDF-joint declarations: a ``floating`` joint declared spherical becomes a native ball
    joint; ``free`` needs a ``floating`` joint; ``planar`` a ``planar`` joint with axis +z."""
    replace = {}
    axes = None
    for spec in sc.joints:
        if len(spec.urdf_joints) != 1 or spec.type in ("revolute", "prismatic"):
            continue
        j = _urdf_joint(model, sc, spec, 0)
        short = model.joints[j].shortname()
        key = f"{spec.key}.urdf_joints[0]"
        if spec.type in ("spherical", "free"):
            if short != "JointModelFreeFlyer":
                forms = ("3 revolute URDF joints (xyz Euler angles) or 1 URDF 'floating' joint (a native ball "
                         "joint)" if spec.type == "spherical" else "1 URDF 'floating' joint")
                raise sc.error(f"{spec.key}.urdf_joints", f"a {spec.type} joint needs {forms}; "
                                                          f"{spec.urdf_joints[0]!r} is a {short}")
            if spec.type == "spherical":
                replace[j] = (pin.JointModelSphericalZYX() if spec.parametrization == "zyx"
                              else pin.JointModelSpherical())
        elif spec.type == "planar":
            if short != "JointModelPlanar":
                raise sc.error(key, f"a planar joint given by one URDF joint needs a URDF 'planar' joint; "
                                    f"{spec.urdf_joints[0]!r} is a {short}")
            axes = axes if axes is not None else urdf_joint_axes(urdf_path)
            axis = axes.get(spec.urdf_joints[0], (None, np.array([1.0, 0, 0])))[1]
            if not np.allclose(axis / max(np.linalg.norm(axis), 1e-300), [0.0, 0.0, 1.0], atol=1e-9):
                raise sc.error(key, f"URDF planar joint {spec.urdf_joints[0]!r} has axis {axis.tolist()}; "
                                    f"Pinocchio moves every planar joint in the xy plane of its frame, so the "
                                    f"axis must be 0 0 1 (turn the joint's origin rpy instead)")
        elif spec.type == "universal" and short != "JointModelUniversal":
            raise sc.error(key, f"a universal joint needs two revolute URDF joints, got one {short}")
    return replace_joints(model, replace) if replace else model


def _physical_joints(model: pin.Model, sc: Sidecar, urdf_path) -> tuple[PhysicalJoint, ...]:
    joints = []
    used: set[int] = set()
    for spec in sc.joints:
        ids = [_urdf_joint(model, sc, spec, i) for i in range(len(spec.urdf_joints))]
        try:
            pj = group(model, spec.name, spec.type, ids)
            if spec.type == "spherical" and pj.parametrization != spec.parametrization:
                raise ModelError(f"expected a {spec.parametrization} spherical joint, got {pj.parametrization}")
            pj = pj.with_settings(alpha=spec.alpha, beta=spec.beta, cone_deg=spec.cone_deg,
                                  socket_axis=spec.socket_axis)
        except ModelError as exc:
            key = f"{spec.key}.urdf_joints" + ("[0]" if len(ids) == 1 else "")
            raise sc.error(key, f"{exc} (in {urdf_path})") from None
        used.update(ids)
        joints.append(pj)
    missing = [model.names[j] for j in range(1, model.njoints) if j not in used]
    if missing:
        raise sc.error("joints", f"URDF joint(s) {_names(missing)} are movable but belong to no physical "
                                 f"joint: list them under joints or under locked_joints")
    return tuple(joints)


def _cables(model: pin.Model, sc: Sidecar, joints) -> CableSet:
    links = {f.name for f in model.frames if f.type == pin.FrameType.BODY}
    inside = massless_members(joints)
    cables = [Cable(spec.name, tuple(_route_element(model, sc, links, inside, p) for p in spec.route),
                    spec.f_min, spec.f_max) for spec in sc.cables]
    try:
        return CableSet(model, cables)
    except ModelError as exc:
        for k, spec in enumerate(sc.cables):
            if repr(spec.name) in str(exc):
                raise sc.error(f"{spec.key}.route", str(exc)) from None
        raise sc.error("cables", str(exc)) from None


def _springs(model: pin.Model, sc: Sidecar, joints):
    """The sidecar's ``springs:`` as a :class:`~mcdm_pin.model.springs.SpringSet` (``None``: none)."""
    from .model.springs import Spring, SpringSet

    if not sc.springs:
        return None
    links = {f.name for f in model.frames if f.type == pin.FrameType.BODY}
    inside = massless_members(joints)
    springs = [Spring(spec.name, tuple(_route_element(model, sc, links, inside, p) for p in spec.route),
                      spec.stiffness, spec.rest_length, spec.tension_only) for spec in sc.springs]
    try:
        return SpringSet(model, springs)
    except ModelError as exc:
        for spec in sc.springs:
            if repr(spec.name) in str(exc):
                raise sc.error(f"{spec.key}.route", str(exc)) from None
        raise sc.error("springs", str(exc)) from None


def _route_element(model: pin.Model, sc: Sidecar, links: set, inside: dict, p):
    """A sidecar route element (point, wrap, pulley or rotating pulley) as the model layer's, its link checked against
    the model's ``links`` and the massless links ``inside`` grouped joints."""
    from .model.cables import Pulley, RotatingPulley, ScrewDrive, Wrap, find_frame
    from .sidecar import PulleySpec, RotatingPulleySpec, WrapSpec

    if isinstance(p, PulleySpec):
        return Pulley(p.divisor)
    if p.link not in links:
        raise sc.error(f"{p.key}.link", f"unknown link {p.link!r}; expected one of "
                                        f"{_names(dict.fromkeys(f.name for f in model.frames if f.type == pin.FrameType.BODY))}")
    jid = int(model.frames[find_frame(model, p.link)].parentJoint)
    if jid in inside:
        raise sc.error(f"{p.key}.link", f"link {p.link!r} is an intermediate massless link of joint "
                                        f"{inside[jid]!r}; attach cables to the parent or child link")
    if isinstance(p, WrapSpec):
        R = _frame_with_z(np.array(p.axis))
        side = None if p.side is None else RoutePoint(p.link, p.side)
        return Wrap(p.link, p.kind, p.radius, p.center, tuple(R.reshape(-1)), side, name=p.key)
    if isinstance(p, RotatingPulleySpec):
        screw = None if p.screw is None else ScrewDrive(*p.screw)
        return RotatingPulley(p.link, p.entry, p.axis, p.radius, screw, name=p.key)
    return RoutePoint(p.link, p.point)


def _frame_with_z(axis: np.ndarray) -> np.ndarray:
    """A rotation whose third column is the unit vector ``axis`` (a cylinder's axis)."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, axis)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(axis, x), axis])


def _actuators(sc: Sidecar, joints) -> tuple[Actuator, ...]:
    out = []
    by_name = {j.name: j for j in joints}
    for spec in sc.joints:
        a = spec.actuated
        if a is None:
            continue
        j = by_name[spec.name]
        if not a.min:  # unbounded (no min, no max)
            out.append(Actuator(j.name, j.idx_v, np.full(j.nv, -np.inf), np.full(j.nv, np.inf), a.weight))
            continue
        if len(a.min) != j.nv:
            raise sc.error(f"{a.key}.min", f"expected {j.nv} bound(s), one per degree of freedom of the "
                                          f"{j.type} joint {j.name!r}, got {len(a.min)}")
        out.append(Actuator(j.name, j.idx_v, np.array(a.min), np.array(a.max), a.weight))
    return tuple(out)
