"""Writing the converted model: the URDF, the sidecar data and the trajectory CSV files.

Every output is a pure function of the CASPR files read (no time stamps, no absolute paths), so a
conversion run twice gives the same bytes.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from xml.sax.saxutils import escape, quoteattr

import numpy as np
import yaml

from ..exceptions import CasprError
from ..urdf import CASPR_PROVENANCE
from .bodies import CasprBodies, CasprLink
from .pulleys import sidecar_element

GRAVITY = (0.0, 0.0, -9.81)


@dataclass(frozen=True)
class Chain:
    """The URDF joints of one CASPR joint: names, URDF types, axes, and the massless links between."""

    link: CasprLink
    urdf_joints: tuple[str, ...]
    urdf_types: tuple[str, ...]
    axes: tuple
    inner_links: tuple[str, ...]


def chains(bodies: CasprBodies) -> list[Chain]:
    out = []
    names = {"base"} | {link.ident for link in bodies.links}
    for link in bodies.links:
        spec = link.kind.chain
        joints = [f"{link.ident}_{label}" for label, _, _, _ in spec]
        inner = [f"{link.ident}__{label}" for label, _, _, _ in spec[:-1]]
        for n in joints + inner:
            if n in names:
                raise CasprError(bodies.path, link.element, f"generated URDF name {n!r} clashes with another "
                                                            f"link or joint name; rename the link")
            names.add(n)
        out.append(Chain(link=link, urdf_joints=tuple(joints), urdf_types=tuple(t for _, t, _, _ in spec),
                         axes=tuple(a if a is not None else link.axis for _, _, a, _ in spec),
                         inner_links=tuple(inner)))
    return out


def comment(text: str) -> str:
    """``text`` made safe inside an XML comment (no ``--``, no trailing ``-``)."""
    text = re.sub(r"-(?=-)", "- ", text)
    return text + " " if text.endswith("-") else text


def _f(x: float) -> str:
    return repr(float(x) + 0.0) if x != 0 else "0"


def _v(v) -> str:
    return " ".join(_f(x) for x in v)


def urdf_text(bodies: CasprBodies, chs: list[Chain], name: str, source: str) -> str:
    lines = ['<?xml version="1.0"?>',
             "<!--", f"  {CASPR_PROVENANCE}{comment(source)}.",  # (read back: urdf.shipped_by_caspr)
             "  Each link's frame is CASPR's body frame {k} (origin at the link's joint point). A CASPR joint",
             "  is one URDF joint (SPATIAL_EULER_XYZ: floating) or a chain of revolute/prismatic joints joined",
             "  by massless links; the sidecar groups them. Units: SI.", "-->",
             f"<robot name={quoteattr(name)}>", '  <link name="base"/>']
    for ch in chs:
        link = ch.link
        for inner in ch.inner_links:
            lines.append(f'  <link name="{inner}"/>')
        I = link.inertia
        lines += [f'  <link name="{link.ident}">  <!-- CASPR link {link.num}: {comment(link.name)} -->',
                  "    <inertial>", f'      <origin xyz="{_v(link.com)}" rpy="0 0 0"/>',
                  f'      <mass value="{_f(link.mass)}"/>',
                  f'      <inertia ixx="{_f(I[0, 0])}" ixy="{_f(I[0, 1])}" ixz="{_f(I[0, 2])}" '
                  f'iyy="{_f(I[1, 1])}" iyz="{_f(I[1, 2])}" izz="{_f(I[2, 2])}"/>', "    </inertial>"]
        lines += _visuals(link)
        lines.append("  </link>")
    for ch in chs:
        lines += _joints(ch, chs)
    lines.append("</robot>")
    return "\n".join(lines) + "\n"


def _joints(ch: Chain, chs: list[Chain]) -> list[str]:
    link = ch.link
    parent = "base" if link.parent == 0 else chs[link.parent - 1].link.ident
    children = list(ch.inner_links) + [link.ident]
    lines = []
    for k, (jname, jtype, axis, spec) in enumerate(zip(ch.urdf_joints, ch.urdf_types, ch.axes, link.kind.chain)):
        origin = link.location if k == 0 else np.zeros(3)
        lines.append(f'  <joint name="{jname}" type="{jtype}">')
        lines.append(f'    <parent link="{parent}"/><child link="{children[k]}"/>')
        if jtype == "floating":
            lines.append(f'    <origin xyz="{_v(origin)}" rpy="0 0 0"/>')
        else:
            c = spec[3]
            lines.append(f'    <origin xyz="{_v(origin)}" rpy="0 0 0"/><axis xyz="{_v(axis)}"/>')
            lines.append(f'    <limit lower="{_f(link.q_min[c])}" upper="{_f(link.q_max[c])}" '
                         f'effort="1e6" velocity="1e3"/>')
        lines.append("  </joint>")
        parent = children[k]
    return lines


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


def sidecar_joints(chs: list[Chain], cone_deg: float | None, actuator_limit: float | None) -> dict:
    joints = {}
    for ch in chs:
        link = ch.link
        spec: dict = {"type": link.kind.sidecar, "urdf_joints": list(ch.urdf_joints)}
        if link.kind.sidecar == "spherical":
            spec.update(socket_axis=[0.0, 0.0, 1.0], alpha=1.0, beta=0.0)
            if cone_deg is not None:
                spec["cone_deg"] = float(cone_deg)
        else:
            spec.update(alpha=0.0, beta=0.0)
        if link.actuated:  # CASPR's motors are unbounded unless a limit is given; weight 1 as CASPR's
            n = link.kind.n_q
            limit = math.inf if actuator_limit is None else float(actuator_limit)
            spec["actuated"] = {"min": [-limit] * n, "max": [limit] * n, "weight": 1.0}
        joints[link.ident] = spec
    return joints


def _route(bodies: CasprBodies, cable) -> list[dict]:
    """A CASPR cable's route as sidecar elements: its rotating pulley if any, then its attachments as
    points (link frames, from the joint point)."""
    route = [] if getattr(cable, "pulley", None) is None else [sidecar_element(cable.pulley)]
    for link, loc in cable.attachments:
        if link == 0:
            point, lname = loc, "base"  # absolute in the base frame in either reference
        else:
            L = bodies.links[link - 1]
            point = L.com + loc if cable.reference == "com" else loc
            lname = L.ident
        route.append({"link": lname, "point": [float(x) + 0.0 for x in point]})
    return route


def sidecar_cables(bodies: CasprBodies, cset) -> list[dict]:
    return [{"name": c.name, "f_min": c.f_min, "f_max": c.f_max, "route": _route(bodies, c)} for c in cset.cables]


def sidecar_springs(bodies: CasprBodies, cset) -> list[dict]:
    """CASPR's passive linear springs: ``K (l - l0)``, not clipped (``CableModelPassiveLinearSpring``)."""
    return [{"name": s.name, "stiffness": s.stiffness["K"], "rest_length": s.stiffness["l0"],
             "route": _route(bodies, s)} for s in cset.springs]


class _Dumper(yaml.SafeDumper):
    pass


def _flow_list(dumper, data):
    flow = all(isinstance(x, (int, float, str)) for x in data) and len(data) <= 32
    return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=flow)


_Dumper.add_representer(list, _flow_list)


def sidecar_text(data: dict, source: str) -> str:
    text = yaml.dump(data, Dumper=_Dumper, sort_keys=False, allow_unicode=True, width=110)
    return (f"# Converted by mcdm-pin import-caspr from {source}.\n"
            f"# Points are in each link's URDF frame (origin at the link's joint point), metres.\n" + text)


def csv_text(names, t, X, V, A) -> str:
    """A trajectory CSV with exact rates (``qd:``/``qdd:`` columns, Pinocchio's tangent space)."""
    head = ["t", *names, *(f"qd:{n}" for n in names), *(f"qdd:{n}" for n in names)]
    rows = [",".join(head)]
    for k in range(len(t)):
        vals = np.concatenate([[t[k]], X[k], V[k], A[k]])
        rows.append(",".join(repr(float(x) + 0.0) for x in vals))
    return "\n".join(rows) + "\n"
