"""Where the time of a warm instant goes: ``solve_trajectory`` along one trajectory, per case.

    python benchmarks/warm_instants.py ROBOT.yaml TRAJECTORY [--cases 1 2 3] [--repeat 3] [--stages]

Per case, after one untimed run: the wall time of ``solve_trajectory`` divided by the instants (the
least of ``--repeat`` runs: everything, model, problem, solver chain, check, wrenches, results), the
median / 99th percentile / largest per-instant ``time_model_s + time_solve_s`` of the last run, and
which stage answered how many instants. ``--stages``: also the time per instant spent in each stage
of the solver chain (the stages timed one by one, in a separate run). For the CASPR neck (a sidecar
whose path contains ``neck``) the paper's weights and cones are used (``_common.neck_case_options``).
The 1-minute load average is printed first: the machine is shared, and figures taken under load are
slower (docs/speed.md, "Warm instants: where the time goes").
"""

from __future__ import annotations

import argparse
import collections
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("robot")
    ap.add_argument("trajectory")
    ap.add_argument("--cases", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--stages", action="store_true")
    args = ap.parse_args(argv)

    from mcdm_pin import jit

    jit.prepare(policy="wait")
    from _common import neck_case_options

    from mcdm_pin import InverseDynamics, Robot
    from mcdm_pin.solvers.base import Stage
    from mcdm_pin.trajectory import load_trajectory

    robot = Robot.load(args.robot)
    traj = load_trajectory(robot, args.trajectory)
    options = neck_case_options(robot.joint_names) if "neck" in args.robot else {c: {} for c in (1, 2, 3)}
    print(f"{args.robot} {args.trajectory}: {len(traj)} instants; 1-minute load average "
          f"{os.getloadavg()[0]:.2f}")
    for case in args.cases:
        ident = InverseDynamics.for_case(robot, case, **options[case])
        ident.solve_trajectory(traj, progress=False)
        walls = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            run = ident.solve_trajectory(traj, progress=False)
            walls.append((time.perf_counter() - t0) / len(traj))
        per = (run.time_model_s + run.time_solve_s) * 1e3
        stages = collections.Counter(str(s) for s in run.stage).most_common()
        print(f"case {case}: wall/instant {min(walls) * 1e3:.3f} ms; model+solve p50 {np.median(per):.3f} "
              f"p99 {np.percentile(per, 99):.3f} max {per.max():.3f} ms; "
              + ", ".join(f"{name} {n}" for name, n in stages))
        if args.stages:
            spent = collections.defaultdict(float)
            original = Stage.__call__

            def timed(self, qp, sol=None, deadline=float("inf")):
                t0 = time.perf_counter()
                try:
                    return original(self, qp, sol, deadline)
                finally:
                    spent[self.name] += time.perf_counter() - t0

            Stage.__call__ = timed
            try:
                t0 = time.perf_counter()
                ident.solve_trajectory(traj, progress=False)
                wall = (time.perf_counter() - t0) / len(traj)
            finally:
                Stage.__call__ = original
            inside = sum(spent.values()) / len(traj)
            print("  per instant: " + ", ".join(f"{k} {v / len(traj) * 1e3:.3f}" for k, v in spent.items())
                  + f" ms; outside the stages {(wall - inside) * 1e3:.3f} ms (of {wall * 1e3:.3f})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
