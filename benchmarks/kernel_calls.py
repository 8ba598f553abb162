"""What a compiled kernel call costs: the interior-point call on captured cold problems, and numba's
dispatch of flat arguments against named structures.

    python benchmarks/kernel_calls.py [ROBOT.yaml] [TRAJECTORY] [--cases 1 3] [--instants 30] [--batches 7]
    python benchmarks/kernel_calls.py --chain 32 --cases 1 2 3 --instants 11   # 96 DoF, 288 cables

1. The problems of ``--instants`` cold instants (shuffled, each after ``InverseDynamics.reset()``)
   are captured as the arguments of ``_fast.ipm_answer``. Each is timed as the least of ``--batches``
   batches of 10 calls, in thread CPU time (``time.thread_time``: a preemption by another process
   does not count) and in wall time; printed: the median and the 99th percentile over the problems.
   Run it at two commits, alternated, to compare the kernels (docs/speed.md, "Fourth pass").
2. numba's dispatch: a kernel of 18 arguments (7 arrays of the neck's sizes, a bool, 10 numbers)
   that returns a 5-tuple, against the same arguments in two namedtuples with a namedtuple returned,
   each half alone, and the two structures passed as plain tuples and named again inside (what the
   library's entry points take: ``mcdm_pin/solvers/_structs.py``). Least of 5 runs of 20,000 calls,
   wall time per call.

Default robot: the CASPR neck with the paper's weights and 15 deg cones
(``_common.neck_case_options``), trajectory ``roll``; ``--chain N``: ``benchmarks/scaling.py``'s
chain of ``N`` links (``3 N`` DoF, ``9 N`` cables) along its ``sweep``. One BLAS thread; the 1-minute load average
is printed first and last (the machine is shared).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import timeit
from collections import namedtuple
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
REPO = Path(__file__).resolve().parent.parent


def _least(fn, args, batches: int, clock) -> float:
    """The least time of one call, over ``batches`` batches of 10, in microseconds."""
    fn(*args)
    best = float("inf")
    for _ in range(batches):
        t0 = clock()
        for _ in range(10):
            fn(*args)
        best = min(best, (clock() - t0) / 10)
    return best * 1e6


def ipm_calls(robot, tr, opts, cases, instants: int, batches: int) -> None:
    from _common import captured_ipm_arguments

    from mcdm_pin import InverseDynamics, jit
    from mcdm_pin.solvers import _fast

    jit.prepare(policy="wait")
    print("| case | problems | thread CPU p50 / p99, us | wall p50 / p99, us |")
    print("|---|---|---|---|")
    for case in cases:
        ident = InverseDynamics.for_case(robot, case, **opts[case])
        # (the entry point takes its structures as plain tuples: mcdm_pin/solvers/_structs.py)
        captured = [tuple(map(tuple, a)) for a in captured_ipm_arguments(ident, tr, instants)]
        cpu = np.array([_least(_fast.ipm_answer, a, batches, time.thread_time) for a in captured])
        wall = np.array([_least(_fast.ipm_answer, a, batches, time.perf_counter) for a in captured])
        print(f"| {case} | {len(captured)} | {np.median(cpu):.1f} / {np.percentile(cpu, 99):.1f} | "
              f"{np.median(wall):.1f} / {np.percentile(wall, 99):.1f} |")


def dispatch() -> None:
    from numba import njit

    Q = namedtuple("Q", "H c r A b lb ub strict")
    L = namedtuple("L", "a b c d e f g h i j")
    Out = namedtuple("Out", "code x y z obj")

    @njit
    def flat(H, c, r, A, b, lb, ub, strict, a, bb, cc, d, e, f, g, h, i, j):
        return 0, c, b, lb, r

    @njit
    def structs(q, lim):
        return Out(0, q.c, q.b, q.lb, q.r)

    @njit
    def structs_in(q, lim):
        return 0, q.c, q.b, q.lb, q.r

    @njit
    def struct_out(H, c, r, A, b, lb, ub, strict, a, bb, cc, d, e, f, g, h, i, j):
        return Out(0, c, b, lb, r)

    @njit
    def plain_in(q, lim):  # the library's entry points: plain tuples in, named again inside
        q, lim = Q(*q), L(*lim)
        return Out(0, q.c, q.b, q.lb, q.r)

    n = 85
    args = (np.eye(n), np.zeros(n), 0.0, np.ones((27, n)), np.ones(27), np.zeros(n), np.ones(n), False, 1, 2, 3.0,
            4.0, 5.0, 6.0, 7.0, True, 1e-9, 1e3)
    q, lim = Q(*args[:8]), L(*args[8:])
    rows = [("18 flat arguments, a tuple returned", flat, args),
            ("two namedtuples in, a namedtuple returned", structs, (q, lim)),
            ("two namedtuples in, a tuple returned", structs_in, (q, lim)),
            ("18 flat arguments, a namedtuple returned", struct_out, args),
            ("two plain tuples in (named inside), a namedtuple returned", plain_in, (tuple(q), tuple(lim)))]
    print("| kernel call | us per call |")
    print("|---|---|")
    for name, fn, a in rows:
        fn(*a)
        per = min(timeit.repeat(lambda: fn(*a), number=20000, repeat=5)) / 20000 * 1e6
        print(f"| {name} | {per:.2f} |")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("robot", nargs="?", default=str(REPO / "robots" / "caspr" / "8S_neck" / "8S_neck.yaml"))
    ap.add_argument("trajectory", nargs="?", default="roll")
    ap.add_argument("--cases", type=int, nargs="+", default=[1, 3])
    ap.add_argument("--instants", type=int, default=30)
    ap.add_argument("--batches", type=int, default=7)
    ap.add_argument("--chain", type=int, help="links of benchmarks/scaling.py's chain instead of ROBOT")
    a = ap.parse_args(argv)
    from _common import load_robot, one_blas_thread

    one_blas_thread()
    print(f"1-minute load average {os.getloadavg()[0]:.2f}")
    ipm_calls(*load_robot(a.robot, a.trajectory, a.chain), a.cases, a.instants, a.batches)
    dispatch()
    print(f"1-minute load average {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
