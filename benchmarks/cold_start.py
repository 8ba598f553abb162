"""What answers a cold instant fastest inside our chain: the interior-point method at several crossover
gaps, or another first stage (the dual guess, DAQP's dual active set, or our active-set solver from an
all-free guess), on the neck and on the scaling study's chains (6 to 96 DoF).

    python benchmarks/cold_start.py [--sizes 2 4 8 16 32] [--repeat 2] [--no-neck]

Every instant is solved alone (``reset()`` then ``solve``), in order, ``--repeat`` times; cells are the
median wall time of ``solve`` per instant (ms) and the mean of the answers' ``iterations`` (interior-
point iterations plus linear KKT solves), with the 99th percentile of the wall times beside the median.
Rows:

- ``ipm gap G``: the default chain with ``Settings(ipm_crossover_gap=G, cold_dual_steps=0)`` (the
  default gap is the first; without the dual guess, so that the interior-point method answers case 1
  too);
- ``dual guess first (default)``: the default chain as it is, for case 1 (strictly convex, diagonal,
  no cones): :class:`~mcdm_pin.solvers.active_set.DualActiveSet` from zero multipliers, the
  interior-point method where it fails;
- ``daqp first``: DAQP (``daqp.solve``, cold, ``eps_prox`` 0) before the default chain's stages, for
  the strictly convex problems without cones (case 1), its multipliers as the answer's duals, then the
  chain's polish, least-norm and check stages as for any answer;
- ``all-free active set first``: the compiled active-set solver from the guess "every variable free,
  no cone held" (``warm_max_pivots`` pivots), the interior-point method where it fails.

The last column is the largest relative objective difference to the default row's answers over the
instants (every row must give the same answer: ``0`` to rounding). One BLAS thread; nothing else should
run (the 1-minute load is printed).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import DEFAULT_CASPR, machine_line, one_blas_thread
from myoarm import top_processes

GAPS = (1e-3, 1e-5, 1e-6, 1e-7)


def first_stage(name: str, answer):
    """A cold answering stage class called ``name`` whose ``run`` is ``answer(qp, settings)`` (a
    :class:`~mcdm_pin.solvers.base.Solution` or ``None``: the next stage answers)."""
    from mcdm_pin.solvers.base import Stage

    class First(Stage):
        def __init__(self, settings):
            self.settings = settings

        def run(self, qp, sol, deadline):
            return answer(qp, self.settings)

    First.name = name
    return First


def daqp_answer(qp, settings):
    """DAQP on a strictly convex problem without cones (``None`` otherwise or when DAQP fails)."""
    import daqp
    from peers.base import finite_bounds
    from peers.daqp_ import _sense

    from mcdm_pin.solvers.base import OPTIMAL, Solution

    if qp.cones or not (qp.structured and qp.P_diag.size and qp.P_diag.min() > 0.0):
        return None
    lb, ub = finite_bounds(qp)
    x, _, flag, info = daqp.solve(np.ascontiguousarray(qp.P), np.ascontiguousarray(qp.c), np.ascontiguousarray(qp.A),
                                  np.concatenate([ub, qp.b]), np.concatenate([lb, qp.b]), _sense(qp.n, len(qp.b)),
                                  eps_prox=0.0)
    if flag != 1:
        return None
    lam, n = np.asarray(info["lam"]), qp.n  # DAQP: H x + f + A^T lam = 0, as our (z, y)
    x = np.array(x)
    return Solution(x, OPTIMAL, qp.objective(x), y=lam[n:].copy(), z=lam[:n].copy(), z_cone=np.zeros((0, 3)),
                    iterations=int(info["iterations"]), stage="daqp")


def all_free_answer(qp, settings):
    """The compiled active-set solver from the guess "every variable free, no cone held"."""
    from mcdm_pin.solvers.active_set import ActiveSet, try_active_set

    none = np.zeros(0, dtype=int)
    return try_active_set(qp, ActiveSet(none, none), settings.warm_max_pivots, stage="all_free_active_set",
                          settings=settings)


def chain_with(first, settings):
    """The default chain with ``first`` (a stage class) before its answering stages."""
    from mcdm_pin.solvers.active_set import WarmActiveSet
    from mcdm_pin.solvers.chains import chain
    from mcdm_pin.solvers.clarabel_ import ClarabelStage
    from mcdm_pin.solvers.ipm import IPMStage

    def make():
        return chain("cold-start study", [first, WarmActiveSet, IPMStage, ClarabelStage], settings, make)
    return make()


def cold(ident, traj, repeat: int):
    """(median ms, p99 ms, mean iterations, objectives of the first run, instants without an answer)."""
    ts, its, objs, bad = [], [], [], 0
    for rep in range(repeat):
        for k in range(len(traj.t)):
            ident.reset()
            t0 = time.perf_counter()
            r = ident.solve(traj.q[k], traj.qd[k], traj.qdd[k])
            ts.append(time.perf_counter() - t0)
            its.append(r.iterations)
            bad += (not r.found) and rep == 0
            if rep == 0:
                objs.append(r.objective)
    return np.median(ts) * 1e3, np.quantile(ts, 0.99) * 1e3, float(np.mean(its)), np.array(objs), bad


def rows(robot, traj, kw: dict, case: int, repeat: int):
    """``(label, ms, p99 ms, iterations, objective difference, no answer)`` per row for one robot and case."""
    from mcdm_pin import InverseDynamics
    from mcdm_pin.settings import DEFAULT

    out, ref = [], None
    no_dual = DEFAULT.replace(cold_dual_steps=0)
    variants = [(f"ipm gap {g:g}", "default", no_dual.replace(ipm_crossover_gap=g)) for g in GAPS]
    if case == 1:
        variants.append(("dual guess first (default)", "default", DEFAULT))
        variants.append(("daqp first", chain_with(first_stage("daqp", daqp_answer), DEFAULT), DEFAULT))
    all_free = first_stage("all_free_active_set", all_free_answer)
    variants.append(("all-free active set first", chain_with(all_free, DEFAULT), DEFAULT))
    for label, solver, settings in variants:
        ident = InverseDynamics.for_case(robot, case, solver=solver, settings=settings, **kw)
        cold(ident, traj, 1)  # untimed: first calls
        ms, p99, it, obj, bad = cold(ident, traj, repeat)
        ref = obj if ref is None else ref
        diff = float(np.nanmax(np.abs(obj - ref) / np.maximum(np.abs(ref), 1.0)))
        out.append((label, ms, p99, it, diff, bad))
    return out


def robots(sizes, neck: bool):
    """``(name, robot, trajectory, {case: for_case options})``: the neck, then the chains."""
    import scaling
    from bench_id import load_case_setup

    if neck:
        robot, traj, kw, _ = load_case_setup("neck", Path(tempfile.mkdtemp()), DEFAULT_CASPR, None)
        yield "neck (24 DoF, 76 cables)", robot, traj, kw
    for n in sizes:
        robot, traj = scaling.build(Path(tempfile.mkdtemp()), n, 9 * n, 11)
        yield f"chain {3 * n} DoF, {9 * n} cables", robot, traj, {1: {}, 2: {}, 3: {}}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sizes", type=int, nargs="+", default=[2, 4, 8, 16, 32], help="links of the chains")
    p.add_argument("--repeat", type=int, default=2)
    p.add_argument("--cases", type=int, nargs="+", default=[1, 2, 3])
    p.add_argument("--no-neck", action="store_true")
    args = p.parse_args(argv)
    one_blas_thread()
    t0 = time.time()
    print(machine_line())
    print(f"1-min load at the start {os.getloadavg()[0]:.2f}; cold instants, {args.repeat} run(s) each; "
          "cells: median and p99 ms per instant, mean iterations, max relative objective difference to the first row")
    print("| robot | case | first stage | ms | p99 ms | iterations | objective diff | no answer |")
    print("|---|---|---|---|---|---|---|---|")
    for name, robot, traj, kw in robots(args.sizes, not args.no_neck):
        for case in args.cases:
            for label, ms, p99, it, diff, bad in rows(robot, traj, kw[case], case, args.repeat):
                print(f"| {name} | {case} | {label} | {ms:.3f} | {p99:.3f} | {it:.2f} | {diff:.1e} | {bad} |",
                      flush=True)
    print(f"\n({time.time() - t0:.0f} s; 1-min load at the end {os.getloadavg()[0]:.2f}; busiest processes at the "
          f"end: {top_processes()})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
