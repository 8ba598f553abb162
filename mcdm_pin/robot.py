"""URDF + sidecar -> :class:`Robot`: the Pinocchio model, its physical joints and its cables.

A *physical joint* is what the paper calls a joint: a spherical joint (three revolute URDF joints with
orthogonal axes meeting at one point, joined by massless links), a revolute or a prismatic joint. The
*coordinates* ``q`` are one number per degree of freedom, in Pinocchio's joint order (the URDF's
depth-first order), e.g. the xyz Euler angles of a spherical joint; :meth:`Robot.pin_q` turns them into
Pinocchio's configuration vector (which differs for continuous joints, stored as cos/sin).
"""

from __future__ import annotations

import os
import site
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from .exceptions import ModelError, SidecarError, StateError
from .sidecar import Sidecar, _names, load_sidecar

_GEOM_TOL = 1e-9  # m and rad: joint points "meet" and axes are "orthogonal" within this


@dataclass(frozen=True)
class PhysicalJoint:
    """One physical joint.

    Attributes:
        name: the sidecar's name.
        type: ``spherical``, ``revolute`` or ``prismatic``.
        urdf_joints: the URDF joint names, parent side first.
        pin_ids: their Pinocchio joint ids.
        child_id: the Pinocchio joint whose frame is the child link's frame at the joint point (the
            last of ``pin_ids``); the interaction wrench is expressed there.
        parent_id: the Pinocchio joint of the parent link (0 = the fixed base).
        socket_placement: the socket frame (fixed in the parent link at the joint point, equal to the
            child frame when the joint's coordinates are zero) relative to ``parent_id``'s frame.
        idx_v: the joint's coordinates in ``q``.
        socket_axis: unit vector in the socket frame: the socket's outward normal, i.e. the
            direction in which the socket pushes the ball when the ball is pressed into it (the
            cone requires ``F . socket_axis > 0`` for the force F of the parent on the child).
        alpha, beta: weights of |F|^2 and |M|^2 in the interaction objective.
        cone_deg: the largest interaction angle the joint tolerates, or ``None``.
    """

    name: str
    type: str
    urdf_joints: tuple[str, ...]
    pin_ids: tuple[int, ...]
    child_id: int
    parent_id: int
    socket_placement: pin.SE3
    idx_v: np.ndarray
    socket_axis: np.ndarray
    alpha: float
    beta: float
    cone_deg: float | None

    @property
    def nv(self) -> int:
        return len(self.idx_v)


@dataclass(frozen=True)
class Cable:
    name: str
    f_min: float
    f_max: float
    links: tuple[str, ...]
    points: np.ndarray  # (k, 3) in each link's URDF frame


def package_share_dirs() -> list[Path]:
    """Folders that hold installed packages for ``package://`` URIs, in search order:
    ``ROS_PACKAGE_PATH`` entries, ``AMENT_PREFIX_PATH``/share, and every ``cmeel.prefix/share``
    in this interpreter's site-packages (where example-robot-data installs its robots)."""
    dirs: list[Path] = []
    for entry in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep):
        if entry:
            dirs.append(Path(entry))
    for entry in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep):
        if entry:
            dirs.append(Path(entry) / "share")
    candidates = list(site.getsitepackages()) + [site.getusersitepackages()] + sys.path
    for sp in candidates:
        share = Path(sp) / "cmeel.prefix" / "share"
        if share.is_dir() and share not in dirs:
            dirs.append(share)
    return dirs


def resolve_package_uri(uri: str, sidecar_path=None, key: str = "urdf") -> Path:
    """Resolve ``package://NAME/rest`` to a file through installed packages (no network)."""
    rest = uri[len("package://"):]
    package, _, inner = rest.partition("/")
    if not package or not inner:
        raise SidecarError(sidecar_path, key, f"expected package://PACKAGE/PATH, got {uri!r}")
    tried = []
    for share in package_share_dirs():
        candidate = share / package / inner
        tried.append(str(share))
        if candidate.is_file():
            return candidate
    raise SidecarError(sidecar_path, key,
                       f"cannot resolve {uri!r}: no installed package {package!r} holds {inner!r} "
                       f"(searched {', '.join(tried) or 'no package folders'}; install the package, "
                       f"e.g. pip install {package})")


