"""The scene of a solved trajectory: what is drawn where, the world turned upright, the camera that
frames the robot; recorded as Meshcat commands (:class:`Scene`) for :mod:`~mcdm_pin.viewer.export`."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..exceptions import McdmError, ResultsError
from . import export, three
from .animation import (ARROW_LENGTH, Track, arrow_share, draw_cables, draw_cones, draw_forces, draw_labels,
                        drawn_forces, force_arrows, labels, safe, track_pose)
from .camera import (ASPECT, LABEL_HEIGHT, VIEW, camera_basis, camera_position, label_layout, robot_box,
                     up_rotation, view_direction)
from .colors import ANCHOR_RGB, BACKGROUND, GRID_RGB, LINK_RGB, PLATFORM_RGB, mute, nice_ceil
from .three import Command
from .visuals import fallback_bones, platforms, robot_visuals

GHOST_OPACITY = 0.3
GHOST_MUTE = 0.8
LINK_STYLES = ("auto", "solid", "ghost")


class ViewerError(McdmError):
    """The viewer cannot be built, served or rendered (e.g. no browser for a screenshot)."""


@dataclass
class Scene:
    """A recorded Meshcat scene: replay it live (:meth:`serve`, :meth:`send`) or write it as one HTML
    file (:meth:`html`, :meth:`write_html`).

    Attributes:
        commands: lowered Meshcat commands, in the order they are replayed.
        tracks: animation tracks per scene path.
        t: (N,) the animation's key times (trajectory time, s); ``status``: (N,) each instant's status.
        fmax: top of the cable colour scale, N; ``arrow_scale``: arrow length per newton, m/N.
        info: title lines for the overlay.
        center: the display-frame point the camera looks at (the middle of the robot in the
            picture); the robot's world is shifted so that it is at the origin.
        extent: the diagonal of the box that holds the robot over the trajectory, m.
        up: (3, 3) the rotation from the robot's world to the display frame (gravity down).
        camera: (3,) the camera's position, display frame, relative to ``center``.
        floor: the height of the floor grid (the lowest thing drawn), relative to ``center``.
    """

    commands: list = field(default_factory=list)
    tracks: dict = field(default_factory=dict)
    t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    status: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=str))
    fmax: float = 1.0
    arrow_scale: float = 0.0
    info: list = field(default_factory=list)
    legend: bool = True
    start_time: float | None = None
    loop: bool = True
    center: np.ndarray = field(default_factory=lambda: np.zeros(3))
    extent: float = 0.5
    up: np.ndarray = field(default_factory=lambda: np.eye(3))
    camera: np.ndarray = field(default_factory=lambda: VIEW.copy())
    floor: float = 0.0

    # ---------------------------------------------------------------------------------- recording
    def set_object(self, path: str, obj: dict) -> None:
        self.commands.append(Command(type="set_object", object=obj, path=path))

    def set_transform(self, path: str, T) -> None:
        self.commands.append(Command(type="set_transform", path=path,
                                     matrix=np.asarray(T, float).T.flatten().tolist()))

    def set_property(self, path: str, key: str, value) -> None:
        self.commands.append(Command(type="set_property", path=path, property=key, value=value))

    def track(self, path: str, name: str, type_: str, values, discrete: bool = False) -> None:
        self.tracks.setdefault(path, []).append(Track(name, type_, self.t, np.asarray(values), discrete))

    def animation_command(self) -> Command | None:
        if not self.tracks or len(self.t) < 2:
            return None
        animations = [{"path": path, "clip": {"fps": 1.0, "name": "default",
                                              "tracks": [tr.lower() for tr in tracks]}}
                      for path, tracks in self.tracks.items()]
        # stored on a path visited after every object, so that a browser connecting later to the
        # live server gets the objects before the animation that binds to their materials
        return Command(type="set_animation", animations=animations,
                       options={"play": self.start_time is None,
                                "repetitions": 1_000_000 if self.loop else 1},
                       path="/meshcat/zz_animation")

    def all_commands(self) -> list:
        anim = self.animation_command()
        return list(self.commands) + ([anim] if anim is not None else [])

    # ------------------------------------------------------------------------------------- output
    def html(self) -> str:
        """One self-contained HTML page (Meshcat's browser client inlined, no network)."""
        return export.scene_html(self)

    def write_html(self, path) -> Path:
        path = Path(path)
        if path.suffix.lower() not in (".html", ".htm"):
            raise ViewerError(f"{path}: expected an .html file name")
        try:
            path.write_text(self.html(), encoding="utf-8")
        except OSError as exc:
            raise ViewerError(f"{path}: cannot write the HTML ({exc.strerror or exc})") from None
        return path

    def send(self, vis) -> None:
        export.send(self, vis)

    def serve(self, zmq_url: str | None = None):
        """Start (or connect to) a Meshcat server, send the scene, return the ``meshcat.Visualizer``.
        Meshcat prints the URL to open. The server lives as long as this Python process."""
        return export.serve(self, zmq_url)


# ------------------------------------------------------------------------------------------ checks
def check_results(robot, result, source: str = "results") -> None:
    """Raise :class:`ResultsError` unless ``result`` was computed for ``robot`` (same joints, cables
    and coordinates, finite trajectory)."""
    where = f" ({robot.sidecar.path})" if robot.sidecar is not None else ""
    for key, want in (("joint_names", robot.joint_names), ("cable_names", robot.cable_names),
                      ("coordinate_names", robot.coordinate_names)):
        got = [str(s) for s in np.asarray(getattr(result, key)).tolist()]
        if got != list(want):
            raise ResultsError(f"{source}: {key} {got} do not match robot {robot.name!r}{where}, which "
                               f"expects {list(want)}")
    n = len(result.t)
    if n == 0:
        raise ResultsError(f"{source}: no instants (t is empty)")
    if np.shape(result.q) != (n, robot.nv):
        raise ResultsError(f"{source}: q has shape {np.shape(result.q)}; expected ({n}, {robot.nv})")
    if np.shape(result.f) != (n, robot.m):
        raise ResultsError(f"{source}: f has shape {np.shape(result.f)}; expected ({n}, {robot.m})")
    if not np.all(np.isfinite(result.q)) or not np.all(np.isfinite(result.t)):
        raise ResultsError(f"{source}: t and q must be finite")
    if n > 1 and np.any(np.diff(result.t) <= 0):
        raise ResultsError(f"{source}: t must be strictly increasing")


# ------------------------------------------------------------------------------------- kinematics
@dataclass
class Kinematics:
    """World placements over the instants: ``link_T`` {link: (N, 4, 4)}, ``joint_T`` (N, nj, 4, 4)
    of the Pinocchio joints, ``points`` (N, P, 3) of the cable route points; ``segments`` (N, S, 2, 3)
    the ends of every drawn cable segment and ``seg_cable`` (S,) its cable (a segment not on the path
    at an instant has both ends at one point)."""

    link_T: dict
    joint_T: np.ndarray
    points: np.ndarray
    segments: np.ndarray | None = None
    seg_cable: np.ndarray | None = None


def kinematics(robot, result, arc_tol: float | None = None) -> Kinematics:
    """The placements of ``result``'s instants; ``arc_tol``: the relative tolerance of wrapped cables'
    drawn length (:func:`mcdm_pin.viewer.arcs.route_polylines`; default its ``ARC_TOL``)."""
    model, data = robot.model, robot.model.createData()
    conf = np.asarray(result.configuration, float)
    if conf.ndim != 2 or conf.shape[1] != robot.nq:
        conf = np.array([robot.configuration(x) for x in np.asarray(result.q, float)]).reshape(-1, robot.nq)
    N = len(conf)
    fids = {name: model.getFrameId(name, pin.FrameType.BODY) for name in robot.link_names}
    links = {name: np.empty((N, 4, 4)) for name in fids}
    joint_T = np.empty((N, model.njoints, 4, 4))
    for k in range(N):
        pin.framesForwardKinematics(model, data, robot.check_configuration(conf[k]))
        for j in range(model.njoints):
            joint_T[k, j] = data.oMi[j].homogeneous
        for name, fid in fids.items():
            links[name][k] = data.oMf[fid].homogeneous
    Tp = joint_T[:, robot.cables.point_joint]
    points = np.einsum("npij,pj->npi", Tp[:, :, :3, :3], robot.cables.point_local) + Tp[:, :, :3, 3]
    cables = robot.cables
    if not cables.configuration_dependent:
        ends = np.stack([points[:, cables.seg_a], points[:, cables.seg_b]], axis=2)
        return Kinematics(links, joint_T, points, ends, cables.seg_cable)
    from .arcs import route_polylines  # imported here: the route maths import numba

    # wrapped routes: each engaged wrap's path on its surface, sampled (mcdm_pin/viewer/arcs.py)
    segments, seg_cable, _ = route_polylines(robot, conf, arc_tol)
    return Kinematics(links, joint_T, points, segments, seg_cable)


# ----------------------------------------------------------------------------------------- build
def build_scene(robot, result, fmax: float | None = None, arrow_scale: float | None = None,
                legend: bool = True, start_time: float | None = None, loop: bool = True,
                source: str = "results", links: str = "auto", aspect: float = ASPECT,
                arc_tol: float | None = None) -> Scene:
    """Build the animated scene of ``result`` (a :class:`~mcdm_pin.results.TrajectoryResult`).

    Args:
        robot: the :class:`~mcdm_pin.robot.Robot` the result was computed for.
        result: the solved trajectory.
        fmax: top of the cable colour scale, N (default: the run's peak force, rounded up to a nice
            value, :func:`~mcdm_pin.viewer.colors.nice_ceil`).
        arrow_scale: interaction-force arrow length per newton, m/N (default: the largest force is
            drawn half as long as the robot's extent).
        legend: draw the colour bar (HTML overlay / live panel) and the time overlay.
        start_time: show the scene paused at this trajectory time, s (default: play from 0).
        loop: repeat the animation (default) or play it once.
        source: how to name ``result`` in error messages (e.g. its file name).
        links: ``solid`` (opaque), ``ghost`` (translucent) or ``auto`` (meshes, i.e. body skins that
            hide the cables inside them, translucent; primitive shapes opaque).
        aspect: width / height of the picture the camera frames the robot for.
        arc_tol: wrapped cables: the largest relative shortfall of a drawn cable against its route,
            which sets how finely each wrap's arc is sampled (default 1e-6,
            :data:`mcdm_pin.viewer.arcs.ARC_TOL`).
    """
    check_results(robot, result, source)
    if fmax is not None and not (np.isfinite(fmax) and fmax > 0):
        raise ViewerError(f"fmax: expected a positive number of newtons, got {fmax}")
    if arrow_scale is not None and not (np.isfinite(arrow_scale) and arrow_scale > 0):
        raise ViewerError(f"arrow_scale: expected a positive number of m/N, got {arrow_scale}")
    if links not in LINK_STYLES:
        raise ViewerError(f"links: expected one of {', '.join(LINK_STYLES)}, got {links!r}")
    t = np.asarray(result.t, float)
    if start_time is not None and not (t[0] - 1e-12 <= start_time <= t[-1] + 1e-12):
        raise ViewerError(f"start time {start_time} s is outside the trajectory ({t[0]:g}..{t[-1]:g} s)")
    if arc_tol is not None and not (np.isfinite(arc_tol) and arc_tol > 0):
        raise ViewerError(f"arc_tol: expected a positive relative tolerance, got {arc_tol}")
    kin = kinematics(robot, result, arc_tol)
    visuals = robot_visuals(robot)
    f = np.asarray(result.f, float)
    wrench = np.asarray(result.interaction_wrench, float)
    fmax = nice_ceil(np.nanmax(f) if np.any(np.isfinite(f)) else 1.0) if fmax is None else float(fmax)
    scene = Scene(t=t, status=np.asarray(result.status, str), fmax=fmax, legend=legend,
                  start_time=start_time, loop=loop, up=up_rotation(robot))
    scene.info = [f"{robot.name}: {result.problem or 'results'}",
                  f"trajectory {result.trajectory or '?'}, solver {result.solver or '?'}"]
    box = robot_box(kin, visuals, scene.up)
    scene.extent = box.extent
    shown = drawn_forces(robot, wrench, f)
    Fmag = np.where(shown, np.linalg.norm(wrench[:, :, :3], axis=2), np.nan)
    Fpeak = np.nanmax(Fmag) if np.any(np.isfinite(Fmag)) else 0.0
    thin = arrow_share(int(shown.any(axis=0).sum()))
    if arrow_scale is None:
        arrow_scale = ARROW_LENGTH * thin * scene.extent / Fpeak if Fpeak > 0 else 0.0
    scene.arrow_scale = float(arrow_scale)
    arrows = force_arrows(robot, kin.joint_T, np.where(shown[:, :, None], wrench, np.nan), scene.arrow_scale)
    direction = view_direction(box, kin, visuals, scene.up)
    tags = labels(robot, LABEL_HEIGHT * scene.extent)
    offsets = label_layout(arrows.origin[0] @ scene.up.T, tags.widths, tags.height, direction)
    _place_camera(scene, box, arrows, tags, offsets, direction, aspect)
    environment(scene)
    _draw_links(scene, robot, kin, visuals, links)
    draw_cables(scene, robot, kin.segments, kin.seg_cable, f, fmax, scene.extent)
    draw_forces(scene, robot, arrows, thin * scene.extent)
    draw_labels(scene, robot, tags, arrows, offsets @ scene.up)
    draw_cones(scene, robot, kin.joint_T, kin.points, result, scene.extent)
    return scene


def empty_scene(like: Scene) -> Scene:
    """The environment of scene ``like`` (background, floor grid, camera) with nothing in it: the
    reference a screenshot of a real scene is compared with."""
    scene = Scene(legend=False, center=like.center, extent=like.extent, up=like.up, camera=like.camera,
                  floor=like.floor)
    environment(scene)
    return scene


def _place_camera(scene: Scene, box, arrows, tags, offsets, direction, aspect: float) -> None:
    """Frame the robot with its arrows and labels; the floor under the lowest thing drawn."""
    R = scene.up
    tips = (arrows.origin + arrows.vector)[arrows.visible] @ R.T
    _, right, _ = camera_basis(direction)
    half = 0.5 * tags.widths[:, None] * right + 0.5 * tags.height * np.array([0.0, 0.0, 1.0])
    lab = (arrows.origin @ R.T + offsets)[arrows.visible]
    half = np.broadcast_to(half, arrows.origin.shape)[arrows.visible]
    pts = np.concatenate([box.points, tips, lab + half, lab - half])
    target, scene.camera = camera_position(pts - box.center, direction, aspect)
    scene.center = box.center + target
    scene.floor = box.floor - float(scene.center[2])


# ------------------------------------------------------------------------------------ environment
def environment(scene: Scene) -> None:
    """Background, the robot's world turned upright and centred on the orbit controls' target, a floor
    grid under it, and the camera. Meshcat's own grid and axes are hidden: they are 20 m wide, and a
    transform set on ``/Grid`` replaces the rotation that lays the grid flat (the band of grid lines
    earlier screenshots had)."""
    scene.set_property("/Background", "top_color", list(BACKGROUND[0]))
    scene.set_property("/Background", "bottom_color", list(BACKGROUND[1]))
    for path in ("/Grid", "/Axes"):
        scene.set_property(path, "visible", False)
    scene.set_transform("/meshcat/mcdm", three.T(p=-scene.center) @ three.T(scene.up))
    half = 0.6 * scene.extent
    step = nice_ceil(half / 5)
    n = int(np.floor(half / step))
    ticks = np.arange(-n, n + 1) * step
    lines = []
    for s in ticks:
        lines += [[s, ticks[0], 0.0], [s, ticks[-1], 0.0], [ticks[0], s, 0.0], [ticks[-1], s, 0.0]]
    lines = np.array(lines)
    scene.set_object("/meshcat/floor", three.line_segments(lines, np.tile(GRID_RGB, (len(lines), 1))))
    scene.set_transform("/meshcat/floor", three.T(p=[0.0, 0.0, scene.floor]))
    # the camera lives in a y-up frame: display (x, y, z) = camera-local (x, -z, y)
    c = scene.camera
    scene.set_property("/Cameras/default/rotated/<object>", "position", [c[0], c[2], -c[1]])


# ------------------------------------------------------------------------------------------ links
def _draw_links(scene: Scene, robot, kin: Kinematics, visuals, style: str) -> None:
    """Every link's visuals (muted colours; meshes translucent in ``auto``), simple shapes for bodies
    without visuals (a platform's hull for a body spanned by its attachment points), and a small dark
    sphere at every cable attachment point."""
    r = 0.015 * scene.extent
    by_link: dict[str, list] = {}
    for v in visuals:
        by_link.setdefault(v.link, []).append(v)
    for link, items in by_link.items():
        base = "/meshcat/mcdm/links/" + safe(link)
        for k, v in enumerate(items):
            ghost = style == "ghost" or (style == "auto" and v.is_mesh)
            opacity = v.rgba[3] * (GHOST_OPACITY if ghost else 1.0)
            rgb = mute(v.rgba, GHOST_MUTE if ghost else None)
            scene.set_object(f"{base}/visual{k}", three.obj(v.geometry, three.material(rgb, opacity=opacity)))
            scene.set_transform(f"{base}/visual{k}", v.placement)
        _pose(scene, base, kin.link_T[link])
    model = robot.model
    drawn = {int(model.frames[model.getFrameId(link, pin.FrameType.BODY)].parentJoint) for link in by_link}
    cables = robot.cables
    plates = platforms(robot, visuals)
    bodies = {}
    for j, hull in plates.items():  # a platform: the body its attachment points span
        base = bodies[j] = "/meshcat/mcdm/bodies/" + safe(model.names[j])
        scene.set_object(f"{base}/platform", three.obj(three.mesh(*hull), three.material(mute(PLATFORM_RGB))))
    for bone in fallback_bones(robot, drawn):
        base = bodies[bone.joint_id] = "/meshcat/mcdm/bodies/" + safe(model.names[bone.joint_id])
        color = three.material(mute(LINK_RGB))
        if bone.sphere and bone.joint_id not in plates:
            scene.set_object(f"{base}/joint", three.obj(three.sphere(1.6 * r), color))
        for k, p in enumerate(bone.ends):
            L = float(np.linalg.norm(p))
            scene.set_object(f"{base}/bone{k}", three.obj(three.cylinder(L, r, r), color))
            scene.set_transform(f"{base}/bone{k}", three.T(three.rot_y_to(p)[0], 0.5 * p))
    for i, (j, p) in enumerate(zip(cables.point_joint, cables.point_local)):
        j = int(j)
        base = bodies.setdefault(j, "/meshcat/mcdm/bodies/" + safe(model.names[j]))
        path = f"{base}/anchors/p{i}"
        scene.set_object(path, three.obj(three.sphere(0.45 * r), three.material(ANCHOR_RGB)))
        scene.set_transform(path, three.T(p=p))
    for j, base in bodies.items():
        _pose(scene, base, kin.joint_T[:, j])


def _pose(scene: Scene, path: str, T: np.ndarray) -> None:
    if np.allclose(T, T[0], atol=1e-12):
        scene.set_transform(path, T[0])
    else:
        track_pose(scene, path, T)
