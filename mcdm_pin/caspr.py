r"""CASPR model files (XML) -> a URDF + a cable sidecar (YAML), so that CASPR users keep their models.

CASPR (darwinlau/CASPR, MATLAB) describes a multilink cable-driven manipulator in three files:
``*_bodies.xml`` (links and joints), ``*_cables.xml`` (one or more cable sets) and
``*_trajectories.xml``. :func:`import_caspr` reads them with :mod:`xml.etree` (the DTD is never
resolved) and writes ``NAME.urdf`` and ``NAME.yaml`` (plus one ``NAME_<id>.csv`` per multi-point
trajectory) into an output folder.

**Frames.** CASPR's body frame :math:`\{k\}` has its origin at link k's joint point and the orientation
:math:`R_{0k} = R_{0,parent} R_{pe}(q_k)`; the URDF link frame is the same frame, so a point in
:math:`\{k\}` is a point in the URDF link ``k``. ``parent/location`` (parent's joint point -> this joint,
parent frame) is the URDF joint origin; the inertia (about the COM, link axes) goes to ``<inertial>``
with its origin at ``com_location``; ``ref="joint"`` inertias are moved to the COM with
:math:`I_G = I_O - m(|r|^2 I_3 - r r^T)`.

**Joints** (:data:`JOINT_TYPES`). One CASPR joint becomes a chain of revolute/prismatic URDF joints
joined by massless links:

========================  =======================  ==========================================
CASPR type                URDF chain (parent first)  sidecar
========================  =======================  ==========================================
``S_EULER_XYZ``           x, y, z                  one ``spherical`` joint, q = (a, b, g)
``S_FIXED_XYZ``           z, y, x                  one ``spherical`` joint, q = (g, b, a)
``R_X``/``R_Y``/``R_Z``   x / y / z                one ``revolute`` joint
``R_AXIS``                the given axis           one ``revolute`` joint
``P_X``/``P_AXIS``        x / the given axis       one ``prismatic`` joint
``U_XY``/``U_XZ``/``U_YZ``  x,y / x,z / y,z        two ``revolute`` joints ``NAME_x``, ``NAME_y``
========================  =======================  ==========================================

``S_FIXED_XYZ`` is :math:`R = R_z(\gamma) R_y(\beta) R_x(\alpha)`: the outermost rotation is about z,
so the chain must start with z, and Pinocchio numbers coordinates in chain order: that joint's three
coordinates appear in ``q`` as (gamma, beta, alpha), the reverse of CASPR's. A tree whose depth-first
order differs from CASPR's link numbering also permutes ``q``. :attr:`CasprImport.q_index` gives the
map (``q_ours[q_index] = q_caspr``) and the sidecar's description states it. For chains of
``S_EULER_XYZ``/``R_*``/``U_*`` joints (both reference models) ``q`` is CASPR's ``q`` unchanged.

A universal joint is two revolute sidecar joints (the sidecar has no universal type); the interaction
wrench of the universal joint is the second one's (both act at the same point).

**Cables.** Only ``cable_ideal``. ``attachment_reference="com"`` points are moved to the joint point by
adding ``com_location``; base points are absolute. Routes of any length over any links are kept (a
segment with both ends on one link adds length but no wrench, as in CASPR). Joint, link and cable order
and cable names are kept, so ``f`` lines up with CASPR's.

**Trajectories.** ``quintic_spline_trajectory`` only. A two-point rest-to-rest trajectory becomes a
sidecar ``type: quintic`` trajectory (spherical joints turn about one fixed axis, CASPR's axis-angle
interpolation; other coordinates follow the scalar quintic). Any other quintic trajectory (several
points, or non-zero end rates) is sampled here exactly, segment by segment, as CASPR does, and written
as a CSV trajectory; :func:`caspr_trajectory` returns the exact samples (with ``qd``, ``qdd``), while
the CSV stores ``q`` only and its rates are re-derived by a spline when it is loaded.

Anything else (other joint, cable, trajectory types, pulleys, actuated joints) raises
:class:`~mcdm_pin.exceptions.CasprError` naming the file and the element.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

from typing import TYPE_CHECKING

import numpy as np
import yaml

from .exceptions import CasprError

if TYPE_CHECKING:
    from .trajectory import Trajectory

GRAVITY = (0.0, 0.0, -9.81)
_X, _Y, _Z = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)

# type -> (sidecar kind, [(label, axis or None = the XML's axis attribute, CASPR coordinate index)])
JOINT_TYPES: dict[str, tuple[str, list[tuple[str, tuple | None, int]]]] = {
    "R_X": ("revolute", [("x", _X, 0)]),
    "R_Y": ("revolute", [("y", _Y, 0)]),
    "R_Z": ("revolute", [("z", _Z, 0)]),
    "R_AXIS": ("revolute", [("axis", None, 0)]),
    "P_X": ("prismatic", [("px", _X, 0)]),
    "P_AXIS": ("prismatic", [("paxis", None, 0)]),
    "U_XY": ("universal", [("x", _X, 0), ("y", _Y, 1)]),
    "U_XZ": ("universal", [("x", _X, 0), ("z", _Z, 1)]),
    "U_YZ": ("universal", [("y", _Y, 0), ("z", _Z, 1)]),
    "S_EULER_XYZ": ("spherical", [("x", _X, 0), ("y", _Y, 1), ("z", _Z, 2)]),
    "S_FIXED_XYZ": ("spherical", [("z", _Z, 2), ("y", _Y, 1), ("x", _X, 0)]),
}
# CASPR types we know but do not convert (named in the error message)
_KNOWN_UNSUPPORTED = ("P_XY", "P_XZ", "T_XYZ", "PLANAR_XY", "PLANAR_XZ", "PLANAR_YZ",
                      "SPATIAL_EULER_XYZ", "S_QUATERNION", "SPATIAL_QUATERNION", "SPHERICAL")
CABLE_TYPES = ("cable_ideal",)
_OTHER_CABLES = ("cable_linear_spring", "cable_passive_linear_spring", "cable_vsd_torsion_spring",
                 "cable_vsd_flexure_linear", "cable_vsd_polynomial", "muscle_hill_type",
                 "pneumatic_artificial_muscle")
TRAJECTORY_TYPES = ("quintic_spline_trajectory",)
_OTHER_TRAJECTORIES = ("cubic_spline_trajectory", "linear_spline_trajectory",
                       "cubic_spline_average_velocity_trajectory", "parabolic_blend_trajectory",
                       "file_trajectory")


# ------------------------------------------------------------------------------------ data read
@dataclass(frozen=True)
class CasprLink:
    """One ``link_rigid`` (SI units; vectors in the link frame {k} unless said otherwise)."""

    num: int
    name: str
    ident: str  # URDF-safe name
    joint_type: str
    parent: int
    location: np.ndarray  # parent's joint point -> this joint point, parent frame
    mass: float
    com: np.ndarray  # joint point -> COM
    end: np.ndarray  # joint point -> end (drawing only)
    inertia: np.ndarray  # (3, 3) about the COM, link axes
    q_min: tuple[float, ...]
    q_max: tuple[float, ...]
    axis: tuple[float, float, float] | None
    element: str

    @property
    def kind(self) -> str:
        return JOINT_TYPES[self.joint_type][0]

    @property
    def n_q(self) -> int:
        return len(JOINT_TYPES[self.joint_type][1])


@dataclass(frozen=True)
class CasprBodies:
    path: Path
    links: tuple[CasprLink, ...]

    @property
    def n_q(self) -> int:
        return sum(link.n_q for link in self.links)


@dataclass(frozen=True)
class CasprCable:
    name: str
    reference: str  # "com" or "joint"
    f_min: float
    f_max: float
    attachments: tuple[tuple[int, np.ndarray], ...]  # (link number, location as written)
    element: str


@dataclass(frozen=True)
class CasprCableSet:
    path: Path
    id: str
    cables: tuple[CasprCable, ...]
    available: tuple[str, ...]
    renamed: dict = field(default_factory=dict)  # {cable number (1-based): (CASPR name, our name)}


@dataclass(frozen=True)
class CasprPoint:
    time: float  # absolute, s
    q: np.ndarray
    q_dot: np.ndarray
    q_ddot: np.ndarray


@dataclass(frozen=True)
class CasprTrajectory:
    """A ``quintic_spline_trajectory`` with absolute point times; q in CASPR's coordinate order."""

    id: str
    time_step: float
    points: tuple[CasprPoint, ...]
    element: str

    @property
    def rest_to_rest_single(self) -> bool:
        return len(self.points) == 2 and all(not np.any(p.q_dot) and not np.any(p.q_ddot)
                                             for p in self.points)


