r"""3-D view of a solved trajectory in Meshcat: links, cables coloured by tension, interaction forces,
stability cones; live in the browser or as one self-contained HTML file.

What the scene shows (paths under ``/meshcat/mcdm``):

* ``links/<link>``: every URDF link's visuals (boxes, cylinders, spheres, STL/OBJ/DAE meshes; other
  mesh formats through trimesh). A link without visuals gets a simple shape: a cylinder from its joint
  to each child joint (or to twice its centre of mass), and a sphere at its joint. The massless links
  inside a spherical joint are not drawn. Every cable attachment point is a small grey sphere.
* ``cables/<cable>/s<k>``: every route segment as a thin cylinder (browsers ignore line widths),
  coloured by the cable's tension on a **fixed colour scale**: the *turbo* colour map from 0 N (dark
  blue) through green and yellow to ``fmax`` (dark red); forces above ``fmax`` keep the top colour.
  ``fmax`` is fixed for the whole animation: by default the run's peak cable force rounded up to
  1, 2 or 5 x 10^k N. At instants without a valid answer the cables are grey.
* ``forces/<joint>``: the interaction force of the parent on the child (``interaction_wrench[:3]``)
  as a magenta arrow (cylinder + cone head) from the joint point, ``arrow_scale`` metres per newton
  (fixed; by default the run's largest force is drawn half as long as the diagonal of the box that
  holds the robot over the trajectory). Hidden where there is no answer.
* ``cones/<joint>``: each spherical joint's stability cone: apex at the joint point, half-angle
  ``rho*`` about the socket axis, drawn in the socket frame (it moves with the parent link), about
  half as long as the child link. It is translucent green while the force is inside
  (``interaction_angle_deg <= rho* + 1e-6``), red when it leaves it and grey where there is no
  answer. ``rho*`` is the run's ``cone_deg`` or, where the run had
  no cone (cases 1 and 2), the sidecar's ``cone_deg``, so a case-1 run shows where it breaks the cone.

**Animation and time.** The animation's clock is the trajectory's time in seconds (keys at the
results' ``t``, one key per instant) and it loops. In the live viewer the *Animations -> default*
folder of the controls has play/pause/reset and the ``time`` field, which is the trajectory time in
seconds. The HTML file also shows the time, the instant's status, the colour bar and the
arrow scale in an overlay (bottom left); the live viewer shows the colour bar as a small legend
panel beside the robot.

Use::

    from mcdm_pin.viewer import build_scene
    scene = build_scene(robot, result)      # result: TrajectoryResult (solved or loaded from .npz)
    scene.write_html("run.html")            # self-contained, opens offline
    vis = scene.serve()                     # live: prints the URL, keeps serving while Python runs

The HTML is written without Meshcat's server: the scene's commands are packed as Meshcat's browser
client expects them (msgpack) and replayed in order by the client bundled with the ``meshcat``
package, so the file needs no network.
"""

from __future__ import annotations

import base64
import html as _html
import io
import json
import os
import shutil
import subprocess
import tempfile
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from .exceptions import McdmError, ResultsError

# turbo colour map (matplotlib's), 11 anchors from 0 to 1, linear in between
TURBO = np.array([
    (0.190, 0.072, 0.232), (0.270, 0.349, 0.796), (0.244, 0.609, 0.997), (0.098, 0.837, 0.803),
    (0.276, 0.971, 0.517), (0.644, 0.990, 0.234), (0.883, 0.866, 0.217), (0.996, 0.643, 0.192),
    (0.941, 0.356, 0.070), (0.765, 0.144, 0.010), (0.480, 0.016, 0.011)])
NO_ANSWER_RGB = (0.55, 0.55, 0.55)
CONE_OK_RGB = (0.15, 0.75, 0.25)
CONE_OUT_RGB = (1.0, 0.0, 0.0)
CONE_TOL_DEG = 1e-6
ARROW_RGB = (0.8, 0.0, 0.8)
LINK_RGB = (0.55, 0.6, 0.7)
BACKGROUND = ((0.98, 0.98, 0.98), (0.80, 0.84, 0.90))  # top, bottom

_DISCRETE = 2300  # THREE.InterpolateDiscrete


class ViewerError(McdmError):
    """The viewer cannot be built, served or rendered (e.g. no browser for a screenshot)."""


# ------------------------------------------------------------------------------------- colours
def tension_rgb(f, fmax: float) -> np.ndarray:
    """Colours (..., 3) of cable forces ``f`` (N) on the fixed scale [0, fmax] (turbo); NaN -> grey."""
    f = np.asarray(f, dtype=float)
    x = np.clip(np.nan_to_num(f, nan=0.0) / fmax, 0.0, 1.0) * (len(TURBO) - 1)
    i = np.minimum(np.floor(x).astype(int), len(TURBO) - 2)
    w = (x - i)[..., None]
    rgb = TURBO[i] * (1 - w) + TURBO[i + 1] * w
    rgb[~np.isfinite(f)] = NO_ANSWER_RGB
    return rgb


def nice_ceil(x: float) -> float:
    """Smallest 1, 2 or 5 x 10^k that is >= x (x > 0)."""
    if not np.isfinite(x) or x <= 0:
        return 1.0
    k = np.floor(np.log10(x))
    for m in (1.0, 2.0, 5.0, 10.0):
        if m * 10**k >= x * (1 - 1e-12):
            return float(m * 10**k)
    return float(10 ** (k + 1))


def _hex(rgb) -> int:
    r, g, b = (int(round(255 * float(np.clip(c, 0, 1)))) for c in rgb[:3])
    return (r << 16) + (g << 8) + b


