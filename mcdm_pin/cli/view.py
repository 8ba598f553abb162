"""``mcdm-pin view``: the 3-D view of a solved trajectory (Meshcat live, or one HTML file); the
``solve --html`` hook."""

from __future__ import annotations

import argparse
import signal
import sys
import time
from pathlib import Path

from ._common import UsageError
from ._files import file_kind, robot_file


def html_file(text: str) -> str:
    """argparse type: a file name ending in .html."""
    if Path(text).suffix.lower() not in (".html", ".htm"):
        raise argparse.ArgumentTypeError(f"expected a file name ending in .html, got {text!r}")
    return text


def _positive(text: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not x > 0 or x == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return x


def _scene_options(args) -> dict:
    return dict(fmax=args.fmax, arrow_scale=args.arrow_scale, start_time=args.time,
                legend=not args.no_legend, links=args.links, arc_tol=args.arc_tol)


def _add_scene_options(p) -> None:
    p.add_argument("--fmax", type=_positive, metavar="N",
                   help="top of the cable colour scale, N (default: the peak force, rounded up)")
    p.add_argument("--arrow-scale", type=_positive, metavar="M_PER_N",
                   help="interaction force arrow length per newton (default: the largest force is "
                        "half the robot's size)")
    p.add_argument("--time", type=float, metavar="T",
                   help="show the scene paused at trajectory time T, s (default: play)")
    p.add_argument("--no-legend", action="store_true", help="no colour bar / time overlay")
    p.add_argument("--arc-tol", type=_positive, metavar="REL",
                   help="wrapped cables: how much shorter than its route a drawn cable may be, relative "
                        "(default 1e-6; larger draws each wrap's arc with fewer pieces: a smaller file)")
    p.add_argument("--links", choices=("auto", "solid", "ghost"), default="auto",
                   help="how links are drawn: auto (default: meshes translucent, so that the cables "
                        "attached inside a body's skin show; primitive shapes opaque), solid or ghost")


# ------------------------------------------------------------------------------------------- view
def add(sub):
    p = sub.add_parser("view", help="3-D view of a solved trajectory (Meshcat: live, or one HTML file)")
    p.add_argument("robot", help="cable sidecar (YAML) or MuJoCo MJCF file")
    p.add_argument("--results", help="results file written by solve --out (.npz)")
    p.add_argument("--workspace", metavar="STORE.zarr",
                   help="instead of --results: a workspace store, its poses as a point cloud of "
                        "--frame's position coloured by --color")
    p.add_argument("--frame", help="with --workspace: the link (or frame) whose positions are shown")
    p.add_argument("--color", default="needed_f_max", choices=("needed_f_max", "needed_cone_deg"),
                   help="with --workspace: the margin that colours the points (default needed_f_max)")
    p.add_argument("--pose", type=int, help="with --workspace: the pose the robot is drawn at "
                                            "(default: the optimal one with the largest margin)")
    p.add_argument("--html", type=html_file, metavar="FILE.html",
                   help="write one self-contained HTML file (opens offline) instead of serving")
    p.add_argument("--no-wait", action="store_true",
                   help="do not serve: write the HTML file (--html, default: RESULTS.html) and exit")
    p.add_argument("--screenshot", metavar="FILE.png",
                   help="also render the HTML file in headless Chromium into this PNG")
    p.add_argument("--size", default="1000x800", help="screenshot size WIDTHxHEIGHT (default 1000x800)")
    _add_scene_options(p)
    p.set_defaults(func=run)
    return p


def run(args) -> int:
    from ..viewer import scene_from_files, screenshot

    if args.screenshot and Path(args.screenshot).suffix.lower() != ".png":
        raise UsageError(f"--screenshot: expected a .png file name, got {args.screenshot!r}")
    try:
        size = tuple(int(x) for x in args.size.lower().split("x"))
        assert len(size) == 2 and min(size) > 0
    except (ValueError, AssertionError):
        raise UsageError(f"--size: expected WIDTHxHEIGHT in pixels, got {args.size!r}") from None
    if args.results is None and args.workspace is None and file_kind(args.robot) == "results":
        raise UsageError(f"ROBOT: {args.robot} is a results file, not a robot; give the robot's sidecar and "
                         f"the results with --results: mcdm-pin view ROBOT.yaml --results {args.robot}")
    if (args.results is None) == (args.workspace is None):
        raise UsageError("give --results FILE.npz or --workspace STORE.zarr (one of them)")
    if args.workspace and not args.frame:
        raise UsageError("--workspace needs --frame LINK: the link whose positions are shown")
    if args.results and file_kind(args.robot) == "results" and file_kind(args.results) != "results":
        args.robot, args.results = args.results, args.robot  # given the other way round
    robot_path = robot_file(args.robot)
    html = args.html
    if html is None and (args.no_wait or args.screenshot):
        html = str(Path(args.results or args.workspace).with_suffix(".html"))
    if args.workspace:
        robot, scene = _workspace_scene(robot_path, args)
    else:
        robot, _, scene = scene_from_files(robot_path, args.results, aspect=size[0] / size[1],
                                           **_scene_options(args))
    if html is not None:
        path = scene.write_html(html)
        print(f"wrote {path}")
        if args.screenshot:
            print(f"wrote {screenshot(path, args.screenshot, size=size)}")
        return 0
    # SIGTERM exits normally too, so that Meshcat's exit handler stops its server process
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    vis = scene.serve()
    print(f"serving {robot.name} / {args.results or args.workspace} at {vis.url()} (press Ctrl-C to stop)",
          flush=True)
    try:
        while True:
            time.sleep(1.0)
    except KeyboardInterrupt:
        print("stopped")
    return 0


def _workspace_scene(robot_path, args):
    """``view --workspace``: the poses of a store as a point cloud (mcdm_pin/workspace/cloud.py)."""
    from ..robot import Robot
    from ..workspace import open_workspace
    from ..workspace.cloud import cloud_scene

    robot = Robot.load(robot_path)
    return robot, cloud_scene(robot, open_workspace(args.workspace), args.frame, color_by=args.color,
                              pose=args.pose)


def solve_html_hook(args, robot, result) -> None:
    """``solve --html FILE.html``: write the 3-D view of the solved trajectory."""
    html = getattr(args, "html", None)
    if not html:
        return
    from ..viewer import build_scene
    path = build_scene(robot, result, source="the solved trajectory").write_html(html)
    print(f"wrote {path}")