@dataclass
class CasprImport:
    """What :func:`import_caspr` wrote.

    Attributes:
        urdf, sidecar: the files written.
        csv_files: ``{trajectory id: CSV file}`` for the multi-point trajectories.
        cable_set: the cable set converted.
        q_index: (n,) ``q_ours[q_index] = q_caspr`` (identity for chains of x-y-z Euler joints).
        trajectories: the CASPR trajectories read (exact, for :func:`caspr_trajectory`).
        joint_names: sidecar joint names, in CASPR's link order.
    """

    urdf: Path
    sidecar: Path
    cable_set: str
    q_index: np.ndarray
    csv_files: dict[str, Path] = field(default_factory=dict)
    trajectories: dict[str, CasprTrajectory] = field(default_factory=dict)
    joint_names: tuple[str, ...] = ()
    renamed_cables: dict = field(default_factory=dict)

    @property
    def q_is_caspr_order(self) -> bool:
        return bool(np.array_equal(self.q_index, np.arange(len(self.q_index))))

    def q_from_caspr(self, q_caspr) -> np.ndarray:
        """CASPR's coordinate vector -> ours."""
        q_caspr = np.asarray(q_caspr, dtype=float)
        out = np.empty_like(q_caspr)
        out[..., self.q_index] = q_caspr
        return out

    def q_to_caspr(self, q) -> np.ndarray:
        """Our coordinate vector -> CASPR's."""
        return np.asarray(q, dtype=float)[..., self.q_index]


# ------------------------------------------------------------------------------------ XML helpers
def _parse_xml(path) -> tuple[Path, ET.Element]:
    path = Path(path)
    try:
        # expat does not fetch the external DTD CASPR's files declare; entities stay unresolved
        return path, ET.parse(path).getroot()
    except FileNotFoundError:
        raise CasprError(path, "", "file not found") from None
    except ET.ParseError as exc:
        raise CasprError(path, "", f"malformed XML ({exc})") from None
    except OSError as exc:
        raise CasprError(path, "", f"cannot read the file ({exc})") from None


def _child(path, elem: ET.Element, tag: str, where: str) -> ET.Element:
    found = elem.find(tag)
    if found is None:
        raise CasprError(path, where, f"missing <{tag}> element")
    return found


def _text(path, elem: ET.Element, tag: str, where: str) -> str:
    text = _child(path, elem, tag, where).text
    if text is None or not text.strip():
        raise CasprError(path, f"{where}/{tag}", "empty; expected a value")
    return text


