"""What the links look like: the URDF's visual model as Pinocchio loads it, or simple shapes.

The visuals come from ``pin.buildGeomFromUrdf(..., pin.GeometryType.VISUAL, package_dirs)`` (boxes,
cylinders, spheres, capsules, cones, ellipsoids, and meshes in any format Pinocchio's loader reads,
scaled as the URDF says), each placed in the frame of its URDF link; ``package://`` paths resolve
through the installed packages (:func:`mcdm_pin.urdf.package_share_dirs`). A body without visuals
(and a robot built in code, which has no URDF) gets a simple shape: a cylinder from its joint to each
child joint (or to twice its centre of mass) and a sphere at its joint; a body that carries three or
more cable attachment points spread over a plane or a volume (the moving platform of a parallel
cable robot) is drawn as the convex hull of those points (:func:`platform_hull`), a flat one given a
thickness of :data:`PLATFORM_THICKNESS` x its span. The massless bodies inside a grouped joint (e.g.
the two inside an Euler-triple spherical joint) are not drawn.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from . import three


@dataclass
class Visual:
    """One visual of one link.

    Attributes:
        link: the link (a BODY frame of the robot's model) it is fixed to.
        placement: (4, 4) its pose in the link's frame (scale included for ellipsoids).
        geometry: the lowered three.js geometry.
        rgba: its URDF colour.
        is_mesh: a mesh (a body's skin) rather than a primitive shape.
        corners: (k, 3) points of its hull (box corners; points on a cylinder's end circles; a
            sphere's, or some of a mesh's vertices), in the link's frame: what the camera frames.
    """

    link: str
    placement: np.ndarray
    geometry: dict
    rgba: tuple
    is_mesh: bool
    corners: np.ndarray


def _box_corners(half) -> np.ndarray:
    h = np.asarray(half, float)
    return np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * h


def _round(radius: float, half_length: float) -> np.ndarray:
    """Points on the end circles of a cylinder along z (16 each)."""
    a = np.linspace(0, 2 * np.pi, 16, endpoint=False)
    ring = np.stack([radius * np.cos(a), radius * np.sin(a), np.zeros_like(a)], axis=1)
    return np.concatenate([ring + [0, 0, half_length], ring - [0, 0, half_length]])


def _ball(radii) -> np.ndarray:
    """Points on an ellipsoid (axes and diagonals)."""
    d = np.array([[x, y, z] for x in (-1, 0, 1) for y in (-1, 0, 1) for z in (-1, 0, 1) if (x, y, z) != (0, 0, 0)],
                 dtype=float)
    return d / np.linalg.norm(d, axis=1, keepdims=True) * np.asarray(radii, float)


def _lower(shape) -> tuple[dict, np.ndarray, np.ndarray, bool] | None:
    """(geometry, transform from the three.js shape to the coal shape's frame, bounding-box corners in
    the coal shape's frame, is_mesh) of a coal shape; ``None`` for shapes it cannot draw."""
    kind = type(shape).__name__
    if kind == "Box":
        half = np.asarray(shape.halfSide, float)
        return three.box(2 * half), np.eye(4), _box_corners(half), False
    if kind in ("Cylinder", "Capsule", "Cone"):  # along z; three.js draws them along y
        r, h = float(shape.radius), float(shape.halfLength)
        reach = h + (r if kind == "Capsule" else 0.0)
        geometry = three.cylinder(2 * h, 0.0 if kind == "Cone" else r, r, 40)
        return geometry, three.T(three.RX90), _round(r, reach), False
    if kind == "Sphere":
        r = float(shape.radius)
        return three.sphere(r), np.eye(4), _ball([r, r, r]), False
    if kind == "Ellipsoid":
        radii = np.asarray(shape.radii, float)
        return three.sphere(1.0), three.T(scale=radii), _ball(radii), False
    if hasattr(shape, "num_tris") and hasattr(shape, "vertices"):  # BVH meshes and convex hulls
        v = np.asarray(shape.vertices(), float).reshape(-1, 3)
        tri = shape.tri_indices
        faces = np.array([[tri(i)[k] for k in range(3)] for i in range(int(shape.num_tris))], dtype=np.int64)
        if len(v) == 0 or len(faces) == 0:
            return None
        return three.mesh(v, faces), np.eye(4), v[:: max(1, len(v) // 64)], True
    return None


def robot_visuals(robot) -> list[Visual]:
    """The visuals of every link of ``robot`` that its model still has (locked joints keep their
    links, fixed to the body they are locked to); [] for a robot built in code."""
    if robot.urdf_path is None:
        return []
    from ..urdf import package_share_dirs

    urdf = str(robot.urdf_path)
    try:
        model = pin.buildModelFromUrdf(urdf)
        geom = pin.buildGeomFromUrdf(model, urdf, pin.GeometryType.VISUAL,
                                     package_dirs=[str(p) for p in package_share_dirs()])
    except Exception as exc:  # a URDF the robot loads from, but whose meshes cannot be read here
        warnings.warn(f"{urdf}: cannot load the visuals ({exc}); drawing simple shapes")
        return []
    links = set(robot.link_names)
    out = []
    for g in geom.geometryObjects:
        frame = model.frames[g.parentFrame]
        if frame.name not in links:
            continue
        lowered = _lower(g.geometry)
        if lowered is None:
            warnings.warn(f"{urdf}: visual {g.name!r} ({type(g.geometry).__name__}) cannot be drawn; "
                          f"skipped")
            continue
        geometry, extra, corners, is_mesh = lowered
        placement = (frame.placement.inverse() * g.placement).homogeneous
        corners = corners @ placement[:3, :3].T + placement[:3, 3]
        rgba = tuple(float(c) for c in np.asarray(g.meshColor, float))
        out.append(Visual(frame.name, placement @ extra, geometry, rgba, is_mesh, corners))
    return out


PLATFORM_THICKNESS = 0.04  # a flat platform's thickness, x its span


def platform_hull(points: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """(vertices (k, 3), faces (t, 3)) of the convex hull of a body's cable attachment points
    ``points`` (n, 3, body frame), with outward-facing triangles; points on one plane are extruded
    by +-half :data:`PLATFORM_THICKNESS` x their span along its normal. ``None`` for fewer than three
    distinct points or points on one line (nothing to span: the body keeps its simple shape)."""
    from scipy.spatial import ConvexHull

    p = np.unique(np.round(np.asarray(points, float).reshape(-1, 3), 12), axis=0)
    if len(p) < 3:
        return None
    center = p.mean(axis=0)
    _, sv, vt = np.linalg.svd(p - center)
    span = float(np.linalg.norm(p.max(axis=0) - p.min(axis=0)))
    if sv[1] <= 1e-6 * span:  # on a line
        return None
    if sv[2] <= 1e-6 * span:  # on a plane: give it a thickness
        n = vt[2] * 0.5 * PLATFORM_THICKNESS * span
        p = np.concatenate([p + n, p - n])
    hull = ConvexHull(p)
    faces = hull.simplices.copy()
    normals = hull.equations[:, :3]  # outward
    tri_n = np.cross(p[faces[:, 1]] - p[faces[:, 0]], p[faces[:, 2]] - p[faces[:, 0]])
    flip = np.einsum("ij,ij->i", tri_n, normals) < 0
    faces[flip] = faces[flip][:, ::-1]
    return p, faces


@dataclass
class Bone:
    """A simple shape for a body without visuals: ``ends`` (k, 3) of cylinders from its joint, in the
    joint's frame, and whether to draw a sphere at the joint."""

    joint_id: int
    ends: np.ndarray
    sphere: bool


def fallback_bones(robot, drawn_joints: set[int]) -> list[Bone]:
    """Simple shapes for the bodies of ``robot.model`` that have no visual (``drawn_joints``: the
    Pinocchio joints whose bodies have one) and are not massless members of a grouped joint."""
    from ..model.joints import massless_members

    model = robot.model
    inside = massless_members(robot.joints)
    bones = []
    for j in range(model.njoints):
        if j in drawn_joints or j in inside:
            continue
        ends = [np.array(model.jointPlacements[c].translation) for c in range(1, model.njoints)
                if model.parents[c] == j]
        lever = np.array(model.inertias[j].lever)
        if not ends and np.linalg.norm(lever) > 1e-9:
            ends.append(2 * lever)
        ends = [e for e in ends if np.linalg.norm(e) > 1e-9]
        if ends or j > 0:
            bones.append(Bone(j, np.array(ends).reshape(-1, 3), sphere=j > 0))
    return bones


def platforms(robot, visuals) -> dict:
    """{Pinocchio joint: hull} of the moving bodies whose cable attachment points span a plane or a
    volume more than twice as wide as the body's own visuals (e.g. CASPR's 1.6 cm centre-of-mass
    sphere on a cable robot's 1 m platform): they are drawn as the hull of those points."""
    model, cables = robot.model, robot.cables
    size: dict[int, float] = {}
    for v in visuals:
        j = int(model.frames[model.getFrameId(v.link, pin.FrameType.BODY)].parentJoint)
        size[j] = max(size.get(j, 0.0), float(np.linalg.norm(np.ptp(v.corners, axis=0))))
    out = {}
    for j in sorted({int(j) for j in cables.point_joint} - {0}):
        p = cables.point_local[cables.point_joint == j]
        span = float(np.linalg.norm(np.ptp(p, axis=0)))
        hull = platform_hull(p) if span > 2.0 * size.get(j, 0.0) else None
        if hull is not None:
            out[j] = hull
    return out
