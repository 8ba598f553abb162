"""Random cable-driven robots for the property-based tests: URDF + sidecar written to a folder.

A :class:`GenRobot` is plain data (tuples of floats), and its ``repr`` is Python that rebuilds it, so a
failing hypothesis example prints a robot that can be pasted into a test; :meth:`GenRobot.texts`
gives the URDF and sidecar text as well (the tests ``note()`` them).

Shape: 1-6 links in a chain or a tree, each attached by a spherical joint (three revolute URDF joints
x, y, z with massless links between them, as the sidecar requires) or a revolute joint (random axis,
``revolute`` with limits or ``continuous``); random masses, centres of mass and inertias (positive
definite, principal moments obeying the triangle inequality); a fixed joint ``world -> base`` whose
placement moves and turns the whole robot (gravity is given in the world frame); 3-6 cables per
degree of freedom, each running from a link (or the base) over 0 or more intermediate links to a
descendant link.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import yaml
from hypothesis import strategies as st

from mcdm_pin.limits import MIN_FORCE_BOUND


@dataclass(frozen=True)
class GenLink:
    parent: int  # 0 = base, k = link k (1-based, earlier link)
    kind: str  # spherical | revolute | continuous
    xyz: tuple  # joint origin in the parent link frame, m
    rpy: tuple  # joint origin rotation, rad
    axis: tuple  # revolute axis (unit), ignored for spherical
    length: float  # m: where children and cable points sit along z
    mass: float  # kg
    com: tuple  # m, link frame
    inertia: tuple  # (ixx, ixy, ixz, iyy, iyz, izz) about the COM, kg m^2
    alpha: float = 1.0
    beta: float = 0.0
    cone_deg: float | None = None


@dataclass(frozen=True)
class GenCable:
    links: tuple  # link indices along the route (0 = base)
    points: tuple  # one (x, y, z) per route point, in that link's frame
    f_min: float
    f_max: float


@dataclass(frozen=True)
class GenRobot:
    links: tuple
    cables: tuple
    base_xyz: tuple = (0.0, 0.0, 0.0)
    base_rpy: tuple = (0.0, 0.0, 0.0)
    gravity_base: tuple = (0.0, 0.0, -9.81)  # gravity in the base frame

    # ------------------------------------------------------------------------------------- derived
    @property
    def nv(self) -> int:
        return sum(3 if link.kind == "spherical" else 1 for link in self.links)

    @property
    def m(self) -> int:
        return len(self.cables)

    def moved(self, xyz, rpy) -> "GenRobot":
        """The same robot with the base placed at ``xyz, rpy`` in the world (gravity turned along)."""
        return replace(self, base_xyz=tuple(float(x) for x in xyz), base_rpy=tuple(float(x) for x in rpy))

    def gravity_world(self) -> np.ndarray:
        return _rpy_matrix(self.base_rpy) @ np.array(self.gravity_base)

    @staticmethod
    def link_name(k: int) -> str:
        return "base" if k == 0 else f"link{k}"

    # ---------------------------------------------------------------------------------------- text
    def urdf(self) -> str:
        out = ['<?xml version="1.0"?>', '<robot name="gen">', '  <link name="world"/>', '  <link name="base"/>',
               f'  <joint name="base_offset" type="fixed"><parent link="world"/><child link="base"/>'
               f'<origin xyz="{_v(self.base_xyz)}" rpy="{_v(self.base_rpy)}"/></joint>']
        for k, link in enumerate(self.links, start=1):
            parent = self.link_name(link.parent)
            name = self.link_name(k)
            ixx, ixy, ixz, iyy, iyz, izz = link.inertia
            inertial = (f'<inertial><origin xyz="{_v(link.com)}" rpy="0 0 0"/><mass value="{link.mass!r}"/>'
                        f'<inertia ixx="{ixx!r}" ixy="{ixy!r}" ixz="{ixz!r}" iyy="{iyy!r}" iyz="{iyz!r}" '
                        f'izz="{izz!r}"/></inertial>')
            origin = f'<origin xyz="{_v(link.xyz)}" rpy="{_v(link.rpy)}"/>'
            if link.kind == "spherical":
                chain = [parent, f"{name}_sx", f"{name}_sy", name]
                out.append(f'  <link name="{name}_sx"/>')
                out.append(f'  <link name="{name}_sy"/>')
                for a, (axis, tag) in enumerate((("1 0 0", "x"), ("0 1 0", "y"), ("0 0 1", "z"))):
                    o = origin if a == 0 else '<origin xyz="0 0 0" rpy="0 0 0"/>'
                    out.append(f'  <joint name="{name}_q{tag}" type="revolute"><parent link="{chain[a]}"/>'
                               f'<child link="{chain[a + 1]}"/>{o}<axis xyz="{axis}"/>'
                               f'<limit lower="-3.2" upper="3.2" effort="0" velocity="0"/></joint>')
            else:
                limit = ('<limit lower="-3.2" upper="3.2" effort="0" velocity="0"/>'
                         if link.kind == "revolute" else "")
                out.append(f'  <joint name="{name}_q" type="{link.kind}"><parent link="{parent}"/>'
                           f'<child link="{name}"/>{origin}<axis xyz="{_v(link.axis)}"/>{limit}</joint>')
            out.append(f'  <link name="{name}">{inertial}</link>')
        out.append("</robot>")
        return "\n".join(out) + "\n"

    def sidecar(self, urdf_name: str = "gen.urdf") -> dict:
        joints = {}
        for k, link in enumerate(self.links, start=1):
            name = self.link_name(k)
            if link.kind == "spherical":
                spec = {"type": "spherical", "urdf_joints": [f"{name}_qx", f"{name}_qy", f"{name}_qz"]}
                if link.cone_deg is not None:
                    spec["cone_deg"] = float(link.cone_deg)
            else:
                spec = {"type": "revolute", "urdf_joints": [f"{name}_q"]}
            spec.update(alpha=float(link.alpha), beta=float(link.beta))
            joints[f"j{k}"] = spec
        cables = []
        for c, cable in enumerate(self.cables):
            cables.append({"name": f"c{c}", "f_min": float(cable.f_min), "f_max": float(cable.f_max),
                           "route": [{"link": self.link_name(k), "point": [float(x) for x in p]}
                                     for k, p in zip(cable.links, cable.points)]})
        return {"version": 1, "name": "gen", "urdf": urdf_name,
                "gravity": [float(x) for x in self.gravity_world()], "joints": joints, "cables": cables}

    def texts(self) -> tuple[str, str]:
        return self.urdf(), yaml.safe_dump(self.sidecar(), sort_keys=False)

    def write(self, folder, stem: str = "gen") -> Path:
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        (folder / f"{stem}.urdf").write_text(self.urdf(), encoding="utf-8")
        path = folder / f"{stem}.yaml"
        path.write_text(yaml.safe_dump(self.sidecar(f"{stem}.urdf"), sort_keys=False), encoding="utf-8")
        return path

    def load(self, folder, stem: str = "gen"):
        from mcdm_pin import Robot

        return Robot.load(self.write(folder, stem))


def _v(x) -> str:
    return " ".join(repr(float(a)) for a in x)


def _rpy_matrix(rpy) -> np.ndarray:
    r, p, y = rpy
    cx, sx, cy, sy, cz, sz = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    Rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


def _r(x) -> float:
    """Round to 6 significant digits: short reprs, exact round trip through the text files."""
    return float(f"{float(x):.6g}")


# ------------------------------------------------------------------------------------ strategies
def _unit(draw, rng_float):
    while True:
        v = np.array([draw(rng_float) for _ in range(3)])
        n = np.linalg.norm(v)
        if n > 0.3:
            return tuple(_r(a) for a in v / n)


@st.composite
def robots(draw, min_links: int = 1, max_links: int = 6, tree: bool | None = None,
           cables_per_dof=(3, 6), mass=(0.05, 2.0), length=(0.1, 0.5), f_bounds=((0.0, 1.0), (200.0, 2000.0)),
           mass_log_spread: float = 0.0, length_log_spread: float = 0.0, with_cones: bool = True,
           base_offset: bool = True, grouped: bool = False) -> GenRobot:
    """A random :class:`GenRobot` (module docstring). ``mass_log_spread`` / ``length_log_spread``
    multiply each link's mass / length by ``10**u``, ``u`` uniform in +-spread (badly scaled robots).
    ``grouped``: cables come in threes, each route turned by 0, 120 and 240 degrees about every
    link's z axis (like the 2-link arm's), so that the cables span the degrees of freedom more often."""
    unit = st.floats(-1.0, 1.0)
    n = draw(st.integers(min_links, max_links), label="links")
    is_tree = draw(st.booleans()) if tree is None else tree
    links = []
    for k in range(1, n + 1):
        parent = draw(st.integers(0, k - 1)) if is_tree else k - 1
        kind = draw(st.sampled_from(("spherical", "revolute", "continuous")))
        spread_l = 10 ** draw(st.floats(-length_log_spread, length_log_spread)) if length_log_spread else 1.0
        spread_m = 10 ** draw(st.floats(-mass_log_spread, mass_log_spread)) if mass_log_spread else 1.0
        L = _r(draw(st.floats(*length)) * spread_l)
        plen = links[parent - 1].length if parent else 0.0
        jitter = 0.2 * (plen if parent else 0.1)
        xyz = (_r(draw(unit) * jitter), _r(draw(unit) * jitter), _r(plen))
        rpy = tuple(_r(0.4 * draw(unit)) for _ in range(3))
        mass_k = _r(draw(st.floats(*mass)) * spread_m)
        com = (_r(0.1 * L * draw(unit)), _r(0.1 * L * draw(unit)), _r(0.5 * L))
        # principal second moments a, b, c > 0 -> moments (b+c, a+c, a+b): the triangle inequality holds
        a, b, c = (mass_k * L * L * draw(st.floats(0.01, 0.1)) for _ in range(3))
        R = _rpy_matrix([draw(unit) * np.pi for _ in range(3)])
        I = R @ np.diag([b + c, a + c, a + b]) @ R.T
        inertia = tuple(_r(x) for x in (I[0, 0], I[0, 1], I[0, 2], I[1, 1], I[1, 2], I[2, 2]))
        cone = _r(draw(st.floats(25.0, 75.0))) if (kind == "spherical" and with_cones) else None
        links.append(GenLink(parent=parent, kind=kind, xyz=xyz, rpy=rpy, axis=_unit(draw, unit), length=L,
                             mass=mass_k, com=com, inertia=inertia, alpha=_r(draw(st.floats(0.1, 1.0))),
                             beta=_r(draw(st.floats(0.0, 0.1))), cone_deg=cone))
    nv = sum(3 if link.kind == "spherical" else 1 for link in links)
    m = draw(st.integers(cables_per_dof[0] * nv, cables_per_dof[1] * nv), label="cables")
    if grouped:
        m = 3 * ((m + 2) // 3)
    cables = []
    for _ in range(m // 3 if grouped else m):
        end = draw(st.integers(1, n))
        path = [end]
        while path[-1] != 0:
            path.append(links[path[-1] - 1].parent if path[-1] else 0)
        start_pos = draw(st.integers(1, len(path) - 1))  # a strict ancestor of `end`
        route = [path[start_pos]]
        for mid in reversed(path[1:start_pos]):
            if draw(st.booleans()):
                route.append(mid)
        route.append(end)
        points = []
        for k in route:
            theta = draw(st.floats(0.0, 2 * np.pi))
            if k == 0:
                rad, z = draw(st.floats(0.1, 0.3)), draw(st.floats(-0.05, 0.05))
            else:
                Lk = links[k - 1].length
                rad, z = draw(st.floats(0.2, 0.6)) * max(Lk, 0.05), draw(st.floats(0.1, 0.9)) * Lk
            points.append((_r(rad * np.cos(theta)), _r(rad * np.sin(theta)), _r(z)))
        f_min = _r(draw(st.floats(*f_bounds[0])))
        if f_min < MIN_FORCE_BOUND:  # a bound other than 0 is at least 1e-100 N (docs/limits.md)
            f_min = 0.0
        f_max = _r(max(draw(st.floats(*f_bounds[1])), 2 * f_min + 1e-3))
        for turn in ((0.0, 2 * np.pi / 3, 4 * np.pi / 3) if grouped else (0.0,)):
            c, s = np.cos(turn), np.sin(turn)
            turned = tuple((_r(c * x - s * y), _r(s * x + c * y), z) for x, y, z in points)
            cables.append(GenCable(links=tuple(route), points=turned, f_min=f_min, f_max=f_max))
    if base_offset:
        base_xyz = tuple(_r(draw(unit)) for _ in range(3))
        base_rpy = tuple(_r(np.pi * draw(unit)) for _ in range(3))
    else:
        base_xyz = base_rpy = (0.0, 0.0, 0.0)
    return GenRobot(links=tuple(links), cables=tuple(cables), base_xyz=base_xyz, base_rpy=base_rpy)
