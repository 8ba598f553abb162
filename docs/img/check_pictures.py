"""What the viewer screenshots in the docs show, measured in their pixels (docs/pictures.md).

    python docs/img/check_pictures.py ROBOT.yaml RUN.npz TIME PICTURE.png [--size 1000x800]

rebuilds the scene that ``mcdm-pin view ROBOT.yaml --results RUN.npz --time TIME`` draws, renders its
environment alone (same camera, no robot) in headless Chromium, and reports, for PICTURE.png (the
screenshot ``view --screenshot`` wrote):

* the robot's pixel bounding box (pixels that differ from the empty scene by more than 0.1 in some
  channel; rows and columns with at least 3 of them) as shares of the picture's height and width;
* stray lines in the upper-left block (300 x 330 pixels): pixels that are not the robot's and differ
  by more than 0.05 from their row's background (the background is a vertical gradient);
* the magenta pixels of the interaction-force arrows, and their share of the robot's pixels;
* the cables' colours at TIME: how many pixels of each colour of the scale the cables have then
  (within 0.06 per channel, and not in the empty scene), the minimum-force colour among them.

The overlay (colour bar, time) is left out of the measures: the masks exclude the bottom-left box.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from mcdm_pin import Robot, TrajectoryResult  # noqa: E402
from mcdm_pin.viewer import build_scene, empty_scene, screenshot, tension_rgb  # noqa: E402

OVERLAY = (slice(640, None), slice(0, 330))  # rows, columns of the legend box at 1000 x 800


def _img(path) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(path).convert("RGB"), dtype=float) / 255.0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("robot")
    p.add_argument("run")
    p.add_argument("time", type=float)
    p.add_argument("picture")
    p.add_argument("--size", default="1000x800")
    args = p.parse_args(argv)
    size = tuple(int(x) for x in args.size.split("x"))
    robot, run = Robot.load(args.robot), TrajectoryResult.load(args.run)
    scene = build_scene(robot, run, start_time=args.time, aspect=size[0] / size[1])
    with tempfile.TemporaryDirectory() as tmp:
        html = empty_scene(scene).write_html(Path(tmp) / "empty.html")
        ref = _img(screenshot(html, Path(tmp) / "empty.png", size=size))
    img = _img(args.picture)
    mask = np.any(np.abs(img - ref) > 0.1, axis=2)
    mask[OVERLAY] = False
    rows, cols = np.flatnonzero(mask.sum(axis=1) >= 3), np.flatnonzero(mask.sum(axis=0) >= 3)
    h, w = (rows[-1] - rows[0] + 1) / img.shape[0], (cols[-1] - cols[0] + 1) / img.shape[1]
    print(f"{args.picture}: robot's bounding box {h:.2f} of the height x {w:.2f} of the width "
          f"(rows {rows[0]}-{rows[-1]}, columns {cols[0]}-{cols[-1]})")
    block, robot_px = img[:300, :330], mask[:300, :330]
    dev = np.abs(block - np.median(block, axis=1, keepdims=True)).max(axis=2)
    print(f"  upper-left 300 x 330 block: {int((dev[~robot_px] > 0.05).sum())} stray pixels off the robot")
    magenta = (img[..., 0] > 0.45) & (img[..., 1] < 0.3) & (img[..., 2] > 0.45) & mask
    print(f"  interaction-force arrows (magenta): {int(magenta.sum())} pixels, "
          f"{magenta.sum() / max(int(mask.sum()), 1):.2f} of the robot's")
    k = int(np.argmin(np.abs(run.t - args.time)))
    colors = tension_rgb(run.f[k], scene.fmax)
    for i, what in ((int(np.nanargmin(run.f[k])), "minimum"), (int(np.nanargmax(run.f[k])), "maximum")):
        rgb = colors[i]
        near = np.all(np.abs(img - rgb) < 0.06, axis=2) & ~np.all(np.abs(ref - rgb) < 0.06, axis=2)
        near[OVERLAY] = False
        print(f"  {what} force at t = {run.t[k]:g} s: {robot.cable_names[i]} {run.f[k, i]:.4g} N, colour "
              f"{np.round(rgb, 3).tolist()}: {int(near.sum())} pixels")
    n_seen = sum(1 for rgb in np.unique(np.round(colors, 3), axis=0)
                 if (np.all(np.abs(img - rgb) < 0.06, axis=2) & ~np.all(np.abs(ref - rgb) < 0.06, axis=2)).sum() >= 15)
    print(f"  {n_seen} of the {len(np.unique(np.round(colors, 3), axis=0))} distinct cable colours at that "
          f"instant have at least 15 pixels on screen")
    return 0


if __name__ == "__main__":
    sys.exit(main())