def _numbers(path, text: str | None, where: str, n: int | None = None) -> tuple[float, ...]:
    if text is None:
        raise CasprError(path, where, f"missing; expected {n or 'some'} numbers")
    parts = text.split()
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        raise CasprError(path, where, f"expected whitespace-separated numbers, got {text.strip()!r}") from None
    if n is not None and len(values) != n:
        raise CasprError(path, where, f"expected {n} number{'s' if n != 1 else ''}, got {len(values)} "
                                      f"({text.strip()!r})")
    if not all(math.isfinite(v) for v in values):
        raise CasprError(path, where, f"expected finite numbers, got {text.strip()!r}")
    return values


def _number(path, text, where: str) -> float:
    return _numbers(path, text, where, 1)[0]


def _integer(path, text, where: str) -> int:
    x = _number(path, text, where)
    if x != int(x):
        raise CasprError(path, where, f"expected an integer, got {text.strip()!r}")
    return int(x)


def _ident(name: str, num: int, taken: set[str]) -> str:
    ident = re.sub(r"[^A-Za-z0-9_]+", "_", name).strip("_") or f"link{num}"
    if ident[0].isdigit():
        ident = f"link_{ident}"
    base, k = ident, 2
    while ident in taken:
        ident = f"{base}_{num}" if k == 2 else f"{base}_{num}_{k}"
        k += 1
    taken.add(ident)
    return ident


# ----------------------------------------------------------------------------------------- bodies
def read_bodies(path) -> CasprBodies:
    """Read and check a CASPR ``*_bodies.xml``."""
    path, root = _parse_xml(path)
    if root.tag != "bodies_system":
        raise CasprError(path, f"<{root.tag}>", "expected the root element <bodies_system>")
    links_el = _child(path, root, "links", "bodies_system")
    links: list[CasprLink] = []
    taken = {"base"}
    for pos, el in enumerate(list(links_el), start=1):
        if el.tag != "link_rigid":
            raise CasprError(path, f"links/<{el.tag}> (element {pos})",
                             "unsupported link element; only <link_rigid> is converted")
        name = el.get("name", "")
        where = f"link_rigid[num={el.get('num')!r}, name={name!r}]"
        num = _integer(path, el.get("num"), f"{where}@num")
        if num != pos:
            raise CasprError(path, f"{where}@num", f"expected num={pos} (links are numbered 1, 2, ... "
                                                   f"in file order), got {num}")
        for child in el:
            if child.tag not in ("joint", "physical", "parent"):
                raise CasprError(path, f"{where}/<{child.tag}>",
                                 "unknown element; expected <joint>, <physical> and <parent>")
        links.append(_read_link(path, el, num, name, where, taken))
    if not links:
        raise CasprError(path, "bodies_system/links", "no <link_rigid> element")
    return CasprBodies(path=path, links=tuple(links))


