"""The least-norm stage's problem solved on the optimal face and by the stage's chain, at the instants
whose optimum is a face, on the shipped robots that have such instants.

    python benchmarks/least_norm.py [--repeat 7]

Each robot's trajectory is solved once, warm, to collect the least-norm stage's inputs (the problem
and the first stage's answer) at the instants where the stage works. Then, per instant and in turns,
``--repeat`` times:

- ``face``: the face's compiled pass (``least_norm._face``: the face, its free directions and the
  least-norm point in them, ``mcdm_pin/solvers/_face_qp.py``), which is what the stage runs;
- ``chain``: the same pass, then the least-norm problem made as a ``QPData`` (``stage2_problem``) and
  solved by the stage's chain seeded with the first stage's answer, projected onto the bounds: what
  the stage runs where the face's point does not answer (a cone not held that breaks there).

The stage runs alike at warm and cold instants (its chain is seeded by the first stage's answer in
both), so one timing covers both; the first call of each path in the process (its caches cold) is
printed apart. Cells: wall time per call, us, p50 / p99 over the instants and rounds; the ratio of
the p50s; the instants where the face's point answers; the largest difference between the two
answers over the largest force. One BLAS thread; the 1-minute load and the busiest other processes
are printed (docs/speed.md, "The least-norm stage on the face itself").
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import REPO, machine_line, one_blas_thread
from myoarm import top_processes

RUNS = (("myosuite/myoarm.yaml", "abduction", 3), ("myosuite/myoelbow.yaml", "flexion", 2),
        ("human_arm.yaml", "abduct", 2), ("human_arm.yaml", "abduct", 3), ("human_arm.yaml", "reach_forward", 3),
        ("caspr/SpiderBot_UR3/SpiderBot_UR3.yaml", "x", 2))


def least_norm_inputs(robot_file: str, trajectory: str, case: int) -> tuple[list, object]:
    """``([(qp, first-stage answer)], the least-norm stage)`` at the instants of a warm run where the
    stage works (the first stage's optimum not proven unique)."""
    from mcdm_pin import InverseDynamics, Robot
    from mcdm_pin.settings import DEFAULT
    from mcdm_pin.solvers import least_norm as LN
    from mcdm_pin.trajectory import load_trajectory

    robot = Robot.load(REPO / "robots" / robot_file)
    traj = load_trajectory(robot, trajectory)
    ident = InverseDynamics.for_case(robot, case)
    stage = next(s for s in ident.solver.inner.stages if isinstance(s, LN.LeastNorm))
    seen, run = [], stage.run

    def spy(qp, sol, deadline):
        if sol.unique is None and (sol.unique_tested or not LN.is_unique(qp, sol, DEFAULT)):
            seen.append((qp, sol))
        return run(qp, sol, deadline)

    stage.run = spy
    ident.solve_trajectory(traj, progress=False)
    stage.run = run
    return seen, stage


def time_paths(inputs: list, stage, repeat: int) -> dict:
    """Wall times (s) of the two paths per call, the first calls apart, the instants the face answers
    and the largest relative difference of the answers."""
    from mcdm_pin.solvers import least_norm as LN
    from mcdm_pin.solvers.check import project_to_bounds

    s = stage.settings

    def face_path(qp, sol):
        return LN._face(qp, sol, s)

    def chain_path(qp, sol):
        face = LN._face(qp, sol, s)
        out = stage.inner.solve(LN.stage2_problem(qp, sol, s, face), hint=sol)
        return project_to_bounds(qp, out, s).x

    times = {"face": [], "chain": []}
    first = {}
    for rnd in range(repeat):
        order = ("face", "chain") if rnd % 2 == 0 else ("chain", "face")
        for qp, sol in inputs:
            for name in order:
                fn = face_path if name == "face" else chain_path
                t0 = time.perf_counter()
                fn(qp, sol)
                dt = time.perf_counter() - t0
                if name not in first:
                    first[name] = dt
                else:
                    times[name].append(dt)
    direct, worst = 0, 0.0
    for qp, sol in inputs:
        face = face_path(qp, sol)
        if face.direct:
            direct += 1
            x_chain = chain_path(qp, sol)
            worst = max(worst, float(np.abs(face.x - x_chain).max() / max(np.abs(x_chain).max(), 1e-300)))
    return dict(times={k: np.array(v) for k, v in times.items()}, first=first, direct=direct, worst=worst)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args(argv)
    one_blas_thread()
    from mcdm_pin import jit

    jit.prepare(policy="wait")
    t_start = time.perf_counter()
    print(f"{machine_line()}; 1-minute load average {os.getloadavg()[0]:.2f}; one BLAS thread\n")
    print("| robot, trajectory, case | least-norm instants | face answers | face, us (p50 / p99) "
          "| chain, us (p50 / p99) | chain / face | first call, face / chain, us | largest difference |")
    print("|---|---|---|---|---|---|---|---|")
    for robot_file, trajectory, case in RUNS:
        inputs, stage = least_norm_inputs(robot_file, trajectory, case)
        if not inputs:
            continue
        r = time_paths(inputs, stage, args.repeat)
        f, c = r["times"]["face"] * 1e6, r["times"]["chain"] * 1e6
        print(f"| {robot_file}, {trajectory}, {case} | {len(inputs)} | {r['direct']} | "
              f"{np.median(f):.1f} / {np.percentile(f, 99):.1f} | {np.median(c):.1f} / {np.percentile(c, 99):.1f} | "
              f"{np.median(c) / np.median(f):.2f} | {r['first']['face'] * 1e6:.0f} / {r['first']['chain'] * 1e6:.0f} | "
              f"{r['worst']:.1e} |")
    print(f"\n({time.perf_counter() - t_start:.0f} s; 1-minute load at the end {os.getloadavg()[0]:.2f}; "
          f"busiest processes at the end: {top_processes()})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
