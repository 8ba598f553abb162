r"""CASPR's ``*_bodies.xml``: links, joints and what each joint type becomes in a URDF and a sidecar.

CASPR's body frame :math:`\{k\}` has its origin at link k's joint point and the orientation
:math:`R_{0k} = R_{0,parent} R_{pe}(q_k)`; its joint point is
:math:`P_k = P_{parent} + R_{0,parent}(\text{location} + r_{rel}(q_k))` (``src/Model/Bodies/Joints``
at CASPR ``a6971ee``). The URDF link of a CASPR link is the same frame, so a point in :math:`\{k\}` is
a point in the URDF link. Every joint type becomes (:data:`JOINT_KINDS`):

=======================  ====================================  =================================
CASPR type               URDF joints (parent first)            sidecar joint
=======================  ====================================  =================================
``R_X/R_Y/R_Z/R_AXIS``   one revolute                          ``revolute``
``P_X/P_AXIS``           one prismatic                         ``prismatic``
``P_XY/P_XZ/T_XYZ``      two or three prismatic                ``translation``
``PLANAR_XY/XZ/YZ``      prismatic, prismatic, revolute        ``planar`` (coordinates x, y, theta
                                                               in CASPR's order)
``U_XY/U_XZ/U_YZ``       two revolute                          ``universal``
``S_EULER_XYZ``          revolute x, y, z                      ``spherical`` (xyz Euler triple)
``S_FIXED_XYZ``          revolute z, y, x                      ``spherical``; q = (gamma, beta, alpha)
``SPATIAL_EULER_XYZ``    one ``floating``                      ``free`` (Pinocchio free-flyer)
=======================  ====================================  =================================

A free joint's coordinates are its position in the parent frame and a rotation vector (not CASPR's
Euler angles); its velocity is Pinocchio's :math:`(R^T\dot p, \omega)`. CASPR's quaternion joints
(``S_QUATERNION``, ``SPATIAL_QUATERNION``, formerly ``SPHERICAL``) are commented out of CASPR's
``JointType`` at ``a6971ee`` (CASPR itself cannot load them) and are refused.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..exceptions import CasprError, InertiaWarning
from ..urdf import breaks_triangle
from ._xml import child, ident, integer, number, numbers, parse_xml, text

_X, _Y, _Z = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)
R, P, F = "revolute", "prismatic", "floating"
AXIS_TOL = 1e-3  # an R_AXIS/P_AXIS axis whose norm is within this of 1 is normalised (CASPR normalises any)


@dataclass(frozen=True)
class JointKind:
    """What a CASPR joint type becomes.

    Attributes:
        sidecar: the sidecar joint type.
        chain: ``(label, URDF type, axis or None (the XML's axis), CASPR coordinate or None)`` per URDF
            joint, parent first.
        n_q: CASPR's number of coordinates (numVars = numDofs for every type converted).
        rotation: ``(convention, first coordinate)`` of the part CASPR interpolates on SO(3)
            (``xyz``: R = Rx Ry Rz, ``fixed``: R = Rz Ry Rx), or ``None``.
    """

    sidecar: str
    chain: tuple
    n_q: int
    rotation: tuple[str, int] | None = None

    @property
    def scalar(self) -> tuple[int, ...]:
        """CASPR coordinates interpolated one by one (all but the rotation part)."""
        rot = set(range(self.rotation[1], self.rotation[1] + 3)) if self.rotation else set()
        return tuple(i for i in range(self.n_q) if i not in rot)


JOINT_KINDS: dict[str, JointKind] = {
    "R_X": JointKind("revolute", (("x", R, _X, 0),), 1),
    "R_Y": JointKind("revolute", (("y", R, _Y, 0),), 1),
    "R_Z": JointKind("revolute", (("z", R, _Z, 0),), 1),
    "R_AXIS": JointKind("revolute", (("axis", R, None, 0),), 1),
    "P_X": JointKind("prismatic", (("px", P, _X, 0),), 1),
    "P_AXIS": JointKind("prismatic", (("paxis", P, None, 0),), 1),
    "P_XY": JointKind("translation", (("px", P, _X, 0), ("py", P, _Y, 1)), 2),
    "P_XZ": JointKind("translation", (("px", P, _X, 0), ("pz", P, _Z, 1)), 2),
    "T_XYZ": JointKind("translation", (("px", P, _X, 0), ("py", P, _Y, 1), ("pz", P, _Z, 2)), 3),
    "PLANAR_XY": JointKind("planar", (("px", P, _X, 0), ("py", P, _Y, 1), ("z", R, _Z, 2)), 3),
    "PLANAR_XZ": JointKind("planar", (("px", P, _X, 0), ("pz", P, _Z, 1), ("y", R, _Y, 2)), 3),
    "PLANAR_YZ": JointKind("planar", (("py", P, _Y, 0), ("pz", P, _Z, 1), ("x", R, _X, 2)), 3),
    "U_XY": JointKind("universal", (("x", R, _X, 0), ("y", R, _Y, 1)), 2),
    "U_XZ": JointKind("universal", (("x", R, _X, 0), ("z", R, _Z, 1)), 2),
    "U_YZ": JointKind("universal", (("y", R, _Y, 0), ("z", R, _Z, 1)), 2),
    "S_EULER_XYZ": JointKind("spherical", (("x", R, _X, 0), ("y", R, _Y, 1), ("z", R, _Z, 2)), 3, ("xyz", 0)),
    "S_FIXED_XYZ": JointKind("spherical", (("z", R, _Z, 2), ("y", R, _Y, 1), ("x", R, _X, 0)), 3, ("fixed", 0)),
    "SPATIAL_EULER_XYZ": JointKind("free", (("free", F, None, None),), 6, ("xyz", 3)),
}
DISABLED_IN_CASPR = ("S_QUATERNION", "SPATIAL_QUATERNION", "SPHERICAL")


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
    q_initial: tuple[float, ...]
    q_min: tuple[float, ...]
    q_max: tuple[float, ...]
    axis: tuple[float, float, float] | None
    actuated: bool
    element: str

    @property
    def kind(self) -> JointKind:
        return JOINT_KINDS[self.joint_type]

    @property
    def n_q(self) -> int:
        return self.kind.n_q


@dataclass(frozen=True)
class CasprBodies:
    """A bodies file: links in CASPR's order, and the notes the reader made (normalised axes)."""

    path: Path
    links: tuple[CasprLink, ...]
    notes: tuple[str, ...] = ()

    @property
    def n_q(self) -> int:
        return sum(link.n_q for link in self.links)

    @property
    def offsets(self) -> list[int]:
        """First CASPR coordinate of each link's joint."""
        out, k = [], 0
        for link in self.links:
            out.append(k)
            k += link.n_q
        return out

    @property
    def q_initial(self) -> np.ndarray:
        return np.concatenate([link.q_initial for link in self.links])


def read_bodies(path) -> CasprBodies:
    """Read and check a CASPR ``*_bodies.xml``."""
    path, root = parse_xml(path)
    if root.tag != "bodies_system":
        raise CasprError(path, f"<{root.tag}>", "expected the root element <bodies_system>")
    links_el = child(path, root, "links", "bodies_system")
    links: list[CasprLink] = []
    notes: list[str] = []
    taken = {"base"}
    for pos, el in enumerate(list(links_el), start=1):
        if el.tag != "link_rigid":
            raise CasprError(path, f"links/<{el.tag}> (element {pos})",
                             "unsupported link element; only <link_rigid> is converted")
        name = el.get("name", "")
        where = f"link_rigid[num={el.get('num')!r}, name={name!r}]"
        num = integer(path, el.get("num"), f"{where}@num")
        if num != pos:
            raise CasprError(path, f"{where}@num", f"expected num={pos} (links are numbered 1, 2, ... "
                                                   f"in file order), got {num}")
        for sub in el:
            if sub.tag not in ("joint", "physical", "parent"):
                raise CasprError(path, f"{where}/<{sub.tag}>",
                                 "unknown element; expected <joint>, <physical> and <parent>")
        links.append(_read_link(path, el, num, name, where, taken, notes))
    if not links:
        raise CasprError(path, "bodies_system/links", "no <link_rigid> element")
    return CasprBodies(path=path, links=tuple(links), notes=tuple(notes))


def _read_joint(path, joint, where, notes):
    jtype = joint.get("type")
    jw = f"{where}/joint@type"
    if jtype in DISABLED_IN_CASPR:
        raise CasprError(path, jw, f"joint type {jtype!r} is commented out of CASPR's JointType at a6971ee "
                                   f"(CASPR itself cannot load it); use S_EULER_XYZ or SPATIAL_EULER_XYZ")
    if jtype not in JOINT_KINDS:
        raise CasprError(path, jw, f"unknown joint type {jtype!r}; expected one of {', '.join(JOINT_KINDS)}")
    n_q = JOINT_KINDS[jtype].n_q
    values = {}
    for attr in ("q_initial", "q_min", "q_max"):
        if joint.get(attr) is None:
            raise CasprError(path, f"{where}/joint@{attr}", f"missing; expected {n_q} number(s)")
        values[attr] = numbers(path, joint.get(attr), f"{where}/joint@{attr}", n_q)
    if any(lo > hi for lo, hi in zip(values["q_min"], values["q_max"])):
        raise CasprError(path, f"{where}/joint@q_max", f"expected q_max >= q_min, got q_min={values['q_min']}, "
                                                       f"q_max={values['q_max']}")
    axis = None
    aw = f"{where}/joint@axis"
    if jtype in ("R_AXIS", "P_AXIS"):
        axis = numbers(path, joint.get("axis"), aw, 3)
        norm = math.sqrt(sum(a * a for a in axis))
        if abs(norm - 1.0) > AXIS_TOL:
            raise CasprError(path, aw, f"expected a unit vector (norm within {AXIS_TOL:g} of 1), got norm "
                                       f"{norm:.6g}: a longer or shorter axis is a typing error, not a direction")
        if norm != 1.0:
            axis = tuple(a / norm for a in axis)
            notes.append(f"{path.name}: {aw}: axis of norm {norm:.9g} normalised (as CASPR does)")
    elif joint.get("axis") is not None:
        raise CasprError(path, aw, f"an axis is allowed only for R_AXIS and P_AXIS, not {jtype}")
    actuated = joint.get("actuated")
    if actuated is not None and actuated.strip() not in ("true", "false"):
        raise CasprError(path, f"{where}/joint@actuated", f"expected 'true' or 'false', got {actuated!r}")
    return jtype, values, axis, actuated is not None and actuated.strip() == "true"


def _read_link(path, el, num, name, where, taken, notes) -> CasprLink:
    jtype, values, axis, actuated = _read_joint(path, child(path, el, "joint", where), where, notes)
    phys = child(path, el, "physical", where)
    pw = f"{where}/physical"
    mass = number(path, text(path, phys, "mass", pw), f"{pw}/mass")
    if mass < 0:
        raise CasprError(path, f"{pw}/mass", f"expected a mass >= 0 kg, got {mass}")
    com = np.array(numbers(path, text(path, phys, "com_location", pw), f"{pw}/com_location", 3))
    end_el = phys.find("end_location")
    end = np.array(numbers(path, end_el.text, f"{pw}/end_location", 3)) if end_el is not None else np.zeros(3)
    inertia = _inertia(path, child(path, phys, "inertia", pw), f"{pw}/inertia", mass, com)
    par = child(path, el, "parent", where)
    parent = integer(path, text(path, par, "num", f"{where}/parent"), f"{where}/parent/num")
    if not 0 <= parent < num:
        raise CasprError(path, f"{where}/parent/num", f"expected a parent number in 0..{num - 1} "
                                                      f"(an earlier link, 0 = base), got {parent}")
    location = np.array(numbers(path, text(path, par, "location", f"{where}/parent"),
                                f"{where}/parent/location", 3))
    return CasprLink(num=num, name=name, ident=ident(name, num, taken), joint_type=jtype, parent=parent,
                     location=location, mass=mass, com=com, end=end, inertia=inertia,
                     q_initial=values["q_initial"], q_min=values["q_min"], q_max=values["q_max"], axis=axis,
                     actuated=actuated, element=where)


def _inertia(path, el, iw, mass, com) -> np.ndarray:
    """The inertia about the COM in link axes; ``ref="joint"`` is moved with
    :math:`I_G = I_O - m(|r|^2 I_3 - r r^T)`."""
    ref = el.get("ref")
    if ref not in ("com", "joint"):
        raise CasprError(path, f"{iw}@ref", f"expected 'com' or 'joint', got {ref!r}")
    v = {k: number(path, text(path, el, k, iw), f"{iw}/{k}") for k in ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")}
    inertia = np.array([[v["Ixx"], v["Ixy"], v["Ixz"]], [v["Ixy"], v["Iyy"], v["Iyz"]],
                        [v["Ixz"], v["Iyz"], v["Izz"]]])
    if ref == "joint":
        inertia = inertia - mass * (com @ com * np.eye(3) - np.outer(com, com))
    eig = np.linalg.eigvalsh(inertia)
    scale = max(float(np.abs(eig).max()), 1e-300)
    if eig.min() < -1e-9 * scale:
        raise CasprError(path, iw, f"the inertia about the COM (ref={ref!r}) is not positive "
                                   f"semidefinite: eigenvalues {np.round(eig, 12).tolist()} kg m^2")
    if breaks_triangle(eig):  # CASPR ships it: converted as given, loudly (docs/limits.md)
        warnings.warn(f"{path}: {iw}: principal moments of inertia {[float(f'{x:.9g}') for x in eig]} kg m^2 "
                      f"(about the COM) break A + B >= C, which every body meets; converted as CASPR ships them",
                      InertiaWarning, stacklevel=2)
    return inertia