def _read_link(path, el, num, name, where, taken) -> CasprLink:
    joint = _child(path, el, "joint", where)
    jtype = joint.get("type")
    jw = f"{where}/joint@type"
    if jtype not in JOINT_TYPES:
        if jtype in _KNOWN_UNSUPPORTED:
            raise CasprError(path, jw, f"joint type {jtype!r} is not supported by mcdm-pin; supported: "
                                       f"{', '.join(JOINT_TYPES)}")
        raise CasprError(path, jw, f"unknown joint type {jtype!r}; expected one of {', '.join(JOINT_TYPES)}")
    if (joint.get("actuated") or "false").strip().lower() == "true":
        raise CasprError(path, f"{where}/joint@actuated",
                         "actuated (motor-driven) joints are not supported: every joint must be passive")
    n_q = len(JOINT_TYPES[jtype][1])
    for attr in ("q_initial", "q_min", "q_max"):
        if joint.get(attr) is None:
            raise CasprError(path, f"{where}/joint@{attr}", f"missing; expected {n_q} number(s)")
    _numbers(path, joint.get("q_initial"), f"{where}/joint@q_initial", n_q)
    q_min = _numbers(path, joint.get("q_min"), f"{where}/joint@q_min", n_q)
    q_max = _numbers(path, joint.get("q_max"), f"{where}/joint@q_max", n_q)
    if any(lo > hi for lo, hi in zip(q_min, q_max)):
        raise CasprError(path, f"{where}/joint@q_max", f"expected q_max >= q_min, got q_min={q_min}, "
                                                       f"q_max={q_max}")
    axis = None
    if jtype in ("R_AXIS", "P_AXIS"):
        axis = _numbers(path, joint.get("axis"), f"{where}/joint@axis", 3)
        norm = math.sqrt(sum(a * a for a in axis))
        if abs(norm - 1.0) > 1e-6:
            raise CasprError(path, f"{where}/joint@axis", f"expected a unit vector (CASPR does not "
                                                          f"normalise it), got norm {norm:.6g}")
    elif joint.get("axis") is not None:
        raise CasprError(path, f"{where}/joint@axis", f"an axis is allowed only for R_AXIS and P_AXIS, "
                                                      f"not {jtype}")

    phys = _child(path, el, "physical", where)
    pw = f"{where}/physical"
    mass = _number(path, _text(path, phys, "mass", pw), f"{pw}/mass")
    if mass < 0:
        raise CasprError(path, f"{pw}/mass", f"expected a mass >= 0 kg, got {mass}")
    com = np.array(_numbers(path, _text(path, phys, "com_location", pw), f"{pw}/com_location", 3))
    end_el = phys.find("end_location")
    end = (np.array(_numbers(path, end_el.text, f"{pw}/end_location", 3)) if end_el is not None
           else np.zeros(3))
    inertia_el = _child(path, phys, "inertia", pw)
    iw = f"{pw}/inertia"
    ref = inertia_el.get("ref")
    if ref not in ("com", "joint"):
        raise CasprError(path, f"{iw}@ref", f"expected 'com' or 'joint', got {ref!r}")
    v = {k: _number(path, _text(path, inertia_el, k, iw), f"{iw}/{k}")
         for k in ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")}
    inertia = np.array([[v["Ixx"], v["Ixy"], v["Ixz"]],
                        [v["Ixy"], v["Iyy"], v["Iyz"]],
                        [v["Ixz"], v["Iyz"], v["Izz"]]])
    if ref == "joint":
        inertia = inertia - mass * (com @ com * np.eye(3) - np.outer(com, com))
    eig = np.linalg.eigvalsh(inertia)
    scale = max(float(np.abs(eig).max()), 1e-300)
    if eig.min() < -1e-9 * scale:
        raise CasprError(path, iw, f"the inertia about the COM (ref={ref!r}) is not positive "
                                   f"semidefinite: eigenvalues {np.round(eig, 12).tolist()} kg m^2")

    par = _child(path, el, "parent", where)
    parent = _integer(path, _text(path, par, "num", f"{where}/parent"), f"{where}/parent/num")
    if not 0 <= parent < num:
        raise CasprError(path, f"{where}/parent/num", f"expected a parent number in 0..{num - 1} "
                                                      f"(an earlier link, 0 = base), got {parent}")
    location = np.array(_numbers(path, _text(path, par, "location", f"{where}/parent"),
                                 f"{where}/parent/location", 3))
    return CasprLink(num=num, name=name, ident=_ident(name, num, taken), joint_type=jtype, parent=parent,
                     location=location, mass=mass, com=com, end=end, inertia=inertia, q_min=q_min,
                     q_max=q_max, axis=axis, element=where)


# ----------------------------------------------------------------------------------------- cables
def read_cables(path, bodies: CasprBodies, cable_set: str | None = None) -> CasprCableSet:
    """Read one cable set of a CASPR ``*_cables.xml`` (default: ``default_cable_set``)."""
    path, root = _parse_xml(path)
    if root.tag != "cables":
        raise CasprError(path, f"<{root.tag}>", "expected the root element <cables>")
    sets = {}
    for el in root:
        if el.tag != "cable_set":
            raise CasprError(path, f"cables/<{el.tag}>", "unknown element; expected <cable_set>")
        sid = el.get("id")
        if not sid:
            raise CasprError(path, "cables/cable_set", "missing id attribute")
        if sid in sets:
            raise CasprError(path, f"cable_set[id={sid!r}]", "duplicate id (ids must be unique)")
        sets[sid] = el
    if not sets:
        raise CasprError(path, "cables", "no <cable_set>")
    if cable_set is None:
        cable_set = root.get("default_cable_set")
        if cable_set is None:
            if len(sets) > 1:
                raise CasprError(path, "cables@default_cable_set",
                                 f"missing, and the file has {len(sets)} cable sets: choose one of "
                                 f"{', '.join(sets)} (--cable-set)")
            cable_set = next(iter(sets))
        elif cable_set not in sets:
            raise CasprError(path, "cables@default_cable_set", f"names {cable_set!r}, which is not a "
                                                               f"cable set; expected one of {', '.join(sets)}")
    elif cable_set not in sets:
        raise CasprError(path, "cable_set", f"no cable set {cable_set!r}; expected one of {', '.join(sets)}")
    set_el = sets[cable_set]
    p = len(bodies.links)
    cables = []
    names = set()
    renamed: dict[str, tuple[str, str]] = {}
    for i, el in enumerate(set_el, start=1):
        name = el.get("name", "")
        where = f"cable_set[id={cable_set!r}]/{el.tag}[{i}, name={name!r}]"
        if el.tag not in CABLE_TYPES:
            known = el.tag in _OTHER_CABLES
            raise CasprError(path, where, f"{'unsupported' if known else 'unknown'} cable type "
                                          f"<{el.tag}>; only <cable_ideal> is converted")
        if not name.strip():
            raise CasprError(path, where, "missing name attribute")
        if name in names:
            # CASPR does not require unique names (the neck file has two pairs); the sidecar does
            k = 2
            while f"{name} #{k}" in names:
                k += 1
            renamed[f"{i}"] = (name, f"{name} #{k}")
            name = f"{name} #{k}"
        names.add(name)
        ref = el.get("attachment_reference")
        if ref not in ("com", "joint"):
            raise CasprError(path, f"{where}@attachment_reference", f"expected 'com' or 'joint', got {ref!r}")
        props = _child(path, el, "properties", where)
        f_min = _number(path, _text(path, props, "force_min", f"{where}/properties"),
                        f"{where}/properties/force_min")
        f_max = _number(path, _text(path, props, "force_max", f"{where}/properties"),
                        f"{where}/properties/force_max")
        if f_min < 0 or not f_max > f_min:
            raise CasprError(path, f"{where}/properties", f"expected 0 <= force_min < force_max, got "
                                                          f"force_min={f_min}, force_max={f_max}")
        atts_el = _child(path, el, "attachments", where)
        atts = []
        for k, a in enumerate(atts_el, start=1):
            aw = f"{where}/attachments/{a.tag}[{k}]"
            if a.tag != "attachment":
                raise CasprError(path, aw, f"<{a.tag}> is not supported (pulleys are not modelled); "
                                           f"expected <attachment>")
            link = _integer(path, _text(path, a, "link", aw), f"{aw}/link")
            if not 0 <= link <= p:
                raise CasprError(path, f"{aw}/link", f"expected a link number in 0..{p}, got {link}")
            loc = np.array(_numbers(path, _text(path, a, "location", aw), f"{aw}/location", 3))
            atts.append((link, loc))
        if len(atts) < 2:
            raise CasprError(path, f"{where}/attachments", f"expected at least two <attachment>, got {len(atts)}")
        if len({link for link, _ in atts}) < 2:
            raise CasprError(path, f"{where}/attachments", "every attachment is on the same link: the "
                                                           "cable cannot move anything")
        cables.append(CasprCable(name=name, reference=ref, f_min=f_min, f_max=f_max,
                                 attachments=tuple(atts), element=where))
    if not cables:
        raise CasprError(path, f"cable_set[id={cable_set!r}]", "no cable")
    return CasprCableSet(path=path, id=cable_set, cables=tuple(cables), available=tuple(sets),
                         renamed={int(k): v for k, v in renamed.items()})


# ----------------------------------------------------------------------------------- trajectories
def read_trajectories(path, bodies: CasprBodies, only=None) -> dict[str, CasprTrajectory]:
    """Read the joint trajectories of a CASPR ``*_trajectories.xml`` (``only``: ids to keep)."""
    path, root = _parse_xml(path)
    if root.tag != "trajectories":
        raise CasprError(path, f"<{root.tag}>", "expected the root element <trajectories>")
    jt = root.find("joint_trajectories")
    elements = list(jt) if jt is not None else []
    ids = [el.get("id") for el in elements]
    if only is not None:
        missing = [i for i in only if i not in ids]
        if missing:
            raise CasprError(path, "joint_trajectories", f"no trajectory {missing[0]!r}; expected one of "
                                                         f"{', '.join(map(str, ids)) or '(none)'}")
    out: dict[str, CasprTrajectory] = {}
    links = bodies.links
    n_q = bodies.n_q
    spherical = np.zeros(n_q, dtype=bool)
    k = 0
    for link in links:
        if link.kind == "spherical":
            spherical[k:k + link.n_q] = True
        k += link.n_q
    for el in elements:
        tid = el.get("id")
        where = f"joint_trajectories/{el.tag}[id={tid!r}]"
        if only is not None and tid not in only:
            continue
        if not tid:
            raise CasprError(path, f"joint_trajectories/{el.tag}", "missing id attribute")
        if tid in out:
            raise CasprError(path, where, "duplicate id (ids must be unique)")
        if el.tag not in TRAJECTORY_TYPES:
            known = el.tag in _OTHER_TRAJECTORIES
            raise CasprError(path, where, f"{'unsupported' if known else 'unknown'} trajectory type "
                                          f"<{el.tag}>; only <quintic_spline_trajectory> is converted "
                                          f"(pick others out with --trajectory ID)")
        tdef = el.get("time_definition")
        if tdef not in ("absolute", "relative"):
            raise CasprError(path, f"{where}@time_definition", f"expected 'absolute' or 'relative', "
                                                               f"got {tdef!r}")
        dt = _number(path, el.get("time_step"), f"{where}@time_step")
        if not dt > 0:
            raise CasprError(path, f"{where}@time_step", f"expected a positive time step, got {dt}")
        pts_el = _child(path, el, "points", where)
        points = []
        for i, pt in enumerate(pts_el, start=1):
            pw = f"{where}/points/point[{i}]"
            if pt.tag != "point":
                raise CasprError(path, pw, f"unknown element <{pt.tag}>; expected <point>")
            q = np.array(_numbers(path, _text(path, pt, "q", pw), f"{pw}/q", n_q))
            qd = np.array(_numbers(path, _text(path, pt, "q_dot", pw), f"{pw}/q_dot", n_q))
            qdd = np.array(_numbers(path, _text(path, pt, "q_ddot", pw), f"{pw}/q_ddot", n_q))
            if np.any(qd[spherical]) or np.any(qdd[spherical]):
                raise CasprError(path, pw, "non-zero q_dot/q_ddot on a spherical joint: CASPR splines "
                                           "spherical joints rest-to-rest only")
            if i == 1:
                t = 0.0  # CASPR ignores the first point's time
            else:
                raw = pt.get("time")
                if raw is None:
                    raise CasprError(path, f"{pw}@time", "missing; every point after the first needs a time")
                tv = _number(path, raw, f"{pw}@time")
                t = tv if tdef == "absolute" else points[-1].time + tv
                if not t > points[-1].time:
                    raise CasprError(path, f"{pw}@time", f"expected a time after {points[-1].time:g} s "
                                                         f"(time_definition={tdef!r}), got {raw}")
                seg = t - points[-1].time
                steps = seg / dt
                if abs(steps - round(steps)) > 1e-6:
                    raise CasprError(path, f"{pw}@time", f"the segment lasts {seg:g} s, not a multiple of "
                                                         f"time_step={dt:g}: CASPR would end its quintic "
                                                         f"at the last sample before {t:g} s; not supported")
            points.append(CasprPoint(time=t, q=q, q_dot=qd, q_ddot=qdd))
        if len(points) < 2:
            raise CasprError(path, f"{where}/points", f"expected at least two <point>, got {len(points)}")
        out[tid] = CasprTrajectory(id=tid, time_step=dt, points=tuple(points), element=where)
    return out


# ----------------------------------------------------------------------------------------- writing
@dataclass(frozen=True)
class _Chain:
    """The URDF joints of one CASPR joint: names, axes, and which CASPR coordinate each carries."""

    link: CasprLink
    urdf_joints: tuple[str, ...]
    axes: tuple[tuple[float, float, float], ...]
    caspr_coord: tuple[int, ...]  # index within the CASPR joint's coordinates
    inner_links: tuple[str, ...]  # massless links between them
    urdf_type: str  # revolute or prismatic


def _chains(bodies: CasprBodies) -> list[_Chain]:
    chains = []
    names = {"base"} | {link.ident for link in bodies.links}
    for link in bodies.links:
        kind, spec = JOINT_TYPES[link.joint_type]
        joints, axes, coords = [], [], []
        for label, axis, c in spec:
            joints.append(f"{link.ident}_{label}")
            axes.append(axis if axis is not None else link.axis)
            coords.append(c)
        inner = [f"{link.ident}__{label}" for label, _, _ in spec[:-1]]
        for n in joints + inner:
            if n in names:
                raise CasprError(bodies.path, link.element, f"generated URDF name {n!r} clashes with another "
                                                            f"link or joint name; rename the link")
            names.add(n)
        chains.append(_Chain(link=link, urdf_joints=tuple(joints), axes=tuple(axes),
                             caspr_coord=tuple(coords), inner_links=tuple(inner),
                             urdf_type="prismatic" if kind == "prismatic" else "revolute"))
    return chains


def _f(x: float) -> str:
    return repr(float(x)) if x != 0 else "0"


def _v(v) -> str:
    return " ".join(_f(x) for x in v)


def _urdf(bodies: CasprBodies, chains: list[_Chain], name: str, source: str) -> str:
    from xml.sax.saxutils import escape

    lines = ['<?xml version="1.0"?>',
             "<!--", f"  Converted by mcdm-pin import-caspr from {escape(source)}.",
             "  Each link's frame is CASPR's body frame {k} (origin at the link's joint point); a CASPR",
             "  joint is a chain of revolute/prismatic joints joined by massless links. Units: SI.", "-->",
             f'<robot name="{escape(name)}">', '  <link name="base"/>']
    for ch in chains:
        link = ch.link
        for inner in ch.inner_links:
            lines.append(f'  <link name="{inner}"/>')
        I = link.inertia
        lines.append(f'  <link name="{link.ident}">  <!-- CASPR link {link.num}: {escape(link.name)} -->')
        lines.append("    <inertial>")
        lines.append(f'      <origin xyz="{_v(link.com)}" rpy="0 0 0"/>')
        lines.append(f'      <mass value="{_f(link.mass)}"/>')
        lines.append(f'      <inertia ixx="{_f(I[0, 0])}" ixy="{_f(I[0, 1])}" ixz="{_f(I[0, 2])}" '
                     f'iyy="{_f(I[1, 1])}" iyz="{_f(I[1, 2])}" izz="{_f(I[2, 2])}"/>')
        lines.append("    </inertial>")
        lines.extend(_visuals(link))
        lines.append("  </link>")
    for ch in chains:
        link = ch.link
        parent = "base" if link.parent == 0 else chains[link.parent - 1].link.ident
        children = list(ch.inner_links) + [link.ident]
        for k, (jname, axis, c) in enumerate(zip(ch.urdf_joints, ch.axes, ch.caspr_coord)):
            origin = link.location if k == 0 else np.zeros(3)
            lines.append(f'  <joint name="{jname}" type="{ch.urdf_type}">')
            lines.append(f'    <parent link="{parent}"/><child link="{children[k]}"/>')
            lines.append(f'    <origin xyz="{_v(origin)}" rpy="0 0 0"/><axis xyz="{_v(axis)}"/>')
            lines.append(f'    <limit lower="{_f(link.q_min[c])}" upper="{_f(link.q_max[c])}" '
                         f'effort="1e6" velocity="1e3"/>')
            lines.append("  </joint>")
            parent = children[k]
    lines.append("</robot>")
    return "\n".join(lines) + "\n"


def _visuals(link: CasprLink) -> list[str]:
    """A sphere at the COM and a rod from the joint point to ``end_location`` (drawing only)."""
    size = max(float(np.linalg.norm(link.end)), float(np.linalg.norm(link.com)), 0.01)
    out = ['    <visual>', f'      <origin xyz="{_v(link.com)}" rpy="0 0 0"/>',
           f'      <geometry><sphere radius="{_f(round(0.06 * size, 6))}"/></geometry>',
           '      <material name="caspr_com"><color rgba="0.8 0.5 0.2 1"/></material>', '    </visual>']
    length = float(np.linalg.norm(link.end))
    if length > 1e-9:
        d = link.end / length
        # rotation taking z to d, as roll-pitch-yaw (R = Rz(y) Ry(p) Rx(r))
        pitch = math.atan2(math.hypot(d[0], d[1]), d[2])
        yaw = math.atan2(d[1], d[0]) if math.hypot(d[0], d[1]) > 1e-12 else 0.0
        out += ['    <visual>', f'      <origin xyz="{_v(link.end / 2)}" rpy="0 {_f(pitch)} {_f(yaw)}"/>',
                f'      <geometry><cylinder radius="{_f(round(0.03 * size, 6))}" '
                f'length="{_f(length)}"/></geometry>',
                '      <material name="caspr_link"><color rgba="0.35 0.45 0.6 1"/></material>',
                '    </visual>']
    return out


def _sidecar_joints(chains: list[_Chain], cone_deg: float | None) -> dict:
    joints = {}
    for ch in chains:
        kind = ch.link.kind
        if kind == "spherical":
            spec = {"type": "spherical", "urdf_joints": list(ch.urdf_joints), "socket_axis": [0.0, 0.0, 1.0],
                    "alpha": 1.0, "beta": 0.0}
            if cone_deg is not None:
                spec["cone_deg"] = float(cone_deg)
            joints[ch.link.ident] = spec
        elif kind == "universal":
            for uj in ch.urdf_joints:
                joints[uj] = {"type": "revolute", "urdf_joints": [uj], "alpha": 0.0, "beta": 0.0}
        else:
            joints[ch.link.ident] = {"type": kind, "urdf_joints": list(ch.urdf_joints),
                                     "alpha": 0.0, "beta": 0.0}
    return joints


def _sidecar_cables(bodies: CasprBodies, cset: CasprCableSet) -> list[dict]:
    out = []
    for cable in cset.cables:
        route = []
        for link, loc in cable.attachments:
            if link == 0:
                point, lname = loc, "base"  # absolute in the base frame in either reference
            else:
                L = bodies.links[link - 1]
                point = L.com + loc if cable.reference == "com" else loc
                lname = L.ident
            route.append({"link": lname, "point": [float(x) for x in point]})
        out.append({"name": cable.name, "f_min": cable.f_min, "f_max": cable.f_max, "route": route})
    return out


def _q_mapping(chains: list[_Chain], q_caspr: np.ndarray) -> dict:
    """CASPR q -> the sidecar's ``{joint: [values in urdf_joints order]}`` form."""
    out = {}
    k = 0
    for ch in chains:
        vals = q_caspr[k:k + ch.link.n_q]
        if ch.link.kind == "universal":
            for uj, c in zip(ch.urdf_joints, ch.caspr_coord):
                out[uj] = [float(vals[c])]
        else:
            out[ch.link.ident] = [float(vals[c]) for c in ch.caspr_coord]
        k += ch.link.n_q
    return out


def _caspr_urdf_names(chains: list[_Chain]) -> list[str]:
    """URDF joint name of each CASPR coordinate, in CASPR's order."""
    names = []
    for ch in chains:
        by_coord = dict(zip(ch.caspr_coord, ch.urdf_joints))
        names.extend(by_coord[c] for c in range(ch.link.n_q))
    return names


class _Dumper(yaml.SafeDumper):
    pass


def _flow_list(dumper, data):
    flow = all(isinstance(x, (int, float, str)) for x in data) and len(data) <= 32
    return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=flow)


