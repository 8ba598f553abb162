"""Batch mode on a long trajectory: sequential run against ``workers`` Dask workers, same results.

    python benchmarks/batch.py [--instants 5000] [--workers 2] [--case 1 2 3] [--repeat 3]

The neck (CASPR's 8S model, the paper's settings, committed under robots/caspr)
follows its roll trajectory's motion, from its first to its last pose, as a rest-to-rest quintic with
CASPR's one-axis interpolation of each ball joint, sampled at ``--instants`` instants over the same
duration. Each case is solved sequentially (one process, every instant warm-started from the
previous one) and in batch mode (``solve_trajectory(workers=N)``: the trajectory cut into N
contiguous pieces, one Dask worker process each); the table gives the wall time per instant of both (median of
the repeats), the speed-up, and how far the two runs' answers are apart: statuses, the objective
(relative) and the forces (N); the last column is how far two sequential runs are apart (the
floor: ProxQP's answer to the same problem varied at rounding level between calls in case 3). With a positive semidefinite objective (cases 2 and 3 with beta = 0)
the optimal forces need not be unique, so the forces may differ where the objective does not.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import DEFAULT_CASPR, import_neck, machine, neck_case_options  # noqa: E402


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--instants", type=int, default=5000)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--case", type=int, nargs="+", default=[1, 2, 3], choices=[1, 2, 3])
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--caspr", default=str(DEFAULT_CASPR))
    args = p.parse_args(argv)

    from mcdm_pin import InverseDynamics, Robot, load_trajectory
    from mcdm_pin.trajectory import quintic_trajectory

    with tempfile.TemporaryDirectory() as tmp:
        robot = Robot.load(import_neck(Path(args.caspr), Path(tmp), ["roll"]).sidecar)
        roll = load_trajectory(robot, "roll")
        duration = float(roll.t[-1] - roll.t[0])
        traj = quintic_trajectory(robot, roll.q[0], roll.q[-1], duration, duration / (args.instants - 1),
                                  name=f"roll, {args.instants} instants")
        options = neck_case_options(robot.joint_names)
        m = machine()
        print(f"neck (8S, 76 cables), {traj.name} over {duration:g} s; {args.workers} workers; median of "
              f"{args.repeat} runs. Machine: {m['cpu']}, {m['nproc']} cores, Python {m['python']}, "
              f"numba {m['versions'].get('numba')}, 1-min load {m['load_avg_1min']}.\n")
        print("| case | instants | sequential, ms / instant | batch, ms / instant | speed-up | same statuses "
              "| max objective difference (relative) | max force difference, N | two sequential runs: objective, forces |")
        print("|---|---|---|---|---|---|---|---|---|")
        for case in args.case:
            ident = InverseDynamics.for_case(robot, case, **options[case])
            ident.solve_trajectory(traj.subsample(50), progress=False)  # warm-up
            seq_t, par_t = [], []
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                seq = ident.solve_trajectory(traj, progress=False)
                seq_t.append(time.perf_counter() - t0)
                t0 = time.perf_counter()
                par = ident.solve_trajectory(traj, progress=False, workers=args.workers)
                par_t.append(time.perf_counter() - t0)
            seq2 = ident.solve_trajectory(traj, progress=False)
            same = bool(np.all(seq.status == par.status))

            def apart(a, b):
                ok = a.found & b.found
                obj = np.abs(a.objective[ok] - b.objective[ok]) / np.maximum(np.abs(a.objective[ok]), 1e-12)
                return obj.max(initial=0.0), np.abs(a.f[ok] - b.f[ok]).max(initial=0.0), ok

            obj, df, ok = apart(seq, par)
            obj2, df2, _ = apart(seq, seq2)
            n = len(traj)
            ts, tp = np.median(seq_t) / n * 1e3, np.median(par_t) / n * 1e3
            print(f"| {case} | {n} | {ts:.3f} | {tp:.3f} | {ts / tp:.2f}x | {same} ({int(ok.sum())} optimal) | "
                  f"{obj:.1e} | {df:.1e} | {obj2:.1e}, {df2:.1e} N |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
