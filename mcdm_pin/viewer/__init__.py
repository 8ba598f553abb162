r"""3-D view of a solved trajectory in Meshcat: links, cables coloured by tension, interaction forces,
stability cones; live in the browser or as one self-contained HTML file.

One module per job: :mod:`~mcdm_pin.viewer.scene` (what is drawn where, the camera),
:mod:`~mcdm_pin.viewer.visuals` (the links, from the visual model Pinocchio loads),
:mod:`~mcdm_pin.viewer.animation` (cables, arrows, cones over time), :mod:`~mcdm_pin.viewer.export`
(HTML file, live server), :mod:`~mcdm_pin.viewer.screenshot` (headless Chromium);
:mod:`~mcdm_pin.viewer.colors` and :mod:`~mcdm_pin.viewer.three` are shared by them.

What the scene shows (paths under ``/meshcat/mcdm``, in the robot's world frame; the whole is turned
so that gravity points down the screen, e.g. example-robot-data's y-up human stands upright):

* ``links/<link>``: every URDF link's visuals as Pinocchio's visual model has them (boxes, cylinders,
  spheres, meshes of any format Pinocchio reads), in muted colours; meshes (body skins, which hide the
  cables attached inside them) translucent by default (``links='auto'``). ``bodies/<joint>``: a simple
  shape for a body without visuals, and a small dark sphere at every cable attachment point;
  ``bodies/<joint>/platform``: a body whose attachment points span more than twice its visuals (a
  cable robot's platform, which CASPR draws as a 1.6 cm sphere) as the convex hull of those points.
* ``cables/<cable>/s<k>``: every route segment as a thin cylinder (browsers ignore line widths),
  coloured by the cable's tension on a **fixed colour scale** from 0 N (clear blue) through cyan,
  green and yellow to ``fmax`` (dark red), :mod:`~mcdm_pin.viewer.colors`; forces above ``fmax`` keep
  the top colour. ``fmax`` is fixed for the whole animation: by default the run's peak cable force
  rounded up to 1, 1.2, 1.5, 2, 2.5, 3, 4, 5, 6 or 8 x 10^k N (53.8 N -> 60 N). At instants without a
  valid answer the cables are grey.
* ``forces/<joint>``: the interaction force of the parent on the child (``interaction_wrench[:3]``)
  as a magenta arrow (cylinder + cone head) from the joint point with the joint's name at its tip,
  ``arrow_scale`` metres per newton (fixed; by default the run's largest force is drawn half as long
  as the diagonal of the box that holds the robot over the trajectory, and arrows are shorter and
  thinner by sqrt(2 / count) when more than two joints have one, e.g. the neck's 8). Hidden where
  there is no answer; a free joint (which transmits nothing: a cable robot's platform) and forces
  below 1e-6 x the run's peak interaction or cable force (round-off) get no arrow.
* ``cones/<joint>``: each spherical joint's stability cone: apex at the joint point, half-angle
  ``rho*`` about the socket axis, drawn in the socket frame (it moves with the parent link), about
  half as long as the child link. It is translucent green while the force is inside
  (``interaction_angle_deg <= rho* + 1e-6``), red when it leaves it and grey where there is no
  answer. ``rho*`` is the run's ``cone_deg`` or, where the run had no cone (cases 1 and 2), the
  sidecar's ``cone_deg``, so a case-1 run shows where it breaks the cone.

A light floor grid lies under the robot's lowest point (``/meshcat/floor``). The camera looks at the
middle of the box that holds the robot over the whole trajectory, from the front-right and a little
above (turned towards the cables when they sit to one side of a larger body), at the distance where
the robot spans 85 % of the picture's height or width (for a 1000 x 800 picture; ``aspect``).

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

from pathlib import Path

from ..exceptions import ResultsError
from .colors import (CABLE_MAP, CONE_OK_RGB, CONE_OUT_RGB, NO_ANSWER_RGB, TURBO, mute, nice_ceil,
                     tension_rgb)
from .scene import Scene, ViewerError, build_scene, camera_position, check_results, empty_scene
from .screenshot import chromium_command, find_chromium, screenshot

__all__ = ["Scene", "ViewerError", "build_scene", "empty_scene", "check_results", "camera_position",
           "scene_from_files", "write_html", "screenshot", "find_chromium", "chromium_command",
           "tension_rgb", "nice_ceil", "mute", "CABLE_MAP", "TURBO", "NO_ANSWER_RGB", "CONE_OK_RGB",
           "CONE_OUT_RGB"]


def scene_from_files(robot_path, results_path, **options) -> tuple:
    """(robot, result, scene) from a sidecar and a results ``.npz``."""
    from ..results import TrajectoryResult
    from ..robot import Robot

    robot = Robot.load(robot_path)
    if Path(results_path).suffix != ".npz":
        raise ResultsError(f"{results_path}: expected a .npz results file (from mcdm-pin solve --out)")
    result = TrajectoryResult.load(results_path)
    return robot, result, build_scene(robot, result, source=str(results_path), **options)


def write_html(robot, result, path, **options) -> Path:
    """Build the scene of ``result`` and write it as one self-contained HTML file."""
    return build_scene(robot, result, **options).write_html(path)