_Dumper.add_representer(list, _flow_list)


def import_caspr(bodies_xml, cables_xml, out_dir, trajectories_xml=None, cable_set: str | None = None,
                 name: str | None = None, trajectory_ids=None, cone_deg: float | None = None) -> CasprImport:
    """Convert CASPR model files into ``out_dir/NAME.urdf`` and ``out_dir/NAME.yaml``.

    Args:
        bodies_xml, cables_xml: CASPR's ``*_bodies.xml`` and ``*_cables.xml``.
        out_dir: output folder (created if missing; files of the same names are overwritten).
        trajectories_xml: optional ``*_trajectories.xml``; its quintic trajectories become sidecar
            trajectories (CSV files for multi-point ones).
        cable_set: the cable set id (default: the file's ``default_cable_set``).
        name: robot name and file stem (default: the bodies file name without ``_bodies.xml``).
        trajectory_ids: convert only these trajectory ids.
        cone_deg: stability cone written on every spherical joint (default: none).

    Raises:
        CasprError: the files are malformed or use an unsupported CASPR feature.
    """
    from .robot import Robot

    bodies = read_bodies(bodies_xml)
    cset = read_cables(cables_xml, bodies, cable_set)
    trajs = (read_trajectories(trajectories_xml, bodies, trajectory_ids)
             if trajectories_xml is not None else {})
    if name is None:
        stem = Path(bodies_xml).name
        name = re.sub(r"(_bodies)?\.xml$", "", stem) or "caspr_robot"
    if not re.fullmatch(r"[A-Za-z0-9_.-]+", name):
        raise CasprError(None, "--name", f"expected letters, digits, '_', '-' or '.', got {name!r}")
    if cone_deg is not None and not 0 < cone_deg < 90:
        raise CasprError(None, "--cone-deg", f"expected an angle in (0, 90) degrees, got {cone_deg!r}")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    chains = _chains(bodies)

    source = (f"{Path(bodies_xml).name} + {Path(cables_xml).name} (cable set {cset.id!r})"
              + (f" + {Path(trajectories_xml).name}" if trajectories_xml is not None else ""))
    urdf_path = out_dir / f"{name}.urdf"
    urdf_path.write_text(_urdf(bodies, chains, name, source), encoding="utf-8")

    sidecar = {"version": 1, "name": name, "description": "", "urdf": urdf_path.name,
               "gravity": list(GRAVITY), "joints": _sidecar_joints(chains, cone_deg),
               "cables": _sidecar_cables(bodies, cset)}
    traj_specs, csv_files = {}, {}
    for tid, tr in trajs.items():
        if tr.rest_to_rest_single:
            p0, p1 = tr.points
            traj_specs[tid] = {"type": "quintic", "q_start": _q_mapping(chains, p0.q),
                               "q_end": _q_mapping(chains, p1.q), "duration": p1.time - p0.time,
                               "dt": tr.time_step, "spherical": "axis-angle"}
        else:
            csv_files[tid] = out_dir / f"{name}_{re.sub(r'[^A-Za-z0-9_.-]+', '_', tid)}.csv"
            traj_specs[tid] = {"type": "csv", "file": csv_files[tid].name}
    if traj_specs:
        sidecar["trajectories"] = traj_specs
    sidecar_path = out_dir / f"{name}.yaml"

    def write(description):
        sidecar["description"] = description
        text = yaml.dump(sidecar, Dumper=_Dumper, sort_keys=False, allow_unicode=True, width=110)
        header = (f"# Converted by mcdm-pin import-caspr from {source}.\n"
                  f"# Points are in each link's URDF frame (origin at the link's joint point), metres.\n")
        sidecar_path.write_text(header + text, encoding="utf-8")

    write(f"Imported from CASPR: {source}.")
    robot = Robot.load(sidecar_path)
    coord = list(robot.coordinate_names)
    q_index = np.array([coord.index(n) for n in _caspr_urdf_names(chains)], dtype=int)
    result = CasprImport(urdf=urdf_path, sidecar=sidecar_path, cable_set=cset.id, q_index=q_index,
                         csv_files=csv_files, trajectories=trajs,
                         joint_names=tuple(robot.joint_names), renamed_cables=dict(cset.renamed))
    if result.q_is_caspr_order:
        order = "q (one coordinate per URDF joint, Pinocchio order) is CASPR's q unchanged."
    else:
        order = ("q differs from CASPR's order: q[q_index[i]] = q_caspr[i] with q_index = "
                 f"{q_index.tolist()} (coordinates {', '.join(coord)}).")
    renamed = "".join(f" Cable {k} is named {a!r} in CASPR like an earlier one; renamed {b!r}."
                      for k, (a, b) in cset.renamed.items())
    write(f"Imported from CASPR: {source}. {order} Spherical joints: alpha 1, beta 0, socket axis +z "
          f"of the parent frame; other joints: alpha = beta = 0.{renamed}")
    for tid, path in csv_files.items():
        traj = caspr_trajectory(robot, trajs[tid], q_index)
        with path.open("w", encoding="utf-8") as fh:
            fh.write("t," + ",".join(coord) + "\n")
            for t, q in zip(traj.t, traj.q):
                fh.write(f"{t:.10g}," + ",".join(f"{x:.17g}" for x in q) + "\n")
    return result


