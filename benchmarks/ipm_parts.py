"""Where the compiled interior-point call of a cold instant spends its time, per case.

    python benchmarks/ipm_parts.py [ROBOT.yaml] [TRAJECTORY] [--cases 1 2 3] [--instants 40] [--calls 50]

The problems of ``--instants`` cold instants (shuffled, each after ``InverseDynamics.reset()``) are
captured as the arguments of ``_fast.ipm_answer``; then, per case, the median over the instants of
(each the mean of ``--calls`` calls on the same arguments): the whole call, the iterations alone (the
same call with the crossover switched off and the iteration limit at the count the whole call took:
per iteration, that time over the count) and the difference (the crossover and the answer's duals,
next guess and uniqueness test). Last, the LU factor of the crossover's non-square KKT systems
(``_kkt_linalg.lu_factor``) on random dense matrices of 49 and 76 rows. ``--objective-scale G ...``: also
the mean iteration count with the objective multiplied by each ``G`` (the start is not scale
invariant). Default robot: the CASPR neck with
the paper's weights and 15 deg cones (``_common.neck_case_options``), trajectory ``roll``. The
1-minute load average is printed first (the machine is shared).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
REPO = Path(__file__).resolve().parent.parent


def _per_call(fn, args, calls: int) -> float:
    fn(*args)
    t0 = time.perf_counter()
    for _ in range(calls):
        fn(*args)
    return (time.perf_counter() - t0) / calls * 1e6


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("robot", nargs="?", default=str(REPO / "robots" / "caspr" / "8S_neck" / "8S_neck.yaml"))
    ap.add_argument("trajectory", nargs="?", default="roll")
    ap.add_argument("--cases", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--instants", type=int, default=40)
    ap.add_argument("--calls", type=int, default=50)
    ap.add_argument("--objective-scale", type=float, nargs="*", default=[])
    a = ap.parse_args(argv)

    from _common import captured_ipm_arguments, load_robot

    from mcdm_pin import InverseDynamics, jit
    from mcdm_pin.solvers import _fast, _kkt_linalg

    jit.prepare(policy="wait")
    print(f"1-minute load average {os.getloadavg()[0]:.2f}")
    robot, tr, opts = load_robot(a.robot, a.trajectory)
    print("| case | iterations p50 | whole call, us | per iteration, us | crossover and answer, us |")
    print("|---|---|---|---|---|")
    for case in a.cases:
        ident = InverseDynamics.for_case(robot, case, **opts[case])
        captured = captured_ipm_arguments(ident, tr, a.instants)
        its, whole, loop = [], [], []
        for args in captured:
            plain = tuple(map(tuple, args))  # (the entry point takes plain tuples: mcdm_pin/solvers/_structs.py)
            it = int(_fast.ipm_answer(*plain).iterations)
            its.append(it)
            whole.append(_per_call(_fast.ipm_answer, plain, a.calls))
            kqp, cones, limits = args  # the iterations alone: no crossover, as many iterations
            only = tuple(map(tuple, (kqp, cones, limits._replace(max_iter=it, crossover_gap=0.0))))
            loop.append(_per_call(_fast.ipm_answer, only, a.calls))
        its, whole, loop = np.array(its), np.array(whole), np.array(loop)
        print(f"| {case} | {np.median(its):.0f} | {np.median(whole):.1f} | {np.median(loop / its):.1f} | "
              f"{np.median(whole - loop):.1f} |")
        for g in a.objective_scale:  # P (and its diagonal and factor), c and r times g
            mean = np.mean([_fast.ipm_answer(tuple(kqp._replace(H=kqp.H * g, d0=kqp.d0 * g, F=kqp.F * np.sqrt(g),
                                                                c=kqp.c * g, r=kqp.r * g)), tuple(cones),
                                             tuple(limits)).iterations
                            for kqp, cones, limits in captured])
            print(f"|   objective x{g:g} | {mean:.2f} (mean) | | | |")
    rng = np.random.default_rng(0)
    for n in (49, 76):
        M = rng.standard_normal((n, n))
        print(f"LU factor {n} x {n}: {_per_call(_kkt_linalg.lu_factor, (M,), 2000):.1f} us")
    return 0


if __name__ == "__main__":
    sys.exit(main())
