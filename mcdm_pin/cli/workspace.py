"""``mcdm-pin workspace ROBOT.yaml ... --out STORE.zarr``: a (stability-aware) workspace over a grid, a
random sample or a file of poses, on this machine's cores or a Dask cluster, into a Zarr store."""

from __future__ import annotations

import sys

import numpy as np

from ..vocabulary import CASES, CONE_FRAMES
from ._files import robot_file
from ._common import UsageError, parse_cones, parse_float, parse_pairs, parse_weights


def add(sub):
    p = sub.add_parser("workspace", help="where the robot can hold itself: many poses into a Zarr store "
                                         "(this machine's cores or a Dask cluster)")
    p.add_argument("robot", help="cable sidecar (YAML) or MuJoCo MJCF file")
    p.add_argument("--case", type=int, choices=CASES, default=1,
                   help="1: min f^T f; 2: min interactions; 3: case 2 + stability cones (default 1)")
    p.add_argument("--cone", help="cone half-angle per joint: JOINT=DEG,... or all=DEG (case 3)")
    p.add_argument("--weights", help="alpha (and beta) per joint: JOINT=ALPHA[:BETA],...")
    p.add_argument("--frame", choices=CONE_FRAMES, default="socket",
                   help="frame of the cone's force (default socket)")
    p.add_argument("--solver", default="default", help="default (the full chain), compiled, proxqp or clarabel")
    poses = p.add_mutually_exclusive_group(required=True)
    poses.add_argument("--grid", action="append", metavar="COORD=LO:HI:N",
                       help="a grid axis (repeatable; the last varies fastest); coordinates as "
                            "mcdm-pin info names them")
    poses.add_argument("--random", type=int, metavar="N",
                       help="N poses drawn uniformly in the joint limits or --range")
    poses.add_argument("--poses", metavar="FILE.csv",
                       help="poses from a CSV file (a header of coordinate names, one pose per row)")
    p.add_argument("--at", action="append", metavar="COORD=VALUE",
                   help="hold a coordinate at a value (repeatable; the others not varied are 0)")
    p.add_argument("--range", action="append", metavar="COORD=LO:HI",
                   help="with --random: the range of a coordinate (default: its joint limits)")
    p.add_argument("--seed", type=int, default=0, help="with --random: the seed (default 0)")
    p.add_argument("--qd", metavar="COORD=VALUE,...",
                   help="constant coordinate velocities at every pose (default 0: static)")
    p.add_argument("--qdd", metavar="COORD=VALUE,...",
                   help="constant coordinate accelerations at every pose (default 0)")
    p.add_argument("--no-margins", action="store_true",
                   help="skip needed_f_max and needed_cone_deg (stored as NaN); faster")
    p.add_argument("--scheduler", default="local",
                   help="local (default: a Dask cluster on this machine's cores), tcp://HOST:PORT (a "
                        "running dask scheduler), or inline (this process, no Dask)")
    p.add_argument("--workers", type=int,
                   help="local: worker processes (default: the cores); tcp: wait for this many workers")
    p.add_argument("--chunk", type=int, help="poses per task and per Zarr chunk (default 256)")
    p.add_argument("--out", required=True, metavar="STORE.zarr", help="the Zarr store to write")
    p.add_argument("--resume", action="store_true",
                   help="complete an interrupted run: compute only the chunks the store lacks")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar")
    p.set_defaults(func=run)
    return p


def _numbers(text: str, option: str, count: int) -> list[float]:
    parts = text.split(":")
    if len(parts) != count:
        form = "LO:HI:N" if count == 3 else "LO:HI"
        raise UsageError(f"{option}: expected {form}, got {text!r}")
    return [parse_float(x, option) for x in parts]


def _pairs(items, option: str) -> dict[str, str]:
    out: dict[str, str] = {}
    for item in items or []:
        for name, value in parse_pairs(item, option).items():
            if name in out:
                raise UsageError(f"{option}: coordinate {name!r} given twice")
            out[name] = value
    return out


