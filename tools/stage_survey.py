"""Which stage of the default chain answers each instant of every shipped robot's first trajectory.

Robots whose sidecar defines no trajectory are skipped.

    python tools/stage_survey.py [--cases 1 2 3] [--robots 'robots/**/*.yaml']

One line per robot and case: instants, wall ms per instant, the statuses, the answering stages and why
the warm active set was refused (``mcdm_pin.solvers.active_set.MISSES``). It shows a problem that is
answered right but by a slower stage than it should be. For example, RMR's shoulder problem went to
the interior-point method and Clarabel at every frame until the active-set solve refined its point
where a variable has no curvature (docs/speed.md). Clarabel in the stages means our interior-point
method could not certify an infeasible instant.
"""

from __future__ import annotations

import argparse
import collections
import glob
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def robot_runs(pattern: str, cases, trajectories: int = 1):
    """Every shipped robot matching ``pattern`` (a glob relative to the repository) along its first
    ``trajectories`` trajectories in each of ``cases`` that applies to it: yields ``(label, ident,
    traj)`` with ``ident`` a fresh :class:`~mcdm_pin.InverseDynamics`. A sidecar that does not load is
    reported and skipped, as are robots without trajectories and cases a robot does not have (case 3
    without a ball joint)."""
    from mcdm_pin import InverseDynamics, Robot, load_trajectory

    files = sorted(glob.glob(str(REPO / pattern), recursive=True))
    os.chdir(tempfile.mkdtemp())  # (MuJoCo writes its log where it runs)
    for f in files:
        name = os.path.relpath(f, REPO / "robots")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                robot = Robot.load(f)
            except Exception as exc:  # a sidecar this tool cannot load is reported, not fatal
                print(f"{name}: not loaded ({type(exc).__name__}: {exc})")
                continue
        specs = robot.sidecar.trajectories if robot.sidecar is not None else {}
        for traj_name in list(specs)[:trajectories]:
            traj = load_trajectory(robot, traj_name)
            for case in cases:
                try:
                    ident = InverseDynamics.for_case(robot, case)
                except Exception:  # e.g. case 3 without a ball joint: not this robot's case
                    continue
                yield f"{name} {traj_name} case {case}", ident, traj


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--cases", nargs="+", type=int, default=[1, 2, 3])
    p.add_argument("--robots", default="robots/**/*.yaml", help="glob, relative to the repository")
    args = p.parse_args(argv)

    from mcdm_pin import jit
    from mcdm_pin.solvers import active_set

    jit.prepare(policy="wait")
    for label, ident, traj in robot_runs(args.robots, args.cases):
        active_set.MISSES.clear()
        t0 = time.perf_counter()
        res = ident.solve_trajectory(traj, progress=False)
        ms = (time.perf_counter() - t0) / len(traj) * 1e3
        stages = dict(collections.Counter(res.stage.tolist()))
        statuses = dict(collections.Counter(res.status.tolist()))
        print(f"{label}: {len(traj)} instants, {ms:.2f} ms each, status {statuses}, "
              f"stages {stages}, refused warm starts {dict(active_set.MISSES)}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
