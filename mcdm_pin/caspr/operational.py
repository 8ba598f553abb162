r"""CASPR's ``*_operational_spaces.xml`` and its operational-space trajectories, solved into joint
trajectories by inverse kinematics (:mod:`mcdm_pin.ik`).

**Operational spaces** (CASPR ``a6971ee``, ``src/Model/Bodies/OperationalSpace``). A file holds
``<operational_set id=...>`` elements and names a ``default_operational_set``; a set holds operational
spaces, each on one link (``<link>``, CASPR's link number) with ``<axes active_axes="...">``:

* ``<position>`` (``OperationalPosition``): the point ``<offset>`` (link frame {k}, metres, from the
  link's joint point) in world coordinates, :math:`y = S\,R_{0k}\,r_{OY}`; axes ``x y z``;
* ``<pose_euler_xyz>`` (``OperationalPoseEulerXYZ``): the point and the angles of :math:`R_{0k} =
  R_z(\gamma)R_y(\beta)R_x(\alpha)` (its ``extractOperationalSpace``: :math:`\alpha =
  \mathrm{atan2}(R_{32}, R_{33})`, ...); axes ``x y z a b g``;
* ``<orientation_euler_xyz>`` (``OperationalOrientationEulerXYZ``): the angles of :math:`R_{0k} =
  R_x(\alpha)R_y(\beta)R_z(\gamma)` (:math:`\beta = \arcsin R_{13}`, ...); axes ``a b g``.

``y`` lists the kept coordinates in the order of ``active_axes``. Each becomes a
:class:`~mcdm_pin.ik.TaskSpace` on the link's frame of the converted URDF (CASPR's body frame {k}, origin
at the joint point) with ``euler`` ``zyx`` (pose) or ``xyz`` (orientation). CASPR's own Jacobian maps
to the world-frame angular velocity for the angle rows; the trajectories' ``y_dot``, ``y_ddot`` are the
splines' derivatives of the angles, so here the angle rows use the Euler-rate Jacobian
:math:`E^{-1}J_\omega` (:mod:`mcdm_pin.ik.space`), which makes the joint rates those of the angles CASPR
splines.

**The set.** CASPR binds one set at model load (``default_operational_set`` unless another is named).
The import does the same (``operational_set``; a file whose default is empty and which has one set
uses that set, with a note). A trajectory whose points do not have one number per coordinate of the
set is refused alone, as CASPR's loader asserts. One operational space per set is supported (every
set of CASPR's library has one).

**Seed.** The first sample's IK starts from the bodies file's ``q_initial`` (CASPR's initial pose);
each later one from the previous solution.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..exceptions import CasprError, TrajectoryError
from ._xml import integer, numbers, parse_xml

KINDS = {"position": ("xyz", "zyx"), "pose_euler_xyz": ("xyzabg", "zyx"), "orientation_euler_xyz": ("abg", "xyz")}


@dataclass(frozen=True)
class OperationalSet:
    """One ``<operational_set>``: its single operational space (``kind``, ``link`` number, ``offset``,
    ``coordinates`` in the order of ``active_axes``)."""

    id: str
    kind: str
    link: int
    offset: tuple[float, float, float]
    coordinates: str
    path: Path
    element: str

    @property
    def dim(self) -> int:
        return len(self.coordinates)

    def task_space(self, bodies):
        """The :class:`~mcdm_pin.ik.TaskSpace` on the converted robot (link frame = CASPR's frame {k})."""
        from ..ik import TaskSpace

        return TaskSpace(frame=bodies.links[self.link - 1].ident, point=self.offset, coordinates=self.coordinates,
                         euler=KINDS[self.kind][1])


@dataclass(frozen=True)
class OperationalChoice:
    """The operational set trajectories are read against, or ``reason`` why there is none."""

    set: OperationalSet | None
    reason: str = ""
    notes: tuple[str, ...] = field(default_factory=tuple)


def beside(bodies_xml) -> Path:
    """``X_operational_spaces.xml`` next to ``X_bodies.xml``."""
    p = Path(bodies_xml)
    stem = p.name[:-len("_bodies.xml")] if p.name.endswith("_bodies.xml") else p.stem
    return p.parent / f"{stem}_operational_spaces.xml"


def read_operational_spaces(path, bodies) -> tuple[str, dict[str, OperationalSet | str]]:
    """``(default set id, {set id: OperationalSet, or the reason it cannot be used})``."""
    path, root = parse_xml(path)
    if root.tag != "operational_spaces":
        raise CasprError(path, f"<{root.tag}>", "expected the root element <operational_spaces>")
    sets: dict = {}
    for k, el in enumerate(root, start=1):
        sid = el.get("id") or f"operational_set[{k}]"
        where = f"operational_set[id={sid!r}]"
        if el.tag != "operational_set":
            raise CasprError(path, f"<{el.tag}>", "expected <operational_set> elements")
        spaces = list(el)
        if len(spaces) != 1:
            sets[sid] = f"{where}: {len(spaces)} operational spaces; one per set is supported"
            continue
        sets[sid] = _space(path, spaces[0], sid, f"{where}/{spaces[0].tag}", bodies)
    return root.get("default_operational_set") or "", sets


def _space(path, el, sid, where, bodies) -> OperationalSet | str:
    if el.tag not in KINDS:
        return f"{where}: unknown operational space <{el.tag}>; expected one of {', '.join(KINDS)}"
    link_el, axes_el = el.find("link"), el.find("axes")
    if link_el is None or axes_el is None:
        raise CasprError(path, where, "expected <link> and <axes active_axes=...> (CASPR's loader reads both)")
    link = integer(path, (link_el.text or "").strip(), f"{where}/link")
    if not 1 <= link <= len(bodies.links):
        raise CasprError(path, f"{where}/link", f"expected a link number in 1..{len(bodies.links)}, got {link}")
    offset = (0.0, 0.0, 0.0)
    if el.tag != "orientation_euler_xyz":  # CASPR's orientation space has no offset (zeros(3, 1))
        off = el.find("offset")
        if off is None:
            raise CasprError(path, f"{where}/offset", "missing; expected 3 numbers (metres, link frame)")
        offset = tuple(numbers(path, off.text, f"{where}/offset", 3))
    axes = axes_el.get("active_axes") or ""
    allowed = KINDS[el.tag][0]
    if not axes or any(a not in allowed for a in axes) or len(set(axes)) != len(axes):
        raise CasprError(path, f"{where}/axes@active_axes", f"expected distinct letters of {allowed!r}, got {axes!r}")
    return OperationalSet(id=sid, kind=el.tag, link=link, offset=offset, coordinates=axes, path=path, element=where)


def choose(bodies_xml, bodies, spaces_xml=None, set_id: str | None = None) -> OperationalChoice:
    """The set of ``spaces_xml`` (default: :func:`beside` the bodies file) to read trajectories
    against: ``set_id``, else the file's default, else its only set."""
    given = spaces_xml is not None
    path = Path(spaces_xml) if given else beside(bodies_xml)
    if not path.is_file():
        if given or set_id is not None:
            raise CasprError(path, "", "the operational-spaces file is not found")
        return OperationalChoice(None, f"no operational-spaces file (looked for {path.name} beside the bodies "
                                       f"file; give one with --operational-spaces)")
    try:
        default, sets = read_operational_spaces(path, bodies)
    except CasprError as exc:
        if given:
            raise
        return OperationalChoice(None, f"the operational-spaces file found beside the bodies file cannot be "
                                       f"read: {exc}")
    notes = []
    if set_id is not None:
        if set_id not in sets:
            raise CasprError(path, "operational_set", f"no set {set_id!r}; expected one of "
                                                      f"{', '.join(sets) or '(none)'}")
        chosen = set_id
    elif default:
        if default not in sets:
            raise CasprError(path, "@default_operational_set", f"names {default!r}, which is not a set here; "
                                                               f"expected one of {', '.join(sets) or '(none)'}")
        chosen = default
    elif len(sets) == 1:
        chosen = next(iter(sets))
        notes.append(f"{path.name} names no default operational set; its only set {chosen!r} is used")
    else:
        return OperationalChoice(None, f"{path.name} names no default operational set and has {len(sets)}; "
                                       f"choose one with --operational-set")
    found = sets[chosen]
    if isinstance(found, str):
        return OperationalChoice(None, found, tuple(notes))
    notes.append(f"operational-space trajectories are read against the set {chosen!r} of {path.name} "
                 f"({found.kind} of link {found.link}, coordinates {found.coordinates})")
    return OperationalChoice(found, "", tuple(notes))


def solve(result, traj, robot):
    """``(Samples, TaskSolution, X)``: the trajectory sampled as CASPR samples it and solved by IK
    on ``robot`` (the converted robot), ``X`` (N, nv) its coordinates."""
    from ..ik import solve_task
    from .sampling import sample_operational

    s = sample_operational(traj)
    space = traj.operational_set.task_space(result.bodies)
    seed = robot.configuration(result.coordinates_from_caspr(result.bodies.q_initial))
    opset = traj.operational_set
    try:
        sol = solve_task(robot.model, space, s.t, s.q, s.qd, s.qdd, seed, name=f"trajectory {traj.id!r}")
    except TrajectoryError as exc:
        raise TrajectoryError(f"{exc} (read as the operational set {opset.id!r} of {opset.path.name}: {opset.kind} "
                              f"of link {opset.link}, coordinates {opset.coordinates}; another set: "
                              f"--operational-set)") from None
    X = np.array([robot.coordinates(q) for q in sol.q]).reshape(len(s.t), robot.nv)
    return s, sol, X
