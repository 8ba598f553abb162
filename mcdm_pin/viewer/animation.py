"""The animated parts of the scene: cables coloured by tension, interaction-force arrows with the name
of their joint, stability cones; and the animation tracks Meshcat's client plays (keys at the
trajectory's time, in seconds)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..settings import DEFAULT
from . import three
from .colors import ARROW_RGB, CONE_OK_RGB, CONE_OUT_RGB, NO_ANSWER_RGB, tension_rgb
from .export import label_png

CONE_TOL_DEG = DEFAULT.cone_deg  # a cone is drawn broken where the default answer check calls it broken
ARROW_LENGTH = 0.5  # the run's largest interaction force is drawn this share of the robot's extent
# (x arrow_share: less for more than two arrows)
FORCE_FLOOR = 1e-6  # forces below this share of the run's peak (interaction or cable) are not drawn
_DISCRETE = 2300  # THREE.InterpolateDiscrete


@dataclass
class Track:
    """One animation track of one scene path."""

    name: str
    type: str
    times: np.ndarray
    values: np.ndarray  # (N, k) or (N,) for bool
    discrete: bool = False

    def lower(self) -> dict:
        # three.js track names: ".position" binds to the clip's root (the path's group),
        # "body.material.color" to the material of its child mesh named "body"
        name = self.name if "." in self.name else "." + self.name
        keys = [{"time": float(t), "value": (bool(v) if self.type == "bool" else [float(x) for x in np.atleast_1d(v)])}
                for t, v in zip(self.times, self.values)]
        out = {"name": name, "type": self.type, "keys": keys}
        if self.discrete:
            out["interpolation"] = _DISCRETE
        return out


def safe(name: str) -> str:
    """A scene path component for ``name``."""
    return "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in str(name))


def track_pose(scene, path: str, T: np.ndarray) -> None:
    """Animate a group's world pose over the instants (T: (N, 4, 4)); set the first as static."""
    scene.set_transform(path, T[0])
    scene.track(path, "position", "vector3", T[:, :3, 3])
    scene.track(path, "quaternion", "quaternion", three.quat_xyzw(T[:, :3, :3]))


def _segment_poses(a: np.ndarray, b: np.ndarray):
    """Unit-height cylinders (+y) stretched from a to b: (N, 4, 4) pose, (N, 3) scale."""
    d = b - a
    L = np.linalg.norm(d, axis=1)
    T = np.repeat(np.eye(4)[None], len(a), axis=0)
    T[:, :3, :3] = three.rot_y_to(d)
    T[:, :3, 3] = 0.5 * (a + b)
    scale = np.stack([np.ones_like(L), np.maximum(L, 1e-6), np.ones_like(L)], axis=1)
    return T, scale


def draw_cables(scene, robot, segments: np.ndarray, seg_cable: np.ndarray, f: np.ndarray, fmax: float,
                extent: float) -> None:
    """Every route segment (``segments`` (N, S, 2, 3) its ends at each instant, ``seg_cable`` (S,) its
    cable) a thin unlit cylinder, coloured by its cable's tension at each instant."""
    radius = 0.004 * extent
    colors = tension_rgb(f, fmax)  # (N, m, 3)
    cables = robot.cables
    count: dict[int, int] = {}
    for s, c in enumerate(seg_cable):
        k = count.get(int(c), 0)
        count[int(c)] = k + 1
        path = f"/meshcat/mcdm/cables/{safe(cables.names[c])}/s{k}"
        T, scale = _segment_poses(segments[:, s, 0], segments[:, s, 1])
        scene.set_object(path, three.obj(three.cylinder(1.0, radius, radius, 12),
                                         three.material(colors[0, c], "MeshBasicMaterial")))
        scene.set_transform(path, T[0] @ three.T(scale=scale[0]))
        scene.track(path, "position", "vector3", T[:, :3, 3])
        scene.track(path, "quaternion", "quaternion", three.quat_xyzw(T[:, :3, :3]))
        scene.track(path, "scale", "vector3", scale)
        scene.track(path, "body.material.color", "color", colors[:, c])