# ------------------------------------------------------------------------------------ geometry
def _rot_y_to(v: np.ndarray) -> np.ndarray:
    """Rotation matrices (N, 3, 3) taking +y to the unit vectors along ``v`` (N, 3); a zero vector
    gives the identity, -y a half turn about x."""
    v = np.asarray(v, dtype=float).reshape(-1, 3)
    n = np.linalg.norm(v, axis=1)
    u = np.where(n[:, None] > 1e-15, v / np.where(n > 1e-15, n, 1.0)[:, None], [0.0, 1.0, 0.0])
    # Rodrigues with axis y x u (unnormalised, |.| = sin), cos = u_y: R = I + K + K^2 / (1 + c)
    c = u[:, 1]
    k = np.stack([u[:, 2], np.zeros_like(c), -u[:, 0]], axis=1)
    K = np.zeros((len(u), 3, 3))
    K[:, 0, 1], K[:, 0, 2] = -k[:, 2], k[:, 1]
    K[:, 1, 0], K[:, 1, 2] = k[:, 2], -k[:, 0]
    K[:, 2, 0], K[:, 2, 1] = -k[:, 1], k[:, 0]
    flip = c < -1 + 1e-12
    denom = np.where(flip, 1.0, 1.0 + c)
    R = np.eye(3) + K + (K @ K) / denom[:, None, None]
    R[flip] = np.diag([1.0, -1.0, -1.0])
    return R


