"""A workspace in the 3-D viewer: every pose as a point at a chosen frame's position, coloured by a
margin, around the robot drawn at one of the poses (solved again, with the store's problem).

Colours (``color_by``: ``needed_f_max`` or ``needed_cone_deg``): the *turbo* map from 0 (dark blue)
to the problem's limit (``f_max``, or the cone half-angle; dark red), so the colour says how much of
the limit a pose uses; poses past the limit are red, poses that no bound or cone makes feasible
(``inf``) and poses without a margin (NaN) are grey. The point cloud is ``/meshcat/mcdm/workspace``.
The drawn pose's cables are coloured on the viewer's tension scale up to the store's peak cable force
(rounded up, :func:`cable_scale`).

Use::

    from mcdm_pin.workspace import open_workspace
    from mcdm_pin.workspace.cloud import cloud_scene
    scene = cloud_scene(robot, open_workspace("arm.zarr"), frame="link2")
    scene.write_html("arm.html")
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..exceptions import ResultsError
from ..extras import optional
from .errors import WorkspaceError

PAST_LIMIT_RGB = (1.0, 0.0, 0.0)
NONE_RGB = (0.55, 0.55, 0.55)
COLOR_BY = ("needed_f_max", "needed_cone_deg")


def frame_positions(robot, q: np.ndarray, frame: str) -> np.ndarray:
    """(n, 3) world positions of Pinocchio frame ``frame`` (a link name, or any frame of the model) at
    the poses ``q`` (n, nv coordinates)."""
    model = robot.model
    if not model.existFrame(frame):
        names = sorted({f.name for f in model.frames if f.type == pin.FrameType.BODY})
        raise WorkspaceError(f"frame {frame!r}: not a frame of {robot.name!r}; links: {', '.join(names)}")
    fid = model.getFrameId(frame)
    data = model.createData()
    out = np.empty((len(q), 3))
    for k, pose in enumerate(q):
        pin.framesForwardKinematics(model, data, robot.pin_q(pose))
        out[k] = data.oMf[fid].translation
    return out


def margin_colors(value: np.ndarray, limit: float) -> np.ndarray:
    """(n, 3) RGB in [0, 1]: turbo over [0, limit], red past it, grey for inf and NaN."""
    from ..viewer import tension_rgb

    value = np.asarray(value, dtype=float)
    rgb = np.tile(np.array(NONE_RGB), (len(value), 1))
    finite = np.isfinite(value)
    inside = finite & (value <= limit)
    if inside.any():
        rgb[inside] = [tension_rgb(v, limit) for v in value[inside]]
    rgb[finite & (value > limit)] = PAST_LIMIT_RGB
    return rgb


def cable_scale(f: np.ndarray) -> float:
    """The top of the drawn pose's cable colour scale, N: the store's peak cable force over every
    pose, rounded up as the trajectory viewer rounds a run's peak (:func:`~mcdm_pin.viewer.nice_ceil`),
    so that the pose's cables are coloured against the whole workspace (not against their own
    maximum, which puts every cable of a pose at its lower bound at the top of the scale)."""
    from ..viewer import nice_ceil

    f = np.asarray(f, float)
    return nice_ceil(float(np.nanmax(f))) if np.isfinite(f).any() else 1.0


def cloud_scene(robot, ds, frame: str, color_by: str = "needed_f_max", pose: int | None = None,
                point_size: float | None = None):
    """The viewer's scene of the robot at pose ``pose`` (default: the optimal pose with the largest
    margin, i.e. the smallest ``color_by``, and of equals the nearest to the mean pose) with every
    pose of the store ``ds`` as a point (see the module docstring)."""
    mg = optional("meshcat.geometry", "the workspace's point cloud")

    from ..results import TrajectoryResult, instant_columns
    from ..trajectory import Trajectory
    from ..viewer import build_scene
    from .evaluate import Setup

    attrs = ds.attrs["workspace"]
    for key, want in (("coordinate", robot.coordinate_names), ("cable", robot.cable_names),
                      ("joint", robot.joint_names)):
        if [str(x) for x in ds[key].values] != list(want):
            raise ResultsError(f"the store's {key} names do not match robot {robot.name!r}")
    if color_by not in COLOR_BY:
        raise WorkspaceError(f"color_by: expected one of {', '.join(COLOR_BY)}, got {color_by!r}")
    if color_by == "needed_cone_deg" and not attrs["cones_deg"]:
        raise WorkspaceError("color_by needed_cone_deg: the store's problem has no cones (case 3)")
    q = ds["q"].values
    status = ds["status"].values
    if pose is None:  # the optimal pose with the largest margin; of equals, the most central one
        margin = np.where(status == "optimal", ds[color_by].values, np.nan)
        if np.isfinite(margin).any():
            best = np.flatnonzero(margin <= np.nanmin(margin) + 1e-9)
            pose = int(best[np.argmin(np.linalg.norm(q[best] - q.mean(axis=0), axis=1))])
        else:
            pose = 0
    if not 0 <= pose < len(q):
        raise WorkspaceError(f"pose: expected an index in 0..{len(q) - 1}, got {pose}")
    setup = Setup(**attrs["setup"])
    qd, qdd = setup.rates(robot)
    res = setup.identify(robot).solve(q[pose], qd, qdd)
    one = TrajectoryResult.from_columns(
        robot, Trajectory(f"pose {pose}", np.zeros(1), q[pose:pose + 1], qd[None], qdd[None]),
        instant_columns([res]), np.full(len(robot.joints), np.nan), problem=attrs["problem"],
        solver=setup.solver, trajectory=f"workspace pose {pose}")
    scene = build_scene(robot, one, source="the workspace pose", fmax=cable_scale(ds["f"].values))
    limit = float(min(attrs["f_max"])) if color_by == "needed_f_max" else max(attrs["cones_deg"].values())
    points = frame_positions(robot, q, frame)
    rgb = margin_colors(ds[color_by].values, limit)
    size = point_size or 0.01 * scene.extent
    obj = mg.Points(mg.PointsGeometry(points.T.astype(np.float32), color=rgb.T.astype(np.float32)),
                    mg.PointsMaterial(size=size))
    scene.set_object("/meshcat/mcdm/workspace", obj.lower())
    scene.info.append(f"{len(q)} poses of {frame!r}, coloured by {color_by} (0 .. {limit:g}; red: past "
                      f"it; grey: none)")
    return scene