class Robot:
    """A cable-driven manipulator: Pinocchio model + physical joints + cables.

    Build one with :meth:`Robot.load` (from a sidecar file) or :meth:`Robot.from_sidecar`.

    Attributes:
        model: the (reduced, if joints are locked) Pinocchio model.
        sidecar: the validated sidecar it was built from.
        joints: the physical joints, in the sidecar's order.
        cables: the cables, in the sidecar's order.
        coordinate_names: the URDF joint name of each coordinate of ``q``.
    """

    def __init__(self, sidecar: Sidecar, model: pin.Model, urdf_path: Path):
        self.sidecar = sidecar
        self.urdf_path = urdf_path
        self.name = sidecar.name
        self.model = model
        self._data = model.createData()
        self.nv = model.nv
        self.coordinate_names = self._coordinates()
        self.link_names, self._link_frame = self._links()
        self.joints = self._physical_joints()
        self.cables = self._cables()
        self.f_min = np.array([c.f_min for c in self.cables])
        self.f_max = np.array([c.f_max for c in self.cables])
        self._build_routes()

    # ----------------------------------------------------------------------------------------- load
    @classmethod
    def load(cls, path) -> "Robot":
        """Load a robot from a sidecar YAML file (which names its URDF)."""
        return cls.from_sidecar(load_sidecar(path))

    @classmethod
    def from_sidecar(cls, sidecar: Sidecar) -> "Robot":
        if sidecar.urdf_path is None:
            urdf_path = resolve_package_uri(sidecar.urdf, sidecar.path)
        else:
            urdf_path = sidecar.urdf_path
            if not urdf_path.is_file():
                raise sidecar.error("urdf", f"URDF file not found: {urdf_path}")
        try:
            model = pin.buildModelFromUrdf(str(urdf_path))
        except Exception as exc:  # pinocchio raises ValueError/RuntimeError with urdfdom's text
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            raise ModelError(f"{urdf_path}: cannot load the URDF ({first})") from None
        _check_model_numbers(model, urdf_path)
        model.gravity.linear = np.array(sidecar.gravity, dtype=float)
        model = _lock_joints(model, sidecar)
        return cls(sidecar, model, urdf_path)

    # ------------------------------------------------------------------------------------ structure
    def _coordinates(self) -> tuple[str, ...]:
        m = self.model
        names = [""] * m.nv
        simple_q, simple_v, rub_q, rub_v = [], [], [], []
        for j in range(1, m.njoints):
            jm = m.joints[j]
            short = jm.shortname()
            if jm.nv != 1 or not (short.startswith("JointModelR") or short.startswith("JointModelP")):
                raise ModelError(f"{self.urdf_path}: joint {m.names[j]!r} is a {short}; only revolute, "
                                 f"continuous and prismatic URDF joints are supported (a floating or "
                                 f"planar base is not)")
            names[jm.idx_v] = m.names[j]
            if jm.nq == 1:
                simple_q.append(jm.idx_q)
                simple_v.append(jm.idx_v)
            else:  # continuous joint: cos, sin
                rub_q.append(jm.idx_q)
                rub_v.append(jm.idx_v)
        self._simple_q, self._simple_v = np.array(simple_q, int), np.array(simple_v, int)
        self._rub_q, self._rub_v = np.array(rub_q, int), np.array(rub_v, int)
        return tuple(names)

    def _links(self):
        frames = {}
        for fid, frame in enumerate(self.model.frames):
            if frame.type == pin.FrameType.BODY and frame.name not in frames:
                frames[frame.name] = fid
        return tuple(frames), frames

    def link_placement(self, link: str):
        """(Pinocchio joint id, placement of the link's URDF frame in that joint's frame)."""
        frame = self.model.frames[self._link_frame[link]]
        return int(frame.parentJoint), frame.placement

    def _physical_joints(self) -> tuple[PhysicalJoint, ...]:
        sc, m = self.sidecar, self.model
        q0 = self.pin_q(np.zeros(self.nv))
        data = m.createData()
        pin.computeJointJacobians(m, data, q0)
        used: dict[str, str] = {}
        joints = []
        for spec in sc.joints:
            ids = []
            for i, uname in enumerate(spec.urdf_joints):
                key = f"{spec.key}.urdf_joints[{i}]"
                if uname in sc.locked_joints:
                    raise sc.error(key, f"URDF joint {uname!r} is also listed in locked_joints")
                if not m.existJointName(uname):
                    raise sc.error(key, f"unknown URDF joint {uname!r}; expected one of "
                                        f"{_names(self.coordinate_names)}")
                ids.append(int(m.getJointId(uname)))
                used[uname] = spec.name
            for i, j in enumerate(ids):
                short = m.joints[j].shortname()
                want = "JointModelP" if spec.type == "prismatic" else "JointModelR"
                if not short.startswith(want):
                    raise sc.error(f"{spec.key}.urdf_joints[{i}]",
                                   f"URDF joint {m.names[j]!r} is a {short}; a {spec.type} joint needs "
                                   f"{'prismatic' if spec.type == 'prismatic' else 'revolute'} URDF joints")
            if spec.type == "spherical":
                _check_spherical(sc, spec, m, data, ids)
            idx_v = np.array([m.joints[j].idx_v for j in ids], dtype=int)
            joints.append(PhysicalJoint(
                name=spec.name, type=spec.type, urdf_joints=spec.urdf_joints, pin_ids=tuple(ids),
                child_id=ids[-1], parent_id=int(m.parents[ids[0]]),
                socket_placement=m.jointPlacements[ids[0]].copy(), idx_v=idx_v,
                socket_axis=np.array(spec.socket_axis), alpha=spec.alpha, beta=spec.beta,
                cone_deg=spec.cone_deg))
        missing = [n for n in self.coordinate_names if n not in used]
        if missing:
            raise sc.error("joints", f"URDF joint(s) {_names(missing)} are movable but belong to no "
                                     f"physical joint: list them under joints or under locked_joints")
        return tuple(joints)

    def _cables(self) -> tuple[Cable, ...]:
        sc = self.sidecar
        massless = {}
        for j in self.joints:
            for pid in j.pin_ids[:-1]:
                massless[pid] = j.name
        cables = []
        for spec in sc.cables:
            jids = []
            for p in spec.route:
                if p.link not in self._link_frame:
                    raise sc.error(f"{p.key}.link", f"unknown link {p.link!r}; expected one of "
                                                    f"{_names(self.link_names)}")
                jid, _ = self.link_placement(p.link)
                if jid in massless:
                    raise sc.error(f"{p.key}.link",
                                   f"link {p.link!r} is an intermediate massless link of spherical joint "
                                   f"{massless[jid]!r}; attach cables to the parent or child link")
                jids.append(jid)
            if len(set(jids)) < 2:
                raise sc.error(f"{spec.key}.route",
                               f"cable {spec.name!r} has no segment spanning two different bodies "
                               f"(every point is on {spec.route[0].link!r} or a link rigidly fixed to "
                               f"it), so it cannot move anything")
            cables.append(Cable(name=spec.name, f_min=spec.f_min, f_max=spec.f_max,
                                links=tuple(p.link for p in spec.route),
                                points=np.array([p.point for p in spec.route], dtype=float)))
        return tuple(cables)

    def _build_routes(self):
        """Flatten every route into arrays: point -> (Pinocchio joint, point in that joint's frame),
        segment -> (start point, end point, cable)."""
        jid, local, seg_a, seg_b, seg_c = [], [], [], [], []
        for c, cable in enumerate(self.cables):
            start = len(jid)
            for link, p in zip(cable.links, cable.points):
                j, placement = self.link_placement(link)
                jid.append(j)
                local.append(placement.act(p))
            n = len(cable.links)
            seg_a.extend(range(start, start + n - 1))
            seg_b.extend(range(start + 1, start + n))
            seg_c.extend([c] * (n - 1))
        self.point_joint = np.array(jid, dtype=int)
        self.point_local = np.array(local, dtype=float)
        self.seg_a = np.array(seg_a, dtype=int)
        self.seg_b = np.array(seg_b, dtype=int)
        self.seg_cable = np.array(seg_c, dtype=int)
        # segments whose two ends are on one body apply no wrench (they only add length)
        self.seg_active = self.point_joint[self.seg_a] != self.point_joint[self.seg_b]
        # subtree indicator: sub[i, j] = 1 when joint j is in the subtree of joint i (i included)
        nj = self.model.njoints
        sub = np.zeros((nj, nj))
        for j in range(nj):
            k = j
            while True:
                sub[k, j] = 1.0
                if k == 0:
                    break
                k = self.model.parents[k]
        self.subtree = sub

    # --------------------------------------------------------------------------------------- state
    @property
    def m(self) -> int:
        """Number of cables."""
        return len(self.cables)

    @property
    def cable_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.cables)

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(j.name for j in self.joints)

    def joint(self, name: str) -> PhysicalJoint:
        for j in self.joints:
            if j.name == name:
                return j
        from .exceptions import ProblemError
        raise ProblemError(f"unknown joint {name!r}; expected one of {_names(self.joint_names)}")

    def pin_q(self, q) -> np.ndarray:
        """Coordinates (one per degree of freedom) -> Pinocchio configuration vector."""
        q = np.asarray(q, dtype=float)
        out = np.zeros(self.model.nq)
        out[self._simple_q] = q[self._simple_v]
        if len(self._rub_q):
            out[self._rub_q] = np.cos(q[self._rub_v])
            out[self._rub_q + 1] = np.sin(q[self._rub_v])
        return out

    def check_vector(self, x, name: str, n: int | None = None) -> np.ndarray:
        """Return ``x`` as a float array of length ``n`` (default: nv), or raise :class:`StateError`."""
        n = self.nv if n is None else n
        try:
            arr = np.asarray(x, dtype=float)
        except (TypeError, ValueError):
            raise StateError(f"{name}: expected {n} numbers, got {type(x).__name__}") from None
        if arr.shape != (n,):
            raise StateError(f"{name}: expected a vector of length {n}, got shape {arr.shape}")
        if not np.all(np.isfinite(arr)):
            bad = np.flatnonzero(~np.isfinite(arr))
            raise StateError(f"{name}: expected finite numbers, entries {bad.tolist()} are not")
        return arr

    def __repr__(self) -> str:
        return (f"Robot({self.name!r}: {len(self.joints)} joints, {self.nv} DoF, {self.m} cables, "
                f"urdf={str(self.urdf_path)!r})")


