"""CASPR XML files written from Python data, for the tests (CASPR's own files are not in the repository).

The layout follows CASPR's templates (``data/model_config/templates``): ``bodies_system/links/link_rigid``,
``cables/cable_set/cable_*``, ``trajectories/joint_trajectories/*_trajectory``.
"""

from __future__ import annotations

import math
from pathlib import Path

N_Q = {"R_X": 1, "R_Y": 1, "R_Z": 1, "R_AXIS": 1, "P_X": 1, "P_AXIS": 1, "P_XY": 2, "P_XZ": 2, "T_XYZ": 3,
       "PLANAR_XY": 3, "PLANAR_XZ": 3, "PLANAR_YZ": 3, "U_XY": 2, "U_XZ": 2, "U_YZ": 2, "S_EULER_XYZ": 3,
       "S_FIXED_XYZ": 3, "SPATIAL_EULER_XYZ": 6, "S_QUATERNION": 4, "SPATIAL_QUATERNION": 7}

LINK = """<link_rigid num="{num}" name="{name}">
  <joint type="{type}" q_initial="{q}" q_min="{qmin}" q_max="{qmax}"{extra}/>
  <physical><mass>{mass}</mass><com_location>{com}</com_location><end_location>{end}</end_location>
    <inertia ref="{ref}"><Ixx>{ixx}</Ixx><Iyy>{iyy}</Iyy><Izz>{izz}</Izz><Ixy>{ixy}</Ixy><Ixz>{ixz}</Ixz><Iyz>{iyz}</Iyz></inertia>
  </physical>
  <parent><num>{parent}</num><location>{loc}</location></parent>
</link_rigid>"""


def _nums(v) -> str:
    return " ".join(repr(float(x)) for x in v) if not isinstance(v, str) else v


def bodies(path: Path, links: list[dict]) -> Path:
    """``links``: dicts with ``type`` and optionally every field of :data:`LINK` (``q``, ``loc``... as
    strings or lists), ``axis`` and ``actuated``."""
    parts = []
    for i, spec in enumerate(links, start=1):
        n = N_Q.get(spec["type"], 1)
        d = dict(num=i, name=f"L{i}", q=[0.0] * n, qmin=[-3.0] * n, qmax=[3.0] * n, mass=1.0, com="0 0 0.1",
                 end="0 0 0.2", ref="com", ixx=0.01, iyy=0.02, izz=0.03, ixy=0.0, ixz=0.0, iyz=0.0, parent=i - 1,
                 loc="0 0 0.2" if i > 1 else "0 0 0")
        d.update({k: v for k, v in spec.items() if k not in ("axis", "actuated")})
        extra = ""
        if "axis" in spec:
            extra += f' axis="{_nums(spec["axis"])}"'
        if spec.get("actuated"):
            extra += ' actuated="true"'
        d.update(extra=extra, **{k: _nums(d[k]) for k in ("q", "qmin", "qmax", "com", "loc", "end")})
        parts.append(LINK.format(**d))
    path.write_text('<?xml version="1.0"?>\n<!DOCTYPE bodies_system SYSTEM "../../../templates/bodies.dtd">\n'
                    f'<bodies_system><links display_range="-1 1 -1 1 0 1" view_angle="0 0">{"".join(parts)}'
                    f"</links></bodies_system>\n")
    return path


def cable(name, atts, ref="com", f_min=0.1, f_max=100.0, tag="cable_ideal") -> str:
    a = "".join(f"<attachment><link>{k}</link><location>{_nums(x)}</location></attachment>" for k, x in atts)
    return (f'<{tag} name="{name}" attachment_reference="{ref}"><properties><force_min>{f_min}</force_min>'
            f"<force_max>{f_max}</force_max></properties><attachments>{a}</attachments></{tag}>")


def cables(path: Path, sets: dict[str, list[str]], default: str | None = None) -> Path:
    body = "".join(f'<cable_set id="{sid}">{"".join(cs)}</cable_set>' for sid, cs in sets.items())
    attr = f' default_cable_set="{default or next(iter(sets))}"' if default is not False else ""
    path.write_text(f'<?xml version="1.0"?>\n<cables{attr}>{body}</cables>\n')
    return path


def ring(link: int, z: float, r: float, n: int) -> list:
    return [(link, [r * math.cos(2 * math.pi * k / n), r * math.sin(2 * math.pi * k / n), z]) for k in range(n)]


def star(n_links: int, n: int = 8, base_r: float = 0.4, height: float = 0.0) -> list[str]:
    """``n`` cables from a base ring to a ring on each link."""
    base = ring(0, height, base_r, n)
    return [cable(f"c{link}_{k}", [base[k], ring(link, 0.0, 0.05, n)[k]])
            for link in range(1, n_links + 1) for k in range(n)]


def point(q, q_dot=None, q_ddot=None, time=None, blend_time=None) -> str:
    attrs = (f' time="{time}"' if time is not None else "") + (f' blend_time="{blend_time}"' if blend_time else "")
    inner = f"<q>{_nums(q)}</q>"
    if q_dot is not None:
        inner += f"<q_dot>{_nums(q_dot)}</q_dot>"
    if q_ddot is not None:
        inner += f"<q_ddot>{_nums(q_ddot)}</q_ddot>"
    return f"<point{attrs}>{inner}</point>"


def trajectory(tag: str, tid: str, points: list[str], dt: float = 0.01, time_definition="absolute", **attrs) -> str:
    extra = "".join(f' {k}="{v}"' for k, v in attrs.items())
    return (f'<{tag} id="{tid}" time_definition="{time_definition}" time_step="{dt}"{extra}><points>'
            f'{"".join(points)}</points></{tag}>')


def trajectories(path: Path, joint: list[str], operational: list[str] = ()) -> Path:
    op = f"<operational_trajectories>{''.join(operational)}</operational_trajectories>" if operational else ""
    path.write_text(f'<?xml version="1.0"?>\n<trajectories><joint_trajectories>{"".join(joint)}'
                    f"</joint_trajectories>{op}</trajectories>\n")
    return path


def sr_arm(folder: Path) -> tuple[Path, Path, Path]:
    """A model shaped like the source paper's SR arm: a spherical shoulder (S_EULER_XYZ), a revolute
    elbow (R_X), four cables to each link, one quintic trajectory."""
    b = bodies(folder / "sr_bodies.xml", [dict(type="S_EULER_XYZ", mass=0.1, ixx=1, iyy=1, izz=1),
                                         dict(type="R_X", mass=0.1, ixx=1, iyy=1, izz=1)])
    cs = []
    for k, (x, y) in enumerate([(0.15, 0), (0, 0.15), (-0.15, 0), (0, -0.15)]):
        cs.append(cable(f"cable {k + 1}", [(0, [x, y, 0]), (1, [x / 3, y / 3, 0])], f_min=0.001, f_max=1000))
    for k, (x, y) in enumerate([(0.2, 0), (0, 0.2), (-0.2, 0), (0, -0.2)]):
        cs.append(cable(f"cable {k + 5}", [(0, [x, y, 0]), (2, [x / 4, y / 4, 0])], f_min=0.001, f_max=1000))
    c = cables(folder / "sr_cables.xml", {"SR_8_cables": cs})
    t = trajectories(folder / "sr_trajectories.xml", [trajectory("quintic_spline_trajectory", "traj", [
        point([0.2, -0.2, -0.1, 0.2], [0] * 4, [0] * 4), point([-0.5, 0.5, 0.2, -0.2], [0] * 4, [0] * 4, time=1)])])
    return b, c, t
