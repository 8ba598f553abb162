"""What each speed-up buys: the per-instant time of the neck's roll (or any robot) with the ProxQP
back-end's accelerations switched off one at a time.

    python benchmarks/ablation.py [--robot PATH.yaml] [--trajectory roll] [--alpha 0.125]
                                  [--cone 15] [--repeat 3]

Without --robot: the 8S neck converted from CASPR and committed (robots/caspr/8S_neck). Rows:
- all on: compiled cable terms, active-set warm start (previous instant's active set, KKT-verified,
  pivoting compiled), cuts kept from the previous instant, ProxQP warm start;
- numpy cable terms: the cable terms by the numpy formulation (``TermsEvaluator(compiled=False)``);
- active set off: every instant solved by ProxQP (cutting planes + SQP polish for the cones);
- + cuts not kept, + no ProxQP warm start: the remaining accelerations removed in turn.
The model evaluation (kinematics, RNEA, M, cable maps, QP assembly) is timed separately.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from mcdm_pin import InverseDynamics, Robot, TermsEvaluator, load_trajectory
from mcdm_pin.solvers import ProxQPSolver

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import DEFAULT_CASPR as CASPR, import_neck  # noqa: E402


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--robot")
    p.add_argument("--trajectory", default="roll")
    p.add_argument("--alpha", type=float, default=0.125)
    p.add_argument("--cone", type=float, default=15.0)
    p.add_argument("--repeat", type=int, default=3)
    args = p.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(args.robot) if args.robot else import_neck(CASPR, Path(tmp)).sidecar
        robot = Robot.load(path)
        traj = load_trajectory(robot, args.trajectory)
        alpha = {j: args.alpha for j in robot.joint_names}
        cones = {j.name: args.cone for j in robot.joints if j.type == "spherical"}
        variants = [("all on", {}, True), ("numpy cable terms", {}, False),
                    ("active set off", dict(active_set=False), True),
                    ("+ cuts not kept", dict(active_set=False, keep_cuts=False), True),
                    ("+ no ProxQP warm start", dict(active_set=False, keep_cuts=False, warm_start=False), True)]
        print(f"{robot.name}, trajectory {args.trajectory} ({len(traj)} instants), median of "
              f"{args.repeat} runs per instant, ms")
        print("| case | variant | model | solve | total | instants solved | by the active set |")
        print("|---|---|---|---|---|---|---|")
        for case in (1, 2, 3):
            kw = {} if case == 1 else {"alpha": alpha}
            if case == 3:
                kw["cones"] = cones
            for name, opts, compiled in variants:
                ident = InverseDynamics.for_case(robot, case, solver=ProxQPSolver(**opts), **kw)
                ident.evaluate = TermsEvaluator(robot, compiled=compiled)
                model, solve, ok, fast = [], [], 0, 0
                for _ in range(args.repeat):
                    run = ident.solve_trajectory(traj, progress=False)
                    model.append(run.time_model_s)
                    solve.append(run.time_solve_s)
                    ok = int(run.found.sum())
                    fast = int((run.found & (run.rounds == 0)).sum())
                m = np.median(np.array(model), axis=0)
                s = np.median(np.array(solve), axis=0)
                print(f"| {case} | {name} | {np.median(m) * 1e3:.3f} | {np.median(s) * 1e3:.3f} | "
                      f"{np.median(m + s) * 1e3:.3f} | {ok} of {len(traj)} | {fast} |")


if __name__ == "__main__":
    t0 = time.perf_counter()
    main()
    print(f"(ran in {time.perf_counter() - t0:.0f} s)")