def _quat_xyzw(R: np.ndarray) -> np.ndarray:
    """(N, 3, 3) rotations -> (N, 4) quaternions [x, y, z, w] (three.js order), sign-continuous."""
    R = np.asarray(R, dtype=float).reshape(-1, 3, 3)
    q = np.empty((len(R), 4))
    tr = np.trace(R, axis1=1, axis2=2)
    # pick, per matrix, the numerically best of the four standard formulas
    d = np.stack([tr, R[:, 0, 0], R[:, 1, 1], R[:, 2, 2]], axis=1)
    case = np.argmax(d, axis=1)
    for k in range(len(R)):
        m = R[k]
        if case[k] == 0:
            s = 2.0 * np.sqrt(max(1.0 + tr[k], 1e-300))
            q[k] = [(m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, 0.25 * s]
        elif case[k] == 1:
            s = 2.0 * np.sqrt(max(1.0 + m[0, 0] - m[1, 1] - m[2, 2], 1e-300))
            q[k] = [0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s, (m[2, 1] - m[1, 2]) / s]
        elif case[k] == 2:
            s = 2.0 * np.sqrt(max(1.0 + m[1, 1] - m[0, 0] - m[2, 2], 1e-300))
            q[k] = [(m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s, (m[0, 2] - m[2, 0]) / s]
        else:
            s = 2.0 * np.sqrt(max(1.0 + m[2, 2] - m[0, 0] - m[1, 1], 1e-300))
            q[k] = [(m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s, (m[1, 0] - m[0, 1]) / s]
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    for k in range(1, len(q)):
        if q[k] @ q[k - 1] < 0:
            q[k] = -q[k]
    return q


def _T(R=None, p=None, scale=None) -> np.ndarray:
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = R
    if scale is not None:
        T[:3, :3] = T[:3, :3] @ np.diag(np.broadcast_to(np.asarray(scale, float), (3,)))
    if p is not None:
        T[:3, 3] = p
    return T


_RX90 = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])  # takes +y to +z (URDF cylinders lie on z)


# ---------------------------------------------------------------------------------- commands
class _Command(dict):
    """A lowered Meshcat command (what ``meshcat.Visualizer`` sends), replayable live or in HTML."""

    def lower(self):
        return self


def _object(geometry: dict, material: dict, name: str = "body", extra: dict | None = None) -> dict:
    """A three.js object JSON for one mesh (``geometry`` and ``material`` as lowered dicts)."""
    data = {"metadata": {"version": 4.5, "type": "Object"}, "geometries": [geometry],
            "materials": [material],
            "object": {"uuid": _uuid(), "type": "Mesh", "name": name, "geometry": geometry["uuid"],
                       "material": material["uuid"], "matrix": np.eye(4).flatten().tolist()}}
    if extra:
        for k, v in extra.items():
            data.setdefault(k, []).extend(v)
    return data


def _uuid() -> str:
    import uuid
    return str(uuid.uuid1())


def _material(rgb, kind="MeshLambertMaterial", opacity=1.0, **extra) -> dict:
    m = {"uuid": _uuid(), "type": kind, "color": _hex(rgb), "side": 2,
         "transparent": bool(opacity < 1.0), "opacity": float(opacity), "depthWrite": bool(opacity >= 1.0)}
    if kind != "MeshBasicMaterial":
        m["reflectivity"] = 0.5
    m.update(extra)
    return m


def _cylinder(height, radius_top, radius_bottom, segments=24) -> dict:
    return {"uuid": _uuid(), "type": "CylinderGeometry", "radiusTop": float(radius_top),
            "radiusBottom": float(radius_bottom), "height": float(height), "radialSegments": segments}


def _sphere(radius) -> dict:
    return {"uuid": _uuid(), "type": "SphereGeometry", "radius": float(radius), "widthSegments": 20,
            "heightSegments": 20}


def _box(size) -> dict:
    return {"uuid": _uuid(), "type": "BoxGeometry", "width": float(size[0]), "height": float(size[1]),
            "depth": float(size[2])}


@dataclass
class _Track:
    name: str
    type: str
    times: np.ndarray
    values: np.ndarray  # (N, k) or (N,) for bool
    discrete: bool = False

    def lower(self) -> dict:
        # three.js track names: ".position" binds to the clip's root (the path's group),
        # "body.material.color" to the material of its child mesh named "body"
        name = self.name if "." in self.name else "." + self.name
        keys = []
        for t, v in zip(self.times, self.values):
            keys.append({"time": float(t), "value": (bool(v) if self.type == "bool"
                                                      else [float(x) for x in np.atleast_1d(v)])})
        out = {"name": name, "type": self.type, "keys": keys}
        if self.discrete:
            out["interpolation"] = _DISCRETE
        return out


@dataclass
class Scene:
    """A recorded Meshcat scene: replay it live (:meth:`serve`, :meth:`send`) or write it as one HTML
    file (:meth:`html`, :meth:`write_html`).

    Attributes:
        commands: lowered Meshcat commands, in the order they are replayed.
        tracks: animation tracks per scene path.
        t: (N,) the animation's key times (trajectory time, s).
        status: (N,) each instant's status.
        fmax: top of the cable colour scale, N.
        arrow_scale: arrow length per newton of interaction force, m/N.
        info: title lines for the overlay.
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

    # ---------------------------------------------------------------------------- recording
    def set_object(self, path: str, obj: dict) -> None:
        self.commands.append(_Command(type="set_object", object=obj, path=path))

    def set_transform(self, path: str, T) -> None:
        self.commands.append(_Command(type="set_transform", path=path,
                                      matrix=np.asarray(T, float).T.flatten().tolist()))

    def set_property(self, path: str, key: str, value) -> None:
        self.commands.append(_Command(type="set_property", path=path, property=key, value=value))

    def track(self, path: str, name: str, type_: str, values, discrete: bool = False) -> None:
        self.tracks.setdefault(path, []).append(_Track(name, type_, self.t, np.asarray(values),
                                                       discrete))

    def animation_command(self) -> _Command | None:
        if not self.tracks or len(self.t) < 2:
            return None
        animations = [{"path": path, "clip": {"fps": 1.0, "name": "default",
                                              "tracks": [tr.lower() for tr in tracks]}}
                      for path, tracks in self.tracks.items()]
        # stored on a path visited after every object, so that a browser connecting later to the
        # live server gets the objects before the animation that binds to their materials
        return _Command(type="set_animation", animations=animations,
                        options={"play": self.start_time is None,
                                 "repetitions": 1_000_000 if self.loop else 1},
                        path="/meshcat/zz_animation")

    def all_commands(self) -> list:
        cmds = list(self.commands)
        anim = self.animation_command()
        if anim is not None:
            cmds.append(anim)
        return cmds

    # ------------------------------------------------------------------------------- output
    def html(self) -> str:
        """One self-contained HTML page (Meshcat's browser client inlined, no network)."""
        import umsgpack
        js = (_meshcat_dist() / "main.min.js").read_text(encoding="utf-8")
        blobs = [base64.b64encode(umsgpack.packb(dict(c))).decode("ascii") for c in self.all_commands()]
        meta = {"t": [float(x) for x in self.t], "status": [str(s) for s in self.status],
                "fmax": self.fmax, "arrow_scale": self.arrow_scale,
                "colors": ["#%06x" % _hex(c) for c in TURBO], "info": self.info,
                "legend": self.legend, "start": self.start_time}
        return _HTML.format(title=_html.escape(self.info[0] if self.info else "mcdm-pin"),
                            mainjs=js.replace("</script", "<\\/script"),
                            commands=json.dumps(blobs), meta=json.dumps(meta))

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
        """Send the scene to a running ``meshcat.Visualizer``."""
        for c in self.all_commands():
            vis.window.send(c)

    def serve(self, zmq_url: str | None = None):
        """Start (or connect to) a Meshcat server, send the scene, return the ``meshcat.Visualizer``.

        Meshcat prints the URL to open. The server lives as long as this Python process."""
        import meshcat
        vis = meshcat.Visualizer(zmq_url=zmq_url)
        if self.legend:
            self._legend_object(vis)
        self.send(vis)
        return vis

    def _legend_object(self, vis) -> None:
        """A small colour-bar panel for the live viewer (the HTML file has an overlay instead)."""
        png = legend_png(self.fmax, self.arrow_scale)
        extent = self.extent
        w, h = 0.5 * extent, 0.5 * extent * png[1] / png[0]
        tex = {"uuid": _uuid(), "wrap": [1001, 1001], "repeat": [1, 1], "image": None}
        img = {"uuid": _uuid(), "url": "data:image/png;base64," + base64.b64encode(png[2]).decode()}
        tex["image"] = img["uuid"]
        mat = _material((1, 1, 1), "MeshBasicMaterial", map=tex["uuid"])
        geom = {"uuid": _uuid(), "type": "PlaneGeometry", "width": w, "height": h}
        obj = _object(geom, mat, extra={"textures": [tex], "images": [img]})
        self.commands.insert(0, _Command(type="set_object", object=obj, path="/meshcat/mcdm/legend"))
        R = np.array([[0.0, 0, 1], [1, 0, 0], [0, 1, 0]])  # plane x -> world y, y -> z, normal -> x
        c = self.center
        T = _T(R, c + np.array([0.0, 0.75 * extent, 0.35 * extent]))
        self.commands.insert(1, _Command(type="set_transform", path="/meshcat/mcdm/legend",
                                         matrix=T.T.flatten().tolist()))


def _meshcat_dist() -> Path:
    import meshcat
    return Path(meshcat.__file__).parent / "viewer" / "dist"


def legend_png(fmax: float, arrow_scale: float = 0.0, width: int = 512) -> tuple[int, int, bytes]:
    """The colour bar as a PNG: (width, height, bytes)."""
    from PIL import Image, ImageDraw, ImageFont
    height = width // 4
    img = Image.new("RGB", (width, height), (255, 255, 255))
    d = ImageDraw.Draw(img)
    try:
        font = ImageFont.load_default(size=height // 6)
    except TypeError:  # Pillow < 10.1
        font = ImageFont.load_default()
    x0, x1, y0, y1 = width // 16, width - width // 16, height // 3, height // 3 + height // 5
    for x in range(x0, x1):
        rgb = tension_rgb(fmax * (x - x0) / (x1 - x0 - 1), fmax)
        d.line([(x, y0), (x, y1)], fill=tuple(int(255 * c) for c in rgb))
    d.text((x0, 4), "cable tension, N", fill=(0, 0, 0), font=font)
    for k in range(5):
        x = x0 + (x1 - x0 - 1) * k / 4
        d.line([(x, y1), (x, y1 + 6)], fill=(0, 0, 0))
        label = f"{fmax * k / 4:g}"
        d.text((x - 4 * len(label), y1 + 8), label, fill=(0, 0, 0), font=font)
    buf = io.BytesIO()
    img.save(buf, format="PNG")
    return width, height, buf.getvalue()


# ------------------------------------------------------------------------------------- checks
def check_results(robot, result, source: str = "results") -> None:
    """Raise :class:`ResultsError` unless ``result`` was computed for ``robot`` (same joints, cables
    and coordinates, finite trajectory)."""
    def names(x):
        return [str(s) for s in np.asarray(x).tolist()]
    for key, want in (("joint_names", robot.joint_names), ("cable_names", robot.cable_names),
                      ("coordinate_names", robot.coordinate_names)):
        got = names(getattr(result, key))
        if got != list(want):
            raise ResultsError(f"{source}: {key} {got} do not match robot {robot.name!r} "
                               f"({robot.sidecar.path}), which expects {list(want)}")
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


# --------------------------------------------------------------------------------------- build
def build_scene(robot, result, fmax: float | None = None, arrow_scale: float | None = None,
                legend: bool = True, start_time: float | None = None, loop: bool = True,
                source: str = "results") -> Scene:
    """Build the animated scene of ``result`` (a :class:`~mcdm_pin.results.TrajectoryResult`).

    Args:
        robot: the :class:`~mcdm_pin.robot.Robot` the result was computed for.
        result: the solved trajectory.
        fmax: top of the cable colour scale, N (default: the run's peak force, rounded up to 1, 2 or
            5 x 10^k).
        arrow_scale: interaction-force arrow length per newton, m/N (default: the largest force is
            drawn half as long as the robot's extent).
        legend: draw the colour bar (HTML overlay / live panel) and the time overlay.
        start_time: show the scene paused at this trajectory time, s (default: play from 0).
        loop: repeat the animation (default) or play it once.
        source: how to name ``result`` in error messages (e.g. its file name).
    """
    check_results(robot, result, source)
    if fmax is not None and not (np.isfinite(fmax) and fmax > 0):
        raise ViewerError(f"fmax: expected a positive number of newtons, got {fmax}")
    if arrow_scale is not None and not (np.isfinite(arrow_scale) and arrow_scale > 0):
        raise ViewerError(f"arrow_scale: expected a positive number of m/N, got {arrow_scale}")
    t = np.asarray(result.t, float)
    if start_time is not None and not (t[0] - 1e-12 <= start_time <= t[-1] + 1e-12):
        raise ViewerError(f"start time {start_time} s is outside the trajectory ({t[0]:g}..{t[-1]:g} s)")
    kin = _kinematics(robot, np.asarray(result.q, float))
    f = np.asarray(result.f, float)
    wrench = np.asarray(result.interaction_wrench, float)
    fpeak = np.nanmax(f) if np.any(np.isfinite(f)) else 1.0
    fmax = nice_ceil(fpeak) if fmax is None else float(fmax)
    lo, hi = kin.bbox
    extent = float(max(np.linalg.norm(hi - lo), 1e-3))
    center = 0.5 * (lo + hi)
    Fmag = np.linalg.norm(wrench[:, :, :3], axis=2)
    Fpeak = np.nanmax(Fmag) if np.any(np.isfinite(Fmag)) else 0.0
    if arrow_scale is None:
        arrow_scale = 0.5 * extent / Fpeak if Fpeak > 0 else 0.0

    scene = Scene(t=t, status=np.asarray(result.status, str), fmax=fmax, arrow_scale=float(arrow_scale),
                  legend=legend, start_time=start_time, loop=loop)
    scene.info = [f"{robot.name}: {result.problem or 'results'}",
                  f"trajectory {result.trajectory or '?'}, solver {result.solver or '?'}"]
    scene.center, scene.extent = center, extent
    _environment(scene, center, extent)
    _links(scene, robot, kin, extent)
    _cables(scene, robot, kin, f, fmax, extent)
    _forces(scene, robot, kin, wrench, float(arrow_scale), extent)
    _cones(scene, robot, kin, result, extent)
    return scene


def empty_scene(center=(0.0, 0.0, 0.2), extent: float = 0.5) -> Scene:
    """The viewer's environment (background, camera) with nothing in it: the reference a screenshot
    of a real scene is compared with."""
    scene = Scene(legend=False, center=np.asarray(center, float), extent=float(extent))
    _environment(scene, np.asarray(center, float), extent)
    return scene


@dataclass
class _Kin:
    link_T: dict  # link -> (N, 4, 4) world placement of its URDF frame
    joint_T: np.ndarray  # (N, nj, 4, 4) Pinocchio joint frames
    points: np.ndarray  # (N, P, 3) cable route points, world
    bbox: tuple


def _kinematics(robot, q: np.ndarray) -> _Kin:
    model = robot.model
    data = model.createData()
    N = len(q)
    links = {name: np.empty((N, 4, 4)) for name in robot.link_names}
    fids = {name: model.getFrameId(name, pin.FrameType.BODY) for name in robot.link_names}
    joint_T = np.empty((N, model.njoints, 4, 4))
    for k in range(N):
        pin.framesForwardKinematics(model, data, robot.pin_q(q[k]))
        for j in range(model.njoints):
            joint_T[k, j] = data.oMi[j].homogeneous
        for name, fid in fids.items():
            links[name][k] = data.oMf[fid].homogeneous
    pj = robot.point_joint
    Tp = joint_T[:, pj]
    R, p = Tp[:, :, :3, :3], Tp[:, :, :3, 3]
    points = np.einsum("npij,pj->npi", R, robot.point_local) + p
    allp = np.concatenate([points.reshape(-1, 3), joint_T[:, :, :3, 3].reshape(-1, 3)])
    return _Kin(links, joint_T, points, (allp.min(axis=0), allp.max(axis=0)))


def _environment(scene: Scene, center, extent) -> None:
    scene.set_property("/Background", "top_color", list(BACKGROUND[0]))
    scene.set_property("/Background", "bottom_color", list(BACKGROUND[1]))
    # the orbit controls look at the origin: shift the world (robot, grid, axes) so that the
    # robot's centre is there
    shift = _T(p=-np.asarray(center, float))
    for path in ("/meshcat", "/Grid", "/Axes"):
        scene.set_transform(path, shift)
    d = np.array([0.85, -0.45, 0.38])
    d = d / np.linalg.norm(d) * 0.9 * extent
    # the camera lives in a y-up frame: world (x, y, z) = local (x, -z, y)
    scene.set_property("/Cameras/default/rotated/<object>", "position", [d[0], d[2], -d[1]])


def _track_pose(scene, path, T):
    """Animate a group's world pose over the instants (T: (N, 4, 4)); set the first as static."""
    scene.set_transform(path, T[0])
    scene.track(path, "position", "vector3", T[:, :3, 3])
    scene.track(path, "quaternion", "quaternion", _quat_xyzw(T[:, :3, :3]))


def _links(scene, robot, kin: _Kin, extent) -> None:
    urdf = _load_urdf(robot)
    links = urdf.links if urdf is not None else {}
    joints = urdf.joints if urdf is not None else []
    by_joint = {j.name: j for j in joints}
    massless = {by_joint[n].child for pj in robot.joints for n in pj.urdf_joints[:-1] if n in by_joint}
    children: dict[str, list] = {}
    for j in joints:
        children.setdefault(j.parent, []).append(j)
    child_links = {j.child for j in joints}
    r = 0.015 * extent
    for name in robot.link_names:
        T = kin.link_T[name]
        base = "/meshcat/mcdm/links/" + _safe(name)
        moving = not np.allclose(T, T[0], atol=1e-12)
        drawn = 0
        link = links.get(name)
        for k, vis in enumerate(link.visuals if link is not None else []):
            drawn += _visual(scene, f"{base}/visual{k}", vis, robot)
        if not drawn and name not in massless and link is not None:
            drawn += _fallback_link(scene, base, link, children.get(name, []), r,
                                    is_root=name not in child_links)
        if drawn or name in _anchor_links(robot):
            scene.set_transform(base, T[0])
            if moving:
                _track_pose(scene, base, T)
    # cable attachment points
    for c, cable in enumerate(robot.cables):
        for k, (lk, p) in enumerate(zip(cable.links, cable.points)):
            path = f"/meshcat/mcdm/links/{_safe(lk)}/anchors/{_safe(cable.name)}_{k}"
            scene.set_object(path, _object(_sphere(0.4 * r), _material((0.35, 0.35, 0.35))))
            scene.set_transform(path, _T(p=p))


def _anchor_links(robot) -> set:
    return {lk for c in robot.cables for lk in c.links}


def _safe(name: str) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in str(name))


@dataclass
class _UVisual:
    origin: np.ndarray  # 4x4 in the link frame
    kind: str  # box, cylinder, sphere, mesh
    size: tuple = ()  # box (x, y, z); cylinder (radius, length); sphere (radius,)
    filename: str = ""
    scale: tuple = (1.0, 1.0, 1.0)
    rgba: tuple | None = None


@dataclass
class _ULink:
    name: str
    visuals: list
    com: np.ndarray | None


@dataclass
class _UJoint:
    name: str
    parent: str
    child: str
    origin: np.ndarray


@dataclass
class _Urdf:
    links: dict
    joints: list


def _floats(text, n, default):
    if text is None:
        return tuple(default)
    vals = [float(x) for x in text.split()]
    if len(vals) != n:
        raise ValueError(f"expected {n} numbers, got {text!r}")
    return tuple(vals)


def _origin(el) -> np.ndarray:
    o = el.find("origin") if el is not None else None
    if o is None:
        return np.eye(4)
    xyz = _floats(o.get("xyz"), 3, (0, 0, 0))
    rpy = _floats(o.get("rpy"), 3, (0, 0, 0))
    return _T(pin.rpy.rpyToMatrix(*rpy), xyz)


def _load_urdf(robot) -> _Urdf | None:
    """The URDF's visuals, centres of mass and joint origins (plain XML reading, no network)."""
    import xml.etree.ElementTree as ET
    try:
        root = ET.parse(str(robot.urdf_path)).getroot()
        colors = {}
        for m in root.findall("material"):
            c = m.find("color")
            if m.get("name") and c is not None:
                colors[m.get("name")] = _floats(c.get("rgba"), 4, (1, 1, 1, 1))
        links = {}
        for lk in root.findall("link"):
            visuals = []
            for v in lk.findall("visual"):
                g = v.find("geometry")
                if g is None or len(g) == 0:
                    continue
                shape = g[0]
                rgba = None
                m = v.find("material")
                if m is not None:
                    c = m.find("color")
                    rgba = (_floats(c.get("rgba"), 4, (1, 1, 1, 1)) if c is not None
                            else colors.get(m.get("name")))
                vis = _UVisual(origin=_origin(v), kind=shape.tag, rgba=rgba)
                if shape.tag == "box":
                    vis.size = _floats(shape.get("size"), 3, (0, 0, 0))
                elif shape.tag == "cylinder":
                    vis.size = (float(shape.get("radius")), float(shape.get("length")))
                elif shape.tag == "sphere":
                    vis.size = (float(shape.get("radius")),)
                elif shape.tag == "mesh":
                    vis.filename = shape.get("filename", "")
                    sc = shape.get("scale")
                    vis.scale = _floats(sc, 3, (1, 1, 1)) if sc else (1.0, 1.0, 1.0)
                else:
                    continue
                visuals.append(vis)
            inertial = lk.find("inertial")
            com = _origin(inertial)[:3, 3] if inertial is not None else None
            links[lk.get("name")] = _ULink(lk.get("name"), visuals, com)
        joints = [_UJoint(j.get("name"), j.find("parent").get("link"), j.find("child").get("link"),
                          _origin(j)) for j in root.findall("joint")]
        return _Urdf(links, joints)
    except Exception as exc:  # a URDF Pinocchio accepts but this reader does not: simple shapes
        warnings.warn(f"{robot.urdf_path}: cannot read the visuals ({exc}); drawing simple shapes")
        return None


def _visual(scene, path, vis: _UVisual, robot) -> int:
    rgb, opacity = LINK_RGB, 1.0
    if vis.rgba is not None:
        rgb, opacity = tuple(vis.rgba[:3]), float(vis.rgba[3])
    material = _material(rgb, opacity=opacity)
    if vis.kind == "box":
        scene.set_object(path, _object(_box(vis.size), material))
        scene.set_transform(path, vis.origin)
    elif vis.kind == "cylinder":
        scene.set_object(path, _object(_cylinder(vis.size[1], vis.size[0], vis.size[0], 40), material))
        scene.set_transform(path, vis.origin @ _T(_RX90))
    elif vis.kind == "sphere":
        scene.set_object(path, _object(_sphere(vis.size[0]), material))
        scene.set_transform(path, vis.origin)
    else:
        geom = _mesh_geometry(vis.filename, robot)
        if geom is None:
            return 0
        scene.set_object(path, _object(geom, material))
        scene.set_transform(path, vis.origin @ _T(scale=vis.scale))
    return 1


def _mesh_geometry(filename: str, robot) -> dict | None:
    from .robot import resolve_package_uri
    try:
        if filename.startswith("package://"):
            path = resolve_package_uri(filename, robot.sidecar.path)
        else:
            path = Path(filename[len("file://"):] if filename.startswith("file://") else filename)
            if not path.is_absolute():
                path = Path(robot.urdf_path).parent / path
        ext = path.suffix.lower()
        if ext in (".stl", ".obj", ".dae"):
            import meshcat.geometry as mg
            loader = {".stl": mg.StlMeshGeometry, ".obj": mg.ObjMeshGeometry,
                      ".dae": mg.DaeMeshGeometry}[ext]
            return loader.from_file(str(path)).lower({})
        import trimesh
        mesh = trimesh.load(str(path), force="mesh")
        import meshcat.geometry as mg
        return mg.StlMeshGeometry.from_stream(io.BytesIO(mesh.export(file_type="stl"))).lower({})
    except Exception as exc:
        warnings.warn(f"mesh {filename!r}: cannot load ({exc}); drawing a simple shape instead")
        return None


def _fallback_link(scene, base, link: _ULink, child_joints, r, is_root) -> int:
    """Cylinders from the link's joint to each child joint (or to twice the centre of mass), and a
    sphere at the joint."""
    ends = [j.origin[:3, 3] for j in child_joints]
    if not ends and link.com is not None and np.linalg.norm(link.com) > 1e-9:
        ends.append(2 * link.com)
    n = 0
    if not is_root:
        scene.set_object(f"{base}/joint", _object(_sphere(1.6 * r), _material(LINK_RGB)))
        n += 1
    for k, p in enumerate(ends):
        L = float(np.linalg.norm(p))
        if L < 1e-9:
            continue
        scene.set_object(f"{base}/bone{k}", _object(_cylinder(L, r, r), _material(LINK_RGB)))
        scene.set_transform(f"{base}/bone{k}", _T(_rot_y_to(p)[0], 0.5 * p))
        n += 1
    return n


def _segment_poses(a: np.ndarray, b: np.ndarray):
    """Unit-height cylinders (+y) stretched from a to b: (N, 4, 4) pose, (N, 3) scale."""
    d = b - a
    L = np.linalg.norm(d, axis=1)
    T = np.repeat(np.eye(4)[None], len(a), axis=0)
    T[:, :3, :3] = _rot_y_to(d)
    T[:, :3, 3] = 0.5 * (a + b)
    scale = np.stack([np.ones_like(L), np.maximum(L, 1e-6), np.ones_like(L)], axis=1)
    return T, scale


def _cables(scene, robot, kin: _Kin, f, fmax, extent) -> None:
    radius = 0.0035 * extent
    colors = tension_rgb(f, fmax)  # (N, m, 3)
    count: dict[int, int] = {}
    for s, (a, b, c) in enumerate(zip(robot.seg_a, robot.seg_b, robot.seg_cable)):
        k = count.get(c, 0)
        count[c] = k + 1
        path = f"/meshcat/mcdm/cables/{_safe(robot.cables[c].name)}/s{k}"
        T, scale = _segment_poses(kin.points[:, a], kin.points[:, b])
        scene.set_object(path, _object(_cylinder(1.0, radius, radius, 12),
                                       _material(colors[0, c], "MeshBasicMaterial")))
        scene.set_transform(path, T[0] @ _T(scale=scale[0]))
        scene.track(path, "position", "vector3", T[:, :3, 3])
        scene.track(path, "quaternion", "quaternion", _quat_xyzw(T[:, :3, :3]))
        scene.track(path, "scale", "vector3", scale)
        scene.track(path, "body.material.color", "color", colors[:, c])


def _forces(scene, robot, kin: _Kin, wrench, scale, extent) -> None:
    if scale <= 0:
        return
    r = 0.013 * extent  # about as thick as typical links: forces often run along them
    head = 0.065 * extent
    for j, joint in enumerate(robot.joints):
        T_child = kin.joint_T[:, joint.child_id]
        F = np.einsum("nab,nb->na", T_child[:, :3, :3], wrench[:, j, :3])  # world
        ok = np.all(np.isfinite(F), axis=1)
        F = np.where(ok[:, None], F, 0.0)
        L = np.linalg.norm(F, axis=1) * scale
        T = np.repeat(np.eye(4)[None], len(F), axis=0)
        T[:, :3, :3] = _rot_y_to(F)
        T[:, :3, 3] = T_child[:, :3, 3]
        k = np.minimum(1.0, L / head)  # short arrows: shrink the head
        shaft = np.maximum(L - k * head, 1e-6)
        path = f"/meshcat/mcdm/forces/{_safe(joint.name)}"
        mat = _material(ARROW_RGB)
        scene.set_object(f"{path}/shaft", _object(_cylinder(1.0, r, r, 16), mat))
        scene.set_object(f"{path}/head", _object(_cylinder(head, 0.0, 2.2 * r, 16), _material(ARROW_RGB)))
        _track_pose(scene, path, T)
        visible = ok & (L > 0)
        scene.set_property(path, "visible", bool(visible[0]))
        scene.track(path, "visible", "bool", visible)
        sp = np.stack([np.zeros_like(L), 0.5 * shaft, np.zeros_like(L)], axis=1)
        ss = np.stack([np.ones_like(L), shaft, np.ones_like(L)], axis=1)
        scene.set_transform(f"{path}/shaft", _T(p=sp[0], scale=ss[0]))
        scene.track(f"{path}/shaft", "position", "vector3", sp)
        scene.track(f"{path}/shaft", "scale", "vector3", ss)
        hp = np.stack([np.zeros_like(L), shaft + 0.5 * k * head, np.zeros_like(L)], axis=1)
        hs = np.repeat(k[:, None], 3, axis=1)
        scene.set_transform(f"{path}/head", _T(p=hp[0], scale=hs[0]))
        scene.track(f"{path}/head", "position", "vector3", hp)
        scene.track(f"{path}/head", "scale", "vector3", hs)


def _cone_height(robot, kin: _Kin, joint, extent) -> float:
    """A cone about half as long as the child link (the distance from the joint to the farthest
    joint or cable point carried by the child), at most 0.22 x the robot's extent."""
    model = robot.model
    T0 = kin.joint_T[0]
    p0 = T0[joint.child_id, :3, 3]
    ends = [T0[j, :3, 3] for j in range(1, model.njoints) if model.parents[j] == joint.child_id]
    ends += list(kin.points[0][robot.point_joint == joint.child_id])
    length = max((float(np.linalg.norm(e - p0)) for e in ends), default=0.0)
    return min(0.22 * extent, 0.5 * length) if length > 0 else 0.22 * extent


def _cones(scene, robot, kin: _Kin, result, extent) -> None:
    angles = np.asarray(result.interaction_angle_deg, float)
    cone_deg = np.asarray(result.cone_deg, float)
    for j, joint in enumerate(robot.joints):
        if joint.type != "spherical":
            continue
        rho = cone_deg[j] if j < len(cone_deg) and np.isfinite(cone_deg[j]) else joint.cone_deg
        if rho is None or not np.isfinite(rho) or not 0 < rho < 90:
            continue
        height = _cone_height(robot, kin, joint, extent)
        radius = height * np.tan(np.radians(rho))
        # socket frame (world) at every instant: parent joint frame * socket placement
        S = kin.joint_T[:, joint.parent_id] @ joint.socket_placement.homogeneous
        R_axis = _rot_y_to(np.asarray(joint.socket_axis, float)[None])[0]
        T_local = _T(R_axis) @ _T(p=[0.0, 0.5 * height, 0.0])  # apex at the joint point
        path = f"/meshcat/mcdm/cones/{_safe(joint.name)}"
        state = np.where(~np.isfinite(angles[:, j]), 2, (angles[:, j] > rho + CONE_TOL_DEG).astype(int))
        palette = np.array([CONE_OK_RGB, CONE_OUT_RGB, NO_ANSWER_RGB])
        colors = palette[state]
        scene.set_object(f"{path}/cone", _object(_cylinder(height, radius, 0.0, 48),
                                                 _material(colors[0], opacity=0.35)))
        scene.set_transform(f"{path}/cone", T_local)
        _track_pose(scene, path, S)
        scene.track(f"{path}/cone", "body.material.color", "color", colors, discrete=True)


# --------------------------------------------------------------------------------------- files
def scene_from_files(robot_path, results_path, **options) -> tuple:
    """(robot, result, scene) from a sidecar and a results ``.npz``."""
    from .results import TrajectoryResult
    from .robot import Robot
    robot = Robot.load(robot_path)
    if Path(results_path).suffix != ".npz":
        raise ResultsError(f"{results_path}: expected a .npz results file (from mcdm-pin solve --out)")
    result = TrajectoryResult.load(results_path)
    return robot, result, build_scene(robot, result, source=str(results_path), **options)


def write_html(robot, result, path, **options) -> Path:
    """Build the scene of ``result`` and write it as one self-contained HTML file."""
    return build_scene(robot, result, **options).write_html(path)


# ------------------------------------------------------------------------------------ chromium
CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")


def find_chromium() -> str | None:
    """Path of a Chromium/Chrome executable (``MCDM_PIN_CHROMIUM`` first, then ``PATH``), or None."""
    env = os.environ.get("MCDM_PIN_CHROMIUM")
    if env:
        return env if Path(env).is_file() else None
    for name in CHROMIUM_NAMES:
        p = shutil.which(name)
        if p:
            return p
    return None


def chromium_command(html_path, png_path, size=(1000, 800), chromium: str | None = None,
                     user_data_dir: str | None = None) -> list[str]:
    """The headless Chromium command that screenshots ``html_path`` with no network access: every
    host name resolves to nothing and every proxied request goes to a closed local port."""
    exe = chromium or find_chromium()
    if exe is None:
        raise ViewerError("no Chromium found (install Debian's chromium: apt-get install chromium, or "
                          "set MCDM_PIN_CHROMIUM to the browser's path)")
    return [exe, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
            "--disable-component-update", "--disable-sync", "--no-first-run",
            "--disable-default-apps", "--disable-extensions", "--mute-audio", "--hide-scrollbars",
            "--host-resolver-rules=MAP * ~NOTFOUND", "--proxy-server=127.0.0.1:9",
            f"--user-data-dir={user_data_dir}", f"--window-size={size[0]},{size[1]}",
            f"--screenshot={Path(png_path).resolve()}", Path(html_path).resolve().as_uri()]


def screenshot(html_path, png_path, size=(1000, 800), timeout: float = 120.0,
               chromium: str | None = None) -> Path:
    """Render an HTML file in headless Chromium (no network) and write a PNG screenshot."""
    png_path = Path(png_path)
    with tempfile.TemporaryDirectory(prefix="mcdm-pin-chromium-") as profile:
        cmd = chromium_command(html_path, png_path, size, chromium, profile)
        if png_path.exists():
            png_path.unlink()
        try:
            proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout,
                                  stdin=subprocess.DEVNULL)
        except subprocess.TimeoutExpired:
            raise ViewerError(f"chromium did not finish the screenshot of {html_path} within "
                              f"{timeout:g} s") from None
    if not png_path.is_file():
        tail = (proc.stderr or "").strip().splitlines()[-3:]
        raise ViewerError(f"chromium wrote no screenshot of {html_path} (exit {proc.returncode}: "
                          f"{' | '.join(tail)})")
    return png_path


_HTML = """<!DOCTYPE html>
<html>
<head>
<meta charset="utf-8">
<title>{title}</title>
<style>
  body {{ margin: 0; }}
  #meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}
  #mcdm-overlay {{ position: absolute; left: 10px; bottom: 10px; padding: 8px 10px;
    background: rgba(255, 255, 255, 0.85); border-radius: 4px; font: 13px sans-serif;
    color: #111; pointer-events: none; min-width: 260px; max-width: 460px; }}
  #mcdm-info div {{ white-space: nowrap; overflow: hidden; text-overflow: ellipsis; }}
  #mcdm-bar {{ height: 12px; margin: 4px 0 2px 0; border: 1px solid #555; }}
  #mcdm-ticks {{ display: flex; justify-content: space-between; font-size: 11px; }}
  .mcdm-small {{ font-size: 11px; color: #333; }}
  #mcdm-time {{ font: bold 15px monospace; }}
</style>
</head>
<body>
<div id="meshcat-pane"></div>
<div id="mcdm-overlay" style="display: none">
  <div id="mcdm-info"></div>
  <div id="mcdm-time"></div>
  <div style="margin-top: 4px">cable tension, N (fixed scale)</div>
  <div id="mcdm-bar"></div>
  <div id="mcdm-ticks"></div>
  <div class="mcdm-small" id="mcdm-arrow"></div>
  <div class="mcdm-small">cone: <span style="color: #26bf40">&#9632;</span> force inside rho*,
    <span style="color: #f00">&#9632;</span> outside, grey: no answer</div>
</div>
<script>
{mainjs}
</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
var MCDM_COMMANDS = {commands};
var MCDM = {meta};
(function () {{
  function bytes(s) {{
    var bin = atob(s), out = new Uint8Array(bin.length);
    for (var i = 0; i < bin.length; i++) out[i] = bin.charCodeAt(i);
    return out;
  }}
  for (var i = 0; i < MCDM_COMMANDS.length; i++) viewer.handle_command_bytearray(bytes(MCDM_COMMANDS[i]));
  var anim = viewer.animator;
  if (MCDM.start !== null && anim.actions.length) {{
    anim.play(); anim.pause(); anim.seek(MCDM.start); anim.display_progress(MCDM.start);
  }}
  if (!MCDM.legend) return;
  var box = document.getElementById("mcdm-overlay");
  box.style.display = "block";
  document.getElementById("mcdm-info").innerHTML = MCDM.info.map(function (s) {{
    return "<div>" + s.replace(/&/g, "&amp;").replace(/</g, "&lt;") + "</div>"; }}).join("");
  document.getElementById("mcdm-bar").style.background =
    "linear-gradient(to right, " + MCDM.colors.join(", ") + ")";
  var ticks = "";
  for (var k = 0; k <= 4; k++) ticks += "<span>" + +(MCDM.fmax * k / 4).toPrecision(4) + "</span>";
  document.getElementById("mcdm-ticks").innerHTML = ticks;
  if (MCDM.arrow_scale > 0) {{
    var n = 0.1 / MCDM.arrow_scale;
    document.getElementById("mcdm-arrow").textContent =
      "interaction force arrows: 0.1 m = " + n.toPrecision(3) + " N";
  }}
  var el = document.getElementById("mcdm-time");
  function tick() {{
    var t = anim.time || 0, T = MCDM.t, k = 0;
    if (T.length) {{
      var lo = 0, hi = T.length - 1;
      while (hi - lo > 1) {{ var mid = (lo + hi) >> 1; if (T[mid] <= t) lo = mid; else hi = mid; }}
      k = (Math.abs(T[hi] - t) < Math.abs(t - T[lo])) ? hi : lo;
      var st = MCDM.status[k];
      el.textContent = "t = " + t.toFixed(3) + " s" + (st === "optimal" ? "" : "  [" + st + "]");
    }}
    requestAnimationFrame(tick);
  }}
  tick();
}})();
</script>
</body>
</html>
"""
