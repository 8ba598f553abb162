"""ProxQP warm-started through ``update`` against a new ProxQP workspace per solve, on the ProxQP chain
alone (``--solver proxqp`` without the active set or Clarabel: every instant answered by ProxQP).

    python benchmarks/proxqp_update.py [--robot PATH.yaml] [--trajectory roll] [--repeat 4]

Without --robot: the 8S neck converted from CASPR and committed (robots/caspr/8S_neck). The two
variants run interleaved, ``--repeat`` times each, along the trajectory (warm, as ``solve_trajectory``
runs them); the table gives the median solve time per instant (the fastest run), ProxQP's inner
iterations in all, how many workspaces were allocated, and how far the two runs' answers are apart.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

from mcdm_pin import InverseDynamics, Robot, load_trajectory
from mcdm_pin.solvers import ProxQPSolver

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import DEFAULT_CASPR as CASPR, import_neck  # noqa: E402


def run(robot, traj, case: int, reuse: bool, kw: dict):
    ident = InverseDynamics.for_case(robot, case, solver=ProxQPSolver(active_set=False, fallback=False,
                                                                      reuse=reuse), **kw)
    res = ident.solve_trajectory(traj, progress=False)
    stage = ident.solver.inner.stage("proxqp")
    return res, float(np.median(res.time_solve_s)), int(res.iterations.sum()), stage.runner.created


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--robot")
    p.add_argument("--trajectory", default="roll")
    p.add_argument("--alpha", type=float, default=0.125)
    p.add_argument("--cone", type=float, default=15.0)
    p.add_argument("--repeat", type=int, default=4)
    args = p.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        robot = Robot.load(Path(args.robot) if args.robot else import_neck(CASPR, Path(tmp)).sidecar)
        traj = load_trajectory(robot, args.trajectory)
    alpha = {j: args.alpha for j in robot.joint_names}
    cones = {j.name: args.cone for j in robot.joints if j.type == "spherical"}
    print(f"{robot.name}, {args.trajectory} ({len(traj)} instants), ProxQP chain alone, fastest of {args.repeat}")
    print("| case | ProxQP workspace | solve, ms / instant | inner iterations | workspaces | statuses | "
          "max force difference, N |")
    print("|---|---|---|---|---|---|---|")
    for case in (1, 2, 3):
        kw = {} if case == 1 else {"alpha": alpha}
        if case == 3:
            kw["cones"] = cones
        best = {}
        for _ in range(args.repeat):
            for reuse in (False, True):
                out = run(robot, traj, case, reuse, kw)
                if reuse not in best or out[1] < best[reuse][1]:
                    best[reuse] = out
        ok = best[False][0].found & best[True][0].found
        diff = float(np.abs(best[False][0].f[ok] - best[True][0].f[ok]).max(initial=0.0))
        for reuse, label in ((False, "new per solve"), (True, "kept, data through update")):
            res, t, it, made = best[reuse]
            states = ", ".join(f"{n} {s}" for s, n in zip(*np.unique(res.status, return_counts=True)))
            print(f"| {case} | {label} | {1e3 * t:.3f} | {it} | {made} | {states} | {diff:.1e} |")


if __name__ == "__main__":
    main()