def _check_model_numbers(model: pin.Model, urdf_path) -> None:
    """Reject masses, inertias and placements that are not finite or so large that the dynamics
    overflow (a CASPR mass of 1e308 kg gave inf terms and crashed the solver: tests/test_fuzz.py)."""
    from .sidecar import MAX_MAGNITUDE

    for j in range(model.njoints):
        inertia = model.inertias[j]
        checks = (("mass", np.array([inertia.mass]), "kg"), ("centre of mass", inertia.lever, "m"),
                  ("inertia", inertia.inertia, "kg m^2"),
                  ("joint origin", model.jointPlacements[j].translation, "m"))
        for what, values, unit in checks:
            values = np.asarray(values, dtype=float)
            if not np.all(np.isfinite(values)) or np.abs(values).max(initial=0.0) > MAX_MAGNITUDE:
                owner = "the fixed base" if j == 0 else f"the body moved by URDF joint {model.names[j]!r}"
                raise ModelError(f"{urdf_path}: {what} of {owner} is {values.tolist()} {unit}; expected "
                                 f"finite numbers of magnitude at most {MAX_MAGNITUDE:g}")
        if inertia.mass < 0:
            raise ModelError(f"{urdf_path}: mass of the body moved by URDF joint {model.names[j]!r} is "
                             f"{inertia.mass!r} kg; expected >= 0")


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