@dataclass
class Arrows:
    """The interaction-force arrows over the instants, robot world frame: ``origin`` (N, J, 3) the
    joint points, ``vector`` (N, J, 3) the force times the arrow scale, ``visible`` (N, J) where the
    force is known and not zero."""

    origin: np.ndarray
    vector: np.ndarray
    visible: np.ndarray


def arrow_share(count: int) -> float:
    """The arrows' length and thickness, x those of one or two arrows: sqrt(2 / count) for more
    (0.5 for the neck's 8 stacked joints), so that many arrows along a chain do not hide it."""
    return float(min(1.0, np.sqrt(2.0 / max(count, 1))))


def drawn_forces(robot, wrench: np.ndarray, f: np.ndarray) -> np.ndarray:
    """(N, J) where an interaction-force arrow is drawn: never for a free joint (it transmits no
    force: what the solver reports there is round-off, e.g. 1e-12 N on a cable robot's platform), and
    only for forces of at least :data:`FORCE_FLOOR` x the run's peak interaction force and x its
    peak cable force (smaller ones are round-off or invisible at any common arrow scale)."""
    F = np.linalg.norm(np.asarray(wrench, float)[:, :, :3], axis=2)
    free = np.array([joint.type == "free" for joint in robot.joints], bool)
    F = np.where(free[None, :] | ~np.isfinite(F), 0.0, F)
    fpeak = float(np.nanmax(np.abs(f))) if np.any(np.isfinite(f)) else 0.0
    return F > FORCE_FLOOR * max(float(F.max(initial=0.0)), fpeak)


def force_arrows(robot, joint_T: np.ndarray, wrench: np.ndarray, scale: float) -> Arrows:
    """The arrow of the force of the parent on the child of every joint, ``scale`` m/N."""
    N, J = len(joint_T), len(robot.joints)
    origin, vector = np.zeros((N, J, 3)), np.zeros((N, J, 3))
    for j, joint in enumerate(robot.joints):
        T_child = joint_T[:, joint.child_id]
        origin[:, j] = T_child[:, :3, 3]
        vector[:, j] = np.einsum("nab,nb->na", T_child[:, :3, :3], wrench[:, j, :3]) * scale  # world
    finite = np.all(np.isfinite(vector), axis=2)
    vector[~finite] = 0.0
    return Arrows(origin, vector, finite & (np.linalg.norm(vector, axis=2) > 0) & (scale > 0))


def draw_forces(scene, robot, arrows: Arrows, extent: float) -> None:
    """Magenta arrows (cylinder + cone head) from the joint points; hidden where there is no answer."""
    r = 0.013 * extent  # about as thick as typical links: forces often run along them
    head = 0.065 * extent
    for j, joint in enumerate(robot.joints):
        if not arrows.visible[:, j].any():
            continue
        L = np.linalg.norm(arrows.vector[:, j], axis=1)
        T = np.repeat(np.eye(4)[None], len(L), axis=0)
        T[:, :3, :3] = three.rot_y_to(arrows.vector[:, j])
        T[:, :3, 3] = arrows.origin[:, j]
        k = np.minimum(1.0, L / head)  # short arrows: shrink the head
        shaft = np.maximum(L - k * head, 1e-6)
        path = f"/meshcat/mcdm/forces/{safe(joint.name)}"
        scene.set_object(f"{path}/shaft", three.obj(three.cylinder(1.0, r, r, 16), three.material(ARROW_RGB)))
        scene.set_object(f"{path}/head", three.obj(three.cylinder(head, 0.0, 2.2 * r, 16),
                                                   three.material(ARROW_RGB)))
        track_pose(scene, path, T)
        _visibility(scene, path, arrows.visible[:, j])
        zeros, ones = np.zeros_like(L), np.ones_like(L)
        _track_part(scene, f"{path}/shaft", np.stack([zeros, 0.5 * shaft, zeros], axis=1),
                    np.stack([ones, shaft, ones], axis=1))
        _track_part(scene, f"{path}/head", np.stack([zeros, shaft + 0.5 * k * head, zeros], axis=1),
                    np.repeat(k[:, None], 3, axis=1))


def _visibility(scene, path: str, visible: np.ndarray) -> None:
    scene.set_property(path, "visible", bool(visible[0]))
    scene.track(path, "visible", "bool", visible)


