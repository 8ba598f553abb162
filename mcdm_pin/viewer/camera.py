"""Where the robot is and where to look from: the world turned upright, the box that holds the robot
over the trajectory, the camera that frames it, and where the joint labels go.

Everything here is in the *display frame*: the robot's world turned so that gravity points down (-z),
since Meshcat's camera and floor are z-up (:func:`up_rotation`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import three

FOV_DEG = 75.0  # Meshcat's default camera (vertical field of view)
ASPECT = 1.25  # the screenshot's 1000 x 800
FILL = 0.85  # share of the picture's height (or width) the robot spans
VIEW = np.array([0.85, -0.45, 0.38])  # default direction from the robot to the camera
BASE_MARGIN = 0.1  # the fixed base is framed up to this share of the box beyond the moving parts
LABEL_HEIGHT = 0.03  # joint labels, x the robot's extent


def up_rotation(robot) -> np.ndarray:
    """The rotation from the robot's world to the display frame: gravity along -z (the smallest turn;
    the identity for the usual z-up robots and for zero gravity)."""
    g = np.asarray(robot.model.gravity.linear, float)
    return np.eye(3) if np.linalg.norm(g) < 1e-12 else three.rotation_between(-g, [0.0, 0.0, 1.0])


@dataclass
class Box:
    """The robot over the trajectory (display frame): ``points`` to frame (cable points, joints, the
    moving links' visuals, the fixed base's visuals clipped to ``BASE_MARGIN``), their box's
    ``center`` and diagonal ``extent``, and the height of the lowest thing drawn (``floor``)."""

    points: np.ndarray
    center: np.ndarray
    extent: float
    floor: float


def robot_box(kin, visuals, up: np.ndarray) -> Box:
    moving = {name for name, T in kin.link_T.items() if not np.allclose(T, T[0], atol=1e-12)}
    core = [kin.points.reshape(-1, 3), kin.joint_T[:, 1:, :3, 3].reshape(-1, 3)]
    base = [np.zeros((0, 3))]
    for v in visuals:  # every visual's hull points at every instant
        T = kin.link_T[v.link]
        c = (np.einsum("nij,pj->npi", T[:, :3, :3], v.corners) + T[:, None, :3, 3]).reshape(-1, 3)
        (core if v.link in moving else base).append(c)
    pts = np.concatenate(core) @ up.T
    base = np.concatenate(base) @ up.T
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    floor = min(float(lo[2]), float(base[:, 2].min()) if len(base) else np.inf)
    if len(base):
        margin = BASE_MARGIN * max(float(np.linalg.norm(hi - lo)), 1e-3)
        base = np.clip(base, lo - margin, hi + margin)
        pts = np.concatenate([pts, base])
        lo, hi = pts.min(axis=0), pts.max(axis=0)
    return Box(pts[:: max(1, len(pts) // 20000)], 0.5 * (lo + hi), float(max(np.linalg.norm(hi - lo), 1e-3)),
               floor)


def view_direction(box: Box, kin, visuals, up: np.ndarray) -> np.ndarray:
    """:data:`VIEW`, turned towards the side the cables are on when they sit off the middle of
    everything drawn (e.g. one arm of a whole human), so that the body does not hide them."""
    u = VIEW / np.linalg.norm(VIEW)
    if kin.points.shape[1] == 0:
        return u
    cables = kin.points[0].mean(axis=0) @ up.T
    drawn = [kin.joint_T[0, :, :3, 3]] + [v.corners @ kin.link_T[v.link][0, :3, :3].T + kin.link_T[v.link][0, :3, 3]
                                          for v in visuals]
    off = (cables - np.concatenate(drawn).mean(axis=0) @ up.T)[:2]
    if np.linalg.norm(off) < 0.1 * box.extent:
        return u
    h = u[:2] / np.linalg.norm(u[:2]) + off / np.linalg.norm(off)
    h = h / np.linalg.norm(h) * np.linalg.norm(u[:2])
    return np.array([h[0], h[1], u[2]])


def camera_basis(direction) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(u, right, up) of a camera looking from ``direction`` at the origin, z up."""
    u = np.asarray(direction, float) / np.linalg.norm(direction)
    right = np.cross(-u, [0.0, 0.0, 1.0])
    right = right / np.linalg.norm(right) if np.linalg.norm(right) > 1e-9 else np.array([1.0, 0, 0])
    return u, right, np.cross(right, -u)


def camera_position(points: np.ndarray, direction, aspect: float = ASPECT, fov_deg: float = FOV_DEG,
                    fill: float = FILL) -> tuple[np.ndarray, np.ndarray]:
    """(target, camera): where to look and where to look from (display frame) so that ``points``
    (k, 3), seen from ``direction``, are centred in the picture and span ``fill`` of its height or
    width, whichever is tighter (a perspective camera of vertical field of view ``fov_deg``)."""
    u, right, cam_up = camera_basis(direction)
    tv = np.tan(np.radians(fov_deg) / 2) * fill
    th = tv * aspect
    pts = np.asarray(points, float)

    def distance(p):
        return max(float(np.max(np.concatenate([p @ u + np.abs(p @ right) / th, p @ u + np.abs(p @ cam_up) / tv]))),
                   1e-3)

    target = np.zeros(3)
    for _ in range(4):  # the distance for the fill, then re-centre on the picture's middle
        p = pts - target
        d = distance(p)
        depth = d - p @ u
        x, y = (p @ right) / depth, (p @ cam_up) / depth
        target = target + d * (0.5 * (x.min() + x.max()) * right + 0.5 * (y.min() + y.max()) * cam_up)
    return target, u * distance(pts - target)


def label_layout(anchors: np.ndarray, widths: np.ndarray, height: float, direction) -> np.ndarray:
    """Offsets (J, 3), display frame, that put each label to the right of its anchor (J, 3; as seen
    from ``direction``) and lift labels that would overlap others (coincident or stacked joints)."""
    _, right, _ = camera_basis(direction)
    up = np.array([0.0, 0.0, 1.0])
    x = anchors @ right + 0.5 * widths + 0.4 * height
    y = anchors @ up
    lift = np.zeros(len(anchors))
    placed: list[int] = []
    for j in np.argsort(y, kind="stable"):
        for i in sorted(placed, key=lambda i: y[i] + lift[i]):
            if abs(x[j] - x[i]) < 0.5 * (widths[i] + widths[j]) and abs(y[j] + lift[j] - y[i] - lift[i]) < 1.2 * height:
                lift[j] = y[i] + lift[i] + 1.2 * height - y[j]
        placed.append(int(j))
    return (0.5 * widths + 0.4 * height)[:, None] * right + lift[:, None] * up