def _rates(robot, text: str | None, option: str):
    if not text:
        return None
    names = list(robot.coordinate_names)
    out = [0.0] * robot.nv
    for name, value in parse_pairs(text, option).items():
        if name not in names:
            raise UsageError(f"{option}: unknown coordinate {name!r}; expected one of {', '.join(names)}")
        out[names.index(name)] = parse_float(value, f"{option} {name}")
    return out


def build(args):
    """(robot, poses, setup) from parsed arguments."""
    from ..robot import Robot
    from ..workspace import Grid, PosesFile, RandomPoses, Setup

    robot = Robot.load(robot_file(args.robot))
    _check_out(args, robot)
    alpha, beta = parse_weights(robot, args.weights)
    cones = parse_cones(robot, args.cone)
    if cones and args.case != 3:
        raise UsageError("--cone applies to --case 3 only")
    at = {k: parse_float(v, f"--at {k}") for k, v in _pairs(args.at, "--at").items()}
    if args.range and args.random is None:
        raise UsageError("--range applies to --random only")
    if args.grid:
        axes = {k: _numbers(v, f"--grid {k}", 3) for k, v in _pairs(args.grid, "--grid").items()}
        poses = Grid(robot, {k: (lo, hi, n) for k, (lo, hi, n) in axes.items()}, at=at)
    elif args.random is not None:
        ranges = {k: _numbers(v, f"--range {k}", 2) for k, v in _pairs(args.range, "--range").items()}
        poses = RandomPoses(robot, args.random, seed=args.seed, ranges=ranges, at=at)
    else:
        poses = PosesFile(robot, args.poses, at=at)
    setup = Setup(case=args.case, cones=cones, alpha=alpha, beta=beta, frame=args.frame,
                  solver=args.solver, qd=_rates(robot, args.qd, "--qd"),
                  qdd=_rates(robot, args.qdd, "--qdd"), margins=not args.no_margins)
    return robot, poses, setup


def _check_out(args, robot) -> None:
    """The store's path checked before any pose is solved: a ``.zarr`` folder name in an existing
    folder, not one of the run's inputs."""
    from pathlib import Path

    out = Path(args.out)
    if out.suffix != ".zarr":
        raise UsageError(f"--out {out}: expected a store name ending in .zarr")
    if not out.resolve().parent.is_dir():
        raise UsageError(f"--out {out}: the folder {out.parent} does not exist")
    if out.exists() and not out.is_dir():
        raise UsageError(f"--out {out}: is a file, not a Zarr store")
    inputs = {Path(p).resolve() for p in (robot.sidecar.path, robot.urdf_path, args.poses) if p is not None}
    if out.resolve() in inputs:
        raise UsageError(f"--out {out}: is an input of this run; choose another name")


def run(args) -> int:
    from ..workspace import compute_workspace, summary

    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers: expected a positive number, got {args.workers}")
    if args.chunk is not None and args.chunk < 1:
        raise UsageError(f"--chunk: expected a positive number, got {args.chunk}")
    robot, poses, setup = build(args)
    report = compute_workspace(robot, poses, args.out, setup, chunk=args.chunk,
                               scheduler=args.scheduler, workers=args.workers, resume=args.resume,
                               progress=False if args.quiet else None)
    for k, why in report.recomputed.items():
        print(f"mcdm-pin: warning: {report.path}: chunk {k} was flagged done but {why}; computed it again",
              file=sys.stderr)
    print(summary(report.open()))
    rate = report.poses_per_s
    print(f"wrote {report.path}: computed {report.computed_chunks} of {report.chunks} chunks "
          f"({report.computed_poses} poses) in {report.compute_s:.2f} s"
          + (f", {rate:.1f} poses/s" if np.isfinite(rate) else "")
          + f" on {report.workers} worker thread(s), scheduler {report.scheduler} "
            f"(start-up {report.startup_s:.2f} s)")
    return 0