@dataclass
class Labels:
    """The joints' name labels: PNG images, their ``widths`` (J,) and common ``height``, m."""

    pngs: list
    widths: np.ndarray
    height: float


def labels(robot, height: float) -> Labels:
    pngs, widths = [], []
    for joint in robot.joints:
        w, h, png = label_png(joint.name)
        pngs.append(png)
        widths.append(height * w / h)
    return Labels(pngs, np.array(widths), float(height))


def draw_labels(scene, robot, tags: Labels, arrows: Arrows, offsets: np.ndarray) -> None:
    """Each joint's name beside its arrow's origin (``offsets`` (J, 3), robot world frame: to the
    right as the camera sees it, lifted where labels would overlap), shown while the arrow is."""
    for j, joint in enumerate(robot.joints):
        if not arrows.visible[:, j].any():
            continue
        path = f"/meshcat/mcdm/labels/{safe(joint.name)}"
        sprite, size = three.sprite(tags.pngs[j], tags.widths[j], tags.height)
        scene.set_object(f"{path}/label", sprite)
        scene.set_transform(f"{path}/label", size)
        position = arrows.origin[:, j] + offsets[j]
        scene.set_transform(path, three.T(p=position[0]))
        scene.track(path, "position", "vector3", position)
        _visibility(scene, path, arrows.visible[:, j])


def _track_part(scene, path: str, position: np.ndarray, scale: np.ndarray) -> None:
    scene.set_transform(path, three.T(p=position[0], scale=scale[0]))
    scene.track(path, "position", "vector3", position)
    scene.track(path, "scale", "vector3", scale)


def _cone_height(robot, joint_T0: np.ndarray, points0: np.ndarray, joint, extent: float) -> float:
    """A cone about half as long as the child link (the distance from the joint to the farthest
    joint or cable point carried by the child), at most 0.22 x the robot's extent."""
    model = robot.model
    p0 = joint_T0[joint.child_id, :3, 3]
    ends = [joint_T0[j, :3, 3] for j in range(1, model.njoints) if model.parents[j] == joint.child_id]
    ends += list(points0[robot.cables.point_joint == joint.child_id])
    length = max((float(np.linalg.norm(e - p0)) for e in ends), default=0.0)
    return min(0.22 * extent, 0.5 * length) if length > 0 else 0.22 * extent


def draw_cones(scene, robot, joint_T: np.ndarray, points: np.ndarray, result, extent: float) -> None:
    """Each spherical joint's stability cone (apex at the joint point, half-angle rho* about the socket
    axis, in the socket frame): green while the force is inside, red outside, grey without answer."""
    angles = np.asarray(result.interaction_angle_deg, float)
    cone_deg = np.asarray(result.cone_deg, float)
    palette = np.array([CONE_OK_RGB, CONE_OUT_RGB, NO_ANSWER_RGB])
    for j, joint in enumerate(robot.joints):
        if joint.type != "spherical":
            continue
        rho = cone_deg[j] if j < len(cone_deg) and np.isfinite(cone_deg[j]) else joint.cone_deg
        if rho is None or not np.isfinite(rho) or not 0 < rho < 90:
            continue
        height = _cone_height(robot, joint_T[0], points[0], joint, extent)
        radius = height * np.tan(np.radians(rho))
        # socket frame (world) at every instant: parent joint frame * socket placement
        S = joint_T[:, joint.parent_id] @ joint.socket_placement.homogeneous
        R_axis = three.rot_y_to(np.asarray(joint.socket_axis, float)[None])[0]
        T_local = three.T(R_axis) @ three.T(p=[0.0, 0.5 * height, 0.0])  # apex at the joint point
        path = f"/meshcat/mcdm/cones/{safe(joint.name)}"
        state = np.where(~np.isfinite(angles[:, j]), 2, (angles[:, j] > rho + CONE_TOL_DEG).astype(int))
        colors = palette[state]
        scene.set_object(f"{path}/cone", three.obj(three.cylinder(height, radius, 0.0, 48),
                                                   three.material(colors[0], opacity=0.35)))
        scene.set_transform(f"{path}/cone", T_local)
        track_pose(scene, path, S)
        scene.track(f"{path}/cone", "body.material.color", "color", colors, discrete=True)