def _check_spherical(sc: Sidecar, spec, m: pin.Model, data: pin.Data, ids: list[int]) -> None:
    key = f"{spec.key}.urdf_joints"
    names = spec.urdf_joints
    for k in (1, 2):
        if m.parents[ids[k]] != ids[k - 1]:
            raise sc.error(key, f"a spherical joint needs three URDF joints in series; the parent joint "
                                f"of {names[k]!r} is {m.names[m.parents[ids[k]]]!r}, not {names[k - 1]!r}")
        t = m.jointPlacements[ids[k]].translation
        if np.linalg.norm(t) > _GEOM_TOL:
            raise sc.error(key, f"a spherical joint needs three URDF joints meeting at one point; "
                                f"{names[k]!r} sits {np.linalg.norm(t):.3g} m from {names[k - 1]!r}")
    # axes, in the first joint's frame at q = 0
    axes = []
    for k, j in enumerate(ids):
        S = pin.getJointJacobian(m, data, j, pin.ReferenceFrame.WORLD)[:, m.joints[j].idx_v]
        axes.append(S[3:] / np.linalg.norm(S[3:]))
    for a, b in ((0, 1), (0, 2), (1, 2)):
        c = abs(float(axes[a] @ axes[b]))
        if c > _GEOM_TOL:
            raise sc.error(key, f"a spherical joint needs mutually orthogonal axes; {names[a]!r} and "
                                f"{names[b]!r} make {np.degrees(np.arccos(min(c, 1.0))):.6g} deg")
    for k in (0, 1):
        j = ids[k]
        inertia = m.inertias[j]
        if inertia.mass > 0 or np.abs(inertia.inertia).max() > 0:
            raise sc.error(key, f"a spherical joint needs massless links between its URDF joints; the "
                                f"link after {names[k]!r} has mass {inertia.mass:.6g} kg (or inertia)")
        children = [c for c in range(1, m.njoints) if m.parents[c] == j and c != ids[k + 1]]
        if children:
            raise sc.error(key, f"the massless link after {names[k]!r} also carries joint "
                                f"{m.names[children[0]]!r}; nothing may hang between a spherical "
                                f"joint's URDF joints")