# ------------------------------------------------------------------------------ exact trajectories
def _quintic_coeffs(x0, v0, a0, x1, v1, a1, T):
    """Coefficients c0..c5 (in powers of t on [0, T]) of the quintic with the given end states."""
    A = np.array([[1, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], [0, 0, 2, 0, 0, 0],
                  [1, T, T**2, T**3, T**4, T**5], [0, 1, 2 * T, 3 * T**2, 4 * T**3, 5 * T**4],
                  [0, 0, 2, 6 * T, 12 * T**2, 20 * T**3]], dtype=float)
    return np.linalg.solve(A, np.array([x0, v0, a0, x1, v1, a1], dtype=float))


def caspr_trajectory(robot, traj: CasprTrajectory, q_index) -> "Trajectory":
    """Sample a CASPR quintic trajectory exactly, as CASPR does, in our coordinate order.

    Each segment is sampled at ``t_p, t_p + dt, ..., t_{p+1}``; the sample at a junction is kept once.
    Spherical joints turn about one fixed axis per segment (rest-to-rest); other coordinates follow
    the quintic through the segment's end positions, rates and accelerations.
    """
    from .trajectory import Trajectory, quintic_trajectory

    q_index = np.asarray(q_index, dtype=int)

    def ours(v):
        out = np.empty(robot.nv)
        out[q_index] = v
        return out

    spherical = np.zeros(robot.nv, dtype=bool)
    for j in robot.joints:
        if j.type == "spherical":
            spherical[j.idx_v] = True
    dt = traj.time_step
    ts, qs, qds, qdds = [], [], [], []
    for k in range(len(traj.points) - 1):
        a, b = traj.points[k], traj.points[k + 1]
        T = b.time - a.time
        seg = quintic_trajectory(robot, ours(a.q), ours(b.q), T, dt, "axis-angle", name=traj.id)
        q, qd, qdd = seg.q.copy(), seg.qd.copy(), seg.qdd.copy()
        va, vb, aa, ab = ours(a.q_dot), ours(b.q_dot), ours(a.q_ddot), ours(b.q_ddot)
        for i in np.flatnonzero(~spherical & ((va != 0) | (vb != 0) | (aa != 0) | (ab != 0))):
            c = _quintic_coeffs(ours(a.q)[i], va[i], aa[i], ours(b.q)[i], vb[i], ab[i], T)
            t = seg.t
            q[:, i] = np.polyval(c[::-1], t)
            qd[:, i] = np.polyval((c[1:] * np.arange(1, 6))[::-1], t)
            qdd[:, i] = np.polyval((c[2:] * np.array([2, 6, 12, 20]))[::-1], t)
        start = 1 if k > 0 else 0
        ts.append(a.time + seg.t[start:])
        qs.append(q[start:])
        qds.append(qd[start:])
        qdds.append(qdd[start:])
    return Trajectory(traj.id, np.concatenate(ts), np.vstack(qs), np.vstack(qds), np.vstack(qdds))


def load_caspr_trajectory(robot, trajectories_xml, traj_id: str, bodies_xml) -> "Trajectory":
    """One CASPR trajectory, sampled exactly, for a robot imported from ``bodies_xml``."""
    bodies = read_bodies(bodies_xml)
    tr = read_trajectories(trajectories_xml, bodies, [traj_id])[traj_id]
    q_index = np.array([list(robot.coordinate_names).index(n) for n in _caspr_urdf_names(_chains(bodies))])
    return caspr_trajectory(robot, tr, q_index)
